"""Aggregation of ``results.csv`` rows: one named selector per quantity the report shows, each called by
both the table and the figure that show it (so the two always agree on which rows they average).

Every selector averages over tasks (and any column not grouped by) per seed, then gives the mean,
standard error and number of seeds per group (:func:`summary`).

The interval selectors at the end give the report's 95% intervals: each puts the rows it needs into
(seed x cell) arrays (:class:`Cells`) and runs the seed-level bootstrap of ``stats.bootstrap.seed_bootstrap``
on the same computation as the point estimate (resampling training seeds, then episodes within each
cell; ``BOOTSTRAP_RESAMPLES`` resamples from the fixed ``BOOTSTRAP_SEED``).
"""

from __future__ import annotations

import itertools
import math
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...protocol.conditions import PAIR_SEPARATOR, TRAIN_SUITE
from ...stats.bootstrap import percentile_interval, seed_bootstrap
from ...stats.proportions import wilson_interval
from ...stats.ranks import rank_hardest_first, rerank, spearman
from ...stats.summaries import (
    count_within,
    group_mean,
    interaction,
    mean_se,
    ols_slope,
    pair_metric,
    pair_metric_array,
    pooled_rates,
)
from ..plan.grid import DEFAULT_WIDTHS
from .rows import parse_stage_counts

Stats = dict[tuple, tuple[float, float, int]]  # group -> (mean over seeds, SE over seeds, number of seeds)


def per_seed(rows: Iterable[dict], value: str, keys: Sequence[str]) -> dict[tuple, dict[int, float]]:
    """``value`` averaged over tasks (and any column not in ``keys``), per group of ``keys`` and seed."""
    acc: dict[tuple, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        v = row[value]
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        acc[tuple(row[k] for k in keys)][row["seed"]].append(float(v))
    return {g: {s: sum(vs) / len(vs) for s, vs in seeds.items()} for g, seeds in acc.items()}


def summary(rows: Iterable[dict], value: str, keys: Sequence[str]) -> Stats:
    """Per group: (mean over seeds, standard error over seeds, number of seeds)."""
    return {g: (*mean_se(list(s.values())), len(s)) for g, s in per_seed(rows, value, keys).items()}


def main_grid(rows: Iterable[dict]) -> list[dict]:
    """The rows of the main grid (default sampling widths; not the radius sweep's extra runs)."""
    return [r for r in rows if r["widths"] == DEFAULT_WIDTHS]


# --- one selector per table and figure ------------------------------------------------------------


def gap_per_factor_and_n(rows: Sequence[dict]) -> Stats:
    """Gap per (method, shifted condition, N), main grid: the gap table and ``gap_vs_n.png`` (``train`` has no
    gap of its own, so a study of ``train`` alone has none)."""
    shifted = [r for r in main_grid(rows) if r["condition"] != TRAIN_SUITE]
    return summary(shifted, "gap", ["method", "condition", "n_train_envs"])


def success_per_condition_and_n(rows: Sequence[dict]) -> Stats:
    """Success rate per (method, condition, N), main grid: the success-rate table and ``success_rates.png``."""
    return summary(main_grid(rows), "success_rate", ["method", "condition", "n_train_envs"])


def gap_per_factor(rows: Sequence[dict], factors: Sequence[str]) -> Stats:
    """Gap per (method, single factor of ``factors``) over N, main grid: the factor-ordering table (its
    first method) and ``methods.png``."""
    single = [r for r in main_grid(rows) if r["condition"] in factors]
    return summary(single, "gap", ["method", "condition"])


def radius_rows(rows: Sequence[dict], radius_factors: Sequence[str]) -> list[dict]:
    """The single-factor rows of the radius sweep's factors (every width, the main grid's included)."""
    return [r for r in rows if r["radius_m"] is not None and r["condition"] in radius_factors]


def gap_per_radius(rows: Sequence[dict], radius_factors: Sequence[str], per_n: bool = False) -> Stats:
    """Gap per (method, factor, radius) of the radius sweep's factors, over N (the radius table) or per
    N (``per_n``: ``gap_vs_radius.png``, keys (method, factor, N, radius))."""
    swept = radius_rows(rows, radius_factors)
    keys = ["method", "condition", "n_train_envs", "radius_m"] if per_n else ["method", "condition", "radius_m"]
    return summary(swept, "gap", keys)


def pair_rows(rows: Sequence[dict]) -> list[dict]:
    """Pair metric and interaction per method x task x N x seed x pair (main grid): the pairs table and
    ``pairs.png``."""
    index = {(r["method"], r["task"], r["n_train_envs"], r["seed"], r["condition"]): r for r in main_grid(rows)}
    out = []
    for key, row in index.items():
        if row["n_factors"] != 2:
            continue
        a, b = row["condition"].split(PAIR_SEPARATOR)
        ra, rb = index.get((*key[:4], a)), index.get((*key[:4], b))
        if ra is None or rb is None:
            continue
        out.append(
            {
                "method": key[0],
                "task": key[1],
                "n_train_envs": key[2],
                "seed": key[3],
                "pair": row["condition"],
                "pair_metric": pair_metric(row["success_rate"], ra["success_rate"], rb["success_rate"]),
                "interaction": interaction(row["gap"], ra["gap"], rb["gap"]),
            }
        )
    return out


@dataclass(frozen=True)
class PairBand:
    """One task's pairs against the paper's band: how many pair metrics (per cell, averaged over N and seeds)
    lie within ±tolerance, below it (the pair is worse than its harder factor) and above it, and the mean
    interaction gap(A+B) - gap(A) - gap(B) (negative: the pair costs less than its two gaps added) with its 95%
    seed-bootstrap interval (NaN where no pair has its train cell)."""

    within: int
    below: int
    above: int
    mean_interaction: float
    interaction_interval: tuple[float, float] = (math.nan, math.nan)
    within_interval: tuple[float, float] = (math.nan, math.nan)  # of the count ``within`` (the task's pair_summary)


def pair_bands(rows: Sequence[dict], method: str, tolerance: float) -> dict[str, PairBand]:
    """Per task, ``method``'s pairs counted against the band ±``tolerance`` (pairs without a metric left out)."""
    metrics: dict[tuple[str, str], list[float]] = defaultdict(list)
    interactions: dict[str, list[float]] = defaultdict(list)
    for row in pair_rows(rows):
        if row["method"] != method:
            continue
        if not math.isnan(row["pair_metric"]):
            metrics[(row["task"], row["pair"])].append(row["pair_metric"])
        if not math.isnan(row["interaction"]):
            interactions[row["task"]].append(row["interaction"])
    out = {}
    intervals = task_interactions(rows, method)
    for task in dict.fromkeys(task for task, _ in metrics):
        means = [float(np.mean(v)) for (t, _), v in metrics.items() if t == task]
        summary_of_task = pair_summary([r for r in rows if r["task"] == task], method, tolerance)
        out[task] = PairBand(
            within=sum(abs(m) <= tolerance for m in means),
            below=sum(m < -tolerance for m in means),
            above=sum(m > tolerance for m in means),
            mean_interaction=float(np.mean(interactions[task])) if interactions[task] else math.nan,
            interaction_interval=intervals.get(task, (math.nan, math.nan)),
            within_interval=summary_of_task.within_per_cell[1:] if summary_of_task else (math.nan, math.nan),
        )
    return out


def factor_ordering(rows: Sequence[dict], method: str, factors: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Mean gap (over N, tasks; mean and SE over seeds) per single factor of the main grid, for ``method``."""
    stats = gap_per_factor(rows, factors)
    return {f: stats[(method, f)][:2] for f in factors if (method, f) in stats}


def stage_counts(rows: Iterable[dict]) -> dict[tuple, dict[str, int]]:
    """Episodes per furthest stage (the ``stages`` column), per (method, task, N, condition) of the main grid,
    pooled over seeds; stages in the column's order (the task's), rows without stage counts left out: the
    "Where episodes fail" table."""
    out: dict[tuple, dict[str, int]] = {}
    for row in main_grid(rows):
        counts = parse_stage_counts(row.get("stages", ""))
        if counts:
            total = out.setdefault((row["method"], row["task"], row["n_train_envs"], row["condition"]), {})
            for name, n in counts.items():
                total[name] = total.get(name, 0) + n
    return out


# --- intervals: the seed-level bootstrap (stats.bootstrap.seed_bootstrap) on (seed x cell) arrays -----------

Interval = tuple[float, float, float]  # (point estimate, 95% interval low, high)
CELL_KEYS = ("method", "task", "n_train_envs", "widths", "condition")


@dataclass(frozen=True)
class Cells:
    """Rows as arrays: ``rates[s, c]`` / ``episodes[s, c]`` of cell ``keys[c]`` (``CELL_KEYS``) for seed
    ``seeds[s]``; NaN rate: no such row; 0 episodes: count unknown (the rate is then not resampled)."""

    seeds: tuple
    keys: tuple[tuple, ...]
    rates: np.ndarray
    episodes: np.ndarray

    @property
    def column(self) -> dict[tuple, int]:
        return {k: i for i, k in enumerate(self.keys)}

    def train_columns(self) -> np.ndarray:
        """Per column, the column of its ``train`` cell (same method, task, N, widths); -1 if none or train."""
        col = self.column
        return np.array(
            [-1 if k[4] == TRAIN_SUITE else col.get((*k[:4], TRAIN_SUITE), -1) for k in self.keys], dtype=int
        )

    def bootstrap(self, statistic: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """:func:`~lerobot_factorworld.stats.bootstrap.seed_bootstrap` drawn by identity (the training seeds, each column's cell key): a cell
        gets the same replicates in every table and report that holds it with the same seeds."""
        return seed_bootstrap(self.rates, self.episodes, statistic, seed_ids=self.seeds, cell_ids=self.keys)


def cells(rows: Iterable[dict], gaps: bool = False) -> Cells:
    """``rows`` as :class:`Cells`. With ``gaps``, a shifted row whose gap is undefined (no train row on the
    same episode seeds) is left out, as the gap summaries leave it out."""
    rows = [r for r in rows if not (gaps and r["condition"] != TRAIN_SUITE and _undefined(r.get("gap", math.nan)))]
    seeds = tuple(sorted({r["seed"] for r in rows}))
    keys = tuple(dict.fromkeys(tuple(r.get(k) for k in CELL_KEYS) for r in rows))
    col, row_of = {k: i for i, k in enumerate(keys)}, {s: i for i, s in enumerate(seeds)}
    rates = np.full((len(seeds), len(keys)), np.nan)
    episodes = np.zeros((len(seeds), len(keys)))
    for r in rows:
        s, c = row_of[r["seed"]], col[tuple(r.get(k) for k in CELL_KEYS)]
        rate = r.get("success_rate")
        if rate is None and r.get("episodes"):
            rate = r["successes"] / r["episodes"]  # rows that carry counts only
        rates[s, c] = math.nan if _undefined(rate) else float(rate)
        episodes[s, c] = r.get("episodes") or 0
    return Cells(seeds, keys, rates, episodes)


def _undefined(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def cell_gaps(rates: np.ndarray, train_columns: np.ndarray) -> np.ndarray:
    """(..., S, C) rates -> gaps P_T - P_F per cell (NaN for train cells and cells without a train cell)."""
    has_train = train_columns >= 0
    return np.where(has_train, rates[..., np.where(has_train, train_columns, 0)] - rates, np.nan)


def _interval(point: np.ndarray, replicates: np.ndarray) -> list[Interval]:
    lo, hi = percentile_interval(replicates)
    return [
        (float(p), float(a), float(b)) for p, a, b in zip(np.atleast_1d(point), np.atleast_1d(lo), np.atleast_1d(hi))
    ]


@dataclass(frozen=True)
class FactorGapBootstrap:
    """The factor ordering's mean gaps of one method (:func:`factor_ordering`) and their seed-bootstrap
    replicates: ``point[f]`` and ``reps[:, f]`` for factor ``names[f]``. One bootstrap, read by every interval
    of the ordering (per factor, Spearman's rho, pairwise differences), so the report resamples once."""

    names: list[str]
    point: np.ndarray
    reps: np.ndarray

    def intervals(self) -> dict[str, Interval]:
        """Per factor: the mean gap with its 95% interval."""
        return dict(zip(self.names, _interval(self.point, self.reps))) if self.names else {}

    def differences(self) -> dict[tuple[str, str], Interval]:
        """Every pair (a, b), a listed before b: gap of a minus gap of b with its 95% interval. Both gaps come
        from the same replicates, so the interval keeps what they share (the same train cells): the test of
        whether the ordering resolves a from b."""
        p, r = self.point, self.reps
        return {
            (self.names[i], self.names[j]): _interval(p[i] - p[j], r[:, i] - r[:, j])[0]
            for i, j in itertools.combinations(range(len(self.names)), 2)
        }

    def rho_interval(self, reference: Mapping[str, float]) -> tuple[float, float]:
        """95% interval of Spearman's rho between the ordering and ``reference`` (each replicate re-ranks the
        factors by its own mean gaps); NaN if rho is mostly undefined."""
        if not self.names:
            return math.nan, math.nan
        rho = spearman_with(reference)
        lo, hi = percentile_interval(
            np.array([rho(rank_hardest_first(dict(zip(self.names, rep.tolist())))) for rep in self.reps])
        )
        return float(lo), float(hi)


def spearman_with(reference: Mapping[str, float]) -> Callable[[Mapping[str, float]], float]:
    """:func:`spearman` of a ranking with ``reference``, computed once per distinct ranking (its items in order,
    so a repeat gives the same float): a bootstrap's thousands of replicates repeat a few orderings."""
    seen: dict[tuple, float] = {}

    def rho(ranks: Mapping[str, float]) -> float:
        key = tuple(ranks.items())
        if key not in seen:
            seen[key] = spearman(ranks, reference)
        return seen[key]

    return rho


def factor_gap_bootstrap(rows: Sequence[dict], method: str, factors: Sequence[str]) -> FactorGapBootstrap:
    """The :class:`FactorGapBootstrap` of ``method`` over ``factors`` (those with data, in their order)."""
    grid = [r for r in main_grid(rows) if r["method"] == method and r["condition"] in (TRAIN_SUITE, *factors)]
    table = cells(grid, gaps=True)
    present = {k[4] for k in table.keys}
    names = [f for f in factors if f in present]
    if not names:
        return FactorGapBootstrap([], np.zeros(0), np.zeros((0, 0)))
    groups = [[i for i, k in enumerate(table.keys) if k[4] == f] for f in names]
    train = table.train_columns()
    point, reps = table.bootstrap(lambda r, n: group_mean(cell_gaps(r, train), groups))
    return FactorGapBootstrap(names, point, reps)


def task_orderings(
    rows: Sequence[dict], method: str, factors: Sequence[str], tasks: Sequence[str]
) -> dict[str, FactorGapBootstrap]:
    """Per task of ``tasks`` with rows: the :class:`FactorGapBootstrap` of ``method`` over ``factors`` on that task's
    rows alone (the "Ordering per task" table, ``ordering_per_task.png`` and report.html's per-task gaps)."""
    present = {r["task"] for r in rows}
    return {
        t: factor_gap_bootstrap([r for r in rows if r["task"] == t], method, factors) for t in tasks if t in present
    }


def tasks_disagree(orderings: Mapping[str, FactorGapBootstrap]) -> bool:
    """Whether two tasks rank the factors they share differently by their point estimates (1 = hardest)."""
    ranked = [rank_hardest_first(dict(zip(b.names, b.point.tolist()))) for b in orderings.values()]
    for a, b in itertools.combinations(ranked, 2):
        shared = [f for f in a if f in b]
        if rerank([a[f] for f in shared]) != rerank([b[f] for f in shared]):
            return True
    return False


def factor_gap_intervals(rows: Sequence[dict], method: str, factors: Sequence[str]) -> dict[str, Interval]:
    """Per factor: mean gap of ``method`` (over tasks, N, seeds) with its 95% seed-bootstrap interval."""
    return factor_gap_bootstrap(rows, method, factors).intervals()


def factor_gap_differences(
    rows: Sequence[dict], method: str, factors: Sequence[str]
) -> dict[tuple[str, str], Interval]:
    """Every pair of ``factors`` with data: :meth:`FactorGapBootstrap.differences`."""
    return factor_gap_bootstrap(rows, method, factors).differences()


def ordering_rho_interval(
    rows: Sequence[dict], method: str, factors: Sequence[str], reference: Mapping[str, float]
) -> tuple[float, float]:
    """95% seed-bootstrap interval of Spearman's rho with ``reference``: :meth:`FactorGapBootstrap.rho_interval`."""
    return factor_gap_bootstrap(rows, method, factors).rho_interval(reference)


def method_gap_differences(
    rows: Sequence[dict], methods: Sequence[str], labels: Mapping[str, Sequence[str]], shared_cells_only: bool = True
) -> dict[tuple[str, str], tuple[Interval, Interval, Interval]]:
    """Every method after the first against the first: per (method, label), the mean gap over the label's
    factors (and tasks, N; then seeds) of the first method, of this one, and their difference (this minus
    the first: negative when this method shrinks the gap), each with its 95% seed-bootstrap interval (main
    grid; one bootstrap, so all share their replicates). A method whose cells (task, N, seed, condition) are not
    the first's (a study made in parts, a condition one method lacks) is compared on the cells both have, in a
    bootstrap of its own: the first's mean over cells the method lacks would compare other tasks, not the
    methods. ``shared_cells_only=False`` leaves that to the caller (two studies' cells that pair by seed at
    different N or widths: ``compare.py``)."""
    factors = {f for names in labels.values() for f in names}
    grid = [r for r in main_grid(rows) if r["method"] in methods and r["condition"] in (TRAIN_SUITE, *factors)]
    trained = {m: {_cell_of(r) for r in grid if r["method"] == m} for m in methods}
    partial = [m for m in methods[1:] if shared_cells_only and trained[m] and trained[m] != trained[methods[0]]]
    out = _gap_differences(
        [r for r in grid if r["method"] not in partial], [m for m in methods if m not in partial], labels
    )
    for method in partial:
        out.update(_gap_differences(shared_cell_rows(grid, [methods[0], method]), [methods[0], method], labels))
    return {(m, label): out[(m, label)] for m in methods[1:] for label in labels if (m, label) in out}


def method_success_differences(
    rows: Sequence[dict], methods: Sequence[str]
) -> dict[str, tuple[Interval, Interval, Interval]]:
    """Every method after the first against the first on the training environments: P_T of the first, of this one
    (each the mean success over tasks and N per seed, then over seeds) and their difference (this minus the first),
    each with its 95% seed-bootstrap interval, on the (task, N, seed) train cells both have. The gap differences
    are read with it: a gap cannot exceed P_T, so a method whose P_T is lower has less gap to lose."""
    grid = [r for r in main_grid(rows) if r["condition"] == TRAIN_SUITE]
    out = {}
    for method in methods[1:]:
        table = cells(shared_cell_rows(grid, [methods[0], method]))
        groups = [[i for i, k in enumerate(table.keys) if k[0] == m] for m in (methods[0], method)]
        if not all(groups):
            continue
        point, reps = table.bootstrap(lambda r, n, g=groups: group_mean(r, g))
        base, own, diff = _interval(
            np.array([point[0], point[1], point[1] - point[0]]),
            np.stack([reps[:, 0], reps[:, 1], reps[:, 1] - reps[:, 0]], axis=-1),
        )
        out[method] = (base, own, diff)
    return out


def _cell_of(row: dict) -> tuple:
    """The cell a main-grid row is, less its method: (task, N, seed, condition); the main grid has the default
    widths only."""
    return row["task"], row["n_train_envs"], row["seed"], row["condition"]


def shared_cell_rows(rows: Sequence[dict], methods: Sequence[str]) -> list[dict]:
    """The rows of ``methods`` on the (task, N, seed, condition) cells that every one of them has: what two
    methods are compared on (none when they share no cell)."""
    mine = [r for r in rows if r["method"] in methods]
    have = [{_cell_of(r) for r in mine if r["method"] == m} for m in dict.fromkeys(methods)]
    both = set.intersection(*have) if have else set()
    return [r for r in mine if _cell_of(r) in both]


def shared_cell_count(rows: Sequence[dict], methods: Sequence[str]) -> int:
    """How many (task, N, seed, condition) cells ``methods`` share (each method's own cells are one each)."""
    return len({_cell_of(r) for r in shared_cell_rows(main_grid(rows), methods)})


def _gap_differences(
    grid: list[dict], methods: Sequence[str], labels: Mapping[str, Sequence[str]]
) -> dict[tuple[str, str], tuple[Interval, Interval, Interval]]:
    """:func:`method_gap_differences` on ``grid``, one bootstrap for all of ``methods``."""
    table = cells(grid, gaps=True)
    wanted = [(m, label) for m in methods for label in labels]
    groups = [[i for i, k in enumerate(table.keys) if k[0] == m and k[4] in labels[label]] for m, label in wanted]
    present = [(w, g) for w, g in zip(wanted, groups) if g]
    if not present or len(methods) < 2:
        return {}
    train = table.train_columns()
    point, reps = table.bootstrap(lambda r, n: group_mean(cell_gaps(r, train), [g for _, g in present]))
    index = {w: i for i, (w, _) in enumerate(present)}
    out = {}
    base = methods[0]
    for method in methods[1:]:
        for label in labels:
            if (method, label) not in index or (base, label) not in index:
                continue
            i, j = index[(method, label)], index[(base, label)]
            intervals = _interval(
                np.array([point[j], point[i], point[i] - point[j]]),
                np.stack([reps[:, j], reps[:, i], reps[:, i] - reps[:, j]], axis=-1),
            )
            out[(method, label)] = (intervals[0], intervals[1], intervals[2])
    return out


@dataclass(frozen=True)
class PairSummary:
    """The pair metric of one method, both ways, with 95% seed-bootstrap intervals.

    ``per_cell[pair]``: the metric of every task x N x seed cell, averaged over tasks and N per seed, then
    over seeds (cells whose harder factor never succeeded left out; the paper's figure's way).
    ``pooled[pair]``: the metric of success rates pooled over seeds per task x N, averaged over tasks and N.
    ``within_*``: how many pairs' metric lies within ±``tolerance`` (point, low, high) of ``pairs`` defined.
    """

    per_cell: dict[str, Interval]
    pooled: dict[str, Interval]
    pooled_undefined: dict[str, tuple[int, int]]  # pair -> (task x N cells without a pooled metric, cells)
    within_per_cell: Interval
    within_pooled: Interval
    pairs_per_cell: int
    pairs_pooled: int


def pair_summary(rows: Sequence[dict], method: str, tolerance: float) -> PairSummary | None:
    """The pair metric of ``method``'s pairs (main grid), per cell and pooled per (task, N), with intervals."""
    grid = [r for r in main_grid(rows) if r["method"] == method]
    table = cells(grid)
    col = table.column
    triples: dict[str, list[tuple[int, int, int]]] = defaultdict(list)
    for key in table.keys:
        if PAIR_SEPARATOR not in key[4]:
            continue
        a, b = key[4].split(PAIR_SEPARATOR)
        ca, cb = col.get((*key[:4], a)), col.get((*key[:4], b))
        if ca is not None and cb is not None:
            triples[key[4]].append((col[key], ca, cb))
    if not triples:
        return None
    pairs = list(triples)
    flat = [t for p in pairs for t in triples[p]]
    ab, a, b = (np.array([t[i] for t in flat], dtype=int) for i in range(3))
    groups, start = [], 0
    for p in pairs:
        groups.append(list(range(start, start + len(triples[p]))))
        start += len(triples[p])

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        per_cell = group_mean(pair_metric_array(r[..., ab], r[..., a], r[..., b]), groups)  # (B, P)
        pooled_r = pooled_rates(r, n)  # (B, C)
        pooled_cells = pair_metric_array(pooled_r[..., ab], pooled_r[..., a], pooled_r[..., b])  # (B, J)
        pooled = group_mean(pooled_cells[..., None, :], groups)  # one "seed": the pooled rates
        counts = np.stack([count_within(per_cell, tolerance), count_within(pooled, tolerance)], axis=-1)
        return np.concatenate([per_cell, pooled, counts], axis=-1)

    point, reps = table.bootstrap(statistic)
    intervals = _interval(point, reps)
    k = len(pairs)
    pooled_point = pooled_rates(table.rates, table.episodes)
    undefined_cells = np.isnan(pair_metric_array(pooled_point[ab], pooled_point[a], pooled_point[b]))
    return PairSummary(
        per_cell=dict(zip(pairs, intervals[:k])),
        pooled=dict(zip(pairs, intervals[k : 2 * k])),
        pooled_undefined={p: (int(undefined_cells[g].sum()), len(g)) for p, g in zip(pairs, groups)},
        within_per_cell=intervals[2 * k],
        within_pooled=intervals[2 * k + 1],
        pairs_per_cell=int(np.isfinite(point[:k]).sum()),
        pairs_pooled=int(np.isfinite(point[k : 2 * k]).sum()),
    )


def task_interactions(rows: Sequence[dict], method: str) -> dict[str, tuple[float, float]]:
    """Per task, the 95% seed-bootstrap interval of ``method``'s mean interaction gap(A+B) - gap(A) - gap(B)
    over its pairs, N and seeds (main grid; a pair counts where its two factors and ``train`` were evaluated)."""
    table = cells([r for r in main_grid(rows) if r["method"] == method])
    col = table.column
    quads: dict[str, list[tuple[int, ...]]] = defaultdict(list)  # task -> [(a+b, a, b, train) columns]
    for key in table.keys:
        if PAIR_SEPARATOR not in key[4]:
            continue
        others = [col.get((*key[:4], c)) for c in (*key[4].split(PAIR_SEPARATOR), TRAIN_SUITE)]
        if None not in others:
            quads[key[1]].append((col[key], *others))
    if not quads:
        return {}
    tasks = list(quads)
    flat = [q for task in tasks for q in quads[task]]
    ab, a, b, train = (np.array([q[i] for q in flat], dtype=int) for i in range(4))
    starts = np.cumsum([0, *(len(quads[task]) for task in tasks)])
    groups = [list(range(starts[i], starts[i + 1])) for i in range(len(tasks))]

    def statistic(r: np.ndarray, _n: np.ndarray) -> np.ndarray:
        # (T - P_AB) - (T - P_A) - (T - P_B)
        return group_mean(r[..., a] + r[..., b] - r[..., ab] - r[..., train], groups)

    point, reps = table.bootstrap(statistic)
    return {task: (low, high) for task, (_, low, high) in zip(tasks, _interval(point, reps), strict=True)}


ALL_FACTORS = "all factors"  # the label of the mean over every factor given


@dataclass(frozen=True)
class GapAgainstN:
    """One method's gaps against the number of training environments: ``gaps[label]`` holds the mean gap
    (over the label's factors, tasks and seeds) at each of ``ns`` and ``change[label]`` the gap at the largest
    N minus the gap at the smallest (negative: more training environments shrink it), each an
    :data:`Interval` from one seed bootstrap."""

    ns: list[int]
    gaps: dict[str, list[Interval]]
    change: dict[str, Interval]


def gap_against_n(rows: Sequence[dict], method: str, factors: Sequence[str]) -> GapAgainstN | None:
    """:class:`GapAgainstN` of ``method`` over each of ``factors`` with data and over all of them
    (:data:`ALL_FACTORS`), main grid; ``None`` unless the method has gaps at two or more N (section 5.1's
    claim that every gap closes as N grows, Fig. 3a)."""
    grid = [r for r in main_grid(rows) if r["method"] == method and r["condition"] in (TRAIN_SUITE, *factors)]
    table = cells(grid, gaps=True)
    ns = sorted({k[2] for k in table.keys if k[4] != TRAIN_SUITE})
    present = [f for f in factors if any(k[4] == f for k in table.keys)]
    if len(ns) < 2 or not present:
        return None
    labels = {f: (f,) for f in present}
    labels[ALL_FACTORS] = tuple(present)
    groups = [
        [i for i, k in enumerate(table.keys) if k[4] in names and k[2] == n] for names in labels.values() for n in ns
    ]
    train = table.train_columns()
    shape = (len(labels), len(ns))

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        means = group_mean(cell_gaps(r, train), groups).reshape(*r.shape[:-2], *shape)
        return np.concatenate([means, means[..., -1:] - means[..., :1]], axis=-1)  # (..., L, N + 1)

    point, reps = table.bootstrap(statistic)
    per_label = [_interval(point[i], reps[:, i]) for i in range(len(labels))]
    return GapAgainstN(
        ns=ns,
        gaps={label: found[:-1] for label, found in zip(labels, per_label)},
        change={label: found[-1] for label, found in zip(labels, per_label)},
    )


RADIUS_STEP_M = 0.025  # the appendix's radii are multiples of it: slopes are reported per step


def radius_slopes(rows: Sequence[dict], radius_factors: Sequence[str]) -> dict[tuple[str, str], Interval]:
    """Per (method, factor) of the radius sweep: least-squares slope of the mean gap (over tasks, N and
    seeds, as the radius table) on the radius, in gap per metre, with its 95% seed-bootstrap interval."""
    swept = radius_rows(rows, radius_factors)
    if not swept:
        return {}
    runs = {(r["method"], r["task"], r["n_train_envs"], r["widths"]) for r in swept}
    trains = [
        r
        for r in rows
        if r["condition"] == TRAIN_SUITE and (r["method"], r["task"], r["n_train_envs"], r["widths"]) in runs
    ]
    table = cells([*swept, *trains], gaps=True)
    radius = {tuple(r.get(k) for k in CELL_KEYS): r["radius_m"] for r in swept}
    lines = sorted({(k[0], k[4]) for k in table.keys if k in radius})
    radii = sorted({v for v in radius.values()})
    groups = [
        [i for i, k in enumerate(table.keys) if (k[0], k[4]) == line and radius.get(k) == rad]
        for line in lines
        for rad in radii
    ]
    train = table.train_columns()
    shape = (len(lines), len(radii))

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        means = group_mean(cell_gaps(r, train), groups)  # a radius without cells: NaN, the slope uses the others
        return ols_slope(radii, means.reshape(*means.shape[:-1], *shape))

    point, reps = table.bootstrap(statistic)
    return dict(zip(lines, _interval(point, reps)))


def pooled_success(rows: Sequence[dict], keys: Sequence[str]) -> dict[tuple, tuple[int, int, float, float]]:
    """Per group of ``keys``: (successes, episodes, low, high) pooled over seeds and every other column.

    The interval accounts for the pooling over training seeds: the 95% seed-bootstrap interval of the
    pooled rate, widened where needed to contain the Wilson interval of the pooled episodes (a percentile
    bootstrap collapses to a point when every episode of every seed succeeds, and with few seeds it
    understates the spread). A group with one seed has no pooling: its interval is the Wilson interval, also when
    other groups have more seeds (a method run at one seed of a study made in parts)."""
    rows = [r for r in rows if r.get("episodes")]
    if not rows:
        return {}
    names, _, reps = _pooled_bootstrap(rows, keys)
    lo, hi = percentile_interval(reps)
    totals: dict[tuple, list[int]] = defaultdict(lambda: [0, 0])
    seeds: dict[tuple, set] = defaultdict(set)
    for r in rows:
        g = tuple(r.get(k) for k in keys)
        totals[g][0] += int(r["successes"])
        totals[g][1] += int(r["episodes"])
        seeds[g].add(r["seed"])
    out = {}
    for name, low, high in zip(names, lo, hi):
        k, n = totals[name]
        w_lo, w_hi = wilson_interval(k, n)
        if len(seeds[name]) == 1:
            out[name] = (k, n, w_lo, w_hi)
        else:
            out[name] = (k, n, float(np.fmin(low, w_lo)), float(np.fmax(high, w_hi)))
    return out


def per_task_success(rows: Sequence[dict], factors: Sequence[str]) -> dict[tuple, tuple[int, int, float, float]]:
    """Success per (method, task, N, condition) of the main grid's ``train`` and single factors (``factors``),
    pooled over seeds with :func:`pooled_success`'s interval: the "Success per task and N" table,
    ``success_rates.png`` and report.html's success figure (one set of rows, so one set of intervals)."""
    conditions = (TRAIN_SUITE, *factors)
    shown = [r for r in main_grid(rows) if r["condition"] in conditions]
    return pooled_success(shown, ["method", "task", "n_train_envs", "condition"])


def pooled_rho_interval(rows: Sequence[dict], key: str, reference: Mapping[str, float]) -> tuple[float, float]:
    """95% seed-bootstrap interval of Spearman's rho between the success rates pooled per value of ``key``
    (:func:`pooled_success`; e.g. per condition of one method's rows) and ``reference`` (their shared values;
    each replicate re-ranks its own pooled rates); NaN with fewer than 3 shared values."""
    rows = [r for r in rows if r.get("episodes") and r.get(key) in reference]
    if len({r[key] for r in rows}) < 3:
        return math.nan, math.nan
    names, _, reps = _pooled_bootstrap(rows, [key])
    rhos = np.array([spearman({name[0]: rate for name, rate in zip(names, rep)}, reference) for rep in reps])
    lo, hi = percentile_interval(rhos)
    return float(lo), float(hi)


def _pooled_bootstrap(rows: Sequence[dict], keys: Sequence[str]) -> tuple[list[tuple], np.ndarray, np.ndarray]:
    """The success rate pooled over seeds and every column but ``keys``, per group: (groups, point (G,),
    seed-bootstrap replicates (B, G))."""
    if any(g not in CELL_KEYS for g in keys):
        raise ValueError(f"pooled_success groups by columns of {CELL_KEYS}, got {keys}")
    table = cells(rows)
    group_of = {k: tuple(dict(zip(CELL_KEYS, k))[g] for g in keys) for k in table.keys}
    names = list(dict.fromkeys(group_of.values()))
    number = {name: i for i, name in enumerate(names)}
    order = np.argsort([number[group_of[k]] for k in table.keys], kind="stable")  # columns, group by group
    starts = np.searchsorted(np.sort([number[group_of[k]] for k in table.keys]), np.arange(len(names)))

    def statistic(r: np.ndarray, n: np.ndarray) -> np.ndarray:
        n = np.where(np.isnan(r), 0.0, n)
        k = np.where(np.isnan(r), 0.0, r * n).sum(axis=-2)[..., order]  # (B, C): pooled over seeds
        total_n = np.add.reduceat(n.sum(axis=-2)[..., order], starts, axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.add.reduceat(k, starts, axis=-1) / total_n

    point, reps = table.bootstrap(statistic)
    return names, point, reps


def method_rho_differences(
    rows: Sequence[dict], methods: Sequence[str], factors: Sequence[str], reference: Mapping[str, float]
) -> dict[str, tuple[Interval, Interval]]:
    """Per method after the first: Spearman's rho of its factor ordering with ``reference`` and that rho minus the
    first method's, each with its 95% seed-bootstrap interval (one bootstrap over the two methods, main grid, on the
    (task, N, seed, condition) cells both have; the factors both have there). E.g. how much an augmentation moves
    the ordering toward the paper's."""
    grid = [r for r in main_grid(rows) if r["method"] in methods and r["condition"] in (TRAIN_SUITE, *factors)]
    if len(methods) > 2:  # each method against the first on the cells those two share
        out = {}
        for method in methods[1:]:
            out.update(method_rho_differences(rows, [methods[0], method], factors, reference))
        return out
    table = cells(shared_cell_rows(grid, methods), gaps=True)
    shared = [f for f in factors if all(any(k[0] == m and k[4] == f for k in table.keys) for m in methods)]
    if len(methods) < 2 or len(shared) < 3:
        return {}
    groups = [[i for i, k in enumerate(table.keys) if k[0] == m and k[4] == f] for m in methods for f in shared]
    train = table.train_columns()
    point, reps = table.bootstrap(lambda r, n: group_mean(cell_gaps(r, train), groups))

    rho_of = spearman_with(reference)

    def rho(gaps: np.ndarray) -> np.ndarray:  # (..., M * F) -> (..., M)
        flat = gaps.reshape(-1, len(methods), len(shared))
        out = [[rho_of(rank_hardest_first(dict(zip(shared, g.tolist())))) for g in row] for row in flat]
        return np.array(out).reshape(*gaps.shape[:-1], len(methods))

    p, r = rho(point), rho(reps)
    out = {}
    for i, method in enumerate(methods[1:], start=1):
        own = _interval(np.array(p[i]), r[:, i])[0]
        diff = _interval(np.array(p[i] - p[0]), r[:, i] - r[:, 0])[0]
        out[method] = (own, diff)
    return out
