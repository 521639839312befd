"""The smallest effect a design resolves: the smallest true value whose interval excludes 0 when the expected
outcome counts are plugged in, for a cell's gap, a mean gap, a difference of two rates, the pair metric and a slope.

Why: a plan says before it runs what it can tell from 0, and a verdict that is not resolved says how far it was.
Only episode noise is counted here, so every number is a lower bound on what a design with seed-to-seed spread
needs.

References: Newcombe (1998a), "Improved confidence intervals for the difference between binomial proportions based
on paired data", Statistics in Medicine 17(22) (method 10, for one cell); the normal approximation for a difference
of proportions, Fleiss, Levin, Paik (2003), "Statistical Methods for Rates and Proportions", 3rd ed., ch. 4;
the variance of a least-squares slope, Rice (2007), "Mathematical Statistics and Data Analysis", 3rd ed., 14.2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .proportions import Z95, newcombe_paired

GRID = 2000  # resolution of the searches over a gap in [0, P_T]


def cell_resolvable_gap(episodes: int, p_train: float, paired: bool = True, z: float = Z95) -> float:
    """Smallest gap whose Newcombe (1998a, method 10) paired 95% interval excludes 0 in a cell of ``episodes``
    paired episodes at train success ``p_train``: best case (``paired``: no episode succeeds only when shifted) on
    whole episode counts, or independent outcomes on expected counts. NaN if even P_F = 0 is not resolved."""
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
    interval (Fleiss et al. 2003, ch. 4) excludes 0, outcomes independent given the rates (at P_T = 0.5 the closed
    form is sqrt(z^2 / 2 / (pairs + z^2)), up to the search's resolution). NaN at P_T = 0, where no gap can open,
    as ``cell_resolvable_gap`` gives."""
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
    outcomes), that a 95% normal interval tells from 0 (Fleiss et al. 2003, ch. 4)."""
    return z * math.sqrt(2 * p * (1 - p) / pairs)


def pair_metric_resolvable(pairs: int, p_min: float, z: float = Z95) -> float:
    """Smallest pair metric |(P_A+B - P_min) / P_min| (Xie et al. 2023) that a 95% normal interval tells from 0:
    :func:`difference_resolvable` relative to ``p_min``."""
    return difference_resolvable(pairs, p_min, z) / p_min


def slope_resolvable(pairs_per_radius: int, radii: Sequence[float], p: float, z: float = Z95) -> float:
    """Smallest least-squares slope of the gap on the radius (gap per metre) that a 95% normal interval
    tells from 0, each radius's mean gap over ``pairs_per_radius`` episodes (independent, small gaps): the
    slope's variance is the points' variance over ``Sxx`` (Rice 2007, 14.2)."""
    mean = sum(radii) / len(radii)
    sxx = sum((r - mean) ** 2 for r in radii)
    if sxx == 0:
        return math.nan
    return z * math.sqrt(2 * p * (1 - p) / pairs_per_radius / sxx)
