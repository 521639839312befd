"""A training's schedule, as arithmetic on its inputs: its gradient steps, the frames an epoch counts, when the
learning curve's checkpoints are saved and where each lies. Its own module so that the plan's cost model and the
evaluation of a curve's checkpoint share it without importing the training stack (``train_step.py``)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

from .inputs import MERGED_FRAMES, TrainInputs, whole_epochs
from .result import TRAIN_DIR


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
