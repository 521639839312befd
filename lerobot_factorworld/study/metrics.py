"""The study's numbers, as pure functions (tested against hand-computed values).

- success rate with a Wilson 95% score interval;
- generalization gap P_T - P_F with Newcombe's paired interval (1998, method 10): train and shifted
  episodes share seeds, so the gap is a difference of paired proportions;
- the paper's pair metric (P_{A+B} - min(P_A, P_B)) / min(P_A, P_B), and the interaction
  gap(A+B) - gap(A) - gap(B);
- mean and standard error over training seeds;
- the factor ordering (hardest first) and Spearman's rank correlation;
- the seed-level bootstrap behind every summary's 95% interval (:func:`seed_bootstrap`): resample the
  training seeds, then the episodes within each drawn cell, recompute the summary, take percentiles;
  with the vectorised pieces the summaries are computed from (:func:`group_mean`,
  :func:`pair_metric_array`, :func:`ols_slope`, :func:`count_within`, :func:`pooled_rates`).

The paper's own numbers, which these are compared with, are in ``paper.py``.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Hashable, Mapping, Sequence

import numpy as np

Z95 = 1.959963984540054  # two-sided 95% normal quantile
BOOTSTRAP_RESAMPLES = 2000  # resamples per interval (Efron & Tibshirani 1993: >= 1000 for percentile intervals)
BOOTSTRAP_SEED = 0  # every interval restarts numpy's PCG64 from this seed: a report is the same on every rebuild
BOOTSTRAP_CHUNK = 200  # resamples drawn (and held in memory) at a time


def two_sided_z(confidence: float) -> float:
    """The normal quantile of a two-sided interval at ``confidence`` (1.96 at 0.95)."""
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    from scipy import stats  # noqa: PLC0415 - scipy.stats takes a second to import; most users of this module never need it

    return float(stats.norm.ppf(1 - (1 - confidence) / 2))


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a success rate; ``(nan, nan)`` for ``n == 0``."""
    if n == 0:
        return math.nan, math.nan
    if not 0 <= successes <= n:
        raise ValueError(f"successes must be in [0, {n}], got {successes}")
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def paired_gap(train: Sequence[bool], shifted: Sequence[bool], z: float = Z95) -> tuple[float, float, float]:
    """Gap ``P_T - P_F`` and Newcombe's (1998, method 10) 95% interval for paired episodes.

    ``train[i]`` and ``shifted[i]`` are the outcomes of episode ``i`` (same seed, same object start).
    """
    if len(train) != len(shifted):
        raise ValueError(f"paired outcomes need equal lengths, got {len(train)} and {len(shifted)}")
    n = len(train)
    if n == 0:
        return math.nan, math.nan, math.nan
    a = sum(1 for t, s in zip(train, shifted) if t and s)
    b = sum(1 for t, s in zip(train, shifted) if t and not s)
    c = sum(1 for t, s in zip(train, shifted) if not t and s)
    return newcombe_paired(a, b, c, n - a - b - c, z)


def newcombe_paired(a: float, b: float, c: float, d: float, z: float = Z95) -> tuple[float, float, float]:
    """Gap and Newcombe's (1998, method 10) interval from the paired 2x2 table: ``a`` episodes succeed in
    both conditions, ``b`` only in train, ``c`` only shifted, ``d`` in neither (expected, non-integer
    counts are accepted: :mod:`.power` uses them)."""
    n = a + b + c + d
    p1, p2 = (a + b) / n, (a + c) / n
    l1, u1 = wilson_interval(a + b, n, z)
    l2, u2 = wilson_interval(a + c, n, z)
    phi = _phi_corrected(a, b, c, d)
    gap = p1 - p2
    lower = gap - math.sqrt(max(0.0, (p1 - l1) ** 2 - 2 * phi * (p1 - l1) * (u2 - p2) + (u2 - p2) ** 2))
    upper = gap + math.sqrt(max(0.0, (u1 - p1) ** 2 - 2 * phi * (u1 - p1) * (p2 - l2) + (p2 - l2) ** 2))
    return gap, max(-1.0, lower), min(1.0, upper)


def newcombe_independent(k1: int, n1: int, k2: int, n2: int, z: float = Z95) -> tuple[float, float, float]:
    """``k1 / n1 - k2 / n2`` and Newcombe's (1998, method 10) hybrid score interval for two independent samples
    (``nan`` where either has no episodes): for rates known only as counts, such as two checkpoints' P_T. Where
    the episodes are in fact paired and positively correlated, it is wider than the paired interval."""
    if n1 == 0 or n2 == 0:
        return math.nan, math.nan, math.nan
    p1, p2 = k1 / n1, k2 / n2
    l1, u1 = wilson_interval(k1, n1, z)
    l2, u2 = wilson_interval(k2, n2, z)
    diff = p1 - p2
    lower = diff - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    upper = diff + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return diff, max(-1.0, lower), min(1.0, upper)


def _phi_corrected(a: int, b: int, c: int, d: int) -> float:
    """Newcombe's phi: ``(ad - bc)`` reduced by ``n/2`` towards zero when positive, 0 if a margin is empty."""
    n = a + b + c + d
    denom = (a + b) * (c + d) * (a + c) * (b + d)
    if denom == 0:
        return 0.0
    num = a * d - b * c
    num = max(num - n / 2, 0.0) if num > 0 else num
    return num / math.sqrt(denom)


def pair_metric(p_ab: float, p_a: float, p_b: float) -> float:
    """The paper's ``(P_{A+B} - min(P_A, P_B)) / min(P_A, P_B)``; ``nan`` when the harder factor never succeeds."""
    harder = min(p_a, p_b)
    if harder == 0 or any(math.isnan(v) for v in (p_ab, p_a, p_b)):
        return math.nan
    return (p_ab - harder) / harder


def interaction(gap_ab: float, gap_a: float, gap_b: float) -> float:
    """``gap(A+B) - gap(A) - gap(B)``: 0 when the two factors' gaps add up, > 0 when they compound."""
    return gap_ab - gap_a - gap_b


def mean_se(values: Sequence[float]) -> tuple[float, float]:
    """Mean and standard error of the mean (sample std / sqrt(n)); NaNs are skipped; se is nan for n < 2."""
    xs = [v for v in values if not math.isnan(v)]
    if not xs:
        return math.nan, math.nan
    mean = sum(xs) / len(xs)
    if len(xs) < 2:
        return mean, math.nan
    var = sum((x - mean) ** 2 for x in xs) / (len(xs) - 1)
    return mean, math.sqrt(var / len(xs))


def rank_hardest_first(gaps: Mapping[str, float]) -> dict[str, float]:
    """Rank factors by gap, 1 = largest (hardest); ties share their average rank; NaN gaps are left out."""
    items = sorted(((g, f) for f, g in gaps.items() if not math.isnan(g)), key=lambda x: -x[0])
    ranks: dict[str, float] = {}
    i = 0
    while i < len(items):
        j = i
        while j + 1 < len(items) and items[j + 1][0] == items[i][0]:
            j += 1
        for k in range(i, j + 1):
            ranks[items[k][1]] = (i + j) / 2 + 1
        i = j + 1
    return ranks


def spearman(ranks_a: Mapping[str, float], ranks_b: Mapping[str, float]) -> float:
    """Spearman's rho over the keys both rankings share (Pearson correlation of the ranks, ties averaged).

    The shared keys are re-ranked among themselves first; ``nan`` with fewer than 3 shared keys or a
    constant ranking.
    """
    keys = [k for k in ranks_a if k in ranks_b]
    if len(keys) < 3:
        return math.nan
    xs = list(rerank([ranks_a[k] for k in keys]))
    ys = list(rerank([ranks_b[k] for k in keys]))
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    sxx = sum((x - mx) ** 2 for x in xs)
    syy = sum((y - my) ** 2 for y in ys)
    if sxx == 0 or syy == 0:
        return math.nan
    return sxy / math.sqrt(sxx * syy)


def rerank(values: Sequence[float]) -> list[float]:
    """Average ranks (1 = smallest) of ``values``."""
    order = sorted(range(len(values)), key=lambda i: values[i])
    ranks = [0.0] * len(values)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and values[order[j + 1]] == values[order[i]]:
            j += 1
        for k in range(i, j + 1):
            ranks[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return ranks


# --- seed-level bootstrap -----------------------------------------------------------------------------


def seed_bootstrap(
    rates: np.ndarray,
    episodes: np.ndarray,
    statistic: Callable[[np.ndarray, np.ndarray], np.ndarray],
    n_boot: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
    seed_ids: Sequence[Hashable] | None = None,
    cell_ids: Sequence[Hashable] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Point estimate and ``n_boot`` bootstrap replicates of ``statistic``, resampling seeds then episodes.

    ``rates`` and ``episodes`` are (S, C): cell ``c``'s success rate and episode count for training seed
    ``s`` (rate NaN: no such cell; episodes 0: count unknown, the rate is kept as it is). Each replicate
    draws S seeds with replacement (a training seed is one dataset and one checkpoint per task and N, so
    its cells move together), then resamples each drawn cell's episodes with replacement: its successes
    are Binomial(episodes, rate), which is what resampling a cell's own episodes gives. A seed drawn twice
    gets two independent episode resamples. Train and shifted cells are resampled independently (only
    their counts are in ``results.csv``), which ignores the positive correlation of paired episodes and
    so widens the intervals of gaps.

    With ``seed_ids`` (the training seeds, S) and ``cell_ids`` (what each column is, C), the draws depend on
    identities, not positions: the seeds are drawn from a generator of ``seed`` and the seeds' values, each
    column's episodes from one of ``seed`` and its cell's identity. A cell then gets the same replicates in
    every table that holds it with the same training seeds, whatever the other columns (one interval per
    cell); without them, one generator draws everything in column order.

    ``statistic(rates, episodes)`` maps (B, S, C) arrays to (B, ...); the point estimate is its value on
    the data itself. Returns (point (...), replicates (n_boot, ...)); deterministic for a given ``seed``.
    """
    rates = np.asarray(rates, dtype=float)
    episodes = np.asarray(episodes, dtype=float)
    if rates.shape != episodes.shape or rates.ndim != 2:
        raise ValueError(f"rates and episodes must both be (seeds, cells), got {rates.shape} and {episodes.shape}")
    point = np.asarray(statistic(rates[None], episodes[None]))[0]
    n_seeds = rates.shape[0]
    if cell_ids is not None:
        return point, _identified_replicates(rates, episodes, statistic, n_boot, seed, seed_ids, cell_ids)
    rng = np.random.default_rng(seed)
    out = []
    for start in range(0, n_boot, BOOTSTRAP_CHUNK):
        b = min(BOOTSTRAP_CHUNK, n_boot - start)
        idx = rng.integers(0, n_seeds, size=(b, n_seeds))
        r, n = rates[idx], episodes[idx]
        known = (n > 0) & ~np.isnan(r)
        k = rng.binomial(np.where(known, n, 0).astype(np.int64), np.where(known, r, 0.0).clip(0.0, 1.0))
        out.append(np.asarray(statistic(np.where(known, k / np.where(known, n, 1.0), r), n)))
    return point, np.concatenate(out)


def identity_seed(identity: Hashable) -> int:
    """A 64-bit seed from what a thing is (its ``repr``), the same on every machine and Python run (unlike
    ``hash``)."""
    return int.from_bytes(hashlib.sha256(repr(identity).encode()).digest()[:8], "little")


def _identified_replicates(
    rates: np.ndarray,
    episodes: np.ndarray,
    statistic: Callable[[np.ndarray, np.ndarray], np.ndarray],
    n_boot: int,
    seed: int,
    seed_ids: Sequence[Hashable] | None,
    cell_ids: Sequence[Hashable],
) -> np.ndarray:
    """:func:`seed_bootstrap`'s replicates drawn by identity: the seed draws from (``seed``, the seeds' values),
    each column's episode draws from (``seed``, its cell's identity)."""
    n_seeds, n_cells = rates.shape
    if len(cell_ids) != n_cells or (seed_ids is not None and len(seed_ids) != n_seeds):
        raise ValueError(f"{len(cell_ids)} cell ids for {n_cells} columns, or seed ids not one per seed")
    seeds = tuple(range(n_seeds)) if seed_ids is None else tuple(seed_ids)
    idx = np.random.default_rng([seed, identity_seed(seeds)]).integers(0, n_seeds, size=(n_boot, n_seeds))
    r, n = rates[idx], episodes[idx]  # (B, S, C)
    known = (n > 0) & ~np.isnan(r)
    k = np.zeros(r.shape)
    for c, cell in enumerate(cell_ids):
        rng = np.random.default_rng([seed, identity_seed(cell)])
        k[..., c] = rng.binomial(np.where(known[..., c], n[..., c], 0).astype(np.int64),
                                 np.where(known[..., c], r[..., c], 0.0).clip(0.0, 1.0))  # fmt: skip
    resampled = np.where(known, k / np.where(known, n, 1.0), r)
    out = [
        np.asarray(statistic(resampled[start : start + BOOTSTRAP_CHUNK], n[start : start + BOOTSTRAP_CHUNK]))
        for start in range(0, n_boot, BOOTSTRAP_CHUNK)
    ]
    return np.concatenate(out)


def percentile_interval(
    replicates: np.ndarray, level: float = 0.95, min_defined: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval over axis 0, NaN replicates left out; NaN where fewer than ``min_defined`` of
    the replicates are defined (the statistic is undefined too often to have an interval)."""
    x = np.asarray(replicates, dtype=float)
    defined = np.isfinite(x)
    enough = defined.mean(axis=0) >= min_defined
    alpha = (1 - level) / 2
    filled = np.where(defined, x, np.nan)
    filled = np.where(enough, filled, 0.0)  # columns without an interval: any value, masked below
    lo = np.nanquantile(filled, alpha, axis=0)
    hi = np.nanquantile(filled, 1 - alpha, axis=0)
    return np.where(enough, lo, np.nan), np.where(enough, hi, np.nan)


def nanmean(x: np.ndarray, axis: int, weights: np.ndarray | None = None) -> np.ndarray:
    """Mean over ``axis`` of the defined (non-NaN) values, optionally weighted; NaN where none is defined."""
    x = np.asarray(x, dtype=float)
    defined = ~np.isnan(x)
    w = defined.astype(float) if weights is None else np.where(defined, weights, 0.0)
    total = w.sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, (np.where(defined, x, 0.0) * w).sum(axis=axis) / total, np.nan)


def group_mean(values: np.ndarray, groups: Sequence[Sequence[int]]) -> np.ndarray:
    """(..., S, C) per-seed cell values -> (..., G): per group of columns, the mean over its columns per seed
    (tasks, N), then the mean over seeds, each over defined values only (``aggregate.summary``'s rule)."""
    per_seed = np.stack([nanmean(values[..., list(cols)], axis=-1) for cols in groups], axis=-1)  # (..., S, G)
    return nanmean(per_seed, axis=-2)


def pooled_rates(rates: np.ndarray, episodes: np.ndarray) -> np.ndarray:
    """(..., S, C) -> (..., C): success pooled over seeds (successes / episodes; equal weights where the
    episode counts are unknown)."""
    weights = np.where(episodes > 0, episodes, 1.0)
    return nanmean(rates, axis=-2, weights=weights)


def pair_metric_array(p_ab: np.ndarray, p_a: np.ndarray, p_b: np.ndarray) -> np.ndarray:
    """:func:`pair_metric` elementwise (NaN where the harder factor never succeeds)."""
    harder = np.minimum(p_a, p_b)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(harder > 0, (p_ab - harder) / np.where(harder > 0, harder, 1.0), np.nan)


def count_within(values: np.ndarray, tolerance: float) -> np.ndarray:
    """(..., P) -> (...): how many of the defined values lie within ``±tolerance``."""
    return (np.abs(np.nan_to_num(values, nan=np.inf)) <= tolerance).sum(axis=-1)


def ols_slope(x: Sequence[float], y: np.ndarray) -> np.ndarray:
    """Least-squares slope of ``y`` (..., R) on ``x`` (R), over the defined points; NaN with fewer than two."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    w = ~np.isnan(y)
    count = w.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx = (w * x).sum(axis=-1) / count
        my = np.where(w, y, 0.0).sum(axis=-1) / count
        dx = np.where(w, x - mx[..., None], 0.0)
        sxx = (dx * dx).sum(axis=-1)
        sxy = (dx * np.where(w, y - my[..., None], 0.0)).sum(axis=-1)
        return np.where((count >= 2) & (sxx > 0), sxy / sxx, np.nan)
