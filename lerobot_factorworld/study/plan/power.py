"""What a plan can resolve before it runs (``--dry-run``): the smallest gap each cell and each summary of
the report can tell from 0, for the plan's episode and seed counts.

"Resolve" means: the 95% interval of the quantity excludes 0 when the true value is exactly that large
(the expected outcome counts plugged in). Methods, per quantity:

- **one cell's gap** P_T - P_F over ``episodes`` paired episodes: Newcombe's paired interval (the one in
  ``results.csv``, :func:`metrics.newcombe_paired`) on the expected 2x2 table, in two cases: *no
  reversals*, no episode succeeds only when shifted (every shifted success is also a train success; whole
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

Only episode noise is counted: training seeds differ from each other too, which widens every summary's
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

from ..metrics import Z95, newcombe_paired
from ..sequential import DECIDED, StopRule, apply_rule
from .config import RADII_M, StudyConfig

PLANNED_P = (0.5, 0.8, 0.95)  # planned success rates on the training environments (P_T), or P_min for pairs
RADIUS_STEP_M = 0.025  # slopes per step of the appendix's radii (as the report)
GRID = 2000  # resolution of the searches over a gap in [0, P_T]


def cell_resolvable_gap(episodes: int, p_train: float, paired: bool = True, z: float = Z95) -> float:
    """Smallest gap whose Newcombe paired 95% interval excludes 0 in a cell of ``episodes`` paired episodes
    at train success ``p_train``: best case (``paired``: no episode succeeds only when shifted) on whole
    episode counts, or independent outcomes on expected counts. NaN if even P_F = 0 is not resolved."""
    n = episodes
    k_train = round(p_train * n)
    if paired:
        for b in range(0, k_train + 1):  # b train-only successes: a = k_train - b, c = 0
            if newcombe_paired(k_train - b, b, 0, n - k_train, z)[1] > 0:
                return b / n
        return math.nan
    for i in range(GRID + 1):
        d = p_train * i / GRID
        p_f = p_train - d
        a, b = n * p_train * p_f, n * p_train * (1 - p_f)
        c, dd = n * (1 - p_train) * p_f, n * (1 - p_train) * (1 - p_f)
        if newcombe_paired(a, b, c, dd, z)[1] > 0:
            return d
    return math.nan


def mean_resolvable_gap(pairs: int, p_train: float, z: float = Z95) -> float:
    """Smallest mean gap over ``pairs`` episode pairs (all cells together) whose normal-approximation 95%
    interval excludes 0, outcomes independent given the rates (at P_T = 0.5 the closed form is
    sqrt(z^2 / 2 / (pairs + z^2)), up to the search's resolution). NaN at P_T = 0, where no gap can open, as
    ``cell_resolvable_gap`` gives."""
    if p_train <= 0:
        return math.nan
    for i in range(1, GRID + 1):
        d = p_train * i / GRID
        p_f = p_train - d
        if z * math.sqrt((p_train * (1 - p_train) + p_f * (1 - p_f)) / pairs) <= d:
            return d
    return math.nan


def difference_resolvable(pairs: int, p: float, z: float = Z95) -> float:
    """Smallest difference between two success rates near ``p``, each over ``pairs`` episodes (independent
    outcomes), that a 95% normal interval tells from 0."""
    return z * math.sqrt(2 * p * (1 - p) / pairs)


def pair_metric_resolvable(pairs: int, p_min: float, z: float = Z95) -> float:
    """Smallest pair metric |(P_A+B - P_min) / P_min| that a 95% normal interval tells from 0."""
    return difference_resolvable(pairs, p_min, z) / p_min


def slope_resolvable(pairs_per_radius: int, radii: Sequence[float], p: float, z: float = Z95) -> float:
    """Smallest least-squares slope of the gap on the radius (gap per metre) that a 95% normal interval
    tells from 0, each radius's mean gap over ``pairs_per_radius`` episodes (independent, small gaps)."""
    mean = sum(radii) / len(radii)
    sxx = sum((r - mean) ** 2 for r in radii)
    if sxx == 0:
        return math.nan
    return z * math.sqrt(2 * p * (1 - p) / pairs_per_radius / sxx)


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
    stops = apply_rule(train, np.zeros((len(counts), 1, n)), rule, k=k)
    decided = np.flatnonzero(stops.reason[:, 0] == DECIDED)
    if not len(decided):
        return math.nan, 0
    return counts[decided[0]] / n, int(stops.episodes[decided[0], 0])


def auto_power_lines(cfg: StudyConfig, planned: Sequence[float] = PLANNED_P) -> list[str]:
    """The ``--dry-run`` lines under ``eval.episodes=auto``: what its rule decides within the budget."""
    rule, k = cfg.eval.stop_rule(), max(1, len(cfg.conditions()))
    every = apply_rule(np.ones((1, rule.max_episodes)), np.zeros((1, 1, rule.max_episodes)), rule, k=k)
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
