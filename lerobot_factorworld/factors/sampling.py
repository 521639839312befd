"""Seeded sampling of factor values and environment configurations (train environments, shifted tests).

Each factor draws from its own child RNG (``[seed, split, factor]``), so adding a factor to a study
never changes the values other factors get, and the same seeds always give the same configurations.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..tasks import TaskSpec, get_task
from .registry import (
    DISTRACTOR_AREA,
    DISTRACTOR_SIZE,
    FACTORS,
    MAX_DISTRACTORS,
    PAPER_STUDY_FACTORS,
    SPLITS,
    check_factor_names,
    check_task_support,
    factor_range,
    format_rgb,
    get_factor,
)
from .values import FactorValues, SceneConfig, SceneObject

MAX_PLACEMENT_TRIES = 2000


@dataclass(frozen=True)
class SamplingOptions:
    """How factor values are drawn.

    Attributes:
        widths: Range width per continuous factor (e.g. ``{"camera_pos": "wide"}``); others use their default.
        texture_folder: A folder of texture images to draw textures from instead of the built-in pool.
        shape_folder: A folder of meshes (.stl/.obj) to draw object shapes and distractors from.
        rgb_fraction: Probability that a texture draw is a flat RGB colour instead of an image.
        n_distractors: Number of distractor objects per environment.
    """

    widths: dict[str, str] = field(default_factory=dict)
    texture_folder: str | None = None
    shape_folder: str | None = None
    rgb_fraction: float = 0.0
    n_distractors: int = 1

    def __post_init__(self) -> None:
        check_factor_names(self.widths)
        for name, width in self.widths.items():
            get_factor(name).range(width)  # raises naming the valid widths
        if not 0.0 <= self.rgb_fraction <= 1.0:
            raise ValueError(f"rgb_fraction must be in [0, 1], got {self.rgb_fraction}")
        if not 0 <= self.n_distractors <= MAX_DISTRACTORS:
            raise ValueError(f"n_distractors must be in [0, {MAX_DISTRACTORS}], got {self.n_distractors}")
        for folder in (self.texture_folder, self.shape_folder):
            if folder is not None and not Path(folder).is_dir():
                raise FileNotFoundError(f"asset folder {folder} does not exist")


def factor_rng(seed: int, split: str, factor: str, *extra: int) -> np.random.Generator:
    return np.random.default_rng([seed, SPLITS.index(_check_split(split)), list(FACTORS).index(factor), *extra])


def sample_factor(
    name: str,
    task: str | TaskSpec,
    rng: np.random.Generator,
    split: str = "train",
    options: SamplingOptions | None = None,
):
    """Draw one value of factor ``name`` for ``task`` from ``split``."""
    options = options or SamplingOptions()
    task = task if isinstance(task, TaskSpec) else get_task(task)
    spec = get_factor(name)
    check_task_support(task, [name])
    _check_split(split)
    if spec.kind in ("vector", "scalar"):
        low, high = factor_range(task, name, options.widths.get(name))
        value = tuple(float(v) for v in rng.uniform(low, high))
        return value[0] if spec.kind == "scalar" else value
    if spec.kind == "asset":
        if spec.asset_kind == "texture":
            return _sample_texture(rng, split, options)
        return _choice(rng, _shape_pool(split, options))
    return _sample_distractors(task, rng, split, options)


def sample_factor_values(
    task: str | TaskSpec,
    factors: Iterable[str],
    n: int,
    seed: int,
    split: str = "train",
    options: SamplingOptions | None = None,
) -> list[FactorValues]:
    """``n`` factor-value sets varying ``factors`` (the others stay at the default scene)."""
    factors = tuple(factors)
    check_factor_names(factors)
    columns = {}
    for name in factors:
        rng = factor_rng(seed, split, name)
        columns[name] = [sample_factor(name, task, rng, split, options) for _ in range(n)]
    return [FactorValues(**{name: columns[name][i] for name in factors}) for i in range(n)]


def sample_configs(
    task: str | TaskSpec,
    n: int,
    seed: int = 0,
    split: str = "train",
    factors: Sequence[str] = PAPER_STUDY_FACTORS,
    options: SamplingOptions | None = None,
) -> list[SceneConfig]:
    """``n`` environments of ``task``: the paper's "N training environments" for ``split="train"``."""
    task = task if isinstance(task, TaskSpec) else get_task(task)
    if n < 1:
        raise ValueError(f"the number of environments must be at least 1, got {n}")
    values = sample_factor_values(task, factors, n, seed, split, options)
    return [SceneConfig(task.name, v, split=split, env_id=f"{task.name}/{split}/{i:03d}") for i, v in enumerate(values)]


def shift_configs(
    base: Sequence[SceneConfig],
    factors: Sequence[str] | str,
    n: int,
    seed: int = 0,
    split: str = "eval",
    options: SamplingOptions | None = None,
) -> list[SceneConfig]:
    """Test environments: training environments with ``factors`` (one or a pair) given new values.

    Environment ``j`` copies ``base[j % len(base)]`` and replaces the shifted factors with draws from
    ``split`` (the held-out asset split by default), as in the paper's protocol.
    """
    factors = (factors,) if isinstance(factors, str) else tuple(factors)
    if not base:
        raise ValueError("shift_configs needs at least one base configuration")
    task = get_task(base[0].task)
    tag = "+".join(factors)
    new_values = sample_factor_values(task, factors, n, seed, split, options)
    out = []
    for j, values in enumerate(new_values):
        parent = base[j % len(base)]
        replaced = parent.factors.set(**{name: getattr(values, name) for name in factors})
        out.append(SceneConfig(task.name, replaced, parent.instruction, split, f"{task.name}/shift-{tag}/{j:03d}"))
    return out


def _check_split(split: str) -> str:
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r}; valid splits: {', '.join(SPLITS)}")
    return split


def _choice(rng: np.random.Generator, pool: tuple[str, ...]) -> str:
    return pool[int(rng.integers(len(pool)))]


def _texture_pool(split: str, options: SamplingOptions) -> tuple[str, ...]:
    from ..assets import split_names

    return split_names("texture", split, options.texture_folder)


def _shape_pool(split: str, options: SamplingOptions) -> tuple[str, ...]:
    from ..assets import split_names

    return split_names("shape", split, options.shape_folder)


def _sample_texture(rng: np.random.Generator, split: str, options: SamplingOptions) -> str:
    # Always draw both numbers so the RNG stream does not depend on rgb_fraction's outcome.
    use_rgb = rng.random() < options.rgb_fraction
    rgb = rng.random(3)
    name = _choice(rng, _texture_pool(split, options))
    return format_rgb(tuple(rgb)) if use_rgb else name


def _sample_distractors(task: TaskSpec, rng, split: str, options: SamplingOptions) -> tuple[SceneObject, ...]:
    from ..scene.layout import keepout_boxes

    blocked = [tuple(b) for b in keepout_boxes(task.name)]
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    items = []
    for _ in range(options.n_distractors):
        shape = _choice(rng, _shape_pool(split, options))
        texture = _sample_texture(rng, split, options)
        size = float(rng.uniform(*DISTRACTOR_SIZE))
        yaw = float(rng.uniform(0.0, 2 * np.pi))
        half = size / 2
        for _ in range(MAX_PLACEMENT_TRIES):
            x, y = float(rng.uniform(xlo + half, xhi - half)), float(rng.uniform(ylo + half, yhi - half))
            box = (x - half, y - half, x + half, y + half)
            if not any(_overlap(box, b) for b in blocked):
                break
        else:
            raise RuntimeError(
                f"could not place {options.n_distractors} distractors on the free table area of {task.name} "
                f"after {MAX_PLACEMENT_TRIES} tries; use fewer distractors (n_distractors)"
            )
        blocked.append(box)
        items.append(SceneObject(shape=shape, x=x, y=y, yaw=yaw, size=size, texture=texture))
    return tuple(items)


def _overlap(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
