"""A worker's side of a study: run the steps it is handed (:func:`run_steps`), each in its step folder, through
the table of step kinds (:data:`RUNNERS`), and record with each result where its time went, the code that made it
and the machine it ran on. The executors (``executors.py``) only hand steps to it."""

from __future__ import annotations

import contextlib
import faulthandler
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ...core import machine, provenance
from ...core.io import atomic_write_text
from ...core.memory import keep_freed_memory
from ...core.timing import Timings
from . import blocks
from .collect_step import run_collect
from .context import EXECUTIONS, running
from .eval_step import EvalSession, run_eval
from .result import (
    INPUTS_FILE,
    LOG_FILE,
    MACHINE,
    PROVENANCE,
    RESULT_FILE,
    TIMINGS,
    dep_folder,
    is_done,
    read_result,
    write_result,
)
from .step import Step
from .train_step import run_train

StepRunner = Callable[[Step, Path, list[Path]], dict[str, Any]]  # (step, its folder, its dependencies' folders)
# The step kinds (``step.KINDS``): what runs a step of each kind, given its folder and its dependencies' folders,
# and returns its result (``result.json`` without the entries :func:`run_step` adds).
RUNNERS: dict[str, StepRunner] = {"collect": run_collect, "train": run_train, "eval": run_eval}


def run_step(step_data: dict[str, Any], study_dir: str, execution: str = "per_step") -> dict[str, Any]:
    """Run one step (in a worker process or a Ray task) and return its result. Idempotent.

    ``execution`` (``EXECUTIONS``) chooses how, never what: ``grouped`` trains in this process and reuses
    a loaded policy across the conditions of its checkpoint. The result records where the time went
    (``timings``: seconds per component, ``total`` the step's own wall time) and the code that made it
    (``provenance``, read once per process, before the first step runs)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    if execution not in EXECUTIONS:
        raise ValueError(f"unknown execution {execution!r}; valid: {', '.join(EXECUTIONS)}")
    step = Step.from_dict(step_data)
    folder = step.folder(study_dir)
    if (folder / RESULT_FILE).is_file():
        return read_result(folder)
    made_by = provenance.current()
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / INPUTS_FILE, json.dumps(step.to_dict(), indent=1, sort_keys=True))
    deps = [dep_folder(study_dir, key) for key in step.deps]
    start = time.perf_counter()
    timings = Timings()
    # progress bars of collection and evaluation go to the step's log
    with running(timings, execution), _output_to(folder / LOG_FILE):
        result = RUNNERS[step.kind](step, folder, deps)
    result["seconds"] = round(time.perf_counter() - start, 2)
    timings.add("total", time.perf_counter() - start)
    result[TIMINGS] = timings.as_dict()
    result[PROVENANCE] = made_by.to_dict()
    result[MACHINE] = machine.current()
    write_result(folder, result, Path(study_dir))
    return result


def warm_up() -> float:
    """Import what steps import (torch, LeRobot's dataset, training and evaluation stacks, the simulation)
    and return the seconds it took: a ``grouped`` worker does it as soon as the pool starts, all workers at
    once, instead of each paying it in the middle of its first step (on the study's critical path)."""
    start = time.perf_counter()
    os.environ.setdefault("MUJOCO_GL", "egl")
    # Deliberately here: these are the heavy imports of a step (seconds), wanted in workers only.
    import lerobot.datasets.lerobot_dataset  # noqa: F401, PLC0415
    import lerobot.scripts.lerobot_eval  # noqa: F401, PLC0415
    import lerobot.scripts.lerobot_train  # noqa: F401, PLC0415

    from ...datasets import collect  # noqa: F401, PLC0415
    from ...envs import factor_env  # noqa: F401, PLC0415

    return time.perf_counter() - start


def run_steps(steps_data: list[dict[str, Any]], study_dir: str, execution: str = "per_step") -> dict[str, str | None]:
    """Run ``steps_data`` one after another in this process (e.g. the evaluations of one checkpoint, which
    then share the loaded policy); ``{key: None}`` for a finished step, ``{key: error}`` for a failed one
    (the others still run). Each step writes its own ``result.json`` as :func:`run_step` does. A ``grouped``
    worker (local or on Ray) keeps freed memory
    (:func:`lerobot_factorworld.core.memory.keep_freed_memory`): a training's speed then does not depend on what
    the worker ran before, and its results do not change; ``per_step`` leaves glibc's malloc as it is."""
    _report_native_crashes()
    if execution == "grouped":
        keep_freed_memory()
    out: dict[str, str | None] = {}
    steps_data = _run_sequential_groups(steps_data, study_dir, execution, out)
    for data in steps_data:
        key = Step.from_dict(data).key
        try:
            run_step(data, study_dir, execution)
            out[key] = None
        except Exception as err:  # noqa: BLE001 - reported per step by the runner, as a lone step's error
            out[key] = f"{type(err).__name__}: {err}"
    return out


def _report_native_crashes() -> None:
    """A worker killed by a native fault (MuJoCo, Mesa's rasteriser, oneDNN) leaves no Python traceback: let
    it print every thread's Python stack to the process's own stderr (a Ray worker's ``.err`` log) first."""
    if not faulthandler.is_enabled() and sys.__stderr__ is not None:
        faulthandler.enable(file=sys.__stderr__, all_threads=True)


def _run_sequential_groups(
    steps_data: list[dict[str, Any]], study_dir: str, execution: str, out: dict[str, str | None]
) -> list[dict[str, Any]]:
    """Run the ``eval.episodes=auto`` groups among ``steps_data`` (``blocks.py``), each as one unit, recording
    ``{key: None | error}`` in ``out``; the other steps, left for :func:`run_steps`."""
    steps = [Step.from_dict(d) for d in steps_data]
    groups: dict[str, list[Step]] = {}
    for step in steps:
        if blocks.is_sequential(step):
            groups.setdefault(blocks.group_id(step), []).append(step)
    for group in groups.values():
        todo = [s for s in group if not is_done(s, study_dir)]
        try:
            if todo:
                _run_group(todo, Path(study_dir), execution)
            out.update({s.key: None for s in group})
        except Exception as err:  # noqa: BLE001 - reported per step by the runner, as a lone step's error
            out.update({s.key: f"{type(err).__name__}: {err}" for s in group if not is_done(s, study_dir)})
    return [d for d, s in zip(steps_data, steps, strict=True) if not blocks.is_sequential(s)]


def _run_group(steps: list[Step], study_dir: Path, execution: str) -> None:
    """One group of sequential evaluations, in this process, each step's folder and result as :func:`run_step`'s.
    Each condition records its own timings, environment steps and wall time (what the cost model refits from):
    the group's time is the sum of its conditions', never counted once per condition."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    made_by = provenance.current()
    own = {condition: Timings() for condition in steps[0].run[blocks.GROUP]}
    wall = dict.fromkeys(own, 0.0)
    for step in steps:
        step.folder(study_dir).mkdir(parents=True, exist_ok=True)
        atomic_write_text(step.folder(study_dir) / INPUTS_FILE, json.dumps(step.to_dict(), indent=1, sort_keys=True))

    @contextlib.contextmanager
    def timed(condition: str) -> Iterator[None]:
        start = time.perf_counter()
        try:
            with running(own[condition], execution):
                yield
        finally:
            wall[condition] += time.perf_counter() - start

    def open_session(step: Step) -> EvalSession:
        deps = [dep_folder(str(study_dir), key) for key in step.deps]
        with _output_to(step.folder(study_dir) / LOG_FILE):
            return EvalSession(step, step.folder(study_dir), deps, reload=True)

    def write(step: Step, result: dict[str, Any]) -> None:
        condition = step.meta["condition"]
        result["seconds"] = round(wall[condition], 2)
        result[TIMINGS] = {**own[condition].as_dict(), "total": wall[condition]}
        result[PROVENANCE] = made_by.to_dict()
        result[MACHINE] = machine.current()
        write_result(step.folder(study_dir), result, study_dir)

    with _output_to(steps[0].folder(study_dir) / LOG_FILE):
        blocks.run_group(steps, study_dir, open_session, write, timed)


@contextlib.contextmanager
def _output_to(path: Path):
    """Send this process's stdout and stderr (Python and C level) to ``path`` for the duration."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with open(path, "a") as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
