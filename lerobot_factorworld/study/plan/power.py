"""What a plan can resolve before it runs (``--dry-run``): the smallest gap each cell and each summary of
the report can tell from 0, for the plan's episode and seed counts.

"Resolve" means: the 95% interval of the quantity excludes 0 when the true value is exactly that large
(the expected outcome counts plugged in). Methods, per quantity:

- **one cell's gap** P_T - P_F over ``episodes`` paired episodes: Newcombe's paired interval (the one in
  ``results.csv``, :func:`lerobot_factorworld.stats.proportions.newcombe_paired`) on the expected 2x2 table, in
  two cases: *no reversals*, no episode succeeds only when shifted (every shifted success is also a train success; whole
  episode counts), and *independent*, the two conditions' outcomes independent given the rates
  (a = n P_T P_F, ...). Real pairs usually lie in between;
- **a factor's mean gap over m cells** (over tasks, N and seeds; or over tasks and seeds at one N): the
  normal approximation for the mean of the m x episodes paired differences with independent outcomes,
  Var = P_T (1 - P_T) + P_F (1 - P_F): the smallest d with z * sqrt(Var / (m * episodes)) <= d (the
  no-reversal variance d (1 - d) is left out: its normal approximation is far too optimistic for the few
  discordant episodes a small gap has);
- **two factors' mean gaps apart** (the ordering): their difference is P_F,B - P_F,A over the same
  episodes; independent outcomes at P_F = P_T: z * sqrt(2 P (1 - P) / (m * episodes));
- **the pair metric** (P_A+B - P_min) / P_min: that difference relative to P_min = P;
- **the radius slope**: the least-squares slope over the sweep's radii, each radius's mean gap over m
  cells with variance 2 P (1 - P) / (m * episodes) (independent outcomes, small gaps), per 0.025 m.

The functions of one design's numbers are :mod:`lerobot_factorworld.stats.power`; this module applies them to a
study config. Only episode noise is counted: training seeds differ from each other too, which widens every summary's
interval, so every number here is a lower bound on what the study needs (the two-task study measured
standard errors of 0.01-0.09 on factor gaps over 3 seeds).

With ``eval.episodes=auto`` none of those fixed-n intervals is reported (the stopping makes them invalid), so the
lines are the rule's own (:func:`auto_power_lines`): the smallest gap its anytime-valid interval decides within the
budget with no reversals (train-only successes spread evenly over the seeds), and the earliest look at which it
can decide anything.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...stats.power import (
    cell_resolvable_gap,
    difference_resolvable,
    mean_resolvable_gap,
    pair_metric_resolvable,
    slope_resolvable,
)
from ...stats.stopping import DECIDED
from ..sequential import StopRule
from .config import RADII_M, StudyConfig

PLANNED_P = (0.5, 0.8, 0.95)  # planned success rates on the training environments (P_T), or P_min for pairs
RADIUS_STEP_M = 0.025  # slopes per step of the appendix's radii (as the report)


def _fmt(value: float) -> str:
    return "   n/a" if math.isnan(value) else f"{value:6.3f}"


def auto_decided_within(rule: StopRule, k: int, p_train: float) -> tuple[float, int]:
    """(smallest gap, its episodes): the smallest gap that ``rule``, corrected over ``k`` conditions, decides within
    its budget when no episode succeeds only when shifted (whole counts of train-only successes, spread evenly
    over the seeds), and the episodes it takes to; (NaN, 0) if even P_F = 0 is not decided."""
    n = rule.max_episodes
    counts = np.arange(round(p_train * n) + 1)
    train = np.zeros((len(counts), n))
    for row, b in enumerate(counts):  # b train-only successes at evenly spaced seeds
        train[row, np.floor(np.arange(b) * n / max(b, 1)).astype(int)] = 1.0
    stops = rule.apply(train, np.zeros((len(counts), 1, n)), k=k)
    decided = np.flatnonzero(stops.reason[:, 0] == DECIDED)
    if not len(decided):
        return math.nan, 0
    return counts[decided[0]] / n, int(stops.episodes[decided[0], 0])


def auto_power_lines(cfg: StudyConfig, planned: Sequence[float] = PLANNED_P) -> list[str]:
    """The ``--dry-run`` lines under ``eval.episodes=auto``: what its rule decides within the budget."""
    rule, k = cfg.eval.stop_rule(), max(1, len(cfg.conditions()))
    every = rule.apply(np.ones((1, rule.max_episodes)), np.zeros((1, 1, rule.max_episodes)), k=k)
    earliest = int(every.episodes[0, 0]) if every.reason[0, 0] == DECIDED else 0  # every pair favouring train
    found = [auto_decided_within(rule, k, p) for p in planned]
    header = "".join(f"  P={p:<5g}" for p in planned)
    return [
        f"  power under eval.episodes=auto ({rule.confidence:.0%} anytime-valid, Bonferroni over {k} condition(s), "
        f"blocks of {rule.block}, budget {rule.max_episodes}; methods in study/plan/power.py): the earliest decision "
        + (f"at {earliest} episodes, every pair favouring train" if earliest else "never, within the budget")
        + "; the smallest gap decided within the budget, at planned P_T (no reversals):",
        f"    {'':58s}{header}",
        f"    {'gap, one condition (anytime-valid; no reversals)':58s}" + "".join(f"  {_fmt(g)}" for g, _ in found),
    ]


def power_lines(cfg: StudyConfig, planned: Sequence[float] = PLANNED_P) -> list[str]:
    """The ``--dry-run`` lines: smallest resolvable gap per cell and per summary, at each planned P_T."""
    if cfg.eval.auto:  # no fixed-n interval is reported: what the rule itself decides
        return auto_power_lines(cfg, planned)
    n, seeds, tasks, ns = cfg.eval.budget, len(cfg.seeds), len(cfg.tasks), len(cfg.n_train_envs)
    m_factor, m_n = tasks * ns * seeds, tasks * seeds
    header = "".join(f"  P={p:<5g}" for p in planned)
    lines = [
        f"  power: smallest effect whose 95% interval excludes 0, at planned P_T (pairs: P_min) below "
        f"({n} paired episodes per cell, {seeds} seed(s); episode noise only, so lower bounds; summaries assume "
        "independent outcomes; methods in study/plan/power.py):",
        f"    {'':58s}{header}",
    ]

    def row(label: str, values: Sequence[float]) -> None:
        lines.append(f"    {label:58s}" + "".join(f"  {_fmt(v)}" for v in values))

    row("gap, one cell (Newcombe; no reversals)", [cell_resolvable_gap(n, p) for p in planned])
    row("gap, one cell (Newcombe; independent outcomes)", [cell_resolvable_gap(n, p, paired=False) for p in planned])
    row(f"factor's mean gap, {m_factor} cell(s)", [mean_resolvable_gap(m_factor * n, p) for p in planned])
    row(f"factor's gap at one N, {m_n} cell(s)", [mean_resolvable_gap(m_n * n, p) for p in planned])
    row(
        f"two factors' mean gaps apart (ordering), {m_factor} cell(s)",
        [difference_resolvable(m_factor * n, p) for p in planned],
    )
    if cfg.pair_conditions():
        row(
            f"pair metric |.|, {m_factor} cell(s), at P_min = P (paper: ±0.06)",
            [pair_metric_resolvable(m_factor * n, p) for p in planned],
        )
    radii = sorted({RADII_M[w] for w in cfg.radius_widths if w in RADII_M})
    if cfg.radius_factors and len(radii) >= 2:
        row(
            f"radius slope, gap per {RADIUS_STEP_M:g} m over {len(radii)} radii",
            [slope_resolvable(m_factor * n, radii, p) * RADIUS_STEP_M for p in planned],
        )
    return lines
