"""Two learning curves side by side: each one's P_T at the checkpoints the two share, and their difference with an
interval.

A controlled run changes one thing in a curve's recipe (one fixed phrasing instead of paraphrases, twice the
demos) and is a study of its own. Whether the change moved P_T is then the difference of the two curves at the
same training budget, which neither study's report gives. Points are matched by their nominal epochs, or by the
gradient step they were saved at (``steps``: a run on twice the demos reaches the same steps in half the epochs).
Each difference is taken on the cells (N, seed, widths) both points have (:func:`.curve.point_difference`). It is
paired episode by episode where both points kept their outcomes and both studies play the same episode seeds, and
taken as two independent samples otherwise. These are pure functions of ``curve.csv`` rows:
``factorworld compare-curves`` reads the files and prints :func:`curve_comparison_lines`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .curve import Difference, point_difference, pooled_curve

MATCHES = ("epochs", "steps")
STEPS_TOLERANCE = 0.05  # match=steps: points saved within 5% of each other's gradient step count as one budget


@dataclass(frozen=True)
class CurveSide:
    """One curve of a study: its ``curve.csv`` rows, where they come from, and which method and task."""

    name: str  # the folder, as the user named it
    rows: Sequence[dict[str, Any]]
    method: str | None = None  # None: the only one the curve has
    task: str | None = None


def curve_comparison_lines(
    first: CurveSide, second: CurveSide, match: str = "epochs", paired: bool = True
) -> list[str]:
    """Markdown lines: the matched points of the two curves, each P_T with its Wilson interval, and first minus
    second with Newcombe's interval (``paired``: whether the two studies play the same episode seeds, so that
    episode i of one may pair with episode i of the other)."""
    if match not in MATCHES:
        raise ValueError(f"unknown match {match!r}; valid: {', '.join(MATCHES)}")
    points = [_points(side) for side in (first, second)]
    pairs = _matched(*(list(p.values()) for p in points), match)
    if not pairs:
        at = {name: sorted(p) for name, p in zip((first.name, second.name), points)}
        raise ValueError(f"the two curves share no checkpoint by {match}: {at}")
    rows, kinds, subset = [], set(), False
    for mine, theirs in pairs:
        found = point_difference(*(p if paired else _unpaired(p) for p in (mine, theirs)))
        cell = "" if found is None else _difference_cell(found)
        if found is not None:
            kinds.add(found.paired)
            subset = subset or found.subset
        rows.append(
            f"| {mine['epochs']:g} ({mine['steps']}) | {theirs['epochs']:g} ({theirs['steps']}) | {_rate(mine)} | "
            f"{_rate(theirs)} | {cell} |"
        )
    (m1, t1), (m2, t2) = (_line(side) for side in (first, second))
    return [
        f"first: {first.name} ({m1}, {t1}); second: {second.name} ({m2}, {t2}); matched by {match}",
        "",
        "| first: epochs (step) | second: epochs (step) | first P_T [95%] (episodes) | second P_T [95%] (episodes) "
        "| first - second [95%] |",
        "|---|---|---|---|---|",
        *rows,
        "",
        _note(kinds, subset, paired),
    ]


def _points(side: CurveSide) -> dict[float, dict[str, Any]]:
    """The side's pooled points by epochs, each with the gradient step it was saved at (the cells' largest)."""
    method, task = _line(side)
    rows = [r for r in side.rows if r["method"] == method and r["task"] == task]
    steps: dict[float, int] = {}
    for row in rows:
        steps[float(row["epochs"])] = max(steps.get(float(row["epochs"]), 0), int(row["steps"]))
    return {p["epochs"]: {**p, "steps": steps[p["epochs"]]} for p in pooled_curve(rows)}


def _line(side: CurveSide) -> tuple[str, str]:
    """The side's method and task: the ones asked for, or the only ones its curve has; refused naming the choices."""
    chosen = []
    for column, wanted in (("method", side.method), ("task", side.task)):
        there = sorted({str(r[column]) for r in side.rows})
        if wanted is None and len(there) != 1:
            raise ValueError(
                f"{side.name}'s curve has {column}s {', '.join(there) or 'none'}: name one with --{column}"
            )
        if wanted is not None and wanted not in there:
            raise ValueError(f"{side.name}'s curve has no {column} {wanted!r}; valid: {', '.join(there)}")
        chosen.append(wanted if wanted is not None else there[0])
    return chosen[0], chosen[1]


def _matched(first: list[dict], second: list[dict], match: str) -> list[tuple[dict, dict]]:
    """Each first point with the second's point of the same epochs, or (``steps``) of the nearest gradient step
    within :data:`STEPS_TOLERANCE`."""
    if match == "epochs":
        by_epochs = {p["epochs"]: p for p in second}
        return [(p, by_epochs[p["epochs"]]) for p in first if p["epochs"] in by_epochs]
    pairs = []
    for point in first:
        nearest = min(second, key=lambda other: abs(other["steps"] - point["steps"]))
        if abs(nearest["steps"] - point["steps"]) <= STEPS_TOLERANCE * max(point["steps"], nearest["steps"]):
            pairs.append((point, nearest))
    return pairs


def _unpaired(point: dict[str, Any]) -> dict[str, Any]:
    """The point without its episodes' outcomes: compared as an independent sample."""
    return {**point, "by_cell": {cell: (k, n, "") for cell, (k, n, _) in point["by_cell"].items()}}


def _rate(point: dict[str, Any]) -> str:
    return f"{point['success_rate']:.2f} [{point['ci_low']:.2f}, {point['ci_high']:.2f}] ({point['episodes']})"


def _difference_cell(found: Difference) -> str:
    return f"{found.diff:+.2f} [{found.low:+.2f}, {found.high:+.2f}]" + (" †" if found.subset else "")


def _note(kinds: set[bool], subset: bool, paired: bool) -> str:
    how = {
        frozenset({True}): "Newcombe's 95% interval for paired samples: episode i of one point with episode i of the "
        "other, each played at seed start_seed + i in its study's training environments",
        frozenset({False}): "Newcombe's 95% interval for two independent samples"
        + ("" if paired else " (the two studies play other episode seeds, so their episodes do not pair)"),
    }.get(frozenset(kinds), "Newcombe's 95% interval, paired where both points kept their episodes' outcomes and "
          "for two independent samples where one did not")  # fmt: skip
    return (
        f"Each P_T: its Wilson 95% interval. Each difference: {how}; each on its own, not corrected for the others, "
        "and of the episodes' noise only (one training seed per curve: the spread between training seeds is not in "
        "it)." + (" † on the cells (N, seed, widths) both points have, where one has more." if subset else "")
    )
