"""A training that survives a kill and grows: ``lerobot-train`` also saves its whole state (weights, optimizer,
scheduler, RNG, step) at the end of every pass of its sampler, and a rerun, or a longer training that extends it,
resumes from the last such state with LeRobot's own ``--resume``.

Why at the end of a pass: LeRobot 0.6.1's sampler shuffles each pass from (seed, pass), and ``--resume`` restores
the RNG and the position in the order; but the resumed run makes a new data-loader iterator, which draws one number
from torch's RNG, where the uninterrupted run makes one only at the start of a pass. Resumed at a pass's start, both
runs draw it at the same point, so the resumed run's checkpoints equal the uninterrupted run's byte for byte
(``tests/test_train_resume.py``). A pass is ``ceil(frames / batch_size)`` gradient steps (the last batch short), a
nominal epoch ``frames / batch_size``: they differ by under one step per epoch.

The saves change nothing LeRobot computes (saving reads the state, draws nothing) and keep the flags it records:
``--save_freq`` stays the learning curve's (what ``train_config.json`` holds), and only this process's choice of
when to save is widened (:func:`saving`). Each save is written beside its folder and renamed into place, so a kill
mid-save leaves the last complete state; an older state that is neither LeRobot's own checkpoint (the curve's, the
last) nor the newest pass-end one is deleted after the next is in place.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from ...core.io import atomic_write_text

CHECKPOINTS_DIR = "checkpoints"
PRETRAINED_DIR = "pretrained_model"
STATE_DIR = "training_state"
TRAIN_CONFIG = "train_config.json"
PARTIAL = ".partial-"  # a save being written (renamed to <step> once complete) or deleted (renamed from it first)
# What a complete save holds (LeRobot writes them in this order; a scheduler's state only when there is one).
COMPLETE = (
    f"{PRETRAINED_DIR}/model.safetensors",
    f"{PRETRAINED_DIR}/{TRAIN_CONFIG}",
    f"{STATE_DIR}/training_step.json",
    f"{STATE_DIR}/rng_state.safetensors",
    f"{STATE_DIR}/optimizer_state.safetensors",
)
SAVES_ENV = "FACTORWORLD_TRAIN_SAVES"  # the Saves of a lerobot-train subprocess (train_process.py), as JSON
# Written by the training as its sampler is made: the steps of one pass, which only the sampler knows (a policy may
# drop frames at episode ends). A training folder without it (older code) is never resumed from.
SAMPLER_FILE = "sampler.json"


def pass_steps(frames: int, batch_size: int) -> int:
    """Gradient steps of one pass of LeRobot's sampler over ``frames`` positions (one process: the last batch short)."""
    return math.ceil(frames / batch_size)


@dataclass(frozen=True)
class Saves:
    """When a training of ``steps`` saves: LeRobot's own checkpoints (every ``save_freq`` steps and the last) and the
    end of every ``every_passes`` passes of ``pass_steps`` steps (the states a rerun resumes from; ``None`` until
    the sampler is made)."""

    steps: int
    save_freq: int
    train_dir: str
    batch_size: int
    pass_steps: int | None = None
    every_passes: int = 1

    def own(self, step: int) -> bool:
        """A checkpoint LeRobot saves by itself (the learning curve's, the last): kept."""
        return step % self.save_freq == 0 or step == self.steps

    def pass_end(self, step: int) -> bool:
        """A state a resumed run continues exactly from: the end of a pass (any, not only every ``every_passes``)."""
        return bool(self.pass_steps) and step > 0 and step % self.pass_steps == 0

    def saves(self, step: int) -> bool:
        return self.own(step) or (self.pass_end(step) and (step // self.pass_steps) % self.every_passes == 0)

    def resumable(self, step: int) -> bool:
        """A saved state a rerun may continue from: a pass's end, or the last step (nothing left to train)."""
        return 0 < step <= self.steps and (self.pass_end(step) or step == self.steps)

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> Saves:
        return cls(**json.loads(text))


def saved_steps(train_dir: Path) -> dict[int, Path]:
    """``{step: folder}`` of the complete saves under ``<train_dir>/checkpoints`` (a kill mid-save of older code
    may have left an incomplete one: it is not counted)."""
    folder = Path(train_dir) / CHECKPOINTS_DIR
    if not folder.is_dir():
        return {}
    return {
        int(d.name): d
        for d in folder.iterdir()
        if d.name.isdigit() and not d.is_symlink() and all((d / name).is_file() for name in COMPLETE)
    }


def recorded_pass_steps(train_dir: Path) -> int | None:
    """The steps of one pass that the training in ``train_dir`` recorded (``None``: older code, recorded none)."""
    path = Path(train_dir) / SAMPLER_FILE
    return json.loads(path.read_text())["pass_steps"] if path.is_file() else None


def resume_point(train_dir: Path, saves: Saves) -> Path | None:
    """The newest complete save under ``train_dir`` (this training's, or the shorter one it extends) that a training
    with ``saves`` continues exactly from: a pass's end, by the pass that training recorded, or ``saves``'s last
    step, made with the same batch size; ``None`` when there is none."""
    passes = recorded_pass_steps(train_dir)
    if passes is None:
        return None
    saves = replace(saves, pass_steps=passes)
    found = saved_steps(train_dir)
    usable = [
        s for s, folder in found.items() if saves.resumable(s) and _batch_size(folder) in (None, saves.batch_size)
    ]
    return found[max(usable)] if usable else None


def _batch_size(folder: Path) -> int | None:
    return json.loads((folder / STATE_DIR / "training_step.json").read_text()).get("batch_size")


def step_of(folder: Path) -> int:
    """The gradient step a save was made at (its folder's name)."""
    return int(folder.name)


def resume_args(folder: Path) -> list[str]:
    """``lerobot-train`` flags that continue from the save in ``folder`` (the other flags are passed as for a fresh
    run and override those of its ``train_config.json``)."""
    return ["--resume=true", f"--config_path={folder / PRETRAINED_DIR / TRAIN_CONFIG}"]


def clear_partial(train_dir: Path) -> None:
    """Remove the saves a kill left half written (``.partial-<step>``): the complete ones stay."""
    folder = Path(train_dir) / CHECKPOINTS_DIR
    if folder.is_dir():
        for d in folder.iterdir():
            if d.name.startswith(PARTIAL):
                shutil.rmtree(d)


PATCHED = ("EpisodeAwareSampler", "should_save_checkpoint", "save_checkpoint", "update_last_checkpoint")


@contextlib.contextmanager
def saving(saves: Saves) -> Iterator[None]:
    """While ``lerobot-train`` runs in this process: record the steps of one pass of its sampler (``sampler.json``),
    save at ``saves.saves`` steps, each save written whole before it takes its name, recorded as a fresh run records
    it (a resumed run's ``train_config.json`` would say ``resume: true`` and name the state it resumed from; its
    policy config the folder it loaded), and delete older pass-end states once a newer one is in place
    (:func:`prune`)."""
    from lerobot.scripts import lerobot_train  # noqa: PLC0415 - LeRobot's training stack, only where a training runs

    originals = {name: getattr(lerobot_train, name) for name in PATCHED}
    save, update_last = originals["save_checkpoint"], originals["update_last_checkpoint"]
    current = [saves]  # with the pass's steps once the sampler is made

    class RecordingSampler(originals["EpisodeAwareSampler"]):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            current[0] = replace(saves, pass_steps=pass_steps(len(self), saves.batch_size))
            record = {"pass_steps": current[0].pass_steps, "positions": len(self), "batch_size": saves.batch_size}
            atomic_write_text(Path(saves.train_dir) / SAMPLER_FILE, json.dumps(record, sort_keys=True))

        def set_epoch(self, epoch: int) -> None:
            """Ignored: the sampler counts its passes itself (each ``__iter__``), as LeRobot's training loop means it
            to. Accelerate's data loader sets the pass to its own count of passes made in this process, which is
            the same number in a run from scratch but 0 in a resumed one: LeRobot 0.6.1's ``--resume`` would then
            restart the order at pass 0 (at the saved offset) instead of the saved pass."""

    def should_save(step: int, save_freq: int, total_steps: int) -> bool:
        return current[0].saves(step)

    def save_whole(checkpoint_dir: Path, step: int, cfg: Any, **kwargs: Any) -> None:
        _save_atomically(save, Path(checkpoint_dir), step, cfg, kwargs)

    def update_and_prune(checkpoint_dir: Path) -> Path:
        out = update_last(checkpoint_dir)
        prune(Path(checkpoint_dir).parent, step_of(Path(checkpoint_dir)), current[0])
        return out

    patched = {
        "EpisodeAwareSampler": RecordingSampler,
        "should_save_checkpoint": should_save,
        "save_checkpoint": save_whole,
        "update_last_checkpoint": update_and_prune,
    }
    for name, value in patched.items():
        setattr(lerobot_train, name, value)
    try:
        yield
    finally:
        for name, value in originals.items():
            setattr(lerobot_train, name, value)


def _save_atomically(save: Callable[..., None], checkpoint_dir: Path, step: int, cfg: Any, kwargs: dict) -> None:
    """LeRobot's ``save_checkpoint`` into ``.partial-<step>``, then renamed to ``<step>`` (replacing a save of the
    same step a resumed run makes again), with the config as a fresh run holds it."""
    partial = checkpoint_dir.parent / f"{PARTIAL}{checkpoint_dir.name}"
    if partial.exists():
        shutil.rmtree(partial)
    with _as_fresh_run(cfg):
        save(checkpoint_dir=partial, step=step, cfg=cfg, **kwargs)
    if checkpoint_dir.exists():  # set aside whole, then replaced: a kill in between leaves the new save partial only
        old = checkpoint_dir.with_name(f"{PARTIAL}old-{checkpoint_dir.name}")
        os.replace(checkpoint_dir, old)
        shutil.rmtree(old)
    os.replace(partial, checkpoint_dir)


@contextlib.contextmanager
def _as_fresh_run(cfg: Any) -> Iterator[None]:
    """``cfg`` (LeRobot's ``TrainPipelineConfig``) as a run started from scratch holds it, for the length of a save:
    not resuming, no state to resume from, the policy not loaded from a folder (a study's policies never are)."""
    policy = cfg.policy
    saved = (cfg.resume, cfg.checkpoint_path, policy.pretrained_path if policy is not None else None)
    if not cfg.resume:
        yield
        return
    cfg.resume, cfg.checkpoint_path = False, None
    if policy is not None:
        policy.pretrained_path = None
    try:
        yield
    finally:
        cfg.resume, cfg.checkpoint_path = saved[0], saved[1]
        if policy is not None:
            policy.pretrained_path = saved[2]


def prune(checkpoints: Path, newest: int, saves: Saves) -> None:
    """Delete the saves before ``newest`` that only a rerun needed (not LeRobot's own), once ``newest`` is a pass's end:
    a rerun then resumes from ``newest``."""
    if not saves.pass_end(newest):
        return
    for step, folder in saved_steps(checkpoints.parent).items():
        if step < newest and not saves.own(step):
            gone = folder.with_name(f"{PARTIAL}{folder.name}")  # renamed first: a kill mid-deletion leaves no half save
            os.replace(folder, gone)
            shutil.rmtree(gone)
