"""One factor's gap in two studies, and their difference, with seed-level bootstrap intervals.

A study's report compares methods within it; a question that spans two committed studies (the same recipe at
84 and 168 px, image textures against flat colours, a method added in a later study) needs the difference of
their gaps with an interval, not one study's point estimate read against the other's interval. Each side is
one method on one task at one N (and widths), over the training seeds both studies ran: a seed's cells
(``train`` and the factor) move together in the bootstrap, and the two studies' cells of the same seed number
are drawn together, as :func:`metrics.seed_bootstrap` does for a report's cells. Only counts are used (as in
the report), so paired episodes are resampled independently, which widens the intervals.
Pure functions of ``results.csv`` rows; ``scripts/compare_gaps.py`` reads the files and prints.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..protocol.conditions import TRAIN_SUITE
from .metrics import nanmean, percentile_interval, seed_bootstrap


@dataclass(frozen=True)
class Side:
    """Which cells of a study: one method on one task at one N and widths (``None``: the only one there is)."""

    method: str
    task: str
    n_train_envs: int | None = None
    widths: str = "default"


@dataclass(frozen=True)
class GapComparison:
    """Mean gap over the shared seeds on each side, their difference (first minus second), 95% intervals."""

    factor: str
    seeds: tuple[int, ...]
    episodes: tuple[int, int]  # episodes per cell on each side
    gaps: tuple[float, float]
    gap_intervals: tuple[tuple[float, float], tuple[float, float]]
    difference: float
    difference_interval: tuple[float, float]


def _cells(rows: Sequence[dict[str, Any]], side: Side, factor: str, label: str) -> dict[int, dict[str, dict]]:
    """seed -> condition -> row for ``side``'s ``train`` and ``factor`` cells; refuses what is missing or ambiguous."""
    chosen = [
        r
        for r in rows
        if r["method"] == side.method
        and r["task"] == side.task
        and r["widths"] == side.widths
        and r["condition"] in (TRAIN_SUITE, factor)
        and (side.n_train_envs is None or r["n_train_envs"] == side.n_train_envs)
    ]
    if not any(r["condition"] == factor for r in chosen):
        methods = sorted({r["method"] for r in rows})
        conditions = sorted({r["condition"] for r in rows if r["condition"] != TRAIN_SUITE})
        raise ValueError(
            f"{label}: no cell of method {side.method!r} on {side.task!r} under {factor!r}; "
            f"its methods: {', '.join(methods)}; its factors: {', '.join(conditions)}"
        )
    ns = sorted({r["n_train_envs"] for r in chosen})
    if len(ns) > 1:
        raise ValueError(f"{label}: cells at N = {ns}; choose one (n_train_envs)")
    out: dict[int, dict[str, dict]] = {}
    for row in chosen:
        seed = out.setdefault(row["seed"], {})
        if row["condition"] in seed:
            raise ValueError(f"{label}: two {row['condition']!r} cells at seed {row['seed']}")
        seed[row["condition"]] = row
    return {s: c for s, c in out.items() if TRAIN_SUITE in c and factor in c}


def compare_gaps(
    first: Sequence[dict[str, Any]], second: Sequence[dict[str, Any]], factor: str, sides: tuple[Side, Side]
) -> GapComparison:
    """``factor``'s gap P_train - P_factor in ``first`` and ``second`` (each side averaged over the seeds both
    hold), and the first's minus the second's, each with a seed-level bootstrap 95% interval."""
    a = _cells(first, sides[0], factor, "first study")
    b = _cells(second, sides[1], factor, "second study")
    seeds = tuple(sorted(set(a) & set(b)))
    if not seeds:
        raise ValueError(
            f"the two studies share no training seed with both cells (first: {sorted(a)}, second: {sorted(b)})"
        )
    order = [(a, TRAIN_SUITE), (a, factor), (b, TRAIN_SUITE), (b, factor)]
    rates = np.array([[cells[s][c]["success_rate"] for cells, c in order] for s in seeds])
    episodes = np.array([[cells[s][c]["episodes"] for cells, c in order] for s in seeds])

    def statistic(r: np.ndarray, _n: np.ndarray) -> np.ndarray:
        gaps = np.stack([nanmean(r[..., 0] - r[..., 1], axis=1), nanmean(r[..., 2] - r[..., 3], axis=1)], axis=-1)
        return np.concatenate([gaps, gaps[..., :1] - gaps[..., 1:]], axis=-1)  # (B, 3): first, second, difference

    point, replicates = seed_bootstrap(rates, episodes, statistic)
    low, high = percentile_interval(replicates)
    per_side = tuple(int(episodes[:, i].max()) for i in (1, 3))
    return GapComparison(
        factor=factor,
        seeds=seeds,
        episodes=per_side,  # type: ignore[arg-type]
        gaps=(float(point[0]), float(point[1])),
        gap_intervals=((float(low[0]), float(high[0])), (float(low[1]), float(high[1]))),
        difference=float(point[2]),
        difference_interval=(float(low[2]), float(high[2])),
    )
