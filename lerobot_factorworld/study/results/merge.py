"""One study's results made in parts (other machines, sessions or commits, each with its own step folders) as one
``results.csv``, ``episodes.parquet`` and ``curve.csv`` (a learning curve's points): ``factorworld merge-results``.
Every row keeps the commit and source hash that made it, so the merged file says which part each number came
from; ``factorworld report`` then renders the whole.

Only rows of one study merge: the same study name, each evaluation (its step key) once. A key found in both parts
must hold the same numbers (the same inputs give the same result: a rerun that differs is what
``factorworld compare-reruns`` reads, not something to average), and a cell (method, task, N, seed, widths,
condition) must not come from two different steps (two grids under one name). Rows come out in the order of the
study's plan, so merging in either order writes the same bytes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..plan.grid import Plan
from .curve import CELL as CURVE_CELL
from .curve import CURVE_COLUMNS, CURVE_FILE, OPTIONAL_CURVE_COLUMNS, last_points, read_curve, write_curve
from .episodes import EPISODES_FILE, read_episodes, write_episodes
from .rows import RESULT_COLUMNS, RESULTS_FILE, read_results, write_results

CELL = ("method", "task", "n_train_envs", "seed", "widths", "condition")
PROVENANCE_COLUMNS = ("commit", "source_hash")  # where a row was made, not what it measured
CURVE_PROVENANCE_COLUMNS = ("trained_on", "trained_since_previous")  # the same, of a learning-curve point
CHANGED_CONFIG = "if the config changed what it plans, --drop_unplanned=true leaves the old rows out"


def merge_rows(parts: Sequence[Sequence[dict[str, Any]]], plan: Plan, names: Sequence[str]) -> list[dict[str, Any]]:
    """The rows of every part, each evaluation once, in ``plan``'s order; conflicts refused in one line naming
    the parts (``names``) and the step."""
    studies = {row["study"] for part in parts for row in part}
    if len(studies) > 1:
        raise ValueError(
            f"the parts hold different studies ({', '.join(sorted(studies))}): only one study's parts merge"
        )
    by_step: dict[str, tuple[dict[str, Any], str]] = {}
    by_cell: dict[tuple, str] = {}
    for part, name in zip(parts, names):
        for row in part:
            measured = {c: row[c] for c in RESULT_COLUMNS if c not in PROVENANCE_COLUMNS}
            seen = by_step.get(row["step"])
            if seen is not None:
                other = {c: seen[0][c] for c in measured}
                if not _same(other, measured):
                    differ = [c for c in measured if not _same({c: other[c]}, {c: measured[c]})]
                    raise ValueError(
                        f"step {row['step']} ({cell_label(row)}) differs between {seen[1]} and {name} in "
                        f"{', '.join(differ)}: compare them with factorworld compare-reruns, merge one"
                    )
                continue
            cell = tuple(str(row[c]) for c in CELL)
            if cell in by_cell and by_cell[cell] != row["step"]:
                raise ValueError(
                    f"{cell_label(row)} comes from two evaluation steps ({by_cell[cell]} and {row['step']}): the "
                    f"parts are of different grids under one study name ({CHANGED_CONFIG})"
                )
            by_step[row["step"]] = (row, name)
            by_cell[cell] = row["step"]
    order = {step.key: i for i, step in enumerate(plan.evaluations())}
    unplanned = [row for row, _ in by_step.values() if row["step"] not in order]
    if unplanned:
        raise ValueError(
            f"{cell_label(unplanned[0])} ({unplanned[0]['step']}) is not in the study's plan: pass its config "
            f"({CHANGED_CONFIG})"
        )
    return [row for row, _ in sorted(by_step.values(), key=lambda item: order[item[0]["step"]])]


def merge_curve_rows(
    parts: Sequence[Sequence[dict[str, Any]]], plan: Plan, names: Sequence[str]
) -> list[dict[str, Any]]:
    """The learning-curve points of every part, each evaluation once and the same numbers where two parts hold
    it, sorted as ``curve.csv`` sorts them (cell, then epochs); a point the plan does not hold is refused."""
    planned = {s.key for s in plan.curve_points()} | {s.key for s in plan.evaluations()}
    by_step: dict[str, tuple[dict[str, Any], str]] = {}
    for part, name in zip(parts, names):
        for row in part:
            if row["step"] not in planned:
                raise ValueError(
                    f"the learning-curve point {row['step']} of {name} is not in the study's plan: pass its "
                    f"config ({CHANGED_CONFIG})"
                )
            seen = by_step.get(row["step"])
            point = {c: row.get(c, "") if c in OPTIONAL_CURVE_COLUMNS else row[c] for c in CURVE_COLUMNS}
            if seen is None:
                by_step[row["step"]] = (point, name)
                continue
            # a column an older curve.csv lacks (empty) is unknown there, not different; where it was made, not
            # what it measured, is never compared (the first part's is kept)
            known = [c for c in CURVE_COLUMNS if c not in OPTIONAL_CURVE_COLUMNS or "" not in (seen[0][c], point[c])]
            known = [c for c in known if c not in CURVE_PROVENANCE_COLUMNS]
            differ = [c for c in known if not _same({c: seen[0][c]}, {c: point[c]})]
            if differ:
                raise ValueError(
                    f"the learning-curve point {row['step']} differs between {seen[1]} and {name} in "
                    f"{', '.join(differ)}"
                )
            filled = {c: point[c] for c in OPTIONAL_CURVE_COLUMNS if point[c] != "" and seen[0][c] == ""}
            if filled:  # this part agrees on every column and holds more: a later conflict is with it
                by_step[row["step"]] = ({**seen[0], **filled}, name)
    rows = [row for row, _ in by_step.values()]
    return sorted(rows, key=lambda r: ([str(r[c]) for c in CURVE_CELL], r["epochs"]))


@dataclass(frozen=True)
class Merged:
    written: list[Path]  # results.csv first
    added: int  # evaluations ``into`` did not hold
    dropped: list[dict[str, Any]]  # rows the plan no longer holds (``drop_unplanned``), once per step
    notes: list[str]  # what a reader should know of the other files (a part without a curve, a removed curve)


def merge_results(
    into: Path, others: Sequence[Path], plan: Plan, *, study: str, drop_unplanned: bool = False
) -> Merged:
    """Merge the ``results.csv`` (``episodes.parquet``, where every part has one; ``curve.csv``, where any part
    has one) of the folders ``others`` into folder ``into``, checked in full before anything is written; every
    row must be of ``study`` (the config's name). ``drop_unplanned``: rows, episodes and curve points of steps
    the plan no longer holds (a method whose budget the config changed) are left out instead of refused, but a
    part none of whose rows the plan holds is refused (a wrong config, not a changed one)."""
    folders = [into, *others]
    parts = [read_results(folder / RESULTS_FILE) for folder in folders]
    names = [str(folder) for folder in folders]
    for part, name in zip(parts, names):
        if {row["study"] for row in part} - {study}:
            found = ", ".join(sorted({row["study"] for row in part}))
            raise ValueError(f"{name} holds study {found}, but the config is of study {study}")
    curved = [folder for folder in folders if (folder / CURVE_FILE).is_file()]
    curves = [read_curve(folder / CURVE_FILE) for folder in curved]
    dropped: list[dict[str, Any]] = []
    if drop_unplanned:
        parts, curves, dropped = _planned_only(parts, curves, plan, names)
    rows = merge_rows(parts, plan, names)
    curve = merge_curve_rows(curves, plan, [str(f) for f in curved])
    kept = {row["step"] for row in rows}
    with_episodes = [folder for folder in folders if (folder / EPISODES_FILE).is_file()]
    episodes = None
    if with_episodes == folders or (drop_unplanned and into in with_episodes):  # else into's episodes stay as they are
        episodes = _merged_episodes(with_episodes if with_episodes == folders else [into], kept, rows)
    last = {s.key for s in last_points(plan)}  # a curve's last point is a grid row: its part should have a curve
    notes = [
        f"{name} has no {CURVE_FILE}: the learning curves of its trainings are not in the merged one"
        for folder, name, part in zip(folders, names, parts)
        if folder not in curved and any(row["step"] in last for row in part)
    ]
    written = [write_results(rows, into / RESULTS_FILE)]
    if episodes is not None:
        written.append(write_episodes(episodes, into / EPISODES_FILE))
    if curve:
        written.append(write_curve(curve, into / CURVE_FILE))
    elif (into / CURVE_FILE).is_file():  # every point dropped: no curve left to show
        (into / CURVE_FILE).unlink()
        notes.append(f"removed {into / CURVE_FILE}: the plan holds none of its points")
    held = {row["step"] for row in parts[0]}
    return Merged(written, sum(row["step"] not in held for row in rows), dropped, notes)


def _planned_only(
    parts: list[list[dict[str, Any]]], curves: list[list[dict[str, Any]]], plan: Plan, names: Sequence[str]
) -> tuple[list[list[dict[str, Any]]], list[list[dict[str, Any]]], list[dict[str, Any]]]:
    """The parts' rows and curve points the plan holds, and the rows it does not (once per step); a part left
    with none of its rows is refused."""
    planned = {s.key for s in plan.evaluations()}
    points = planned | {s.key for s in plan.curve_points()}
    for part, name in zip(parts, names):
        if part and not any(row["step"] in planned for row in part):
            raise ValueError(f"the config plans none of the {len(part)} rows of {name}: is it this study's config?")
    dropped = {row["step"]: row for part in parts for row in part if row["step"] not in planned}
    kept_parts = [[row for row in part if row["step"] in planned] for part in parts]
    kept_curves = [[row for row in part if row["step"] in points] for part in curves]
    return kept_parts, kept_curves, list(dropped.values())


def _merged_episodes(folders: Sequence[Path], kept: set[str], rows: Sequence[dict[str, Any]]) -> list[dict]:
    """The episodes of the ``kept`` steps, each once, in the rows' order."""
    seen: set[tuple[str, int]] = set()
    merged = []
    for folder in folders:
        for episode in read_episodes(folder / EPISODES_FILE):
            key = (episode["step"], episode["episode_ix"])
            if episode["step"] in kept and key not in seen:
                seen.add(key)
                merged.append(episode)
    order = {row["step"]: i for i, row in enumerate(rows)}
    return sorted(merged, key=lambda e: (order[e["step"]], e["episode_ix"]))


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Equal, NaN equal to NaN (an undefined gap in both)."""
    return all(x == y or (x != x and y != y) for x, y in ((a[k], b[k]) for k in a))


def cell_label(row: dict[str, Any]) -> str:
    """``method=... task=... n_train_envs=... seed=... widths=... condition=...``: a row named in a message."""
    return " ".join(f"{c}={row[c]}" for c in CELL)
