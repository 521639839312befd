"""Two learning curves side by side: each one's P_T at the checkpoints the two share, and their difference with an
interval.

A controlled run changes one thing in a curve's recipe (one fixed phrasing instead of paraphrases, twice the
demos) and is a study of its own. Whether the change moved P_T is then the difference of the two curves at the
same training budget, which neither study's report gives. Points are matched by their nominal epochs, or by the
gradient step they were saved at (``steps``: a run on twice the demos reaches the same steps in half the epochs).
Each difference is taken on the cells (N, seed, widths) both points have (:func:`.curve.point_difference`). It is
paired episode by episode where both points kept their outcomes and both studies play the same episode seeds, and
taken as two independent samples otherwise. Each interval is 95% on its own; points declared beforehand as one
finding (``family``: the first curve's epochs) are compared alone, each interval Bonferroni-corrected over them,
and the finding is stated from those intervals only. These are pure functions of ``curve.csv`` rows:
``factorworld compare-curves`` reads the files and prints :func:`curve_comparison_lines`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ...stats.proportions import two_sided_z
from .curve import Difference, point_difference, pooled_curve

MATCHES = ("epochs", "steps")
STEPS_TOLERANCE = 0.05  # match=steps: points saved within 5% of each other's gradient step count as one budget
ERROR = 0.05  # each interval's, or a family's split evenly between its points (Bonferroni)


@dataclass(frozen=True)
class CurveSide:
    """One curve of a study: its ``curve.csv`` rows, where they come from, and which method and task."""

    name: str  # the folder, as the user named it
    rows: Sequence[dict[str, Any]]
    method: str | None = None  # None: the only one the curve has
    task: str | None = None


def curve_comparison_lines(
    first: CurveSide,
    second: CurveSide,
    match: str = "epochs",
    paired: bool = True,
    family: Sequence[float] | None = None,
) -> list[str]:
    """Markdown lines: the matched points of the two curves, each P_T with its Wilson interval, and first minus
    second with Newcombe's interval (``paired``: whether the two studies play the same episode seeds, so that
    episode i of one may pair with episode i of the other). ``family``: the first curve's epochs that form one
    finding: only they are compared, each difference at ``1 - 0.05 / k`` over their ``k``, and a line says where
    the finding is resolved."""
    if match not in MATCHES:
        raise ValueError(f"unknown match {match!r}; valid: {', '.join(MATCHES)}")
    points = [_points(side) for side in (first, second)]
    pairs = _matched(*(list(p.values()) for p in points), match)
    if not pairs:
        at = {name: sorted(p) for name, p in zip((first.name, second.name), points)}
        raise ValueError(f"the two curves share no checkpoint by {match}: {at}")
    corrected_over = 0  # points in the family: 0 without one
    if family is not None:
        pairs = _family_pairs(pairs, family, first.name, second.name, match)
        corrected_over = len(pairs)
    level = 1 - ERROR / max(corrected_over, 1)
    z = two_sided_z(level)
    rows, kinds, subset, found_at = [], set(), False, []
    for mine, theirs in pairs:
        found = point_difference(*(p if paired else _unpaired(p) for p in (mine, theirs)), z)
        cell = "" if found is None else _difference_cell(found)
        if found is not None:
            kinds.add(found.paired)
            subset = subset or found.subset
        found_at.append((mine["epochs"], found))
        rows.append(
            f"| {mine['epochs']:g} ({mine['steps']}) | {theirs['epochs']:g} ({theirs['steps']}) | {_rate(mine)} | "
            f"{_rate(theirs)} | {cell} |"
        )
    (m1, t1), (m2, t2) = (_line(side) for side in (first, second))
    corrected = f", Bonferroni over {corrected_over}" if corrected_over else ""
    return [
        f"first: {first.name} ({m1}, {t1}); second: {second.name} ({m2}, {t2}); matched by {match}",
        "",
        "| first: epochs (step) | second: epochs (step) | first P_T [95%] (episodes) | second P_T [95%] (episodes) "
        f"| first - second [{_percent(level)}{corrected}] |",
        "|---|---|---|---|---|",
        *rows,
        "",
        *([_finding(found_at, level), ""] if corrected_over else []),
        _note(kinds, subset, paired, level, corrected_over),
    ]


def _family_pairs(
    pairs: list[tuple[dict, dict]], family: Sequence[float], first: str, second: str, match: str
) -> list[tuple[dict, dict]]:
    """The matched pairs whose first point is one of the family's epochs; refused where one is not matched."""
    by_epochs = {mine["epochs"]: (mine, theirs) for mine, theirs in pairs}
    wanted = sorted({float(e) for e in family})
    missing = [e for e in wanted if e not in by_epochs]
    valid = ", ".join(f"{e:g}" for e in sorted(by_epochs))
    if not wanted:
        raise ValueError(f"the family names no epochs; name some of {first}'s matched by {match}: {valid}")
    if missing:
        what = ", ".join(f"{e:g}" for e in missing)
        raise ValueError(
            f"the family names epochs {what}, not a point of {first} matched in {second} by {match}; valid: {valid}"
        )
    return [by_epochs[e] for e in wanted]


def _finding(found_at: list[tuple[float, Difference | None]], level: float) -> str:
    """Where the family's corrected intervals lie wholly above or below zero, and where neither."""
    where: dict[str, list[str]] = {"first above second": [], "first below second": [], "not resolved": []}
    for epochs, found in found_at:
        side = "not resolved"
        if found is not None and found.low > 0:
            side = "first above second"
        elif found is not None and found.high < 0:
            side = "first below second"
        where[side].append(f"{epochs:g}")
    parts = [f"{side} at {', '.join(at)} epochs" for side, at in where.items() if at]
    return (
        f"As one finding ({_points_text(len(found_at))}, each interval at {_percent(level)}): " + "; ".join(parts) + "."
    )


def _points_text(k: int) -> str:
    return f"{k} point" + ("" if k == 1 else "s")


def _percent(level: float) -> str:
    """95% as ``95%``, a corrected level to one decimal (``98.3%``)."""
    return f"{level:.0%}" if round(level * 100, 6).is_integer() else f"{level:.1%}"


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


def _note(kinds: set[bool], subset: bool, paired: bool, level: float = 0.95, family: int = 0) -> str:
    how = {
        frozenset({True}): "Newcombe's interval for paired samples: episode i of one point with episode i of the "
        "other, each played at seed start_seed + i in its study's training environments",
        frozenset({False}): "Newcombe's interval for two independent samples"
        + ("" if paired else " (the two studies play other episode seeds, so their episodes do not pair)"),
    }.get(frozenset(kinds), "Newcombe's interval, paired where both points kept their episodes' outcomes and "
          "for two independent samples where one did not")  # fmt: skip
    corrected = (
        f"each at {_percent(level)}, Bonferroni-corrected over the {_points_text(family)} named as one finding"
        if family
        else "each at 95% on its own, not corrected for the others"
    )
    return (
        f"Each P_T: its Wilson 95% interval. Each difference: {how}; {corrected}, "
        "and of the episodes' noise only (one training seed per curve: the spread between training seeds is not in "
        "it)." + (" † on the cells (N, seed, widths) both points have, where one has more." if subset else "")
    )
