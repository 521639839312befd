"""The ``pick`` family's facts, in one place: objects, names, phrasings, splits, success rule.

Everything else (the task row, the scene, the expert, sampling, the support matrix and the docs)
derives from this module.

Objects are (shape family, colour) pairs drawn as MuJoCo primitives large enough to tell apart at
84x84 (about 5-12 cm, the width the Sawyer gripper can hold). A scene never holds two objects of the
same shape family or of the same colour, so every phrasing names exactly one object.

Held-out objects and phrasings are split with the project's asset-split function
(:func:`lerobot_factorworld.assets.split_pool`: a seeded sha256 ranking, identical on every machine),
so that "new objects" and "new phrasings" are fixed, documented sets like the held-out textures and
shapes. Held-out objects are new (shape, colour) pairs: each shape and each colour is seen in training.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache

from ..assets.library import SPLITS_SEED, split_pool
from ..core.splits import check_split
from ..tasks import get_task

PICK_TASK = "pick"
"""The family's task name (``factorworld tasks``, ``--env.task=pick``)."""
_ROW = get_task(PICK_TASK)

# --- success rule ------------------------------------------------------------------------------

LIFT_HEIGHT = 0.05
"""Metres the named object's centre must rise above where it rested for the lift to count."""
HOLD_STEPS = 10
"""Consecutive control steps (12.5 ms each: 0.125 s) the named object must stay lifted."""
LIFT_MARGIN = 0.03
"""The lift goal (the state vector's goal slot) lies this much above the success height."""
WRONG_LIFT_HEIGHT = 0.02
"""An other object whose centre rises this much above its rest has been lifted: the episode fails."""
REACH_RADIUS = 0.03
"""The gripper's centre this close to an object's has reached it (Meta-World pick-place's ``near_object``), the
named object or, for the ``reached_other`` stage, another."""
MAX_EPISODE_STEPS = _ROW.max_episode_steps
"""Horizon (the task row's): the scripted expert needs about 80 steps."""

# --- scene size ----------------------------------------------------------------------------------

MIN_OBJECTS, MAX_OBJECTS = 3, 6
DEFAULT_OBJECTS = 4
"""Objects on the table per scene (``--sampling.n_objects``)."""

SLOTS: tuple[tuple[float, float], ...] = tuple((x, y) for y in (-0.06, 0.10) for x in (-0.17, 0.0, 0.17))
"""Where objects stand (table frame, metres from the table centre): a 3 x 2 grid wide enough that the
open gripper (fingers 9.4 cm apart along y) never touches a neighbour of the object it grasps."""
SLOT_JITTER = 0.008
"""Each object stands up to this far (x and y) from its slot centre."""


@dataclass(frozen=True)
class ShapeFamily:
    """One shape family: how it is named and built.

    Attributes:
        name: Identifier (part of object names).
        nouns: The primary noun and a synonym used by phrasings ("mug", "cup").
        asset_family: The procedural shape family (:mod:`lerobot_factorworld.assets`) it looks like: no
            distractor is drawn from these families, so no distractor looks like a pick object.
        half_height: Half of the object's height: its centre rests this high above the table.
        footprint: Half extents (x, y) of its footprint in its own frame (layout and keep-out).
        max_yaw: Largest |yaw| (radians) a scene gives it: elongated shapes stay across the gripper,
            whose fingers close along y.
    """

    name: str
    nouns: tuple[str, str]
    asset_family: str
    half_height: float
    footprint: tuple[float, float]
    max_yaw: float


SHAPES: dict[str, ShapeFamily] = {
    s.name: s
    for s in (
        ShapeFamily("cube", ("cube", "block"), "box", 0.026, (0.026, 0.026), 0.35),
        ShapeFamily("can", ("can", "tin"), "cylinder", 0.04, (0.026, 0.026), 3.1416),
        ShapeFamily("ball", ("ball", "sphere"), "ellipsoid", 0.03, (0.03, 0.03), 3.1416),
        ShapeFamily("mug", ("mug", "cup"), "mug", 0.035, (0.05, 0.027), 0.35),
        ShapeFamily("bar", ("bar", "stick"), "superellipsoid", 0.02, (0.06, 0.018), 0.2),
        ShapeFamily("dumbbell", ("dumbbell", "weight"), "capsule", 0.022, (0.067, 0.022), 0.2),
    )
}
"""The six shape families (MuJoCo primitives, see :mod:`lerobot_factorworld.pick.scene`)."""

COLOURS: dict[str, tuple[float, float, float]] = {
    "red": (0.85, 0.08, 0.08),
    "green": (0.12, 0.62, 0.15),
    "blue": (0.1, 0.28, 0.92),
    "yellow": (0.95, 0.82, 0.08),
    "purple": (0.55, 0.18, 0.78),
    "white": (0.93, 0.93, 0.93),
}
"""Object colours by the word phrasings use for them."""


@dataclass(frozen=True)
class PickObject:
    """One catalogue object: a shape family in a colour."""

    shape: str
    colour: str

    @property
    def name(self) -> str:
        """Identifier used in configurations and dataset metadata, e.g. ``red_mug``."""
        return f"{self.colour}_{self.shape}"

    @property
    def rgb(self) -> tuple[float, float, float]:
        return COLOURS[self.colour]

    @property
    def family(self) -> ShapeFamily:
        return SHAPES[self.shape]


OBJECTS: dict[str, PickObject] = {
    obj.name: obj for obj in (PickObject(shape, colour) for shape in SHAPES for colour in COLOURS)
}
"""All 36 catalogue objects by name."""


def get_object(name: str) -> PickObject:
    if name not in OBJECTS:
        raise ValueError(f"unknown pick object {name!r}; valid objects: {', '.join(OBJECTS)}")
    return OBJECTS[name]


# --- phrasings ---------------------------------------------------------------------------------

TEMPLATES: tuple[str, ...] = (
    "pick up the {colour} {noun}",
    "pick {colour} {noun}",
    "grab the {colour} {noun}",
    "lift the {colour} {synonym}",
    "pick up the {noun}",
    "grab the {synonym}",
    "lift the {noun}",
    "pick the {colour} {synonym} up",
    "take the {colour} {noun}",
    "raise the {synonym}",
    "get the {colour} {synonym}",
    "hold up the {noun}",
    "pick up the {synonym}",
    "grasp the {colour} {noun} and lift it",
)
"""Phrasing templates. ``{noun}``/``{synonym}`` are the target's shape nouns, ``{colour}`` its colour;
every template names the shape, so a distractor of another shape family is never referred to."""

_FIELDS = re.compile(r"\{(\w+)\}")
_INSTRUCTION = re.compile(r"^[a-z]+( [a-z]+)*$")


def render(template: str, name: str) -> str:
    """The instruction a template gives for object ``name``: only words, never an id, value or seed."""
    if template not in TEMPLATES:
        raise ValueError(f"unknown phrasing template {template!r}; valid templates: {list(TEMPLATES)}")
    obj = get_object(name)
    noun, synonym = obj.family.nouns
    text = template.format(colour=obj.colour, noun=noun, synonym=synonym)
    check_instruction(text)
    return text


def check_instruction(text: str) -> None:
    """An instruction is lowercase words separated by single spaces (no digits, ids or punctuation)."""
    if not _INSTRUCTION.match(text):
        raise ValueError(f"instruction {text!r} is not plain lowercase words")


def referents(text: str, names: tuple[str, ...] | list[str]) -> list[str]:
    """The objects among ``names`` that ``text`` can refer to (its shape noun, and colour when named)."""
    words = set(text.split())
    out = []
    for name in names:
        obj = get_object(name)
        if not words & set(obj.family.nouns):
            continue
        named_colours = words & set(COLOURS)
        if named_colours and named_colours != {obj.colour}:
            continue
        out.append(name)
    return out


# --- splits ------------------------------------------------------------------------------------


@cache
def object_split() -> dict[str, tuple[str, ...]]:
    """``{"train": names, "eval": names}``: held-out objects are new (shape, colour) pairs."""
    split = split_pool(list(OBJECTS), "shape", SPLITS_SEED)
    for kind, values in (("shape", SHAPES), ("colour", COLOURS)):
        seen = {getattr(OBJECTS[n], kind) for n in split["train"]}
        assert seen == set(values), f"the object split leaves a {kind} out of train: {set(values) - seen}"
    return split


@cache
def phrasing_split() -> dict[str, tuple[str, ...]]:
    """``{"train": templates, "eval": templates}`` (held-out phrasings), in :data:`TEMPLATES` order."""
    split = split_pool(list(TEMPLATES), "shape", SPLITS_SEED)
    ordered = {k: tuple(t for t in TEMPLATES if t in v) for k, v in split.items()}
    fields = {f for t in ordered["train"] for f in _FIELDS.findall(t)}
    assert fields == {"colour", "noun", "synonym"}, f"train phrasings use only {fields}"
    return ordered


def split_objects(split: str) -> tuple[str, ...]:
    check_split(split)
    return object_split()[split]


def split_templates(split: str) -> tuple[str, ...]:
    check_split(split)
    return phrasing_split()[split]


# --- the task row's facts ------------------------------------------------------------------------

DEFAULT_INSTRUCTION = _ROW.instruction
"""The task row's instruction, shown by ``factorworld tasks``; every episode gets its own instruction."""

LOOKALIKE_FAMILIES: tuple[str, ...] = tuple(sorted({s.asset_family for s in SHAPES.values()}))
"""Procedural shape families no distractor is drawn from in pick scenes."""

UNSUPPORTED_FACTORS: tuple[tuple[str, str], ...] = _ROW.unsupported
"""Factors that do not apply to the family, with the reason (the task row's)."""
