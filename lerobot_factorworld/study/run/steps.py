"""Content-hashed study steps: collect (scripted demos), train (``lerobot-train``), eval (LeRobot's
``eval_policy_all`` on the ``factorworld`` env, as ``lerobot-eval`` does).

A step's key hashes its kind, its inputs and the keys of the steps it depends on, so a change to one
setting changes the keys of exactly the steps that depend on it. Inputs hold what changes results
(settings, the versions of the packages that compute them, the dataset format, weight files' content);
settings documented not to change results (workers, evaluation threads, where a weights file lies)
travel in ``meta["run"]`` instead; an evaluation's batch size is in its inputs when above 1. Each step works
in ``<study>/steps/<kind>/<key>/`` and counts as done only once its ``result.json`` is written (atomically,
last): an interrupted step is redone, a finished one is never redone. Results name their files relative to the study folder, so a
moved study folder still resumes. Every result records the code that made it (``provenance``:
commit, clean tree, source hash; ``core/provenance.py``), never in the key: the runner compares it with
the current code to find steps made by other code (``runner.py``).
"""

from __future__ import annotations

import contextlib
import contextvars
import faulthandler
import functools
import itertools
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import warnings
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path
from typing import Any

from ... import __version__  # the package root registers the env and policy types (in a fresh worker too)
from ...core import machine, provenance
from ...core.children import forked_children_die_with_this_process
from ...core.fingerprint import folder_fingerprint
from ...core.io import atomic_write_text
from ...core.memory import keep_freed_memory
from ...core.timing import Timings
from ...datasets.frame_cache import cached_frames
from ...datasets.merge import merge_datasets
from ...envs.stages import stage_names
from ...families import family_of
from ...protocol.conditions import fingerprint
from ...protocol.coverage import coverage
from . import blocks
from .checkpoint import GIVEN_CHECKPOINT, checkpoint_folder
from .eval_env import eval_env_config
from .inputs import MERGED_FRAMES, CollectInputs, EvalInputs, TrainInputs, whole_epochs
from .recording import MEASURES_KEY, RECORD_SETTING, RECORDED_KEY, EpisodeRecorder, write_recorded
from .step import STEPS_DIR, Step, short_hash, step_folder
from .train_state import (
    CHECKPOINTS_DIR,
    SAVES_ENV,
    Saves,
    clear_partial,
    resume_args,
    resume_point,
    saved_steps,
    saving,
    step_of,
)

KINDS = ("collect", "train", "eval")
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
DISTRIBUTION = "lerobot_env_factorworld"
TIMINGS = "timings"  # result entry: where the step's time went (seconds); never in a key or in results.csv
PROVENANCE = "provenance"  # result entry: the code that made the step (Provenance.to_dict()); never in a key
MACHINE = "machine"  # result entry: the CPU that made the step (core/machine.py); never in a key
# How steps run (never what they compute: the same step keys, results, checkpoints and datasets either way):
# ``per_step`` runs every step on its own (``lerobot-train`` as a subprocess, each evaluation loading its
# policy); ``grouped`` trains in the worker process and evaluates all conditions of a checkpoint in one task.
EXECUTIONS = ("grouped", "per_step")
VERSIONED = ("lerobot", "torch", "mujoco", "metaworld")  # packages whose version changes what a step computes


@functools.cache
def versions() -> dict[str, str]:
    """The versions in every step's key: this project's and those of the packages that compute results.

    A code change without a version bump keeps the keys (bump ``STEP_FORMAT`` or the package version when
    a change alters what a step computes); the runner still names cached steps made by other code, from
    their recorded provenance.
    """
    out = {"lerobot_factorworld": _version(DISTRIBUTION, __version__)}
    out.update({name: _version(name, "unknown") for name in VERSIONED})
    return out


def _version(distribution: str, default: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return default


def evaluated(step: Step) -> str:
    """What an evaluation step evaluates, the same for every condition of it: the key of its training step,
    or for a given checkpoint (no dependency), a hash of the checkpoint's content and its environments. The
    runner groups a checkpoint's evaluations by it, and the report pairs each condition with its ``train``."""
    if step.deps:
        return step.deps[0]
    inputs = step.inputs
    return short_hash({"checkpoint": inputs["checkpoint"], "environments": inputs["environments"]})


def is_done(step: Step, study_dir: str | Path) -> bool:
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
    deps = [_dep_folder(study_dir, key) for key in step.deps]
    start = time.perf_counter()
    timings = Timings()
    token = _CURRENT.set((timings, execution))
    try:
        with _output_to(folder / LOG_FILE):  # progress bars of collection and evaluation go to the step's log
            result = RUNNERS[step.kind](step, folder, deps)
    finally:
        _CURRENT.reset(token)
    result["seconds"] = round(time.perf_counter() - start, 2)
    timings.add("total", time.perf_counter() - start)
    result[TIMINGS] = timings.as_dict()
    result[PROVENANCE] = made_by.to_dict()
    result[MACHINE] = machine.current()
    stored = _portable(result, Path(study_dir))
    atomic_write_text(folder / RESULT_FILE, json.dumps(stored, indent=1, sort_keys=True))
    return result


# (timings, execution) of the step this process runs now: what the runners record into, and how they run
_CURRENT: contextvars.ContextVar[tuple[Timings, str]] = contextvars.ContextVar("study_step")


def _current() -> tuple[Timings, str]:
    """The running step's timings and execution (fresh ones when a runner is called on its own)."""
    return _CURRENT.get((Timings(), "per_step"))


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
        token = _CURRENT.set((own[condition], execution))
        try:
            yield
        finally:
            _CURRENT.reset(token)
            wall[condition] += time.perf_counter() - start

    def open_session(step: Step) -> EvalSession:
        deps = [_dep_folder(str(study_dir), key) for key in step.deps]
        with _output_to(step.folder(study_dir) / LOG_FILE):
            return EvalSession(step, step.folder(study_dir), deps, reload=True)

    def write(step: Step, result: dict[str, Any]) -> None:
        condition = step.meta["condition"]
        result["seconds"] = round(wall[condition], 2)
        result[TIMINGS] = {**own[condition].as_dict(), "total": wall[condition]}
        result[PROVENANCE] = made_by.to_dict()
        result[MACHINE] = machine.current()
        stored = _portable(result, study_dir)
        atomic_write_text(step.folder(study_dir) / RESULT_FILE, json.dumps(stored, indent=1, sort_keys=True))

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


def _dep_folder(study_dir: str, key: str) -> Path:
    for kind in KINDS:
        folder = step_folder(study_dir, kind, key)
        if (folder / RESULT_FILE).is_file():
            return folder
    raise RuntimeError(f"step {key} that this step depends on has not finished")


def _dep_of_kind(deps: list[Path], kind: str) -> Path:
    return next(d for d in deps if d.parent.name == kind)


# --- collect ------------------------------------------------------------------------------------


def collect_config(inputs: CollectInputs | dict[str, Any], root: Path, key: str, workers: int = 1):
    """The ``factorworld collect`` settings of a collect step."""
    # Deliberately here: the collection module imports LeRobot (about 2 s), which planning and reporting
    # never need.
    from ...datasets.collect import CollectConfig  # noqa: PLC0415

    if not isinstance(inputs, CollectInputs):
        inputs = CollectInputs.from_dict(inputs)
    sampling = inputs.sampling_options()
    return CollectConfig(
        task=inputs.task,
        factors=list(inputs.train_factors),
        n_envs=inputs.n_envs,
        demos=inputs.demos,
        seed=inputs.seed,
        cameras=inputs.cameras,
        image_size=inputs.image_size,
        action_noise=inputs.action_noise,
        max_episode_steps=inputs.max_episode_steps,
        use_videos=inputs.use_videos,
        root=str(root),
        repo_id=f"local/factorworld_{key}",
        workers=workers,
        mode="new",
        sampling=sampling,
        quality=inputs.render_quality,
    )


def _run_collect(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    timings, execution = _current()
    with timings.span("imports"):
        # Deliberately here: LeRobot's dataset code (seconds to import), only in the process that collects.
        from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

        from ...datasets.collect import SIDECAR, collect  # noqa: PLC0415

    root = folder / DATA_DIR
    cfg = collect_config(step.inputs, root, step.key, step.run.get("workers", 1))
    if (root / SIDECAR).is_file():  # merged before an interruption: nothing left to do
        meta = LeRobotDatasetMetadata(cfg.repo_id, root=root)
        return {
            "root": str(root),
            "repo_id": cfg.repo_id,
            "episodes": meta.total_episodes,
            "frames": meta.total_frames,
            "failures": {},
        }
    report = collect(cfg)
    timings.update(report.timings)
    return {
        "root": str(root),
        "repo_id": cfg.repo_id,
        "episodes": report.episodes,
        "frames": report.frames,
        "failures": report.failures,
    }


# --- train --------------------------------------------------------------------------------------


def policy_args(policy: dict[str, Any], prefix: str = "--policy") -> list[str]:
    """``{type: bc, augmentation: shift}`` -> ``["--policy.type=bc", "--policy.augmentation=shift"]``."""
    args = []
    for name, value in policy.items():
        if isinstance(value, dict):
            args += policy_args(value, f"{prefix}.{name}")
        else:
            text = json.dumps(value) if isinstance(value, (list, bool)) or value is None else str(value)
            args.append(f"{prefix}.{name}={text}")
    return args


def train_steps(inputs: TrainInputs, frames: int) -> int:
    """Gradient steps: ``steps``, or ``ceil(epochs * frames / batch_size)`` when ``epochs`` is set."""
    if inputs.epochs is None:
        return int(inputs.steps)
    return max(1, math.ceil(inputs.epochs * frames / inputs.batch_size))


def epoch_frames(inputs: TrainInputs, frames: list[int]) -> int:
    """The frames an epoch counts, from each dataset's (the task's own first): its own (``epochs_over`` unset:
    other tasks' data changes the mix, not the steps), or all of them (``merged``)."""
    return sum(frames) if inputs.epochs_over == MERGED_FRAMES else frames[0]


def curve_saves(inputs: TrainInputs, frames: int, steps: int) -> dict[str, int]:
    """The learning curve's checkpoints before the last, ``{nominal epochs: gradient step}``: LeRobot saves every
    ``save_freq`` steps, so checkpoint ``j`` is at ``j * ceil(curve_every * frames / batch_size)`` steps, at most a
    batch past ``j * curve_every`` epochs (``curve.csv`` states its steps and exact epochs)."""
    if not inputs.curve_every:
        return {}
    every = max(1, math.ceil(inputs.curve_every * frames / inputs.batch_size))
    saves = {}
    for j in itertools.count(1):
        if j * every >= steps or j * inputs.curve_every >= inputs.epochs:
            return saves
        epochs = j * inputs.curve_every
        saves[str(whole_epochs(epochs))] = j * every


def curve_checkpoint(train_folder: Path, saved_at: int) -> Path:
    """The checkpoint LeRobot saved at gradient step ``saved_at`` (its folder is the zero-padded step)."""
    for folder in (train_folder / TRAIN_DIR / "checkpoints").iterdir():
        if folder.name.isdigit() and int(folder.name) == saved_at:
            return folder / "pretrained_model"
    raise FileNotFoundError(f"no checkpoint of step {saved_at} in {train_folder / TRAIN_DIR / 'checkpoints'}")


def _run_train(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    timings, execution = _current()
    datasets = [read_result(d) for d in deps if d.parent.name == "collect"]  # the task's own first
    prefix = next((d / TRAIN_DIR for d in deps if d.parent.name == "train"), None)  # the training it extends
    data = datasets[0]
    inputs = TrainInputs.from_dict(step.inputs)
    require_device("train.device", inputs.device)
    policy = step.run.get("policy", inputs.policy)  # absolute paths; the key holds their content hashes
    extra_args = step.run.get("extra_args", list(inputs.extra_args))
    frames = epoch_frames(inputs, [d["frames"] for d in datasets])
    steps = train_steps(inputs, frames)
    curve = curve_saves(inputs, frames, steps)
    if len(datasets) > 1:
        with timings.span("merge"):
            data = _merged_training_data(datasets, folder, step.key)
    loaders = step.run.get("loader_workers", 0)
    if loaders and stores_video(Path(data["root"])):  # a lent loader reads PNG frames only (loader_args)
        loaders = 0
    out = folder / TRAIN_DIR
    save_freq = min(curve.values(), default=steps)  # the curve's first checkpoint; then every as many
    saves = Saves(steps, save_freq, str(out), inputs.batch_size, every_passes=step.run.get("save_every_passes", 1))
    state, continues_own = _starting_state(out, prefix, saves, curve)
    start_step = step_of(state) if state is not None else 0
    if start_step < steps:
        runs = _record_run(folder, start_step, Path(data["root"]), continues_own)
    else:
        runs = _recorded_runs(folder)
    cmd = [
        sys.executable,
        "-m",
        "lerobot_factorworld.study.run.train_process",
        *policy_args(policy),
        f"--policy.device={inputs.device}",
        "--policy.push_to_hub=false",
        f"--dataset.repo_id={data['repo_id']}",
        f"--dataset.root={data['root']}",
        f"--steps={steps}",
        f"--batch_size={inputs.batch_size}",
        f"--seed={inputs.seed}",
        *loader_args(loaders),
        f"--save_freq={save_freq}",
        f"--log_freq={max(1, steps // 10)}",
        "--wandb.enable=false",
        f"--output_dir={out}",
        *extra_args,
        *(resume_args(state) if state is not None else []),
    ]
    start = time.perf_counter()
    log_start = (folder / LOG_FILE).stat().st_size if (folder / LOG_FILE).is_file() else 0
    if start_step < steps:
        if execution == "grouped":
            _train_in_process(cmd[3:], folder, inputs.threads, timings, saves)
        else:
            _train_subprocess(cmd, folder, inputs.threads, saves)
    _point_last_at(out, steps)
    with open(folder / LOG_FILE, "rb") as log:
        log.seek(log_start)
        logged = train_log_seconds(log.read().decode(errors="replace"), steps - start_step)
    timings.update(logged)
    # what is left: process start and imports (subprocess), dataset and policy set-up, checkpoint saving
    timings.add("startup_save", time.perf_counter() - start - sum(logged.values()) - timings.seconds.get("imports", 0))
    result = {"checkpoint": str(out / CHECKPOINT), "steps": steps}
    own = {epochs: at for epochs, at in curve.items() if inputs.extends is None or float(epochs) > inputs.extends}
    if own:  # an extension's points up to the prefix's end are the prefix's (their evaluations depend on it)
        result["curve"] = own
    if start_step:  # trained from this saved step on: after a kill, or from the training it extends
        result["resumed_from"] = start_step
    if prefix is not None:
        result[EXTENDS] = prefix.parent.name
    prefix_runs = read_result(prefix.parent).get(TRAINED_ON, []) if prefix is not None else []
    result[TRAINED_ON] = [run for run in prefix_runs if run["from_step"] < (runs[0]["from_step"] if runs else 0)] + runs
    return result


def _recorded_runs(folder: Path) -> list[dict[str, Any]]:
    path = folder / RUNS_FILE
    return json.loads(path.read_text()) if path.is_file() else []


def _record_run(folder: Path, start_step: int, dataset: Path, continues_own: bool) -> list[dict[str, Any]]:
    """Record that the training in the step ``folder`` runs from ``start_step`` here (``runs.json``): the machine
    and the dataset's content hash. A training resumed on another machine, or on a dataset collected again there,
    is then told apart from one that ran in one go. Its earlier runs are kept only where it continues its own
    state (not after it started over, or from the training it extends), and only those before ``start_step``: a
    run that saved nothing before it was stopped left no mark on the weights."""
    earlier = _recorded_runs(folder) if continues_own else []
    runs = [run for run in earlier if run["from_step"] < start_step]
    runs.append({"from_step": start_step, "machine": machine.current(), "dataset": folder_fingerprint(dataset)})
    atomic_write_text(folder / RUNS_FILE, json.dumps(runs, indent=1, sort_keys=True))
    return runs


def _starting_state(out: Path, prefix: Path | None, saves: Saves, curve: dict[str, int]) -> tuple[Path | None, bool]:
    """The saved state a training continues from, and whether it is its own: its own newest (a rerun after a kill),
    else the newest of the training it extends; ``None``: from scratch, in an emptied folder. A prefix's state that
    is one of this training's own checkpoints (a curve point or its last at a pass's end) is copied in, as it would
    have saved it."""
    clear_partial(out)
    own = resume_point(out, saves)
    theirs = resume_point(prefix, saves) if prefix is not None else None
    if own is not None and (theirs is None or step_of(own) >= step_of(theirs)):
        return own, True
    if out.exists():  # nothing of its own to continue from: LeRobot refuses an existing output_dir, start over
        shutil.rmtree(out)
    if theirs is not None and (step_of(theirs) in curve.values() or step_of(theirs) == saves.steps):
        shutil.copytree(theirs, out / CHECKPOINTS_DIR / theirs.name, symlinks=True)
        return out / CHECKPOINTS_DIR / theirs.name, False
    return theirs, False


def _point_last_at(out: Path, steps: int) -> Path:
    """``checkpoints/last`` pointed at the training's last save (a kill may have come between the save and LeRobot's
    pointing): the folder it names."""
    final = saved_steps(out).get(steps)
    if final is None:
        raise RuntimeError(f"lerobot-train finished without a checkpoint of step {steps} in {out / CHECKPOINTS_DIR}")
    last = out / CHECKPOINTS_DIR / "last"
    if last.is_symlink() or last.exists():
        if last.resolve() == final.resolve():
            return last
        last.unlink()
    last.symlink_to(final.name)
    return last


def loader_args(workers: int) -> list[str]:
    """``lerobot-train``'s data-loading flags for ``workers`` loader processes (0: in the training process).
    With workers, each epoch forks fresh ones (not persistent): LeRobot's training then draws from torch's global
    RNG exactly as with loading in process (a data loader iterator draws its base seed when it is created, and
    persistent workers create it once), so the checkpoint is byte-identical, augmentation included; ``fork``,
    since a spawned loader would first import LeRobot for seconds every epoch. Only for PNG frames
    (:func:`stores_video`): LeRobot warns that its video decoders are not safe to fork."""
    if workers < 1:
        return ["--num_workers=0"]
    return [f"--num_workers={workers}", "--persistent_workers=false", "--dataloader_multiprocessing_context=fork"]


def stores_video(root: Path) -> bool:
    """Whether the LeRobotDataset at ``root`` stores any camera as video (``meta/info.json``)."""
    features = json.loads((root / "meta" / "info.json").read_text())["features"]
    return any(feature["dtype"] == "video" for feature in features.values())


def _merged_training_data(datasets: list[dict[str, Any]], folder: Path, key: str) -> dict[str, Any]:
    """The task's dataset and the extra tasks' merged into ``<step>/merged_data`` (reused once complete)."""
    root, repo_id = folder / MERGED_DATA_DIR, f"local/factorworld_{key}_merged"
    frames = merge_datasets([(d["repo_id"], Path(d["root"])) for d in datasets], repo_id, root)
    return {"repo_id": repo_id, "root": str(root), "frames": frames}


def _train_subprocess(cmd: list[str], folder: Path, threads: int, saves: Saves) -> None:
    """``lerobot-train`` in a new Python process (the ``per_step`` execution), saving as ``saves`` say."""
    n = str(threads)
    env = {**os.environ, "OMP_NUM_THREADS": n, "MKL_NUM_THREADS": n, "TOKENIZERS_PARALLELISM": "false"}
    env[SAVES_ENV] = saves.to_json()
    with open(folder / LOG_FILE, "a") as log:
        log.write(" ".join(cmd) + "\n")
        log.flush()
        proc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=folder)
    if proc.returncode != 0:
        tail = (folder / LOG_FILE).read_text()[-2000:]
        raise RuntimeError(f"lerobot-train failed (exit {proc.returncode}); log {folder / LOG_FILE}:\n{tail}")


def _train_in_process(args: list[str], folder: Path, threads: int, timings: Timings, saves: Saves) -> None:
    """``lerobot-train`` with ``args`` in this (persistent worker) process, saving as ``saves`` say: no interpreter
    start and no imports per run, PNG frames decoded once (``datasets/frame_cache.py``: the loader then needs a
    fraction of a core), and a checkpoint byte-identical to the subprocess's (``scripts/bench_study.py`` checks)."""
    with timings.span("imports"):
        from lerobot.scripts import lerobot_train  # noqa: PLC0415 - LeRobot's training stack (seconds, once)

    print("lerobot-train (in process) " + " ".join(args), flush=True)
    forked_children_die_with_this_process()  # a killed worker's loaders must not keep its Ray connection open
    try:
        with (
            as_lerobot_process("lerobot-train", args, folder, threads),
            saving(saves),
            cached_frames(),
            warnings.catch_warnings(),
        ):
            # A lent loader (loader_args) forks this worker, whose renderer and arrow threads sit idle meanwhile:
            # its children only read PNG frames from parquet, so Python's warning about forking with threads is
            # noise here.
            warnings.filterwarnings("ignore", r"This process .* is multi-threaded, use of fork\(\)", DeprecationWarning)
            lerobot_train.main()
    except SystemExit as err:  # draccus exits on a bad flag
        raise RuntimeError(f"lerobot-train failed (exit {err.code}); log {folder / LOG_FILE}") from None


@contextlib.contextmanager
def as_lerobot_process(command: str, args: list[str], cwd: Path, threads: int) -> Iterator[None]:
    """Run a LeRobot console script's ``main()`` (``lerobot-train``, ``lerobot-eval``) in this process as a new
    process would run it: everything such a process fixes at its start is fixed here (the command line
    LeRobot parses, the working directory, torch's threads, ``TOKENIZERS_PARALLELISM``; the scripts seed every
    RNG themselves), restored afterwards, and accelerate's process-wide state forgotten."""
    import torch  # noqa: PLC0415 - deliberately here: only a training (or evaluating) worker needs torch

    saved = (list(sys.argv), os.getcwd(), torch.get_num_threads(), os.environ.get("TOKENIZERS_PARALLELISM"))
    sys.argv = [command, *args]
    os.environ["TOKENIZERS_PARALLELISM"] = "false"
    torch.set_num_threads(threads)
    os.chdir(cwd)
    try:
        yield
    finally:
        sys.argv, previous_cwd, n, tokenizers = saved
        os.chdir(previous_cwd)
        torch.set_num_threads(n)
        if tokenizers is None:
            os.environ.pop("TOKENIZERS_PARALLELISM", None)
        else:
            os.environ["TOKENIZERS_PARALLELISM"] = tokenizers
        _reset_accelerate()


def _reset_accelerate() -> None:
    """Forget accelerate's process-wide state, so that the next in-process run starts as a new process would."""
    from accelerate.state import AcceleratorState, GradientState, PartialState  # noqa: PLC0415 - with lerobot-train only

    for state in (AcceleratorState, GradientState, PartialState):
        state._reset_state()


_TRAIN_LOG = re.compile(r"updt_s:([0-9.]+).*?data_s:([0-9.]+)")


def train_log_seconds(log: str, steps: int) -> dict[str, float]:
    """``{"update": s, "data": s}`` of a ``lerobot-train`` log: the mean of its logged per-step averages
    (``updt_s``, ``data_s``) times the steps run; ``{}`` when it logged none."""
    found = [(float(u), float(d)) for u, d in _TRAIN_LOG.findall(log)]
    if not found:
        return {}
    return {
        "update": steps * sum(u for u, _ in found) / len(found),
        "data": steps * sum(d for _, d in found) / len(found),
    }


# --- eval ---------------------------------------------------------------------------------------


def _run_eval(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    session = EvalSession(step, folder, deps)
    inputs = session.inputs
    successes = session.episodes(inputs.start_seed, inputs.episodes)
    return session.result(successes, [inputs.start_seed + i for i in range(len(successes))])


class EvalSession:
    """One condition of one checkpoint, ready to run episodes: its environments, policy and records. A plain
    evaluation runs its episodes once; ``eval.episodes=auto`` (``blocks.py``) runs them block by block."""

    def __init__(self, step: Step, folder: Path, deps: list[Path], reload: bool = False) -> None:
        timings, execution = _current()
        with timings.span("imports"):  # paid once per worker process: later steps find them imported
            # Deliberately here: torch and LeRobot's evaluation stack (seconds to import), only in the process
            # that evaluates (planning never needs them).
            import torch  # noqa: PLC0415
            from lerobot.envs.factory import make_env, make_env_pre_post_processors  # noqa: PLC0415

        inputs, run = EvalInputs.from_dict(step.inputs), step.run
        torch.set_num_threads(run.get("threads", 1))
        if inputs.checkpoint is not None:  # a given checkpoint, unchanged since it was planned, in its environments
            checkpoint = str(checkpoint_folder(run[GIVEN_CHECKPOINT], inputs.checkpoint))
            env_cfg = eval_env_config(inputs.environments, None, inputs)
        else:  # trained on a dataset, whose own environments are the training condition
            collect_folder = _dep_of_kind(deps, "collect")
            collect_inputs = CollectInputs.from_dict(json.loads((collect_folder / INPUTS_FILE).read_text())["inputs"])
            train_folder = _dep_of_kind(deps, "train")
            trained = read_result(train_folder)
            checkpoint = trained["checkpoint"]
            if inputs.checkpoint_epochs is not None:  # a learning curve's earlier checkpoint
                saved_at = trained.get("curve", {}).get(str(inputs.checkpoint_epochs))
                if saved_at is None:
                    raise RuntimeError(
                        f"the training saved no checkpoint at {inputs.checkpoint_epochs} epochs ({train_folder})"
                    )
                checkpoint = str(curve_checkpoint(train_folder, saved_at))
            env_cfg = eval_env_config(collect_inputs, read_result(collect_folder)["root"], inputs)
        self.inputs, self.folder, self.timings, self.env_cfg = inputs, folder, timings, env_cfg
        self.checkpoint, self.task = checkpoint, env_cfg.task_names[0]
        self.configs = env_cfg.suites(self.task)[inputs.condition]
        # reload: every block starts from the RNG state a fresh load leaves (blocks.py), so a block's outcomes
        # depend on its seeds only; a plain evaluation loads once, cached across a grouped worker's conditions
        self.cached = reload or execution == "grouped"
        self.reload = reload
        self._load()
        with timings.span("env_build"):
            self.env_pre, self.env_post = make_env_pre_post_processors(env_cfg=env_cfg, policy_cfg=self.policy_cfg)
            self.envs = make_env(env_cfg, n_envs=inputs.batch_size or 1, use_async_envs=False)
        # Stages, lengths and the first episodes' frames, from the envs' own observer hook (instances only).
        recorded = range(inputs.start_seed, inputs.start_seed + min(run.get(RECORD_SETTING, 0), inputs.episodes))
        self.recorder = EpisodeRecorder(frozenset(recorded), family_of(self.task).episode_measures)

    def _load(self) -> None:
        with self.timings.span("policy_load"):
            self.policy_cfg, self.policy, self.preprocessor, self.postprocessor = _load_policy(
                self.checkpoint, self.env_cfg, self.inputs.device, self.inputs.start_seed, cached=self.cached
            )

    def episodes(self, start_seed: int, n: int) -> list[bool]:
        """Run ``n`` episodes reset with seeds ``start_seed`` on (LeRobot's ``eval_policy_all``); their successes."""
        import torch  # noqa: PLC0415 - imported by __init__ already (seconds the first time)
        from lerobot.scripts.lerobot_eval import eval_policy_all  # noqa: PLC0415 - LeRobot's evaluation stack

        if self.reload:
            self._load()
        timings = self.timings
        # timed, unchanged (each part exclusive of the parts inside it): scene compilation and rendering, the
        # environments' resets and steps (on these env instances), the policy's actions, the rest of LeRobot's rollout
        with contextlib.ExitStack() as stack:
            for env in _factorworld_envs(self.envs):
                env.episode_observer = self.recorder  # stages, lengths and the first episodes' frames
                env.timer = timings.span  # scene compilation and rendering, from the env's own hook
                stack.enter_context(timings.wrap(env, "reset", "env_reset"))
                stack.enter_context(timings.wrap(env, "step", "env_step"))
            stack.enter_context(timings.wrap(self.policy, "select_action", "policy"))
            stack.enter_context(timings.span("rollout_other"))
            stack.enter_context(torch.no_grad())
            info = eval_policy_all(
                self.envs,
                self.policy,
                self.env_pre,
                self.env_post,
                self.preprocessor,
                self.postprocessor,
                n_episodes=n,
                max_episodes_rendered=0,
                start_seed=start_seed,
            )
        return [bool(s) for s in info["per_task"][0]["metrics"]["successes"]]

    def result(
        self,
        successes: list[bool],
        seeds: list[int],
        stages: list[str] | None = None,
        lengths: list[int] | None = None,
        tracked: list[str] | None = None,
        measures: list[dict[str, float]] | None = None,
    ) -> dict[str, Any]:
        """The step's result for these episodes (``stages``, ``lengths`` and the stages ``tracked``: blocks', read
        back from their cache; else this run's, which tracks the task's stages of now)."""
        with self.timings.span("records"):
            recorder, configs, folder = self.recorder, self.configs, self.folder
            cover = coverage(seeds, len(configs))
            width = self.env_cfg.sampling.widths.get("object_pos")
            result = {
                "env_steps": self.timings.calls.get("env_step", 0),  # the cost model's unit (not a result)
                "condition": self.inputs.condition,
                "successes": successes,
                "seeds": seeds,
                "stages": stages or of_seeds(recorder.stages, seeds),  # the furthest stage of every episode
                "stage_names": tracked or list(stage_names(self.task)),  # the stages that were tracked
                "lengths": lengths or of_seeds(recorder.lengths, seeds),  # steps of every episode
                "n_envs": len(configs),
                "envs_visited": cover.visited,
                "equal_visits": cover.equal,
                "fingerprint": fingerprint(configs, width),
                "checkpoint": self.checkpoint,
                "policy_type": self.policy_cfg.type,  # a given checkpoint's type is known from it only
            }
            if recorder.measure_keys:  # the family's per-episode measures (e.g. how close the gripper came)
                result[MEASURES_KEY] = measures if measures is not None else of_seeds(recorder.measures, seeds)
            if recorder.frames:  # the recorded episodes' frames as videos (not results: they change no number)
                result[RECORDED_KEY] = write_recorded(recorder, seeds, folder)
            family = family_of(self.task)
            if family.content_key:  # what every episode asked for (e.g. instruction, named object), for breakdowns
                result[family.content_key] = family.episode_records(configs, seeds, width)
        return result


def _factorworld_envs(envs: dict) -> Iterator[Any]:
    """The Factor World envs of LeRobot's ``{suite: {task_id: vector env}}`` (synchronous, in this process)."""
    for suite in envs.values():
        for vector_env in suite.values():
            for env in vector_env.envs:
                yield env.unwrapped


def of_seeds[T](recorded: dict[int, T], seeds: list[int]) -> list[T]:
    """What was recorded for the episodes reset with ``seeds``, in their order; every one must have ended."""
    missing = [seed for seed in seeds if seed not in recorded]
    if missing:
        raise RuntimeError(f"nothing recorded at the end of the episode(s) of seed(s) {missing}: they never ended")
    return [recorded[seed] for seed in seeds]


# The policy loaded by the last evaluation of this (``grouped``) worker, with the RNG state right after
# loading it: the next condition of the same checkpoint starts from exactly that state.
_LOADED: dict[tuple, tuple] = {}


def _load_policy(checkpoint: str, env_cfg, device: str, start_seed: int, cached: bool) -> tuple:
    """(policy config, policy, preprocessor, postprocessor) of ``checkpoint``, seeded with ``start_seed`` before loading
    as ``lerobot-eval`` does. ``cached``: reuse the one this process loaded last for the same checkpoint,
    device and seed, with the RNG state restored to what it was right after loading (what a fresh load
    would leave), so every condition computes what it computes on its own."""
    # Deliberately here: LeRobot's policy stack (seconds to import), only in the process that evaluates.
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415
    from lerobot.policies.factory import make_policy, make_pre_post_processors  # noqa: PLC0415
    from lerobot.utils.import_utils import register_third_party_plugins  # noqa: PLC0415
    from lerobot.utils.random_utils import get_rng_state, set_rng_state, set_seed  # noqa: PLC0415

    key = (checkpoint, device, start_seed, _mtime(checkpoint))
    if cached and key in _LOADED:
        *loaded, state = _LOADED[key]
        set_rng_state(state)
        return tuple(loaded)
    _LOADED.clear()
    register_third_party_plugins()  # as lerobot-eval does: Factor World's env and policy types, and any other plugin
    policy_cfg = PreTrainedConfig.from_pretrained(checkpoint)
    policy_cfg.pretrained_path = Path(checkpoint)
    policy_cfg.device = require_device("eval.device", device)
    set_seed(start_seed)
    policy = make_policy(cfg=policy_cfg, env_cfg=env_cfg)
    preprocessor, postprocessor = make_pre_post_processors(
        policy_cfg=policy_cfg,
        pretrained_path=checkpoint,
        preprocessor_overrides={"device_processor": {"device": str(policy_cfg.device)}},
    )
    if cached:
        _LOADED[key] = (policy_cfg, policy, preprocessor, postprocessor, get_rng_state())
    return policy_cfg, policy, preprocessor, postprocessor


def _mtime(path: str) -> int:
    weights = Path(path) / "model.safetensors"
    return weights.stat().st_mtime_ns if weights.is_file() else 0


def device_problem(setting: str, device: str, cuda_count: int, mps: bool) -> str | None:
    """Why ``device`` (the value of ``setting``: ``train.device`` or ``eval.device``) cannot run on a machine with
    ``cuda_count`` CUDA devices and MPS or not; ``None`` where it can."""
    if device.startswith("cuda") and int(device.partition(":")[2] or 0) >= cuda_count:
        return f"{setting}={device} but this machine has {cuda_count} CUDA device(s); use --{setting}=cpu"
    if device == "mps" and not mps:
        return f"{setting}=mps but this machine has no MPS device; use --{setting}=cpu"
    return None


def machine_devices() -> tuple[int, bool]:
    """This machine's CUDA devices and whether it has MPS. Asking CUDA keeps this process from forking workers
    that use it: only a process that runs on the device, or a child Python, should ask."""
    import torch  # noqa: PLC0415 - deliberately here: only a training or evaluating process needs torch (seconds)

    return torch.cuda.device_count(), torch.backends.mps.is_available()


def require_device(setting: str, device: str) -> str:
    """``device``, refused when this process cannot use it, rather than run elsewhere: LeRobot's configs quietly
    fall back to the CPU."""
    if device == "cpu":
        return device
    problem = device_problem(setting, device, *machine_devices())
    if problem:
        raise RuntimeError(problem)
    return device


RUNNERS = {"collect": _run_collect, "train": _run_train, "eval": _run_eval}
