"""The study's numbers, as pure functions (tested against hand-computed values).

- success rate with a Wilson 95% score interval;
- generalization gap P_T - P_F with Newcombe's paired interval (1998, method 10): train and shifted
  episodes share seeds, so the gap is a difference of paired proportions;
- the paper's pair metric (P_{A+B} - min(P_A, P_B)) / min(P_A, P_B), and the interaction
  gap(A+B) - gap(A) - gap(B);
- mean and standard error over training seeds;
- the factor ordering (hardest first) and Spearman's rank correlation.

The paper's own numbers, which these are compared with, are in ``paper.py``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

Z95 = 1.959963984540054  # two-sided 95% normal quantile


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
    d = n - a - b - c
    p1, p2 = (a + b) / n, (a + c) / n
    l1, u1 = wilson_interval(a + b, n, z)
    l2, u2 = wilson_interval(a + c, n, z)
    phi = _phi_corrected(a, b, c, d)
    gap = p1 - p2
    lower = gap - math.sqrt(max(0.0, (p1 - l1) ** 2 - 2 * phi * (p1 - l1) * (u2 - p2) + (u2 - p2) ** 2))
    upper = gap + math.sqrt(max(0.0, (u1 - p1) ** 2 - 2 * phi * (u1 - p1) * (p2 - l2) + (p2 - l2) ** 2))
    return gap, max(-1.0, lower), min(1.0, upper)


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
