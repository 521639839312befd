"""What a step leaves in its folder, read without running anything: the names of its files and result entries,
whether it is done, and its ``result.json`` read back (paths absolute) or written (paths relative).

Each step works in ``<study>/steps/<kind>/<key>/`` and counts as done only once its ``result.json`` is written
(atomically, last): an interrupted step is redone, a finished one is never redone. Results name their files relative
to the study folder, so a moved study folder still resumes. Every result records the code that made it
(``provenance``: commit, clean tree, source hash; ``core/provenance.py``), never in the key: the runner compares it
with the current code to find steps made by other code (``runner.py``). Its own module so that what reads finished
steps (the plan, the results, the pack) imports none of the code that runs them (torch, LeRobot).
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import Any

from ...core import provenance
from ...core.io import atomic_write_text
from .step import KINDS, STEPS_DIR, Step, step_folder

RESULT_FILE = "result.json"
INPUTS_FILE = "step.json"
LOG_FILE = "log.txt"
DATA_DIR = "data"
MERGED_DATA_DIR = "merged_data"  # a training step's own dataset when other tasks' data joins the task's
TRAIN_DIR = "train"
RUNS_FILE = "runs.json"  # in a training's step folder: each run of it (from which step, on which machine and dataset)
TRAINED_ON = "trained_on"  # result entry of a training: its runs, the trainings it extends first; never in a key
EXTENDS = "extends"  # result entry of a training that continues another: that one's key
CHECKPOINT = "checkpoints/last/pretrained_model"
RESULT_PATHS = ("root", "checkpoint")  # result entries that name files: stored relative to the study folder
TIMINGS = "timings"  # result entry: where the step's time went (seconds); never in a key or in results.csv
PROVENANCE = "provenance"  # result entry: the code that made the step (Provenance.to_dict()); never in a key
MACHINE = "machine"  # result entry: the CPU that made the step (core/machine.py); never in a key


def is_done(step: Step, study_dir: str | Path) -> bool:
    """Whether ``step`` has finished in ``study_dir`` (its ``result.json`` is written last)."""
    return (step.folder(study_dir) / RESULT_FILE).is_file()


def provenance_of(result: dict[str, Any]) -> provenance.Provenance | None:
    """The code that made a step's result; ``None`` for a result written before provenance was recorded."""
    data = result.get(PROVENANCE)
    return provenance.Provenance.from_dict(data) if data else None


def read_result(step_or_folder: Step | Path, study_dir: str | Path | None = None) -> dict[str, Any]:
    """A step's result, its paths (``root``, ``checkpoint``) absolute under the study folder it is in now."""
    folder = step_or_folder.folder(study_dir) if isinstance(step_or_folder, Step) else Path(step_or_folder)
    result = json.loads((folder / RESULT_FILE).read_text())
    base = folder.parents[2]  # <study>/steps/<kind>/<key>
    return {k: str(_absolute(v, base)) if k in RESULT_PATHS and v else v for k, v in result.items()}


def _absolute(value: str, study_dir: Path) -> Path:
    """A stored path made absolute: relative ones (this format) are under ``study_dir``; an absolute one
    (older results) is re-rooted there when the study folder has moved since."""
    path = Path(value)
    if not path.is_absolute():
        return study_dir / path
    if path.exists():
        return path
    parts = path.parts
    for i in range(len(parts) - 2, -1, -1):
        if parts[i] == STEPS_DIR and parts[i + 1] in KINDS:
            return study_dir.joinpath(*parts[i:])
    return path


def _portable(result: dict[str, Any], study_dir: Path) -> dict[str, Any]:
    """The result with its paths relative to the study folder (where they lie inside it)."""
    out = dict(result)
    for key in RESULT_PATHS:
        if out.get(key):
            path = Path(out[key])
            with contextlib.suppress(ValueError):
                out[key] = path.resolve().relative_to(study_dir.resolve()).as_posix()
    return out


def write_result(folder: Path, result: dict[str, Any], study_dir: Path) -> None:
    """Write ``result`` as the step's ``result.json`` (atomically: the step is done from then on), its paths
    relative to ``study_dir``."""
    atomic_write_text(folder / RESULT_FILE, json.dumps(_portable(result, study_dir), indent=1, sort_keys=True))


def dep_folder(study_dir: str, key: str) -> Path:
    """The folder of the finished step ``key`` (of whichever kind) that a step depends on."""
    for kind in KINDS:
        folder = step_folder(study_dir, kind, key)
        if (folder / RESULT_FILE).is_file():
            return folder
    raise RuntimeError(f"step {key} that this step depends on has not finished")
