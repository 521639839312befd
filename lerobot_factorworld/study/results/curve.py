"""``curve.csv``: a learning curve's points (``train.curve_every``), P_T of each checkpoint against its training
epochs, one row per (method, task, N, seed, widths, checkpoint), the last point being the grid's own ``train``
evaluation. Each row has its Wilson 95% interval; :func:`pooled_curve` sums a method's episodes over cells and
seeds per checkpoint (the figure's and the report table's points)."""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...core import machine
from ...core.io import atomic_write_text, read_table
from ...protocol.conditions import TRAIN_SUITE
from ...stats.proportions import Z95, newcombe_independent, paired_gap, wilson_interval
from ..plan.config import StudyConfig
from ..plan.grid import CURVE_EPOCHS, Plan
from ..run.inputs import whole_epochs
from ..run.result import TRAINED_ON, is_done, read_result
from ..run.step import Step, step_folder
from .rows import Evaluation, csv_text, in_stage_order, parse_stage_counts, policy_of, stage_counts_text

CURVE_FILE = "curve.csv"
CURVE_COLUMNS = (
    "study",
    "method",
    "policy",
    "task",
    "n_train_envs",
    "seed",
    "widths",
    "epochs",  # nominal: a multiple of train.curve_every, or train.epochs for the last checkpoint
    "steps",  # the gradient step the checkpoint was saved at
    "episodes",
    "successes",
    "success_rate",
    "ci_low",
    "ci_high",
    "step",  # key of the eval step
    "stages",  # episodes per furthest stage, as results.csv's column: where the checkpoint's failures end
    "trained_on",  # the machines that trained the checkpoint, in the order they did (MACHINES_SEPARATOR between)
    "trained_since_previous",  # those that trained its steps after the cell's previous point (a chain: its link)
    "outcomes",  # each episode's success in episode order ("1" or "0"; episode i played at seed start_seed + i)
)
OPTIONAL_CURVE_COLUMNS = (
    "stages",
    "trained_on",
    "trained_since_previous",
    "outcomes",
)  # added later: older curve.csv files lack them
MACHINES_SEPARATOR = " | "  # between the machines of trained_on (machine.describe's text holds ';' and ',')
CELL = ("method", "task", "n_train_envs", "seed", "widths")


def curve_rows(cfg: StudyConfig, plan: Plan, study_dir: str | Path) -> list[dict[str, Any]]:
    """The finished points of every learning curve of ``plan`` (none without ``train.curve_every``), in the
    plan's order with each cell's points by epochs."""
    if not plan.curve_points():
        return []
    points = [(s, s.meta[CURVE_EPOCHS]) for s in plan.curve_points()]
    trained = {s.key: s.inputs for s in plan.of_kind("train")}
    points += [(s, whole_epochs(trained[s.deps[0]]["epochs"])) for s in last_points(plan)]  # the training's epochs
    found, trainings = [], {}  # each training's result read once for all its checkpoints
    for step, epochs in points:
        if not is_done(step, study_dir):
            continue
        key = step.deps[0]
        if key not in trainings:
            trainings[key] = read_result(step_folder(study_dir, "train", key))
        trained = trainings[key]
        saved_at = trained.get("curve", {}).get(str(epochs), trained["steps"])
        row = _row(cfg, Evaluation(step, read_result(step, study_dir)), epochs, saved_at)
        found.append(({**row, "trained_on": machines_text(trained.get(TRAINED_ON, []), saved_at)}, trained))
    found.sort(key=lambda pair: ([str(pair[0][c]) for c in CELL], pair[0]["epochs"]))
    rows, previous = [], {}  # per cell: the step its previous point was saved at
    for row, trained in found:
        cell = tuple(str(row[c]) for c in CELL)
        since = machines_between(trained.get(TRAINED_ON, []), previous.get(cell, 0), row["steps"])
        rows.append({**row, "trained_since_previous": since})
        previous[cell] = row["steps"]
    return rows


def machines_text(runs: Sequence[dict[str, Any]], saved_at: int) -> str:
    """The machines that trained a checkpoint saved at ``saved_at``, from its training's runs (``trained_on``):
    each distinct one once, in the order it first trained ("" for a training that recorded none)."""
    machines = [machine.describe(run["machine"]) for run in runs if run["from_step"] < saved_at]
    return MACHINES_SEPARATOR.join(dict.fromkeys(machines))


def machines_between(runs: Sequence[dict[str, Any]], after: int, saved_at: int) -> str:
    """The machines that trained steps ``after`` to ``saved_at`` of a checkpoint's lineage (its training's runs,
    those of the trainings it extends first): each distinct one once, in the order it trained. A run ends where
    the next one starts; one that saved nothing before the next started trained none of the lineage's steps."""
    ends = [run["from_step"] for run in runs[1:]] + [math.inf]
    machines = [
        machine.describe(run["machine"])
        for run, end in zip(runs, ends)
        if run["from_step"] < saved_at and end > after and end > run["from_step"]
    ]
    return MACHINES_SEPARATOR.join(dict.fromkeys(machines))


def last_points(plan: Plan) -> list[Step]:
    """Each curve's last point: the grid's own ``train`` evaluation of a training that saves a curve."""
    curved = {s.key for s in plan.of_kind("train") if s.inputs.get("curve_every")}
    return [s for s in plan.evaluations() if s.meta["condition"] == TRAIN_SUITE and s.deps and s.deps[0] in curved]


def _row(cfg: StudyConfig, evaluation: Evaluation, epochs: float, saved_at: int) -> dict[str, Any]:
    meta, successes = evaluation.labels, evaluation.result["successes"]
    k, n = sum(successes), len(successes)
    low, high = wilson_interval(k, n)
    return {
        "study": cfg.name,
        **{c: meta[c] for c in CELL[:1]},
        "policy": policy_of(cfg, evaluation),
        **{c: meta[c] for c in CELL[1:]},
        "epochs": epochs,
        "steps": saved_at,
        "episodes": n,
        "successes": k,
        "success_rate": k / n if n else math.nan,
        "ci_low": low,
        "ci_high": high,
        "step": evaluation.step.key,
        "stages": stage_counts_text(
            meta["task"], evaluation.result.get("stages"), evaluation.result.get("stage_names")
        ),
        "outcomes": outcomes_text(successes),
    }


def outcomes_text(successes: Sequence[bool]) -> str:
    """Episodes' successes as ``curve.csv`` holds them: one character each, in episode order."""
    return "".join("1" if success else "0" for success in successes)


def _in_task_order(task: str, counts: Counter) -> dict[str, int]:
    """Stage counts in the task's order of stages (as ``results.csv`` writes them), any other stage after them."""
    return {name: counts[name] for name in in_stage_order(task, counts) if name in counts}


def write_curve(rows: Sequence[dict[str, Any]], path: Path) -> Path:
    """``curve.csv``; a later column no row holds is left out, so points read from an older file are written back
    as that file's bytes."""
    empty = {c for c in OPTIONAL_CURVE_COLUMNS if not any(row.get(c) for row in rows)}
    atomic_write_text(path, csv_text(rows, [c for c in CURVE_COLUMNS if c not in empty]))
    return path


def read_curve(path: str | Path) -> list[dict[str, Any]]:
    """``curve.csv``'s rows with their numbers as numbers (epochs as :func:`curve_rows` holds them, whole ones as
    integers, so that written again they give the same bytes)."""
    integers = ("n_train_envs", "seed", "steps", "episodes", "successes")
    required = [c for c in CURVE_COLUMNS if c not in OPTIONAL_CURVE_COLUMNS]
    rows = read_table(path, required, integers, ("epochs", "success_rate", "ci_low", "ci_high"))
    return [{**dict.fromkeys(OPTIONAL_CURVE_COLUMNS, ""), **row, "epochs": whole_epochs(row["epochs"])} for row in rows]


def pooled_curve(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (method, task, epochs): the episodes and successes summed over N, seeds and widths, with the Wilson
    95% interval of the pooled rate (episodes of one checkpoint are independent given it; seeds add variance
    this interval does not hold, so it is a lower bound on the spread between seeds), the episodes per
    furthest stage summed the same way (``{}`` where a row has no stage counts), and each cell's successes,
    episodes and episode outcomes by (N, seed, widths) (``by_cell``), from which two points are compared."""
    pooled: dict[tuple, list] = defaultdict(lambda: [0, 0, 0, Counter(), True, {}])
    for row in rows:
        point = pooled[(row["method"], row["task"], float(row["epochs"]))]
        point[0] += row["successes"]
        point[1] += row["episodes"]
        point[2] += 1
        stages = parse_stage_counts(row.get("stages", ""))
        point[3].update(stages)
        point[4] = point[4] and bool(stages)
        k, n, outcomes = point[5].get(_paired_cell(row), (0, 0, ""))  # a cell once per point, but for rows without one
        point[5][_paired_cell(row)] = (k + row["successes"], n + row["episodes"], outcomes + row.get("outcomes", ""))
    out = []
    for (method, task, epochs), (k, n, cells, stages, staged, by_cell) in sorted(pooled.items()):
        low, high = wilson_interval(k, n)
        out.append({"method": method, "task": task, "epochs": epochs, "cells": cells, "successes": k,
                    "episodes": n, "success_rate": k / n if n else math.nan, "ci_low": low, "ci_high": high,
                    "stages": _in_task_order(task, stages) if staged else {}, "by_cell": by_cell})  # fmt: skip
    return out


def _paired_cell(row: dict[str, Any]) -> tuple[str, ...]:
    """What two points' cells must share to be compared (the same training environments and episode seeds): N,
    seed and widths; the method and the checkpoint may differ."""
    return tuple(str(row.get(c, "")) for c in CELL[2:])


@dataclass(frozen=True)
class Comparison:
    """Two pooled points set side by side on the cells both have (:func:`compare_points`): episode by episode
    (``paired``, ``first`` and ``second`` the outcomes) where every shared cell holds both points' outcomes for the
    same number of episodes, else as two independent samples (``first`` and ``second`` are ``(successes,
    episodes)``); ``subset`` when a point has cells the other lacks, which the comparison leaves out."""

    paired: bool
    subset: bool
    first: Any
    second: Any


def compare_points(point: dict[str, Any], other: dict[str, Any]) -> Comparison | None:
    """``point`` against ``other`` on the cells both have (``None`` without one): every checkpoint of a cell, and
    every method's, plays the same episode seeds in the same training environments, so episode i pairs with
    episode i where both points kept their outcomes (an older ``curve.csv`` did not)."""
    mine, theirs = point.get("by_cell", {}), other.get("by_cell", {})
    shared = sorted(set(mine) & set(theirs))
    if not shared:
        return None
    subset = len(shared) < max(len(mine), len(theirs))
    pairs = [(mine[c][2], theirs[c][2]) for c in shared]
    whole = all(len(by_cell[c][2]) == by_cell[c][1] for by_cell in (mine, theirs) for c in shared)
    if whole and all(a and len(a) == len(b) for a, b in pairs):
        first = [o == "1" for a, _ in pairs for o in a]
        return Comparison(True, subset, first, [o == "1" for _, b in pairs for o in b])
    return Comparison(False, subset, _counts(mine, shared), _counts(theirs, shared))


def _counts(by_cell: dict[tuple[str, ...], tuple[int, int, str]], cells: Sequence[tuple[str, ...]]) -> tuple[int, int]:
    """``(successes, episodes)`` summed over ``cells``."""
    return sum(by_cell[c][0] for c in cells), sum(by_cell[c][1] for c in cells)


@dataclass(frozen=True)
class Difference:
    """``point`` minus ``other`` (:func:`point_difference`) with Newcombe's interval, paired or not, and whether
    it leaves out cells one point has and the other lacks."""

    diff: float
    low: float
    high: float
    paired: bool
    subset: bool


def point_difference(point: dict[str, Any] | None, other: dict[str, Any] | None, z: float = Z95) -> Difference | None:
    """Two pooled points' difference on the cells both have (:func:`compare_points`), its interval at the normal
    quantile ``z`` (95% by default); ``None`` without both."""
    comparison = compare_points(point, other) if point and other else None
    if comparison is None:
        return None
    if comparison.paired:
        diff, low, high = paired_gap(comparison.first, comparison.second, z)
    else:
        diff, low, high = newcombe_independent(*comparison.first, *comparison.second, z)
    return Difference(diff, low, high, comparison.paired, comparison.subset)
