"""What a Factor World dataset was collected in: its side-car ``meta/factorworld.json``, read back.

:data:`SIDECAR` is the side-car's path inside a dataset (written by
:func:`lerobot_factorworld.datasets.collect.collect`).
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from ..core.checks import split_list
from ..factors.values import SceneConfig
from .sampling import SamplingOptions

SIDECAR = "meta/factorworld.json"
"""The side-car's path inside a dataset root."""


@dataclass(frozen=True)
class DatasetCondition:
    """What a Factor World dataset was collected in (its ``meta/factorworld.json``)."""

    root: str
    tasks: tuple[str, ...]
    n_envs: int
    factors: tuple[str, ...]
    seed: int
    sampling: SamplingOptions
    environments: tuple[SceneConfig, ...]
    # How its frames were made; None where the side-car does not record it (hand-made or older ones).
    quality: str | None = None  # render quality (``scene.build.QUALITIES``)
    cameras: tuple[str, ...] | None = None  # each stored as ``observation.images.<camera>``
    image_size: int | None = None

    def train_configs(self, task: str) -> list[SceneConfig]:
        configs = sorted((c for c in self.environments if c.task == task), key=lambda c: c.env_id)
        if not configs:
            raise ValueError(
                f"dataset {self.root} holds no environment of task {task!r}; its tasks: {', '.join(self.tasks)}"
            )
        return configs


def read_dataset_condition(root: str | Path) -> DatasetCondition:
    """The training environments and sampling settings a dataset was collected with."""
    path = Path(root) / SIDECAR
    if not path.is_file():
        raise FileNotFoundError(
            f"{root} is not a Factor World dataset ({SIDECAR} is missing); collect it with `factorworld collect`"
        )
    sidecar = json.loads(path.read_text())
    settings = sidecar["settings"]
    environments = tuple(
        SceneConfig.from_dict(c) for c in sidecar["environments"] if c.get("split", "train") == "train"
    )
    tasks = tuple(t.strip() for t in settings["task"].split(",") if t.strip())
    per_task = Counter(c.task for c in environments)
    return DatasetCondition(
        root=str(root),
        tasks=tasks,
        n_envs=max(per_task.values()) if per_task else int(settings["n_envs"]),
        factors=tuple(settings["factors"]),
        seed=int(settings["seed"]),
        sampling=SamplingOptions(**settings.get("sampling", {})),
        environments=environments,
        quality=settings.get("quality"),
        cameras=tuple(split_list(settings["cameras"])) if "cameras" in settings else None,
        image_size=int(settings["image_size"]) if "image_size" in settings else None,
    )


def check_against_dataset(dataset: DatasetCondition, requested: dict[str, Any]) -> None:
    """Refuse settings given explicitly (not ``None``) that disagree with what the dataset was collected with
    (as far as its side-car records it)."""
    recorded = {
        "n_train_envs": dataset.n_envs,
        "train_factors": sorted(dataset.factors),  # each factor has its own RNG: the order does not matter
        "seed": dataset.seed,
        "sampling": dataset.sampling,
        "quality": dataset.quality,
        "cameras": dataset.cameras,
        "image_size": dataset.image_size,
    }
    requested = {k: sorted(v) if k == "train_factors" and v is not None else v for k, v in requested.items()}
    wrong = [
        f"{key}={value!r} but the dataset has {recorded[key]!r}"
        for key, value in requested.items()
        if value is not None and recorded[key] is not None and _normalise(value) != _normalise(recorded[key])
    ]
    if wrong:
        raise ValueError(
            f"the training condition disagrees with dataset {dataset.root}: {'; '.join(wrong)}. "
            "Leave these settings out to take them from the dataset."
        )


def _normalise(value: Any) -> Any:
    if isinstance(value, SamplingOptions):
        return json.dumps(asdict(value), sort_keys=True)
    if isinstance(value, (list, tuple)):
        return [_normalise(v) for v in value]
    return value
