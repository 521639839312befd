"""Intervals of success rates and of differences between two, from episode counts.

- a success rate with Wilson's score interval;
- a generalization gap P_T - P_F with Newcombe's paired interval: train and shifted episodes share seeds, so the
  gap is a difference of paired proportions;
- a difference of two rates known only as counts with Newcombe's interval for independent samples.

References: Wilson (1927), "Probable inference, the law of succession, and statistical inference", JASA 22(158);
Newcombe (1998a), "Improved confidence intervals for the difference between binomial proportions based on
paired data", Statistics in Medicine 17(22) (method 10); Newcombe (1998b), "Interval estimation for the
difference between independent proportions: comparison of eleven methods", Statistics in Medicine 17(8)
(method 10).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Z95 = 1.959963984540054  # two-sided 95% normal quantile


def two_sided_z(confidence: float) -> float:
    """The normal quantile of a two-sided interval at ``confidence`` (1.96 at 0.95): ``Phi^-1(1 - alpha / 2)``, the
    standard normal's inverse (Abramowitz & Stegun (1964), "Handbook of Mathematical Functions", 26.2)."""
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    from scipy import stats  # noqa: PLC0415 - scipy.stats takes a second to import; most users of this module never need it

    return float(stats.norm.ppf(1 - (1 - confidence) / 2))


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson's (1927) score interval of a success rate; ``(nan, nan)`` for ``n == 0``."""
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
    """Gap ``P_T - P_F`` and Newcombe's (1998a, method 10) 95% interval for paired episodes.

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
    """Gap and Newcombe's (1998a, method 10: Wilson score limits combined with the continuity-corrected phi)
    interval from the paired 2x2 table: ``a`` episodes succeed in both conditions, ``b`` only in train, ``c`` only
    shifted, ``d`` in neither (expected, non-integer counts are accepted: :mod:`.power` uses them)."""
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
    """``k1 / n1 - k2 / n2`` and Newcombe's (1998b, method 10: Wilson limits without continuity correction) hybrid
    score interval for two independent samples (``nan`` where either has no episodes): for rates known only as
    counts, such as two checkpoints' P_T. Where the episodes are in fact paired and positively correlated, it is
    wider than the paired interval."""
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
