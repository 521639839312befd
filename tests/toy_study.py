"""The toy study the training tests share: one handle-press dataset of one environment and 2 demos (51 frames) at
48 px, bc at batch 8, evaluations of one episode of 8 steps. Each test states only what it changes."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml

TOY_STUDY: dict[str, Any] = {
    "tasks": ["handle-press"],
    "n_train_envs": [1],
    "seeds": [0],
    "train_factors": ["light"],
    "factors": [],
    "methods": [{"name": "bc", "policy": {"type": "bc"}}],
    "collect": {"demos": 2, "max_episode_steps": 60, "image_size": 48},
    "train": {"batch_size": 8},
    "eval": {"n_test_envs": 1, "episodes": 1, "max_episode_steps": 8, "record_episodes": 0},
    "workers": 1,
}


def write_toy_study(path: Path, out: Path, **settings: Any) -> Path:
    """The toy study's YAML at ``path``, its outputs in ``out``; ``settings`` replace top-level settings, and a
    section's given as a mapping (``train={"epochs": 20}``) updates that section."""
    config = copy.deepcopy(TOY_STUDY)
    for name, value in settings.items():
        if isinstance(value, dict) and isinstance(config.get(name), dict):
            config[name].update(value)
        else:
            config[name] = value
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump({"name": path.stem, "out_dir": str(out), **config}, sort_keys=False))
    return path
