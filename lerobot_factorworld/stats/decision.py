"""The interval a verdict is decided on, and the sample sizes that would resolve an effect it leaves open.

Why a hull: at few training seeds the bootstrap's percentile interval is too narrow (it cannot see more spread
between seeds than the seeds it has), and the t-interval over seeds ignores episode noise within each; the wider of
the two, both ways, is honest for both.

The p-value that orders comparisons for a correction is, likewise, the larger of the bootstrap's and the t-test's.

References: the percentile interval, Efron & Tibshirani (1993), "An Introduction to the Bootstrap", ch. 13; the
bootstrap p-value, Davison & Hinkley (1997), "Bootstrap Methods and their Application", ch. 4 (``(1 + #) /
(B + 1)``, doubled for two sides); the t-interval, the t-test and the seeds they need, Student (1908), "The probable
error of a mean", Biometrika 6(1).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy import stats

from .bootstrap import percentile_interval
from .estimate import Estimate

HULL = "bootstrap-t hull"  # the decision interval's method
MAX_EPISODES = 100_000  # the search for the episodes that would resolve an effect stops here (for seeds: 1000)


def decision_interval(point: float, reps: np.ndarray, per_seed: np.ndarray, level: float) -> Estimate:
    """The hull of Efron & Tibshirani's (1993) percentile interval of the bootstrap ``reps`` and Student's
    t-interval over the ``per_seed`` values at ``level``, around ``point`` (NaN ends with fewer than two seeds or a
    bootstrap undefined too often: no seed-level interval)."""
    lo, hi = percentile_interval(reps, level=level)
    if len(per_seed) < 2 or not (np.isfinite(lo) and np.isfinite(hi)):
        return Estimate(point, math.nan, math.nan, level, HULL)
    half = stats.t.ppf(1 - (1 - level) / 2, df=len(per_seed) - 1) * np.std(per_seed, ddof=1) / math.sqrt(len(per_seed))
    mean = float(np.mean(per_seed))
    return Estimate(point, min(float(lo), mean - half), max(float(hi), mean + half), level, HULL)


def bootstrap_p_value(reps: np.ndarray, threshold: float) -> float:
    """Two-sided bootstrap p-value of the replicates ``reps`` against ``threshold`` (Davison & Hinkley 1997, ch. 4:
    ``2 (1 + #(on the rarer side)) / (B + 1)``, capped at 1); 1 where fewer than half the replicates are defined
    (the statistic is undefined too often)."""
    x = reps[np.isfinite(reps)] - threshold
    if x.size < len(reps) / 2:
        return 1.0
    return float(min(1.0, 2 * (min(np.sum(x <= 0), np.sum(x >= 0)) + 1) / (x.size + 1)))


def decision_p_value(p_boot: float, per_seed: np.ndarray, threshold: float) -> float:
    """Two-sided p-value against ``threshold``: the larger of the bootstrap's ``p_boot`` and Student's (1908) t-test
    over the ``per_seed`` values (1 with one seed: the spread between seeds is unknown)."""
    if len(per_seed) < 2:
        return 1.0
    sd = float(np.std(per_seed, ddof=1))
    diff = float(np.mean(per_seed)) - threshold
    if sd == 0:
        p_t = 0.0 if diff != 0 else 1.0
    else:
        p_t = float(2 * stats.t.sf(abs(diff) / (sd / math.sqrt(len(per_seed))), df=len(per_seed) - 1))
    return max(p_boot, p_t)


def episodes_needed(resolvable: Callable[[float, float], float], effect: float, z: float) -> float:
    """Episodes per cell whose resolution ``resolvable(episodes, z)`` (a :mod:`.power` function of the design)
    reaches ``effect``, searched from 1 in steps of 10% up to ``MAX_EPISODES`` (NaN: none does)."""
    if not (np.isfinite(effect) and effect > 0):
        return math.nan
    e = 1
    while e <= MAX_EPISODES:
        resolved = resolvable(e, z)
        if np.isfinite(resolved) and resolved <= effect:
            return float(e)
        e = max(e + 1, math.ceil(e * 1.1))
    return math.nan


def seeds_needed(per_seed: np.ndarray, effect: float, level: float) -> float:
    """Seeds whose Student (1908) t-interval at ``level``, at the observed spread of ``per_seed``, has a half-width
    below ``effect`` (NaN with fewer than two seeds, or none up to 1000)."""
    if len(per_seed) < 2 or not effect > 0:
        return math.nan
    sd = float(np.std(per_seed, ddof=1))
    if sd == 0:
        return float(len(per_seed))
    for s in range(2, 1001):
        if stats.t.ppf(1 - (1 - level) / 2, df=s - 1) * sd / math.sqrt(s) < effect:
            return float(s)
    return math.nan
