"""Rankings and their agreement: a factor ordering, hardest first, and Spearman's rank correlation between two.

Why here: the study compares its ordering of factors with the paper's; ties get their average rank, as in
Spearman (1904), "The proof and measurement of association between two things", American Journal of Psychology
15(1), with the tie correction of computing Pearson's correlation on the average ranks (Kendall & Gibbons (1990),
"Rank Correlation Methods", 5th ed., ch. 3).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence


def rank_hardest_first(gaps: Mapping[str, float]) -> dict[str, float]:
    """Rank factors by gap, 1 = largest (hardest); ties share their average rank (Kendall & Gibbons 1990); NaN gaps
    are left out."""
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
    """Spearman's (1904) rho over the keys both rankings share (Pearson correlation of the ranks, ties averaged).

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
    """Average ranks (1 = smallest) of ``values``, ties sharing their mean rank (Kendall & Gibbons 1990)."""
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
