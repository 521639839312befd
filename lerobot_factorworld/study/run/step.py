"""A study's unit of work, :class:`Step`: what it computes (its key) and where it keeps its outputs. Its own module
so that what builds on steps (``blocks.py``, the plan) needs none of the code that runs them (``worker.py``).

A step's key hashes its kind, its inputs and the keys of the steps it depends on, so a change to one
setting changes the keys of exactly the steps that depend on it. Inputs hold what changes results
(settings, the versions of the packages that compute them (:func:`versions`), the dataset format, weight files'
content); settings documented not to change results (workers, evaluation threads, where a weights file lies)
travel in ``meta["run"]`` instead; an evaluation's batch size is in its inputs when above 1.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import cache, cached_property
from importlib import metadata
from pathlib import Path
from typing import Any

from ... import __version__

KINDS = ("collect", "train", "eval")
STEP_FORMAT = 2  # bump when a step's meaning changes: every key changes with it (2: versions, content hashes)
RUN = "run"  # meta entry: how to run a step, without changing its results (not in the key, not in labels)
STEPS_DIR = "steps"  # <study>/steps/<kind>/<key>/


KEY_DIGITS = 16  # a step's key: this many hex digits of a SHA-256 (its folder's name)
RUN_CONFIG_FILE = "config.json"  # the settings a study ran with, written into its folder by every run
DISTRIBUTION = "lerobot_env_factorworld"
VERSIONED = ("lerobot", "torch", "mujoco", "metaworld")  # packages whose version changes what a step computes


def is_step_key(name: str) -> bool:
    """Whether a folder's name is a step's key (not, say, a redone step's old ``<key>.stale-<commit>`` folder)."""
    return len(name) == KEY_DIGITS and all(c in "0123456789abcdef" for c in name)


def short_hash(payload: dict[str, Any]) -> str:
    """16 hex digits of the SHA-256 of ``payload`` as sorted JSON: a step's key, or what an evaluation evaluates."""
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:KEY_DIGITS]


@dataclass(frozen=True)
class Step:
    """One unit of work. ``inputs`` (JSON-able) and ``deps`` decide ``key``; ``meta`` only labels it."""

    kind: str
    inputs: dict[str, Any]
    deps: tuple[str, ...] = ()
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    @cached_property
    def key(self) -> str:
        """Computed once: a plan reads each step's key many times (its dependents' keys hash it again), and a
        step's inputs are never changed after it is made."""
        return short_hash({"format": STEP_FORMAT, "kind": self.kind, "inputs": self.inputs, "deps": list(self.deps)})

    @property
    def label(self) -> str:
        return f"{self.kind} " + " ".join(f"{k}={v}" for k, v in self.meta.items() if k != RUN)

    @property
    def run(self) -> dict[str, Any]:
        """How to run this step (worker count, threads, paths): never changes its results."""
        return self.meta.get(RUN, {})

    def folder(self, study_dir: str | Path) -> Path:
        return step_folder(study_dir, self.kind, self.key)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "inputs": self.inputs, "deps": list(self.deps), "meta": self.meta, "key": self.key}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Step:
        return cls(data["kind"], data["inputs"], tuple(data["deps"]), data.get("meta", {}))


def step_folder(study_dir: str | Path, kind: str, key: str) -> Path:
    """``<study>/steps/<kind>/<key>/``: where a step keeps its result and outputs."""
    return Path(study_dir) / STEPS_DIR / kind / key


@cache
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
