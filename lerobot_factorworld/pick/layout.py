"""What a pick environment holds: which objects stand where, and which of them an episode may name.

A :class:`PickLayout` is plain frozen data, part of a :class:`~lerobot_factorworld.factors.values.SceneConfig`
(its ``pick`` field): saved, compared and fingerprinted with it. Like ``object_pos``, the target and
the phrasing are either pinned by the configuration or drawn every episode from the reset seed
(:meth:`PickLayout.for_episode`), so that every training environment is demonstrated with every one
of its objects named, and a policy has to read the instruction to succeed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any, ClassVar

import numpy as np

from ..core.splits import check_split
from ..factors.registry import get_factor
from .catalog import (
    DEFAULT_OBJECTS,
    MAX_OBJECTS,
    MIN_OBJECTS,
    SHAPES,
    SLOT_JITTER,
    SLOTS,
    TEMPLATES,
    get_object,
    render,
    split_objects,
    split_templates,
)

MAX_TRIES = 200


@dataclass(frozen=True)
class PlacedObject:
    """A catalogue object standing on the table: position (table frame, metres) and yaw (radians)."""

    name: str
    x: float
    y: float
    yaw: float = 0.0

    def __post_init__(self) -> None:
        obj = get_object(self.name)
        for key in ("x", "y", "yaw"):
            value = float(getattr(self, key))
            if not math.isfinite(value):
                raise ValueError(f"pick object {self.name}: {key} must be finite, got {value!r}")
            object.__setattr__(self, key, value)
        limit = obj.family.max_yaw + 1e-9
        if abs(_wrap(self.yaw)) > limit and abs(_wrap(self.yaw - math.pi)) > limit:
            raise ValueError(
                f"pick object {self.name}: yaw {self.yaw:.3f} puts it along the gripper's fingers; a {obj.shape} "
                f"needs |yaw| <= {obj.family.max_yaw} (or that plus pi)"
            )

    @property
    def radius(self) -> float:
        """Radius of a circle around its footprint (what neighbours must keep clear of)."""
        return math.hypot(*get_object(self.name).family.footprint)


@dataclass(frozen=True)
class PickLayout:
    """The objects of a pick environment and how each episode chooses what to ask for.

    Attributes:
        objects: The objects and their poses (3 to 6; distinct shape families and distinct colours).
        targets: Objects an episode may name; empty: any of ``objects``.
        phrasings: Template split the phrasing is drawn from (``train``, or ``eval``: held-out phrasings).
        target: The named object; empty: drawn every episode from the reset seed among ``targets``.
        template: The phrasing template; empty: drawn every episode from ``phrasings``.
    """

    kind: ClassVar[str] = "pick layout"  # what error messages call it
    family: ClassVar[str] = "pick"

    objects: tuple[PlacedObject, ...]
    targets: tuple[str, ...] = ()
    phrasings: str = "train"
    target: str = ""
    template: str = ""

    def __post_init__(self) -> None:
        objects = tuple(o if isinstance(o, PlacedObject) else PlacedObject(**o) for o in self.objects)
        object.__setattr__(self, "objects", objects)
        object.__setattr__(self, "targets", tuple(self.targets))
        if not MIN_OBJECTS <= len(objects) <= MAX_OBJECTS:
            raise ValueError(f"a pick scene holds {MIN_OBJECTS} to {MAX_OBJECTS} objects, got {len(objects)}")
        for kind in ("shape", "colour"):
            values = [getattr(get_object(o.name), kind) for o in objects]
            if len(set(values)) != len(values):
                raise ValueError(
                    f"pick objects must differ in {kind} so that every instruction names one object, got "
                    f"{', '.join(o.name for o in objects)}"
                )
        _check_workspace(objects)
        _check_clearance(objects)
        names = self.names
        strays = [t for t in (*self.targets, *([self.target] if self.target else [])) if t not in names]
        if strays:
            raise ValueError(f"target(s) {strays} are not in the scene; its objects: {', '.join(names)}")
        if self.target and self.targets and self.target not in self.targets:
            raise ValueError(f"target {self.target!r} is not one of the layout's targets {list(self.targets)}")
        check_split(self.phrasings, "phrasings split")
        if self.template and self.template not in TEMPLATES:
            raise ValueError(f"unknown phrasing template {self.template!r}; valid templates: {list(TEMPLATES)}")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)

    @property
    def candidates(self) -> tuple[str, ...]:
        """The objects an episode may name."""
        return self.targets or self.names

    @property
    def instruction(self) -> str | None:
        """The instruction, once target and phrasing are pinned (else ``None``: it varies per episode)."""
        return render(self.template, self.target) if self.target and self.template else None

    def for_episode(self, rng: np.random.Generator) -> PickLayout:
        """This layout with the episode's target and phrasing pinned (drawn from ``rng`` where not pinned).

        Always draws the same two numbers, so pinning one choice never shifts the other's stream.
        """
        i, j = (int(v) for v in rng.integers(0, 2**31 - 1, size=2))
        templates = split_templates(self.phrasings)
        return replace(
            self,
            target=self.target or self.candidates[i % len(self.candidates)],
            template=self.template or templates[j % len(templates)],
        )

    def placed(self, offset: tuple[float, float] | np.ndarray = (0.0, 0.0)) -> tuple[PlacedObject, ...]:
        """The objects moved by the episode's arrangement offset (the ``object_pos`` factor)."""
        dx, dy = (float(v) for v in offset)
        return tuple(replace(o, x=o.x + dx, y=o.y + dy) for o in self.objects)

    def to_dict(self) -> dict[str, Any]:
        return {
            "objects": [asdict(o) for o in self.objects],
            "targets": list(self.targets),
            "phrasings": self.phrasings,
            "target": self.target,
            "template": self.template,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PickLayout:
        known = {"objects", "targets", "phrasings", "target", "template"}
        unknown = set(data) - known
        if unknown:
            raise ValueError(f"unknown pick layout keys {sorted(unknown)}; valid keys: {sorted(known)}")
        values = dict(data)
        values["objects"] = tuple(PlacedObject(**o) if isinstance(o, dict) else o for o in values["objects"])
        values["targets"] = tuple(values.get("targets", ()))
        return cls(**values)


def episode_record(layout: PickLayout, offset: tuple[float, float]) -> dict[str, Any]:
    """What an episode's metadata says about its pick scene (JSON-able): instruction, target, objects."""
    if not layout.instruction:
        raise ValueError("an episode record needs a layout with its target and phrasing pinned (for_episode)")
    return {
        "instruction": layout.instruction,
        "target": layout.target,
        "template": layout.template,
        "phrasings": layout.phrasings,
        "objects": [asdict(o) for o in layout.placed(offset)],
    }


def default_layout() -> PickLayout:
    """The default scene: the first train objects with distinct shapes and colours, in the first slots."""
    names = choose_objects(None, split_objects("train"), (), DEFAULT_OBJECTS)
    return PickLayout(tuple(PlacedObject(name, *SLOTS[i]) for i, name in enumerate(names)))


def _check_workspace(objects: tuple[PlacedObject, ...]) -> None:
    """Objects stand on the slot grid (within the jitter): where the keep-out and the reach are measured."""
    xs, ys = [x for x, _ in SLOTS], [y for _, y in SLOTS]
    lo, hi = (min(xs) - SLOT_JITTER, min(ys) - SLOT_JITTER), (max(xs) + SLOT_JITTER, max(ys) + SLOT_JITTER)
    for o in objects:
        if not (lo[0] - 1e-9 <= o.x <= hi[0] + 1e-9 and lo[1] - 1e-9 <= o.y <= hi[1] + 1e-9):
            raise ValueError(
                f"pick object {o.name} at ({o.x:.3f}, {o.y:.3f}) is off the pick workspace x in [{lo[0]:.3f}, "
                f"{hi[0]:.3f}], y in [{lo[1]:.3f}, {hi[1]:.3f}] (table frame, metres)"
            )


def _check_clearance(objects: tuple[PlacedObject, ...]) -> None:
    for i, a in enumerate(objects):
        for b in objects[i + 1 :]:
            gap = math.hypot(a.x - b.x, a.y - b.y) - a.radius - b.radius
            if gap < 0:
                raise ValueError(
                    f"pick objects {a.name} at ({a.x:.3f}, {a.y:.3f}) and {b.name} at ({b.x:.3f}, {b.y:.3f}) overlap"
                )


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def workspace_keepout(clearance: float) -> tuple[float, float, float, float]:
    """The box (table frame: xmin, ymin, xmax, ymax) any pick object can reach: every slot, its jitter,
    the largest footprint and the widest arrangement offset (``object_pos``), plus ``clearance``.
    Distractors stand outside it, so they never block a grasp."""
    spec = get_factor("object_pos")
    low, high = spec.widest
    reach = max(math.hypot(*s.footprint) for s in SHAPES.values()) + SLOT_JITTER + clearance
    xs, ys = [x for x, _ in SLOTS], [y for _, y in SLOTS]
    return (min(xs) + low[0] - reach, min(ys) + low[1] - reach, max(xs) + high[0] + reach, max(ys) + high[1] + reach)


def choose_objects(
    rng: np.random.Generator | None, primary: Sequence[str], fill: Sequence[str], k: int
) -> tuple[str, ...]:
    """``k`` objects with distinct shapes and colours: as many from ``primary`` as fit, then from ``fill``.

    With ``rng`` the pools are shuffled (a few greedy passes keep the largest set found); without it
    they are taken in order (the default scene).
    """
    best: tuple[str, ...] = ()
    for _ in range(MAX_TRIES if rng is not None else 1):
        first = list(primary) if rng is None else [primary[i] for i in rng.permutation(len(primary))]
        chosen = _greedy(first, [], k)
        if len(chosen) > len(best):
            best = tuple(chosen)
        if len(best) == k:
            break
    if len(best) < k:
        rest = list(fill) if rng is None else [fill[i] for i in rng.permutation(len(fill))]
        best = tuple(_greedy(rest, list(best), k))
    if len(best) < k:
        raise ValueError(f"cannot find {k} objects with distinct shapes and colours in the pools")
    return best


def _greedy(pool: Sequence[str], chosen: list[str], k: int) -> list[str]:
    chosen = list(chosen)
    for name in pool:
        if len(chosen) == k:
            break
        obj = get_object(name)
        if all(get_object(c).shape != obj.shape and get_object(c).colour != obj.colour for c in chosen):
            chosen.append(name)
    return chosen
