"""Verdicts on the paper's claims, computed from a study's rows (``results.csv``), never written by hand.

Each claim (``claim_config.py``) becomes one or more *comparisons*: a statistic of the rows (a mean gap, a
difference of two, a change over N, a slope over the radius, a pair metric), a threshold and the side of it
the paper is on. A comparison is decided on an interval at 95%, made honest at few seeds:

- the seed-level bootstrap of the report (``aggregate.Cells.bootstrap``: training seeds, then episodes);
- a t-interval over seeds: the statistic computed on each training seed alone, mean ± t(S-1) · sd / sqrt(S);
  with one seed there is none (the spread between training seeds is unknown), so nothing is resolved;

and the decision interval is their hull (the wider of the two, both ways). Within a study (one finding) the
comparisons of every claim are corrected together with Holm's step-down: the comparison with the k-th
smallest p-value (the larger of the t-test's and the bootstrap's) is decided at level 0.05 / (m - k + 1), and
once one is not resolved no later one is. The interval printed is the one decided on, at its own level.

A comparison is **agrees** when its interval lies on the paper's side of the threshold, **disagrees** when it
lies on the other side, otherwise **capped** when the most the statistic could move the paper's way (bounded
by the success rates: a gap by P_T, a difference of gaps by the easier factor's P_F, a shrinking gap by
itself) is below the smallest effect the design resolves, else **not resolved**. A claim of several
comparisons (an ordering, a band) disagrees if one does, agrees if all do, is capped if every comparison left
is, and is not resolved otherwise. "Not resolved" comes with the smallest effect this design resolves
(``stats/power.py``: episode noise only, a lower bound) and what would resolve the observed effect: the episodes
per cell at these seeds (episode noise), and the seeds at the observed spread between seeds.

The numbers themselves (the decision interval and p-values, Holm's levels and step-down, the power and the sample
sizes) are the statistics library's (``stats/decision.py``, ``multitest.py``, ``power.py``); this module says what
they are computed on and turns them into verdicts.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ...protocol.conditions import PAIR_SEPARATOR, TRAIN_SUITE
from ...stats.bootstrap import percentile_interval
from ...stats.decision import (
    bootstrap_p_value,
    decision_interval,
    decision_p_value,
    episodes_needed,
    seeds_needed,
)
from ...stats.estimate import Estimate
from ...stats.multitest import HOLM, rank_levels, step_down
from ...stats.power import difference_resolvable, mean_resolvable_gap, pair_metric_resolvable, slope_resolvable
from ...stats.proportions import two_sided_z
from ...stats.summaries import group_mean, nanmean, ols_slope, pair_metric_array, pooled_rates
from ..plan.claim_config import ClaimConfig
from ..plan.config import StudyConfig
from .aggregate import Cells, cell_gaps, cells, main_grid, radius_rows, shared_cell_rows

ALPHA = 0.05
AGREES, DISAGREES, NOT_RESOLVED, CAPPED = "agrees", "disagrees", "not resolved", "capped"
CONFOUNDED = "confounded (P_T fell)"  # a gap resolved smaller, but only because success fell
VERDICTS = (AGREES, DISAGREES, NOT_RESOLVED, CAPPED, CONFOUNDED)

PAPER_TIERS_STATED = [
    ["camera_pos", "object_texture", "table_pos", "table_texture"],
    ["floor_texture"],
    ["light", "distractors"],
]
PAPER_TIERS_FIG3A = [["camera_pos", "object_texture"], ["table_pos", "table_texture"], *PAPER_TIERS_STATED[1:]]

Statistic = Callable[[np.ndarray, np.ndarray], np.ndarray]  # (B, S, C) rates, episodes -> (B,)


@dataclass(frozen=True)
class Comparison:
    """One statistic against a threshold; the paper says ``sign * (statistic - threshold) > 0``."""

    label: str
    table: Cells
    statistic: Statistic
    threshold: float
    sign: int
    headroom: float  # the most the statistic can move from the threshold the paper's way (NaN: unbounded)
    resolvable: Callable[[float, float], float]  # (episodes per cell, z) -> smallest |effect| resolved (stats/power.py)
    contrary: float = math.nan  # the most it can move from the threshold the other way (NaN: unbounded)
    success: SuccessChange | None = None  # for a gap that shrinks: the treatment's P_T and P_F minus the baseline's


@dataclass(frozen=True)
class SuccessChange:
    """What a shrinking gap is made of: the treatment's (the other method's, or the larger N's) success on the
    training environments (P_T) and under the claim's factors (P_F) minus the baseline's, on the same cells. A gap
    cannot exceed P_T, so a gap that shrinks while P_T falls may only mean that success fell everywhere."""

    p_t: Statistic
    p_f: Statistic


@dataclass(frozen=True)
class Decided:
    """A comparison decided: the statistic, its decision interval (at ``level``) and its verdict."""

    label: str
    threshold: float
    sign: int
    point: float
    low: float
    high: float
    level: float
    p_value: float
    verdict: str
    headroom: float  # the most the statistic can move the paper's way (NaN: unbounded)
    smallest: float  # smallest |effect| the design resolves (episode noise)
    episodes_needed: float  # episodes per cell at these seeds that would resolve the observed effect
    seeds_needed: float  # seeds at the observed spread that would resolve it (NaN: one seed)
    seeds: int  # training seeds with a value of the statistic
    bootstrap: tuple[float, float]  # the bootstrap's interval alone, at ``level`` (with one seed: episodes only)
    contrary: float = math.nan  # the most the statistic can move the other way (NaN: unbounded)
    cells: int = 0  # the cells (method x task x N x seed x condition) it was computed on
    p_t_change: tuple[float, float, float] | None = None  # a shrink's treatment minus baseline P_T: point, interval
    p_f_change: tuple[float, float, float] | None = None  # ... and P_F under the claim's factors
    forced: bool = False  # a shrink whose sign P_T forces: the treatment's P_T is at most the baseline's gap

    @property
    def leans_other_way(self) -> bool:
        """The estimate lies on the other side of the threshold from the paper."""
        return bool(np.isfinite(self.point) and self.sign * (self.point - self.threshold) < 0)


@dataclass(frozen=True)
class ClaimVerdict:
    claim: ClaimConfig
    comparisons: list[Decided]
    verdict: str
    corrected_over: int = 0  # comparisons in the Holm correction that decided it (its finding's)
    studies: tuple[str, ...] = ()  # the studies whose cells it was decided on

    @property
    def summary(self) -> Decided | None:
        """The comparison the table shows: one that gives the claim its verdict, the weakest of them (the smallest
        effect the paper's way; the first that disagrees, for a claim that disagrees)."""
        if not self.comparisons:
            return None
        deciding = [c for c in self.comparisons if c.verdict == self.verdict] or self.comparisons
        if self.verdict == DISAGREES:
            return deciding[0]
        return min(deciding, key=lambda c: c.sign * (c.point - c.threshold))


# --- statistics on a (seed x cell) table ---------------------------------------------------------------------


def _gap_table(rows: Sequence[dict], methods: Sequence[str], conditions: Sequence[str], task: str | None) -> Cells:
    """The main grid's rows of ``methods`` on ``train`` and ``conditions`` as :class:`Cells`; with several methods,
    only the cells (task, N, seed, condition) every one of them has: a method merged on part of the grid is
    compared where both ran, not against the other's mean over tasks or seeds it lacks."""
    grid = [
        r
        for r in main_grid(rows)
        if r["method"] in methods and r["condition"] in (TRAIN_SUITE, *conditions) and task in (None, r["task"])
    ]
    return cells(shared_cell_rows(grid, methods) if len(set(methods)) > 1 else grid, gaps=True)


def _columns(table: Cells, method: str, conditions: Sequence[str], n: int | None = None) -> list[int]:
    return [i for i, k in enumerate(table.keys) if k[0] == method and k[4] in conditions and (n is None or k[2] == n)]


def _mean_gap(table: Cells, groups: list[list[int]]) -> Statistic:
    train = table.train_columns()
    return lambda r, n: group_mean(cell_gaps(r, train), groups)


def _pooled(table: Cells, columns: list[int]) -> float:
    """Success pooled over seeds and over ``columns`` (their mean)."""
    rates = pooled_rates(table.rates, table.episodes)[columns]
    return float(np.nanmean(rates)) if len(rates) and not np.all(np.isnan(rates)) else math.nan


def _train_of(table: Cells, columns: list[int]) -> list[int]:
    train = table.train_columns()
    return sorted({int(train[c]) for c in columns if train[c] >= 0})


def _episodes(table: Cells) -> float:
    known = table.episodes[table.episodes > 0]
    return float(np.median(known)) if known.size else math.nan


def _cells_per_side(table: Cells, columns: list[int]) -> int:
    return int(np.sum(~np.isnan(table.rates[:, columns])))


def gap_comparison(label: str, table: Cells, method: str, factors: Sequence[str]) -> Comparison | None:
    """The mean gap of ``factors`` (over tasks, N and seeds) against 0: the paper says it opens."""
    cols = _columns(table, method, factors)
    if not cols:
        return None
    p_train = _pooled(table, _train_of(table, cols))
    m = _cells_per_side(table, cols)
    return Comparison(
        label, table, lambda r, n: _mean_gap(table, [cols])(r, n)[..., 0], 0.0, +1, p_train,
        lambda e, z: mean_resolvable_gap(max(1, round(m * e)), p_train, z), contrary=1.0 - p_train,
    )  # fmt: skip


def difference_comparison(
    label: str, table: Cells, first: tuple[str, Sequence[str]], second: tuple[str, Sequence[str]], sign: int
) -> Comparison | None:
    """Mean gap of ``first`` (method, factors) minus that of ``second``; the paper's side is ``sign``. A gap lies in
    [P_T - 1, P_T], so the difference lies in [``first``'s P_T - 1 - ``second``'s gap, ``first``'s P_T - ``second``'s
    gap]: the headroom is the room between 0 and the bound on the paper's side, ``contrary`` the room on the other.
    (A gap below 0 is rare enough that a shrink's headroom is ``second``'s gap.) With ``sign`` -1 and two methods,
    the claim is that ``first`` shrinks the gap: its :class:`SuccessChange` goes with it."""
    a, b = _columns(table, *first), _columns(table, *second)
    if not a or not b:
        return None
    p_first, gap_second = _pooled(table, _train_of(table, a)), _gap_of(table, b)
    top, bottom = p_first - gap_second, gap_second
    headroom, contrary = (top, bottom + 1.0 - p_first) if sign > 0 else (bottom, top)
    p = _pooled(table, [*a, *b])
    m = min(_cells_per_side(table, a), _cells_per_side(table, b))
    success = _success_change(table, a, b) if sign < 0 and first[0] != second[0] else None
    return Comparison(
        label, table, lambda r, n: _mean_gap(table, [a, b])(r, n) @ np.array([1.0, -1.0]), 0.0, sign, headroom,
        lambda e, z: difference_resolvable(max(1, round(m * e)), p, z), contrary, success,
    )  # fmt: skip


def _success_change(table: Cells, treatment: list[int], baseline: list[int]) -> SuccessChange:
    """Treatment minus baseline: P_T over their ``train`` cells, P_F over their shifted ``treatment`` / ``baseline``
    columns (each the mean over cells per seed, then over seeds, as a gap is)."""
    t_train, b_train = _train_of(table, treatment), _train_of(table, baseline)
    difference = np.array([1.0, -1.0])
    return SuccessChange(
        p_t=lambda r, n: group_mean(r, [t_train, b_train]) @ difference,
        p_f=lambda r, n: group_mean(r, [treatment, baseline]) @ difference,
    )


def _gap_of(table: Cells, columns: list[int]) -> float:
    return float(_mean_gap(table, [columns])(table.rates[None], table.episodes[None])[0, 0])


# --- claims -> comparisons ---------------------------------------------------------------------------------------


def comparisons(
    claim: ClaimConfig, cfg: StudyConfig, rows: Sequence[dict], method: str | None = None
) -> list[Comparison]:
    """The comparisons that test ``claim`` on ``rows`` (those without data are left out); ``method``: the claim's,
    else the study's first."""
    method = method or claim.method or cfg.methods[0].name
    kind = claim.kind
    found: list[Comparison | None] = []
    if kind == "gap_opens":
        table = _gap_table(rows, [method], claim.factors, claim.task)
        found = [gap_comparison(" + ".join(claim.factors), table, method, claim.factors)]
    elif kind == "gap_exceeds":
        a, b = claim.factors
        table = _gap_table(rows, [method], [a, b], claim.task)
        found = [difference_comparison(f"{a} - {b}", table, (method, [a]), (method, [b]), +1)]
    elif kind == "ordering":
        tiers = [t for t in claim.tiers if t]
        table = _gap_table(rows, [method], [f for t in tiers for f in t], claim.task)
        for i, upper in enumerate(tiers):
            for lower in tiers[i + 1 :]:
                for a in upper:
                    for b in lower:
                        found.append(difference_comparison(f"{a} - {b}", table, (method, [a]), (method, [b]), +1))
    elif kind == "method_shrinks":
        table = _gap_table(rows, [method, claim.baseline], claim.factors, claim.task)
        label = f"{method} - {claim.baseline} on {' + '.join(claim.factors)}"
        found = [difference_comparison(label, table, (method, claim.factors), (claim.baseline, claim.factors), -1)]
    elif kind == "trend":
        found = [_trend_comparison(claim, method, rows)]
    elif kind == "pair":
        found = _pair_comparisons(claim, method, rows)
    return [c for c in found if c is not None]


def _trend_comparison(claim: ClaimConfig, method: str, rows: Sequence[dict]) -> Comparison | None:
    sign = -1 if claim.direction == "shrinks" else +1
    label = f"{' + '.join(claim.factors)} over {'N' if claim.over == 'n' else 'the radius'}"
    if claim.over == "n":
        table = _gap_table(
            _shared_across_n(rows, method, claim.factors, claim.task), [method], claim.factors, claim.task
        )
        ns = sorted({k[2] for k in table.keys if k[4] in claim.factors and k[0] == method})
        if len(ns) < 2:
            return None
        first, last = _columns(table, method, claim.factors, ns[0]), _columns(table, method, claim.factors, ns[-1])
        statistic = lambda r, n: _mean_gap(table, [last, first])(r, n) @ np.array([1.0, -1.0])  # noqa: E731
        start, p_last = _gap_of(table, first), _pooled(table, _train_of(table, last))
        headroom, contrary = (start, p_last - start) if sign < 0 else (p_last - start, start + 1.0 - p_last)
        p = _pooled(table, [*first, *last])
        m = min(_cells_per_side(table, first), _cells_per_side(table, last))
        success = _success_change(table, last, first) if sign < 0 else None
        return Comparison(label, table, statistic, 0.0, sign, headroom,
                          lambda e, z: difference_resolvable(max(1, round(m * e)), p, z), contrary, success)  # fmt: skip
    swept = [r for r in radius_rows(rows, claim.factors) if r["method"] == method and claim.task in (None, r["task"])]
    runs = {(r["task"], r["n_train_envs"], r["widths"]) for r in swept}
    trains = [
        r
        for r in rows
        if r["method"] == method
        and r["condition"] == TRAIN_SUITE
        and (r["task"], r["n_train_envs"], r["widths"]) in runs
    ]
    table = cells([*swept, *trains], gaps=True)
    radius = {tuple(r.get(k) for k in ("method", "task", "n_train_envs", "widths", "condition")): r["radius_m"]
              for r in swept}  # fmt: skip
    radii = sorted(set(radius.values()))
    if len(radii) < 2:
        return None
    groups = [[i for i, k in enumerate(table.keys) if radius.get(k) == rad] for rad in radii]
    train = table.train_columns()

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        return ols_slope(radii, group_mean(cell_gaps(r, train), groups)) * (radii[1] - radii[0])

    widest, narrowest = groups[-1], groups[0]
    start = _gap_of(table, narrowest)
    span = (len(radii) - 1) or 1
    p_widest = _pooled(table, _train_of(table, widest))
    headroom = (start if sign < 0 else p_widest - start) / span
    contrary = (p_widest - start if sign < 0 else start) / span
    p = _pooled(table, widest)
    m = min(_cells_per_side(table, g) for g in groups)
    step = radii[1] - radii[0]
    return Comparison(label + " (per radius step)", table, statistic, 0.0, sign, headroom,
                      lambda e, z: slope_resolvable(max(1, round(m * e)), radii, p, z) * step, contrary)  # fmt: skip


def _shared_across_n(rows: Sequence[dict], method: str, factors: Sequence[str], task: str | None) -> list[dict]:
    """``method``'s main-grid rows (of ``task``, on ``train`` and ``factors``) at the smallest and largest N where
    a factor ran, on the (task, seed, condition) cells both N have: a change over N compares the same tasks and
    seeds."""
    grid = [
        r
        for r in main_grid(rows)
        if r["method"] == method and r["condition"] in (TRAIN_SUITE, *factors) and task in (None, r["task"])
    ]
    ns = sorted({r["n_train_envs"] for r in grid if r["condition"] in factors})
    if len(ns) < 2:
        return []
    at = {n: {(r["task"], r["seed"], r["condition"]) for r in grid if r["n_train_envs"] == n} for n in (ns[0], ns[-1])}
    both = at[ns[0]] & at[ns[-1]]
    return [r for r in grid if r["n_train_envs"] in (ns[0], ns[-1]) and (r["task"], r["seed"], r["condition"]) in both]


def _matched_columns(table: Cells, method: str, conditions: Sequence[str]) -> list[list[int]] | None:
    """Each condition's columns, position ``i`` the same cell (task, N, widths) for all of them; ``None`` unless
    every condition ran in the same non-empty set of cells. Columns follow the order rows were first seen, which
    a merged or hand-made results file may give each condition differently."""
    by_cell = [{k[:4]: i for i, k in enumerate(table.keys) if k[0] == method and k[4] == c} for c in conditions]
    if not by_cell[0] or any(d.keys() != by_cell[0].keys() for d in by_cell[1:]):
        return None
    return [[d[cell] for cell in by_cell[0]] for d in by_cell]


def _pair_comparisons(claim: ClaimConfig, method: str, rows: Sequence[dict]) -> list[Comparison | None]:
    a, b = claim.pair.split(PAIR_SEPARATOR)
    table = _gap_table(rows, [method], [a, b, claim.pair], claim.task)
    matched = _matched_columns(table, method, (a, b, claim.pair))
    if matched is None:
        return [None]
    ca, cb, cab = matched

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        pooled = pooled_rates(r, n)  # (B, C): per task x N, pooled over seeds, then the metric's mean
        metric = pair_metric_array(pooled[..., cab], pooled[..., ca], pooled[..., cb])
        return nanmean(metric, axis=-1)

    p_min = min(_pooled(table, ca), _pooled(table, cb))
    m = _cells_per_side(table, cab)
    tol = claim.tolerance

    def resolvable(e: float, z: float) -> float:
        return pair_metric_resolvable(max(1, round(m * e)), p_min, z) if p_min > 0 else math.nan

    if claim.relation == "within":
        return [
            Comparison(f"{claim.pair} metric < +{tol:g}", table, statistic, +tol, -1, 1.0 + tol, resolvable),
            Comparison(f"{claim.pair} metric > -{tol:g}", table, statistic, -tol, +1, math.inf, resolvable),
        ]
    return [Comparison(f"{claim.pair} metric < -{tol:g}", table, statistic, -tol, -1, 1.0 - tol, resolvable)]


# --- deciding ---------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Evidence:
    point: float
    reps: np.ndarray  # bootstrap replicates (NaN where undefined)
    per_seed: np.ndarray  # the statistic on each training seed alone
    p_value: float  # the larger of the bootstrap's and the t-test's (1 with one seed)
    p_bootstrap: float


def _evidence(c: Comparison) -> _Evidence:
    point, reps, per_seed = _replicates(c.table, c.statistic)
    p_boot = bootstrap_p_value(reps, c.threshold)
    return _Evidence(point, reps, per_seed, decision_p_value(p_boot, per_seed, c.threshold), p_boot)


def _replicates(table: Cells, statistic: Statistic) -> tuple[float, np.ndarray, np.ndarray]:
    """A statistic's point, its bootstrap replicates (NaN where undefined) and its value on each training seed
    alone (the defined ones)."""
    point, reps = table.bootstrap(lambda r, n: np.asarray(statistic(r, n)))
    per_seed = np.array(
        [float(np.asarray(statistic(table.rates[None, s : s + 1], table.episodes[None, s : s + 1]))[0])
         for s in range(len(table.seeds))]
    )  # fmt: skip
    return float(point), np.asarray(reps, dtype=float), per_seed[np.isfinite(per_seed)]


def _verdict(c: Comparison, low: float, high: float, smallest: float, *, counts_known: bool) -> str:
    """``smallest`` is NaN both when the success rates leave nothing to resolve (capped) and when the episode
    counts are unknown (``counts_known`` false: no power, so an unresolved comparison stays not resolved).
    Headroom is judged on both sides: a comparison capped the paper's way whose estimate leans the other way,
    where this design could resolve that side, is not resolved (it may yet disagree), not capped."""
    if np.isfinite(low) and np.isfinite(high):
        above, below = low > c.threshold, high < c.threshold
        if above or below:
            return AGREES if (above if c.sign > 0 else below) else DISAGREES
    if counts_known and not np.isfinite(smallest):
        return CAPPED  # the success rates leave nothing this design can resolve (e.g. P_T or P_min at 0)
    if np.isfinite(c.headroom) and (c.headroom <= 0 or c.headroom < smallest):
        return CAPPED  # no room the paper's way, or less than the design resolves
    return NOT_RESOLVED


def _uncapped_the_other_way(c: Comparison, point: float, smallest: float) -> bool:
    """A capped comparison whose estimate lies the other way, with room there that this design resolves."""
    leans = np.isfinite(point) and c.sign * (point - c.threshold) < 0
    return bool(leans and np.isfinite(smallest) and not (np.isfinite(c.contrary) and c.contrary < smallest))


def _change(table: Cells, statistic: Statistic, level: float) -> tuple[float, float, float]:
    """A success change with its interval at ``level``: the decision interval (bootstrap and t, hulled), or with
    one seed the bootstrap's alone (episodes only)."""
    point, reps, per_seed = _replicates(table, statistic)
    hull = decision_interval(point, reps, per_seed, level)
    low, high = hull.low, hull.high
    if not np.isfinite(low):  # one seed (both ends are NaN together)
        low, high = (float(x) for x in percentile_interval(reps, level=level))
    return point, float(low), float(high)


def _confounded(verdict: str, forced: bool, p_t: tuple[float, float, float], p_f: tuple[float, float, float]) -> bool:
    """A shrink that agrees on its gap, but whose treatment's P_T is resolved below the baseline's (or is at most
    the baseline's gap, which forces the sign), agrees only if its P_F is resolved above the baseline's: else the
    gap shrank because success fell, not because the policy generalizes better. Resolved means at the comparison's
    level on seed-level intervals: a gap that agrees has two seeds or more, so its success changes have them too."""
    if verdict != AGREES:
        return False
    fell, improved = p_t[2] < 0, p_f[1] > 0
    return (fell or forced) and not improved


@dataclass(frozen=True)
class _Part:
    """One study's claims and rows, decided together with the other studies of its finding."""

    claims: Sequence[ClaimConfig]
    cfg: StudyConfig
    rows: Sequence[dict]


def _cell_label(row: dict) -> tuple:
    return tuple(row.get(k) for k in ("method", "task", "n_train_envs", "seed", "widths", "condition"))


def _claim_groups(parts: Sequence[_Part]) -> dict[tuple[int, int], tuple[int, list[dict], tuple[str, ...]]]:
    """(part, claim) -> (group, rows, studies). A group is one (method, baseline, task) in the studies whose cells of
    it are all cells of another's (the same evaluation steps: a study that re-reports part of another's grid), so
    that comparison is decided once, on the larger study's cells. Two studies that share only some cells (each has
    cells the other lacks) test different comparisons and keep their own."""
    claims = []  # (part, claim, (method, baseline, task), its rows, their evaluation steps)
    for i, part in enumerate(parts):
        default = part.cfg.methods[0].name
        for j, claim in enumerate(part.claims):
            who = (claim.method or default, claim.baseline, claim.task)
            mine = [r for r in part.rows if r["method"] in who[:2]]
            claims.append((i, j, who, mine, {r["step"] for r in mine if r.get("step")}))
    group = list(range(len(claims)))  # union-find over claims: same who, and the same study or a shared step

    def root(x: int) -> int:
        while group[x] != x:
            x = group[x]
        return x

    for x, (i, _, who, _, steps) in enumerate(claims):
        for y, (k, _, other, _, other_steps) in enumerate(claims[:x]):
            if other == who and (i == k or (steps and other_steps and (steps <= other_steps or other_steps <= steps))):
                group[root(x)] = root(y)
    out = {}
    for x, (i, j, *_) in enumerate(claims):
        members = [c for y, c in enumerate(claims) if root(y) == root(x)]
        seen: set = set()
        rows = []
        for member in sorted(members, key=lambda c: -len(c[3])):  # the largest study's cells, then any it lacks
            for row in member[3]:
                if _cell_label(row) not in seen:
                    seen.add(_cell_label(row))
                    rows.append(row)
        studies = tuple(dict.fromkeys(parts[c[0]].cfg.name for c in sorted(members, key=lambda c: c[0])))
        out[(i, j)] = (root(x), rows, studies)
    return out


def decide(claims: Sequence[ClaimConfig], cfg: StudyConfig, rows: Sequence[dict]) -> list[ClaimVerdict]:
    """Every claim's verdict, the comparisons of all of them corrected together (Holm): one study, one finding."""
    return decide_together([(claims, cfg, rows)])[0]


def decide_together(
    studies: Sequence[tuple[Sequence[ClaimConfig], StudyConfig, Sequence[dict]]],
) -> list[list[ClaimVerdict]]:
    """The claims of several studies of one finding, corrected once: Holm over every comparison of all of them.
    A comparison two claims share (the same statistic of the same method, baseline and task: both readings of the
    ordering, or one claim in two studies that share its cells) is one test, counted once and decided on the
    union of its studies' cells. Per study, its claims' verdicts in order."""
    parts = [_Part(list(c), cfg, list(r)) for c, cfg, r in studies]
    groups = _claim_groups(parts)
    per_claim: dict[tuple[int, int], list[tuple]] = {}
    unique: dict[tuple, Comparison] = {}
    for (i, j), (group, rows, _) in groups.items():
        claim = parts[i].claims[j]
        method = claim.method or parts[i].cfg.methods[0].name
        found = [((group, c.label), c) for c in comparisons(claim, parts[i].cfg, rows, method)]
        per_claim[(i, j)] = [key for key, _ in found]
        for key, c in found:
            unique.setdefault(key, c)
    keys = list(unique)
    evidence = {key: _evidence(unique[key]) for key in keys}
    order = sorted(keys, key=lambda key: (evidence[key].p_value, evidence[key].p_bootstrap, key[1], key[0]))
    levels = [1 - a for a in rank_levels(len(order), ALPHA, HOLM)]  # Holm: the k-th smallest p at ALPHA / (m - k)
    first = [_interval(unique[key], evidence[key], level) for key, level in zip(order, levels)]
    held = step_down([looked.verdict in (AGREES, DISAGREES) for looked in first])  # Holm's step-down
    decided = {
        key: _decide_one(unique[key], evidence[key], looked, rejected)
        for key, looked, rejected in zip(order, first, held)
    }
    out: list[list[ClaimVerdict]] = []
    for i, part in enumerate(parts):
        mine = []
        for j, claim in enumerate(part.claims):
            found = [decided[key] for key in per_claim[(i, j)]]
            mine.append(ClaimVerdict(claim, found, combine([d.verdict for d in found]), len(order), groups[(i, j)][2]))
        out.append(mine)
    return out


@dataclass(frozen=True)
class _Looked:
    """A comparison at its Holm level, before the step-down: its decision interval and its verdict on it alone."""

    level: float
    interval: Estimate
    z: float
    smallest: float
    verdict: str


def _interval(c: Comparison, ev: _Evidence, level: float) -> _Looked:
    """One comparison at its own level: its decision interval and the verdict that interval gives, as if it were
    the only comparison (the step-down may yet leave it not resolved)."""
    interval = decision_interval(ev.point, ev.reps, ev.per_seed, level)
    z = two_sided_z(level)
    episodes = _episodes(c.table)
    smallest = c.resolvable(episodes, z) if np.isfinite(episodes) else math.nan  # counts unknown: no power
    verdict = _verdict(c, interval.low, interval.high, smallest, counts_known=bool(np.isfinite(episodes)))
    if verdict == CAPPED and _uncapped_the_other_way(c, ev.point, smallest):
        verdict = NOT_RESOLVED  # it cannot agree, but it may yet disagree
    return _Looked(level, interval, z, smallest, verdict)


def _decide_one(c: Comparison, ev: _Evidence, looked: _Looked, rejected: bool) -> Decided:
    """One comparison decided: ``rejected`` is Holm's step-down on its null (false once an earlier comparison was
    left unresolved, so it is not resolved either; a confounded shrink's gap did shrink, so Holm goes on past it)."""
    level, verdict, smallest = looked.level, looked.verdict, looked.smallest
    if not rejected and verdict in (AGREES, DISAGREES):
        verdict = NOT_RESOLVED  # Holm: nothing after the first comparison left unresolved is resolved
    p_t = p_f = None
    forced = False
    if c.success is not None:
        p_t, p_f = _change(c.table, c.success.p_t, level), _change(c.table, c.success.p_f, level)
        forced = bool(np.isfinite(c.contrary) and c.contrary <= 0)
        if _confounded(verdict, forced, p_t, p_f):
            verdict = CONFOUNDED
    effect = abs(ev.point - c.threshold)
    return Decided(
        c.label, c.threshold, c.sign, ev.point, looked.interval.low, looked.interval.high, level, ev.p_value,
        verdict, c.headroom, smallest, episodes_needed(c.resolvable, effect, looked.z),
        seeds_needed(ev.per_seed, effect, level), len(ev.per_seed),
        tuple(float(x) for x in percentile_interval(ev.reps, level=level)), c.contrary,
        int(np.sum(~np.isnan(c.table.rates))), p_t, p_f, forced,
    )  # fmt: skip


def combine(verdicts: Sequence[str]) -> str:
    """A claim of several comparisons: disagrees if one does, agrees if all do, confounded if the rest agree but
    one shrank only as success fell, capped if all the rest are."""
    if not verdicts:
        return NOT_RESOLVED
    if DISAGREES in verdicts:
        return DISAGREES
    if all(v == AGREES for v in verdicts):
        return AGREES
    if all(v in (AGREES, CONFOUNDED) for v in verdicts):
        return CONFOUNDED
    if all(v in (AGREES, CAPPED) for v in verdicts):
        return CAPPED
    return NOT_RESOLVED


# --- the paper's ordering, for every study -------------------------------------------------------------------------


def ordering_claims(factors: Sequence[str]) -> list[ClaimConfig]:
    """The paper's ordering (section 5.1) over the study's ``factors``: its text's three tiers, and the four
    tiers of our reading of Fig. 3a; each where at least two tiers have a factor of the study."""
    out = []
    for tiers, text, source in (
        (PAPER_TIERS_STATED, "the factor ordering, the text's tiers", "section 5.1 (text)"),
        (PAPER_TIERS_FIG3A, "the factor ordering, Fig. 3a's tiers (our reading)", "section 5.1, Fig. 3a"),
    ):
        kept = [[f for f in tier if f in factors] for tier in tiers]
        kept = [t for t in kept if t]
        if len(kept) >= 2:
            out.append(ClaimConfig(kind="ordering", text=text, source=source, tiers=kept))
    return out


def study_claims(cfg: StudyConfig) -> list[ClaimConfig]:
    """The claims a study tests: its own (``claims``), else the paper's ordering over its factors."""
    return list(cfg.claims) if cfg.claims else ordering_claims(cfg.shifted_factors())
