"""The ``train`` step: ``lerobot-train`` on the step's dataset (the task's own, merged with other tasks' where the
method asks), resumed from its newest save after a kill, or continued from the training it extends; its result
names the last checkpoint, the learning curve's and the runs it took (``runs.json``)."""

from __future__ import annotations

import json
import re
import shutil
import sys
import time
from pathlib import Path
from typing import Any

from ...core import machine
from ...core.fingerprint import folder_fingerprint
from ...core.io import atomic_write_text
from ...datasets.merge import merge_datasets
from .context import current
from .device import require_device
from .inputs import TrainInputs
from .lerobot_process import train_in_process, train_subprocess
from .result import (
    CHECKPOINT,
    EXTENDS,
    LOG_FILE,
    MERGED_DATA_DIR,
    RUNS_FILE,
    TRAIN_DIR,
    TRAINED_ON,
    read_result,
)
from .step import Step
from .train_schedule import curve_saves, epoch_frames, train_steps
from .train_state import CHECKPOINTS_DIR, Saves, clear_partial, resume_args, resume_point, saved_steps, step_of


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


def run_train(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    """Train ``step`` in ``folder`` on its collections in ``deps`` (``worker.RUNNERS``), from its newest save or the
    training it extends; its result names the last checkpoint and the curve's."""
    timings, execution = current()
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
            train_in_process(cmd[3:], folder, inputs.threads, timings, saves)
        else:
            train_subprocess(cmd, folder, inputs.threads, saves)
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
