"""One factor's gap in two studies, and their difference, with seed-level bootstrap intervals.

A study's report compares methods within it; a question that spans two committed studies (the same recipe at
84 and 168 px, image textures against flat colours, a method added in a later study) needs the difference of
their gaps with an interval, not one study's point estimate read against the other's interval. Each side is
one method on one task at one N (main grid), over the training seeds both studies ran. The two sides become
two methods of one table and go through the report's own :func:`aggregate.method_gap_differences`: a seed's
cells move together in the bootstrap, and the two studies' cells of the same seed number are drawn together.
Only counts are used (as in the report), so paired episodes are resampled independently, which widens the
intervals. Pure functions of ``results.csv`` rows; ``factorworld compare-gaps`` reads the files and prints :func:`comparison_lines`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ...protocol.conditions import TRAIN_SUITE
from .aggregate import Interval, main_grid, method_gap_differences

FIRST, SECOND = "first", "second"  # the two sides' names as methods of one table


@dataclass(frozen=True)
class Side:
    """Which cells of a study: one method on one task at one N (``None``: the only one there is)."""

    method: str
    task: str
    n_train_envs: int | None = None


@dataclass(frozen=True)
class GapComparison:
    """Mean gap over the shared seeds on each side and their difference (first minus second), each an
    :data:`aggregate.Interval` (point, 95% low, high)."""

    factor: str
    seeds: tuple[int, ...]
    episodes: tuple[tuple[int, ...], tuple[int, ...]]  # the episode counts of each side's factor cells
    gaps: tuple[Interval, Interval]
    difference: Interval


def _side_rows(rows: Sequence[dict[str, Any]], side: Side, factor: str, label: str) -> list[dict[str, Any]]:
    """``side``'s ``train`` and ``factor`` rows; refuses what is missing or ambiguous, naming the choices."""
    grid = main_grid(rows)
    chosen = [
        r
        for r in grid
        if r["method"] == side.method
        and r["task"] == side.task
        and r["condition"] in (TRAIN_SUITE, factor)
        and (side.n_train_envs is None or r["n_train_envs"] == side.n_train_envs)
    ]
    if not any(r["condition"] == factor for r in chosen):
        methods = sorted({r["method"] for r in grid})
        conditions = sorted({r["condition"] for r in grid if r["condition"] != TRAIN_SUITE})
        raise ValueError(
            f"{label}: no cell of method {side.method!r} on {side.task!r} under {factor!r}; "
            f"its methods: {', '.join(methods)}; its factors: {', '.join(conditions)}"
        )
    ns = sorted({r["n_train_envs"] for r in chosen})
    if len(ns) > 1:
        raise ValueError(f"{label}: cells at N = {ns}; choose one (n_train_envs)")
    cells = [(r["seed"], r["condition"]) for r in chosen]
    if len(set(cells)) < len(cells):
        raise ValueError(f"{label}: more than one cell per seed and condition")
    return chosen


def _seeds_with_both(rows: Sequence[dict[str, Any]], factor: str) -> set[int]:
    return {r["seed"] for r in rows if r["condition"] == factor} & {
        r["seed"] for r in rows if r["condition"] == TRAIN_SUITE
    }


def compare_gaps(
    first: Sequence[dict[str, Any]], second: Sequence[dict[str, Any]], factor: str, sides: tuple[Side, Side]
) -> GapComparison:
    """``factor``'s gap P_train - P_factor in ``first`` and ``second`` (each side averaged over the seeds both
    hold), and the first's minus the second's, each with a seed-level bootstrap 95% interval."""
    a = _side_rows(first, sides[0], factor, "first study")
    b = _side_rows(second, sides[1], factor, "second study")
    seeds = _seeds_with_both(a, factor) & _seeds_with_both(b, factor)
    if not seeds:
        raise ValueError(
            f"the two studies share no training seed with both cells (first: {sorted(_seeds_with_both(a, factor))}, "
            f"second: {sorted(_seeds_with_both(b, factor))})"
        )
    rows = [{**r, "method": name} for name, side in ((FIRST, a), (SECOND, b)) for r in side if r["seed"] in seeds]
    # the second as the base: the difference is then the first minus the second
    # the sides pair by seed (restricted above); their N and widths may differ between the studies
    found = method_gap_differences(rows, [SECOND, FIRST], {factor: [factor]}, shared_cells_only=False).get(
        (FIRST, factor)
    )
    if found is None:  # a cell whose gap is undefined (no train episodes on the same seeds) is left out
        raise ValueError(f"no defined {factor!r} gap on both sides at the shared seeds {sorted(seeds)}")
    second_gap, first_gap, difference = found

    def counts(side: list[dict[str, Any]]) -> tuple[int, ...]:
        return tuple(sorted({r["episodes"] for r in side if r["condition"] == factor and r["seed"] in seeds}))

    return GapComparison(factor, tuple(sorted(seeds)), (counts(a), counts(b)), (first_gap, second_gap), difference)


def comparison_lines(
    first: tuple[str, Sequence[dict[str, Any]]],
    second: tuple[str, Sequence[dict[str, Any]]],
    factor: str,
    sides: tuple[Side, Side],
) -> list[str]:
    """``factorworld compare-gaps``'s text: each side's gap and the difference (the last line), each with its
    seed-level bootstrap 95% interval."""
    result = compare_gaps(first[1], second[1], factor, sides)
    lines = [
        f"{factor} on {sides[0].task}, seeds {', '.join(map(str, result.seeds))} (seed-level bootstrap 95% intervals)"
    ]
    for name, side, (gap, low, high), counts in zip(
        (first[0], second[0]), sides, result.gaps, result.episodes, strict=True
    ):
        episodes = "-".join(map(str, sorted({counts[0], counts[-1]})))
        lines.append(
            f"  {name} ({side.method}, {episodes} episodes per cell): gap {gap:+.3f} [{low:+.3f}, {high:+.3f}]"
        )
    difference, low, high = result.difference
    lines.append(f"difference (first minus second): {difference:+.3f} [{low:+.3f}, {high:+.3f}]")
    return lines
