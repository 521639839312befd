"""Seeded sampling of factor values and environment configurations (train environments, shifted tests).

Each factor draws from its own child RNG (``[seed, split, factor]``), so the same seeds always give the
same configurations and adding a factor to a study never changes the values other factors get, except
where two rules tie factors of one environment together: the object texture never equals the table
texture (as in the public Factor World; a table texture also avoids the textures a fixture object keeps
when its texture is not varied), and no distractor comes from a shape family the task's scene shows (its
object's, its fixtures' meshes: :func:`~lerobot_factorworld.assets.scenes.scene_shape_families`). A value
that would break a rule is replaced without drawing again (see :func:`_draw`), so a rule changes only
that value and never shifts any RNG stream. The rules bind sampled and shifted values only: a
configuration written by hand is taken as given.
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..assets import DEFAULT_ASSET_SPLIT, DEFAULT_TABLE_TEXTURE, asset_family, check_asset_split
from ..assets import split_names as asset_split_names
from ..assets.scenes import scene_assets, scene_shape_families
from ..core.splits import SPLITS, check_split
from ..factors.registry import (
    DISTRACTOR_AREA,
    DISTRACTOR_SIZE,
    FACTORS,
    MAX_DISTRACTORS,
    PAPER_STUDY_FACTORS,
    SceneObject,
    check_factor_names,
    check_task_support,
    factor_range,
    format_rgb,
    get_factor,
)
from ..factors.values import FactorValues, SceneConfig
from ..families import all_families, family_of
from ..tasks import TaskSpec, get_task
from . import keepout

MAX_PLACEMENT_TRIES = 2000

DEFAULT_RGB_FRACTION = 0.5
"""Share of texture draws (object, table, floor, distractor textures) that are a flat colour drawn
uniformly in [0, 1]^3 instead of an image. The paper samples textures "from 162 texture images (81 for
train, 81 for eval) and continuous RGB values in [0, 1]^3" without giving the share, and the public code
samples images only; one half, the two sources on an equal footing, is this project's reading
(docs/factors.md, "Textures: images and flat colours")."""


@dataclass(frozen=True)
class SamplingOptions:
    """How factor values are drawn.

    Attributes:
        widths: Range width per continuous factor (e.g. ``{"camera_pos": "wide"}``); others use their default.
        texture_folder: A folder of texture images to draw textures from instead of the built-in pool.
        shape_folder: A folder of meshes (.stl/.obj) to draw object shapes and distractors from.
        rgb_fraction: Probability that a texture draw is a flat RGB colour (uniform in [0, 1]^3) instead
            of an image (default :data:`DEFAULT_RGB_FRACTION`). Colours, like images, come from the
            factor's stream of the split, so held-out (eval) colours are other draws than training ones.
        n_distractors: Number of distractor objects per environment.
        n_objects: Objects on the table in a scene of a family that reads it (its ``sampling_options``;
            checked by the family); other tasks ignore it.
        template: The pick family's phrasing template every episode of the sampled scenes is phrased with (one of
            its training templates, e.g. ``"pick up the {colour} {noun}"``: the instruction fixed to the named
            object's colour and noun); ``""``: drawn per episode from the split's templates. Other tasks ignore it.
        asset_split: How assets are split between train and eval: ``family`` (default) holds whole
            families out, so test textures and shapes are unlike any training one (the paper's unseen
            images and objects); ``variant`` splits name by name (new variants of seen families). In a
            folder, a top-level subfolder is a family.
    """

    widths: dict[str, str] = field(default_factory=dict)
    texture_folder: str | None = None
    shape_folder: str | None = None
    rgb_fraction: float = DEFAULT_RGB_FRACTION
    n_distractors: int = 1
    asset_split: str = DEFAULT_ASSET_SPLIT
    n_objects: int = 4
    template: str = ""

    def __post_init__(self) -> None:
        check_asset_split(self.asset_split)
        check_factor_names(self.widths)
        for name, width in self.widths.items():
            get_factor(name).range(width)  # raises naming the valid widths
        if not 0.0 <= self.rgb_fraction <= 1.0:
            raise ValueError(f"rgb_fraction must be in [0, 1], got {self.rgb_fraction}")
        if not 0 <= self.n_distractors <= MAX_DISTRACTORS:
            raise ValueError(f"n_distractors must be in [0, {MAX_DISTRACTORS}], got {self.n_distractors}")
        for family in all_families():  # the options only a task family reads (pick: n_objects, template)
            family.check_sampling(self)
        for folder in (self.texture_folder, self.shape_folder):
            if folder is not None and not Path(folder).is_dir():
                raise FileNotFoundError(f"asset folder {folder} does not exist")


def unset_options(options: SamplingOptions) -> tuple[str, ...]:
    """The fields a family reads only when set (``TaskFamily.keyed_when_set``) that are at their default: a
    dataset's record leaves them out, so data collected before they existed keeps its bytes."""
    defaults = SamplingOptions()
    return tuple(
        name
        for family in all_families()
        for name in family.keyed_when_set
        if getattr(options, name) == getattr(defaults, name)
    )


def factor_rng(seed: int, split: str, factor: str, *extra: int) -> np.random.Generator:
    return np.random.default_rng([seed, SPLITS.index(check_split(split)), list(FACTORS).index(factor), *extra])


def sample_factor(
    name: str,
    task: str | TaskSpec,
    rng: np.random.Generator,
    split: str = "train",
    options: SamplingOptions | None = None,
    scene: Mapping[str, Any] | None = None,
):
    """Draw one value of factor ``name`` for ``task`` from ``split``.

    ``scene`` holds the environment's other factor values that are already fixed (drawn before, or
    inherited from a training environment): the drawn value obeys the rules between factors against them.
    """
    options = options or SamplingOptions()
    return _sample(name, task, rng, split, options, scene or {}, _Pools(split, options))


def _sample(
    name: str,
    task: str | TaskSpec,
    rng: np.random.Generator,
    split: str,
    options: SamplingOptions,
    scene: Mapping[str, Any],
    pools: _Pools,
):
    task = task if isinstance(task, TaskSpec) else get_task(task)
    spec = get_factor(name)
    check_task_support(task, [name])
    check_split(split)
    if spec.kind in ("vector", "scalar"):
        low, high = factor_range(task, name, options.widths.get(name))
        value = tuple(float(v) for v in rng.uniform(low, high))
        return value[0] if spec.kind == "scalar" else value
    if name == "object_texture":
        table = scene.get("table_texture") or DEFAULT_TABLE_TEXTURE
        return _sample_texture(rng, pools.texture, options, avoid=(table,))
    if name == "table_texture":  # the object's texture, or what its default scene paints it with
        own = scene.get("object_texture")
        avoid = (own,) if own else scene_assets(task.name).object_textures
        return _sample_texture(rng, pools.texture, options, avoid=avoid)
    if name == "floor_texture":
        return _sample_texture(rng, pools.texture, options, avoid=())
    if name == "object_shape":
        shapes = pools.shape
        taken = {shapes.family_of(item.shape) for item in scene.get("distractors") or ()}
        return _draw(rng, shapes, lambda shape: shapes.family_of(shape) not in taken, "object shape")
    return _sample_distractors(task, rng, options, scene, pools)


def sample_factor_values(
    task: str | TaskSpec,
    factors: Iterable[str],
    n: int,
    seed: int,
    split: str = "train",
    options: SamplingOptions | None = None,
    base: Sequence[FactorValues] | None = None,
) -> list[FactorValues]:
    """``n`` factor-value sets varying ``factors``; the others stay at the default scene, or, with ``base``,
    at the values of ``base[i % len(base)]``, which the rules between factors then respect."""
    factors = tuple(factors)
    check_factor_names(factors)
    options = options or SamplingOptions()
    pools = _Pools(split, options)
    scenes: list[dict[str, Any]] = [
        {k: v for k, v in (base[i % len(base)].non_default() if base else {}).items() if k not in factors}
        for i in range(n)
    ]
    for name in sorted(factors, key=lambda f: (f not in _DRAWN_FIRST, list(FACTORS).index(f))):
        rng = factor_rng(seed, split, name)
        for scene in scenes:
            scene[name] = _sample(name, task, rng, split, options, scene, pools)
    return [FactorValues(**{name: scene[name] for name in factors}) for scene in scenes]


_DRAWN_FIRST = ("table_texture", "object_shape")
"""Factors that a rule of another factor reads (object texture vs table texture, distractors vs object
shape) are drawn first. Each factor keeps its own RNG, so the order changes no stream."""


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
    contents = family_of(task).sample_contents(task, n, seed, split, options or SamplingOptions())
    return [
        SceneConfig(task.name, v, split=split, env_id=f"{task.name}/{split}/{i:03d}", content=content)
        for i, (v, content) in enumerate(zip(values, contents, strict=True))
    ]


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
    ``split`` (the held-out asset split by default), as in the paper's protocol. The inherited factors are
    kept exactly; a shifted value obeys the rules between factors against them.
    """
    factors = (factors,) if isinstance(factors, str) else tuple(factors)
    if not base:
        raise ValueError("shift_configs needs at least one base configuration")
    if not factors:
        raise ValueError("shift_configs needs at least one factor to shift")
    if n < 1:
        raise ValueError(f"the number of environments must be at least 1, got {n}")
    tasks = sorted({c.task for c in base})
    if len(tasks) > 1:
        raise ValueError(f"shift_configs needs base configurations of one task, got {tasks}")
    task = get_task(tasks[0])
    tag = "+".join(factors)
    new_values = sample_factor_values(task, factors, n, seed, split, options, base=[c.factors for c in base])
    out = []
    for j, values in enumerate(new_values):
        parent = base[j % len(base)]
        replaced = parent.factors.set(**{name: getattr(values, name) for name in factors})
        out.append(replace(parent, factors=replaced, split=split, env_id=f"{task.name}/shift-{tag}/{j:03d}"))
    return out


@dataclass(frozen=True)
class _Pool:
    """The asset names of one split and the family of each (for the look-alike rule)."""

    kind: str
    names: tuple[str, ...]
    families: Mapping[str, str]
    folder: str | None = None  # the asset folder the names come from: an inherited file's family is its subfolder

    @classmethod
    def of(cls, kind: str, split: str, options: SamplingOptions) -> _Pool:
        folder = options.texture_folder if kind == "texture" else options.shape_folder
        names = asset_split_names(kind, split, folder, mode=options.asset_split)  # type: ignore[arg-type]
        return cls(kind, names, {name: asset_family(name, folder) for name in names}, folder)

    def family_of(self, name: str) -> str:
        """Family of a pool name, or of any other asset: one inherited from another split's pool of the same
        folder (its top-level subfolder) or from a hand-made config."""
        return self.families.get(name) or asset_family(name, self.folder)


class _Pools:
    """The texture and shape pools of one split, resolved once per sampling call (a folder is scanned once)."""

    def __init__(self, split: str, options: SamplingOptions) -> None:
        self.split, self.options = split, options

    @functools.cached_property
    def texture(self) -> _Pool:
        return _Pool.of("texture", self.split, self.options)

    @functools.cached_property
    def shape(self) -> _Pool:
        return _Pool.of("shape", self.split, self.options)


def _draw(rng: np.random.Generator, pool: _Pool, allowed: Callable[[str], bool], what: str) -> str:
    """A uniform draw among the names of ``pool`` that obey a rule; ``rng`` advances by one draw whatever
    the rule did, so a rule changes only the value that broke it and never the stream of later draws.

    ``k`` is drawn from all ``n`` names; when ``pool.names[k]`` breaks the rule, the replacement is drawn
    uniformly from the ``m`` allowed names by :func:`_aside` (which leaves ``rng`` as it is). Each allowed
    name then has probability ``1/n + (n - m)/n * 1/m = 1/m``.
    """
    k = int(rng.integers(len(pool.names)))
    if allowed(pool.names[k]):
        return pool.names[k]
    ok = [name for name in pool.names if allowed(name)]
    if not ok:
        raise ValueError(f"no {what} in the {pool.kind} pool obeys the rules between factors (all excluded)")
    return ok[int(_aside(rng).integers(len(ok)))]


def _aside(rng: np.random.Generator) -> np.random.Generator:
    """A generator seeded by ``rng``'s current state (sha256 of it): as seeded as ``rng`` itself, and
    drawing from it does not advance ``rng``."""
    state = json.dumps(rng.bit_generator.state, sort_keys=True, default=lambda a: np.asarray(a).tolist())
    return np.random.default_rng(int.from_bytes(hashlib.sha256(state.encode()).digest()[:16], "little"))


def _sample_texture(rng: np.random.Generator, pool: _Pool, options: SamplingOptions, avoid: Collection[str]) -> str:
    # Always draw both numbers so the RNG stream does not depend on rgb_fraction's outcome.
    use_rgb = rng.random() < options.rgb_fraction
    rgb = format_rgb(tuple(rng.random(3)))
    colour = use_rgb and rgb not in avoid
    try:
        name = _draw(rng, pool, lambda texture: texture not in avoid, "texture")
    except ValueError:  # every image is excluded: a problem only when the draw asked for an image
        if colour:
            return rgb
        raise
    return rgb if colour else name


def _sample_distractors(
    task: TaskSpec, rng: np.random.Generator, options: SamplingOptions, scene: Mapping[str, Any], pools: _Pools
) -> tuple[SceneObject, ...]:
    shapes, textures = pools.shape, pools.texture
    own_shape = scene.get("object_shape")
    lookalike = set(scene_shape_families(task.name, shapes.family_of(own_shape) if own_shape else None))
    blocked = [tuple(b) for b in keepout.keepout_boxes(task.name)]
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    items = []
    for _ in range(options.n_distractors):
        shape = _draw(rng, shapes, lambda name: shapes.family_of(name) not in lookalike, "distractor shape")
        texture = _sample_texture(rng, textures, options, avoid=())
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
