"""The 11 factors of variation: names, meaning, ranges and applicability, in one place.

Continuous ranges follow the paper's appendix table (narrow / medium / wide radii for camera and table
position, narrow / medium for object position); lighting samples ambient and diffuse in [0.2, 0.8].
Everything else (sampling, validation, the support matrix, docs) derives from :data:`FACTORS`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from ..tasks import TASKS, TaskSpec, get_task

WIDTHS = ("narrow", "medium", "wide")
RGB_SCHEME = "rgb:"  # a flat colour instead of an image: rgb:r,g,b
TEXTURE_SCHEMES = ("proc:", "metaworld:", "file:", RGB_SCHEME)
SHAPE_SCHEMES = ("proc:", "metaworld:", "file:")

Range = tuple[tuple[float, ...], tuple[float, ...]]


def _box(*pairs: tuple[float, float]) -> Range:
    return tuple(p[0] for p in pairs), tuple(p[1] for p in pairs)


def _cube(radius: float, dims: int) -> Range:
    return _box(*[(-radius, radius)] * dims)


@dataclass(frozen=True)
class FactorSpec:
    """How one factor varies.

    Attributes:
        name: Identifier used in configs, CLI flags, info dicts and dataset columns.
        title: The paper's name for the factor.
        description: What changes in the scene.
        kind: ``vector``/``scalar`` (continuous), ``asset`` (drawn from an asset split), ``objects``.
        visual: True when the factor only changes appearance (physics is provably unchanged).
        ranges: Continuous sampling ranges by width name; values must lie inside the widest one.
        default_width: Width used when none is requested.
        components: Names of the vector components (for tables and dataset columns).
        asset_kind: For asset factors, which asset pool (``texture`` or ``shape``) feeds it.
        applies: Returns ``None`` when the factor applies to a task, else the reason it does not.
    """

    name: str
    title: str
    description: str
    kind: Literal["vector", "scalar", "asset", "objects"]
    visual: bool
    ranges: Mapping[str, Range] = field(default_factory=dict)
    default_width: str = "narrow"
    components: tuple[str, ...] = ()
    asset_kind: Literal["texture", "shape", ""] = ""
    applies: Callable[[TaskSpec], str | None] = lambda task: None

    def range(self, width: str | None = None) -> Range:
        width = width or self.default_width
        if width not in self.ranges:
            raise ValueError(
                f"factor {self.name!r} has no {width!r} range; valid widths: {', '.join(self.ranges) or 'none'}"
            )
        return self.ranges[width]

    @property
    def widest(self) -> Range:
        lows = [r[0] for r in self.ranges.values()]
        highs = [r[1] for r in self.ranges.values()]
        return tuple(map(min, zip(*lows))), tuple(map(max, zip(*highs)))


def _loose_object_only(task: TaskSpec) -> str | None:
    if task.object_is_free:
        return None
    return (
        f"{task.name}'s object ({', '.join(task.object_bodies)}) is an articulated fixture; resizing or "
        "reshaping it would change the task's mechanics and success test"
    )


def _reshapeable_only(task: TaskSpec) -> str | None:
    reason = _loose_object_only(task)
    if reason or task.reshapeable:
        return reason
    return (
        f"{task.name}'s scripted expert is tuned to its own object's shape and fails (<90%) with other "
        "shapes, so demonstrations could not be collected"
    )


# Geometry of the distractor area, in the table frame (metres from the table centre).
DISTRACTOR_AREA = _box((-0.6, 0.6), (-0.33, 0.33))
DISTRACTOR_SIZE = (0.05, 0.12)
MAX_DISTRACTORS = 5


@dataclass(frozen=True)
class SceneObject:
    """A rigid object standing on the table: a distractor (or, for multi-object tasks, a named item).

    Positions are in the table frame (metres from the table centre), so objects move with the table.
    Defined here, next to the area and sizes it is validated against, so that the registry needs no
    value module (:mod:`.values` re-exports it).
    """

    shape: str
    x: float
    y: float
    yaw: float
    size: float
    texture: str
    name: str = ""


FACTORS: dict[str, FactorSpec] = {
    spec.name: spec
    for spec in (
        FactorSpec(
            "object_pos",
            "Object position",
            "Offset (dx, dy) of the object's initial position from the task's nominal one. None re-samples "
            "it every episode from the reset seed (the paper's protocol).",
            "vector",
            visual=False,
            ranges={"narrow": _box((-0.05, 0.05), (-0.05, 0.05)), "medium": _box((-0.1, 0.1), (-0.075, 0.075))},
            components=("dx", "dy"),
        ),
        FactorSpec(
            "arm_pos",
            "Initial arm position",
            "Offset (dx, dy, dz) of the gripper's initial position from the task's default.",
            "vector",
            visual=False,
            ranges={
                "narrow": _box((-0.1, 0.1), (-0.05, 0.05), (-0.03, 0.03)),
                "medium": _box((-0.15, 0.15), (-0.1, 0.1), (-0.03, 0.05)),
            },
            components=("dx", "dy", "dz"),
        ),
        FactorSpec(
            "camera_pos",
            "Camera position",
            "Perturbation of each scene camera's pose: position (dx, dy, dz) and quaternion (dq1..dq4, "
            "renormalised), as in the paper's appendix table.",
            "vector",
            visual=True,
            ranges={w: _cube(r, 7) for w, r in zip(WIDTHS, (0.025, 0.05, 0.075))},
            components=("dx", "dy", "dz", "dq1", "dq2", "dq3", "dq4"),
        ),
        FactorSpec(
            "table_pos",
            "Table position",
            "Offset (dx, dy, dz) of the table and everything on it relative to the robot, its cameras and the floor.",
            "vector",
            visual=False,
            ranges={
                "narrow": _cube(0.025, 3),
                "medium": _box((-0.05, 0.05), (-0.05, 0.05), (-0.05, 0.025)),
                "wide": _box((-0.075, 0.075), (-0.075, 0.075), (-0.05, 0.025)),
            },
            components=("dx", "dy", "dz"),
        ),
        FactorSpec(
            "object_size",
            "Object size",
            "Uniform scale of the manipulated object.",
            "scalar",
            visual=False,
            ranges={"narrow": ((0.8,), (1.2,)), "medium": ((0.7,), (1.3,))},
            default_width="medium",
            applies=_loose_object_only,
        ),
        FactorSpec(
            "object_shape",
            "Object shape",
            "Mesh replacing the manipulated object's geometry (same footprint, mass and grasp height).",
            "asset",
            visual=False,
            asset_kind="shape",
            applies=_reshapeable_only,
        ),
        FactorSpec(
            "object_texture",
            "Object texture",
            "Texture image or flat RGB colour of the object.",
            "asset",
            visual=True,
            asset_kind="texture",
        ),
        FactorSpec(
            "table_texture",
            "Table texture",
            "Texture image or flat RGB colour of the table.",
            "asset",
            visual=True,
            asset_kind="texture",
        ),
        FactorSpec(
            "floor_texture",
            "Floor (background) texture",
            "Texture image or flat RGB colour of the floor.",
            "asset",
            visual=True,
            asset_kind="texture",
        ),
        FactorSpec(
            "light",
            "Lighting",
            "Ambient and diffuse intensity (grey) of the scene's headlight.",
            "vector",
            visual=True,
            ranges={"paper": _box((0.2, 0.8), (0.2, 0.8))},
            default_width="paper",
            components=("ambient", "diffuse"),
        ),
        FactorSpec(
            "distractors",
            "Distractor objects",
            "Static objects (shape, texture, size, position, yaw) placed on free parts of the table.",
            "objects",
            visual=False,
            asset_kind="shape",
        ),
    )
}
"""All factors by name, in the paper's order."""


def get_factor(name: str) -> FactorSpec:
    if name not in FACTORS:
        raise ValueError(f"unknown factor {name!r}; valid factors: {', '.join(FACTORS)}")
    return FACTORS[name]


def check_factor_names(names: Mapping[str, Any] | list[str] | tuple[str, ...]) -> None:
    unknown = [n for n in names if n not in FACTORS]
    if unknown:
        raise ValueError(f"unknown factor(s) {', '.join(map(repr, unknown))}; valid factors: {', '.join(FACTORS)}")


def support_reason(factor: str, task: str | TaskSpec) -> str | None:
    """``None`` if ``factor`` applies to ``task``, else why it does not."""
    spec = get_factor(factor)
    task = task if isinstance(task, TaskSpec) else get_task(task)
    return dict(task.unsupported).get(factor) or spec.applies(task)


def supported_factors(task: str | TaskSpec) -> tuple[str, ...]:
    return tuple(name for name in FACTORS if support_reason(name, task) is None)


def check_task_support(task: TaskSpec, factors: Mapping[str, Any] | list[str] | tuple[str, ...]) -> None:
    """Raise a clear error if a requested factor cannot apply to ``task``."""
    check_factor_names(factors)
    if isinstance(factors, Mapping):
        check_task_limits(task, factors)
    for name in factors:
        reason = support_reason(name, task)
        if reason:
            raise ValueError(
                f"factor {name!r} does not apply to task {task.name!r}: {reason}. "
                f"Factors supported by {task.name}: {', '.join(supported_factors(task))}"
            )


def support_matrix() -> dict[str, dict[str, bool]]:
    """task -> factor -> applies?"""
    return {task: {f: support_reason(f, task) is None for f in FACTORS} for task in TASKS}


def support_matrix_markdown() -> str:
    """The support matrix as a Markdown table (printed by ``factorworld factors`` and shown in the docs)."""
    names = list(FACTORS)
    lines = ["| task | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    for task, row in support_matrix().items():
        lines.append(f"| {task} | " + " | ".join("yes" if row[n] else "—" for n in names) + " |")
    return "\n".join(lines)


def factor_range(task: TaskSpec, factor: str, width: str | None = None) -> Range:
    """A continuous factor's range for ``task``: the width's range clipped to the task's limits."""
    low, high = get_factor(factor).range(width)
    limit = task.limit(factor)
    if limit is None:
        return low, high
    return tuple(map(max, low, limit[0])), tuple(map(min, high, limit[1]))


def check_task_limits(task: TaskSpec, values: Mapping[str, Any]) -> None:
    for name, (low, high) in task.limits:
        value = values.get(name)
        if value is None:
            continue
        items = value if isinstance(value, tuple) else (value,)
        if not all(lo - 1e-9 <= v <= hi + 1e-9 for v, lo, hi in zip(items, low, high)):
            bounds = ", ".join(f"[{lo}, {hi}]" for lo, hi in zip(low, high))
            raise ValueError(f"{name}={value} is outside the range where {task.name} stays solvable: {bounds}")


def validate_value(name: str, value: Any) -> Any:
    """Check one factor value and return it in canonical form (tuples of floats, str)."""
    spec = get_factor(name)
    if spec.kind in ("vector", "scalar"):
        return _validate_continuous(spec, value)
    if spec.kind == "asset":
        schemes = TEXTURE_SCHEMES if spec.asset_kind == "texture" else SHAPE_SCHEMES
        return _validate_asset_name(name, value, schemes)
    return _validate_objects(value)


def _validate_continuous(spec: FactorSpec, value: Any) -> Any:
    low, high = spec.widest
    scalar = spec.kind == "scalar"
    items = (value,) if scalar else value
    try:
        items = tuple(float(v) for v in items)
    except (TypeError, ValueError):
        raise ValueError(f"factor {spec.name!r} expects {_shape_text(spec)}, got {value!r}") from None
    if len(items) != len(low):
        raise ValueError(f"factor {spec.name!r} expects {_shape_text(spec)}, got {len(items)} values: {value!r}")
    for i, (v, lo, hi) in enumerate(zip(items, low, high)):
        if not (lo - 1e-9 <= v <= hi + 1e-9) or math.isnan(v):
            label = spec.components[i] if spec.components else "value"
            raise ValueError(
                f"factor {spec.name!r} {label}={v!r} is outside its range [{lo}, {hi}] "
                f"(widest of {', '.join(spec.ranges)})"
            )
    return items[0] if scalar else items


def _shape_text(spec: FactorSpec) -> str:
    if spec.kind == "scalar":
        return "one number"
    return f"{len(spec.components)} numbers ({', '.join(spec.components)})"


def _validate_asset_name(factor: str, value: Any, schemes: tuple[str, ...]) -> str:
    if not isinstance(value, str) or not value.startswith(schemes):
        raise ValueError(
            f"factor {factor!r} expects an asset name starting with one of {', '.join(schemes)} "
            f"(e.g. 'proc:checker-003'{', or rgb:0.2,0.5,0.9' if RGB_SCHEME in schemes else ''}), got {value!r}"
        )
    if is_rgb(value):
        parse_rgb(value)
    return value


def is_rgb(value: str) -> bool:
    """Whether a texture value is a flat colour (``rgb:r,g,b``) rather than an image."""
    return value.startswith(RGB_SCHEME)


def parse_rgb(value: str) -> tuple[float, float, float]:
    """``rgb:r,g,b`` with components in [0, 1] -> floats."""
    try:
        rgb = tuple(float(v) for v in value.removeprefix(RGB_SCHEME).split(","))
    except ValueError:
        rgb = ()
    if len(rgb) != 3 or not all(0.0 <= c <= 1.0 for c in rgb):
        raise ValueError(f"bad colour {value!r}; expected 'rgb:r,g,b' with three components in [0, 1]")
    return rgb  # type: ignore[return-value]


def format_rgb(rgb: tuple[float, float, float]) -> str:
    return RGB_SCHEME + ",".join(f"{c:.4f}" for c in rgb)


def _validate_objects(value: Any) -> tuple:
    items = tuple(value)
    if len(items) > MAX_DISTRACTORS:
        raise ValueError(f"at most {MAX_DISTRACTORS} distractors are supported, got {len(items)}")
    out = []
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    for item in items:
        if isinstance(item, dict):
            item = SceneObject(**item)
        if not isinstance(item, SceneObject):
            raise ValueError(f"distractors must be SceneObject values or dicts, got {item!r}")
        _validate_asset_name("distractors.shape", item.shape, SHAPE_SCHEMES)
        _validate_asset_name("distractors.texture", item.texture, TEXTURE_SCHEMES)
        if not (xlo <= item.x <= xhi and ylo <= item.y <= yhi):
            raise ValueError(
                f"distractor position ({item.x}, {item.y}) is off the distractor area "
                f"x in [{xlo}, {xhi}], y in [{ylo}, {yhi}] (table frame, metres)"
            )
        if not DISTRACTOR_SIZE[0] - 1e-9 <= item.size <= DISTRACTOR_SIZE[1] + 1e-9:
            raise ValueError(f"distractor size {item.size} is outside [{DISTRACTOR_SIZE[0]}, {DISTRACTOR_SIZE[1]}] m")
        out.append(item)
    return tuple(out)


PAPER_STUDY_FACTORS = (
    "camera_pos",
    "table_pos",
    "object_texture",
    "table_texture",
    "floor_texture",
    "light",
    "distractors",
)
"""The seven factors of the paper's simulated study (object size/shape and arm pose are excluded
there; object position is re-randomised every episode)."""


def check_factors(factors: Sequence[str], tasks: Sequence[str], setting: str = "factors") -> None:
    """Known factor names, each once, that apply to every task (the error says why one does not)."""
    factors = list(factors)
    check_factor_names(factors)
    duplicates = sorted({f for f in factors if factors.count(f) > 1})
    if duplicates:
        raise ValueError(f"{setting}: factor(s) {', '.join(duplicates)} given more than once")
    for task in tasks:
        check_task_support(get_task(task), factors)
