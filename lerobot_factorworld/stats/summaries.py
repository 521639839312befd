"""Summaries of a study's cells: the paper's pair metric, the interaction of two factors, mean and standard error,
and the vectorised forms the bootstrap recomputes on every replicate (arrays shaped (..., seeds, cells)).

Why vectorised: :func:`.bootstrap.seed_bootstrap` evaluates a summary on thousands of resampled tables at once;
each function here maps a batch of tables to a batch of values, NaN where a value is undefined.

References: the pair metric is Xie, Lee, Xiao, Finn (2023), "Decomposing the Generalization Gap in Imitation
Learning for Visual Robotic Manipulation", section 5.2; the standard error of a mean and the least-squares slope are
textbook (e.g. Rice (2007), "Mathematical Statistics and Data Analysis", 3rd ed., sections 7.3 and 14.2); a mean
over seeds of means over cells is a two-stage (cluster) mean, each seed a cluster (Cochran (1977), "Sampling
Techniques", 3rd ed.).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def pair_metric(p_ab: float, p_a: float, p_b: float) -> float:
    """Xie et al.'s (2023) ``(P_{A+B} - min(P_A, P_B)) / min(P_A, P_B)``; ``nan`` when the harder factor never
    succeeds."""
    harder = min(p_a, p_b)
    if harder == 0 or any(math.isnan(v) for v in (p_ab, p_a, p_b)):
        return math.nan
    return (p_ab - harder) / harder


def interaction(gap_ab: float, gap_a: float, gap_b: float) -> float:
    """``gap(A+B) - gap(A) - gap(B)``: 0 when the two factors' gaps add up (an additive model's interaction term,
    e.g. Montgomery (2017), "Design and Analysis of Experiments", ch. 5), > 0 when they compound."""
    return gap_ab - gap_a - gap_b


def mean_se(values: Sequence[float]) -> tuple[float, float]:
    """Mean and standard error of the mean (sample std / sqrt(n); Rice 2007, 7.3); NaNs are skipped; se is nan for
    n < 2."""
    xs = [v for v in values if not math.isnan(v)]
    if not xs:
        return math.nan, math.nan
    mean = sum(xs) / len(xs)
    if len(xs) < 2:
        return mean, math.nan
    var = sum((x - mean) ** 2 for x in xs) / (len(xs) - 1)
    return mean, math.sqrt(var / len(xs))


def nanmean(x: np.ndarray, axis: int, weights: np.ndarray | None = None) -> np.ndarray:
    """Mean over ``axis`` of the defined (non-NaN) values, optionally weighted (the weighted arithmetic mean, Rice
    2007, 7.3); NaN where none is defined."""
    x = np.asarray(x, dtype=float)
    defined = ~np.isnan(x)
    w = defined.astype(float) if weights is None else np.where(defined, weights, 0.0)
    total = w.sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, (np.where(defined, x, 0.0) * w).sum(axis=axis) / total, np.nan)


def group_mean(values: np.ndarray, groups: Sequence[Sequence[int]]) -> np.ndarray:
    """(..., S, C) per-seed cell values -> (..., G): per group of columns, the mean over its columns per seed
    (tasks, N), then the mean over seeds, each over defined values only (``aggregate.summary``'s rule: a two-stage
    mean, each seed a cluster, Cochran 1977)."""
    per_seed = np.stack([nanmean(values[..., list(cols)], axis=-1) for cols in groups], axis=-1)  # (..., S, G)
    return nanmean(per_seed, axis=-2)


def pooled_rates(rates: np.ndarray, episodes: np.ndarray) -> np.ndarray:
    """(..., S, C) -> (..., C): success pooled over seeds (successes / episodes, the pooled proportion of Fleiss,
    Levin, Paik (2003), "Statistical Methods for Rates and Proportions"; equal weights where the episode counts are
    unknown)."""
    weights = np.where(episodes > 0, episodes, 1.0)
    return nanmean(rates, axis=-2, weights=weights)


def pair_metric_array(p_ab: np.ndarray, p_a: np.ndarray, p_b: np.ndarray) -> np.ndarray:
    """:func:`pair_metric` (Xie et al. 2023) elementwise (NaN where the harder factor never succeeds)."""
    harder = np.minimum(p_a, p_b)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(harder > 0, (p_ab - harder) / np.where(harder > 0, harder, 1.0), np.nan)


def count_within(values: np.ndarray, tolerance: float) -> np.ndarray:
    """(..., P) -> (...): how many of the defined values lie within ``±tolerance`` (the band Xie et al. 2023 read the
    pair metric against)."""
    return (np.abs(np.nan_to_num(values, nan=np.inf)) <= tolerance).sum(axis=-1)


def ols_slope(x: Sequence[float], y: np.ndarray) -> np.ndarray:
    """Least-squares slope (Rice 2007, 14.2) of ``y`` (..., R) on ``x`` (R), over the defined points; NaN with fewer
    than two."""
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
