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
(``power.py``: episode noise only, a lower bound) and what would resolve the observed effect: the episodes per
cell at these seeds (episode noise), and the seeds at the observed spread between seeds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ...protocol.conditions import PAIR_SEPARATOR, TRAIN_SUITE
from ..metrics import group_mean, nanmean, ols_slope, pair_metric_array, percentile_interval, pooled_rates
from ..plan.claim_config import ClaimConfig
from ..plan.config import StudyConfig
from ..plan.power import difference_resolvable, mean_resolvable_gap, pair_metric_resolvable, slope_resolvable
from .aggregate import Cells, cell_gaps, cells, main_grid, radius_rows

ALPHA = 0.05
AGREES, DISAGREES, NOT_RESOLVED, CAPPED = "agrees", "disagrees", "not resolved", "capped"
VERDICTS = (AGREES, DISAGREES, NOT_RESOLVED, CAPPED)
MAX_EPISODES = 100_000  # the search for the episodes that would resolve an effect stops here

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
    resolvable: Callable[[float, float], float]  # (episodes per cell, z) -> smallest |effect| resolved (power.py)


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


@dataclass(frozen=True)
class ClaimVerdict:
    claim: ClaimConfig
    comparisons: list[Decided]
    verdict: str

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
    grid = [
        r
        for r in main_grid(rows)
        if r["method"] in methods and r["condition"] in (TRAIN_SUITE, *conditions) and task in (None, r["task"])
    ]
    return cells(grid, gaps=True)


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
        lambda e, z: mean_resolvable_gap(max(1, round(m * e)), p_train, z),
    )  # fmt: skip


def difference_comparison(
    label: str, table: Cells, first: tuple[str, Sequence[str]], second: tuple[str, Sequence[str]], sign: int
) -> Comparison | None:
    """Mean gap of ``first`` (method, factors) minus that of ``second``; the paper's side is ``sign``. The most
    it can move the paper's way: with ``sign`` +1, ``first``'s P_T minus ``second``'s gap (``first``'s gap
    cannot grow past its P_T); with -1, ``second``'s gap (``first``'s cannot shrink below 0)."""
    a, b = _columns(table, *first), _columns(table, *second)
    if not a or not b:
        return None
    headroom = _pooled(table, _train_of(table, a)) - _gap_of(table, b) if sign > 0 else _gap_of(table, b)
    p = _pooled(table, [*a, *b])
    m = min(_cells_per_side(table, a), _cells_per_side(table, b))
    return Comparison(
        label, table, lambda r, n: _mean_gap(table, [a, b])(r, n) @ np.array([1.0, -1.0]), 0.0, sign, headroom,
        lambda e, z: difference_resolvable(max(1, round(m * e)), p, z),
    )  # fmt: skip


def _gap_of(table: Cells, columns: list[int]) -> float:
    return float(_mean_gap(table, [columns])(table.rates[None], table.episodes[None])[0, 0])


# --- claims -> comparisons ---------------------------------------------------------------------------------------


def comparisons(claim: ClaimConfig, cfg: StudyConfig, rows: Sequence[dict]) -> list[Comparison]:
    """The comparisons that test ``claim`` on ``rows`` (those without data are left out)."""
    method = claim.method or cfg.methods[0].name
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
        table = _gap_table(rows, [method], claim.factors, claim.task)
        ns = sorted({k[2] for k in table.keys if k[4] in claim.factors and k[0] == method})
        if len(ns) < 2:
            return None
        first, last = _columns(table, method, claim.factors, ns[0]), _columns(table, method, claim.factors, ns[-1])
        statistic = lambda r, n: _mean_gap(table, [last, first])(r, n) @ np.array([1.0, -1.0])  # noqa: E731
        start = _gap_of(table, first)
        headroom = start if sign < 0 else _pooled(table, _train_of(table, last)) - start
        p = _pooled(table, [*first, *last])
        m = min(_cells_per_side(table, first), _cells_per_side(table, last))
        return Comparison(label, table, statistic, 0.0, sign, headroom,
                          lambda e, z: difference_resolvable(max(1, round(m * e)), p, z))  # fmt: skip
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
    headroom = (start if sign < 0 else _pooled(table, _train_of(table, widest)) - start) / span
    p = _pooled(table, widest)
    m = min(_cells_per_side(table, g) for g in groups)
    step = radii[1] - radii[0]
    return Comparison(label + " (per radius step)", table, statistic, 0.0, sign, headroom,
                      lambda e, z: slope_resolvable(max(1, round(m * e)), radii, p, z) * step)  # fmt: skip


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
    point, reps = c.table.bootstrap(lambda r, n: np.asarray(c.statistic(r, n)))
    per_seed = np.array(
        [float(np.asarray(c.statistic(c.table.rates[None, s : s + 1], c.table.episodes[None, s : s + 1]))[0])
         for s in range(len(c.table.seeds))]
    )  # fmt: skip
    per_seed = per_seed[np.isfinite(per_seed)]
    p_boot = _p_bootstrap(c, reps)
    return _Evidence(float(point), np.asarray(reps, dtype=float), per_seed, _p_value(c, p_boot, per_seed), p_boot)


def _p_bootstrap(c: Comparison, reps: np.ndarray) -> float:
    """Two-sided bootstrap p-value against the threshold (1 where the statistic is undefined too often)."""
    x = reps[np.isfinite(reps)] - c.threshold
    if x.size < len(reps) / 2:
        return 1.0
    return float(min(1.0, 2 * (min(np.sum(x <= 0), np.sum(x >= 0)) + 1) / (x.size + 1)))


def _p_value(c: Comparison, p_boot: float, per_seed: np.ndarray) -> float:
    """Two-sided p-value against the threshold: the larger of the bootstrap's and the t-test's (1 with one seed)."""
    if len(per_seed) < 2:
        return 1.0
    sd = float(np.std(per_seed, ddof=1))
    diff = float(np.mean(per_seed)) - c.threshold
    if sd == 0:
        p_t = 0.0 if diff != 0 else 1.0
    else:
        p_t = float(2 * stats.t.sf(abs(diff) / (sd / math.sqrt(len(per_seed))), df=len(per_seed) - 1))
    return max(p_boot, p_t)


def decision_interval(reps: np.ndarray, per_seed: np.ndarray, level: float) -> tuple[float, float]:
    """The hull of the bootstrap's percentile interval and the t-interval over seeds at ``level`` (NaN
    with fewer than two seeds or a bootstrap undefined too often: no seed-level interval)."""
    lo, hi = percentile_interval(reps, level=level)
    if len(per_seed) < 2 or not (np.isfinite(lo) and np.isfinite(hi)):
        return math.nan, math.nan
    half = stats.t.ppf(1 - (1 - level) / 2, df=len(per_seed) - 1) * np.std(per_seed, ddof=1) / math.sqrt(len(per_seed))
    mean = float(np.mean(per_seed))
    return min(float(lo), mean - half), max(float(hi), mean + half)


def _verdict(c: Comparison, low: float, high: float, smallest: float, *, counts_known: bool) -> str:
    """``smallest`` is NaN both when the success rates leave nothing to resolve (capped) and when the episode
    counts are unknown (``counts_known`` false: no power, so an unresolved comparison stays not resolved)."""
    if np.isfinite(low) and np.isfinite(high):
        above, below = low > c.threshold, high < c.threshold
        if above or below:
            return AGREES if (above if c.sign > 0 else below) else DISAGREES
    if counts_known and not np.isfinite(smallest):
        return CAPPED  # the success rates leave nothing this design can resolve (e.g. P_T or P_min at 0)
    if np.isfinite(c.headroom) and (c.headroom <= 0 or c.headroom < smallest):
        return CAPPED  # no room the paper's way, or less than the design resolves
    return NOT_RESOLVED


def _episodes_needed(c: Comparison, effect: float, z: float) -> float:
    """Episodes per cell (at these seeds) whose power-code resolution reaches ``effect`` (NaN: none does)."""
    if not (np.isfinite(effect) and effect > 0):
        return math.nan
    e = 1
    while e <= MAX_EPISODES:
        resolved = c.resolvable(e, z)
        if np.isfinite(resolved) and resolved <= effect:
            return float(e)
        e = max(e + 1, math.ceil(e * 1.1))
    return math.nan


def _seeds_needed(per_seed: np.ndarray, effect: float, level: float) -> float:
    """Seeds whose t-interval (at ``level``) at the observed spread between seeds excludes ``effect``."""
    if len(per_seed) < 2 or not effect > 0:
        return math.nan
    sd = float(np.std(per_seed, ddof=1))
    if sd == 0:
        return float(len(per_seed))
    for s in range(2, 1001):
        if stats.t.ppf(1 - (1 - level) / 2, df=s - 1) * sd / math.sqrt(s) < effect:
            return float(s)
    return math.nan


def decide(claims: Sequence[ClaimConfig], cfg: StudyConfig, rows: Sequence[dict]) -> list[ClaimVerdict]:
    """Every claim's verdict, the comparisons of all of them corrected together (Holm). A comparison two claims
    share (the same factors, method and task: e.g. both readings of the ordering) is one test, counted once."""
    default = cfg.methods[0].name
    per_claim = [
        [((c.label, claim.method or default, claim.baseline, claim.task), c) for c in comparisons(claim, cfg, rows)]
        for claim in claims
    ]
    unique = {key: c for found in per_claim for key, c in found}
    keys = list(unique)
    evidence = {key: _evidence(unique[key]) for key in keys}
    order = sorted(keys, key=lambda key: (evidence[key].p_value, evidence[key].p_bootstrap, key[0]))
    decided: dict[tuple, Decided] = {}
    stopped = False
    for rank, key in enumerate(order):
        c, ev = unique[key], evidence[key]
        level = 1 - ALPHA / (len(order) - rank)
        low, high = decision_interval(ev.reps, ev.per_seed, level)
        z = float(stats.norm.ppf(1 - (1 - level) / 2))
        episodes = _episodes(c.table)
        smallest = c.resolvable(episodes, z) if np.isfinite(episodes) else math.nan  # counts unknown: no power
        verdict = _verdict(c, low, high, smallest, counts_known=bool(np.isfinite(episodes)))
        if stopped and verdict in (AGREES, DISAGREES):
            verdict = NOT_RESOLVED  # Holm: nothing after the first comparison left unresolved is resolved
        if verdict not in (AGREES, DISAGREES):
            stopped = True
        effect = abs(ev.point - c.threshold)
        decided[key] = Decided(
            c.label, c.threshold, c.sign, ev.point, low, high, level, ev.p_value, verdict, c.headroom, smallest,
            _episodes_needed(c, effect, z), _seeds_needed(ev.per_seed, effect, level), len(ev.per_seed),
            tuple(float(x) for x in percentile_interval(ev.reps, level=level)),
        )  # fmt: skip
    out = []
    for claim, found in zip(claims, per_claim):
        mine = [decided[key] for key, _ in found]
        out.append(ClaimVerdict(claim, mine, combine([d.verdict for d in mine])))
    return out


def combine(verdicts: Sequence[str]) -> str:
    """A claim of several comparisons: disagrees if one does, agrees if all do, capped if all the rest are."""
    if not verdicts:
        return NOT_RESOLVED
    if DISAGREES in verdicts:
        return DISAGREES
    if all(v == AGREES for v in verdicts):
        return AGREES
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
