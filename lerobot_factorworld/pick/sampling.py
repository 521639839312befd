"""Seeded pick layouts for training environments, and the two language-generalization conditions.

Layouts draw from their own stream (``[seed, split, LAYOUT_STREAM]``), apart from every factor's, so
adding pick content never changes a factor value and the same seeds always give the same scenes.

Conditions (evaluated like a shifted factor: test environment ``j`` derives from training environment
``j % N``, same factors, same object poses):

- ``held_out_phrasings``: the same scenes and targets, phrased with the held-out templates only;
- ``held_out_objects``: the same object poses, holding held-out objects (new shape-colour pairs),
  and every episode names one of them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from ..core.splits import SPLITS
from ..families import family_of
from .catalog import SLOT_JITTER, SLOTS, get_object, split_objects, split_templates
from .layout import PickLayout, PlacedObject, choose_objects

LAYOUT_STREAM = 1_000  # beyond every factor's index in ``factor_rng``
HELD_OUT_PHRASINGS = "held_out_phrasings"
HELD_OUT_OBJECTS = "held_out_objects"
CONDITIONS = (HELD_OUT_PHRASINGS, HELD_OUT_OBJECTS)
"""The language-generalization conditions (``--env.shifts='[held_out_phrasings,held_out_objects]'``)."""


def layout_rng(seed: int, split: str, *extra: int) -> np.random.Generator:
    return np.random.default_rng([seed, SPLITS.index(split), LAYOUT_STREAM, *extra])


def _poses(rng: np.random.Generator, names: Sequence[str], slots: Sequence[int]) -> tuple[PlacedObject, ...]:
    out = []
    for name, slot in zip(names, slots, strict=True):
        x, y = SLOTS[slot]
        jitter = rng.uniform(-SLOT_JITTER, SLOT_JITTER, size=2)
        out.append(PlacedObject(name, x + float(jitter[0]), y + float(jitter[1]), _yaw(rng, name)))
    return tuple(out)


def _yaw(rng: np.random.Generator, name: str) -> float:
    """A yaw the gripper can grasp from: within the family's limit, either way round."""
    limit = get_object(name).family.max_yaw
    yaw, flip = float(rng.uniform(-limit, limit)), bool(rng.integers(2))
    return yaw + (np.pi if flip and limit < np.pi else 0.0)


def check_fixed_template(template: str) -> None:
    """A fixed phrasing (``SamplingOptions.template``) is one of the training templates: a held-out one would put
    the ``held_out_phrasings`` condition's phrasings in the training data (the error names the valid ones)."""
    train = split_templates("train")
    if template and template not in train:
        raise ValueError(f"template must be one of the training phrasings {list(train)} (or empty), got {template!r}")


def sample_layouts(n: int, seed: int, split: str = "train", n_objects: int = 4, template: str = "") -> list[PickLayout]:
    """``n`` layouts of ``n_objects`` objects from ``split``'s objects (``eval``: held-out objects named), every
    episode phrased with ``template`` where one is given (else a template drawn per episode). The template is drawn
    from no stream: a fixed phrasing leaves the scenes and targets as they are."""
    rng = layout_rng(seed, split)
    out = []
    for _ in range(n):
        if split == "train":
            names = choose_objects(rng, split_objects("train"), (), n_objects)
        else:
            names = choose_objects(rng, split_objects("eval"), split_objects("train"), n_objects)
        slots = rng.permutation(len(SLOTS))[:n_objects]
        targets = () if split == "train" else tuple(n for n in names if n in split_objects("eval"))
        out.append(PickLayout(_poses(rng, names, slots), targets=targets, template=template))
    return out


def held_out_phrasings(layouts: Sequence[PickLayout]) -> list[PickLayout]:
    """The same layouts, phrased with held-out templates (a pinned template is dropped)."""
    return [replace(layout, phrasings="eval", template="") for layout in layouts]


def held_out_objects(layouts: Sequence[PickLayout], seed: int) -> list[PickLayout]:
    """The same object poses holding held-out objects; every episode names one of them."""
    rng = layout_rng(seed, "eval", 1)
    out = []
    for layout in layouts:
        k = len(layout.objects)
        names = choose_objects(rng, split_objects("eval"), split_objects("train"), k)
        objects = tuple(
            PlacedObject(name, old.x, old.y, _yaw(rng, name)) for name, old in zip(names, layout.objects, strict=True)
        )
        held_out = tuple(n for n in names if n in split_objects("eval"))
        out.append(replace(layout, objects=objects, targets=held_out, target=""))
    return out


def check_condition(condition: str, tasks: Sequence[str]) -> None:
    """A language condition applies to pick tasks only (the error names them)."""
    others = [t for t in tasks if condition not in family_of(t).conditions]
    if others:
        raise ValueError(
            f"condition {condition!r} applies to the pick family only (its held-out phrasings and objects), "
            f"not to {', '.join(others)}"
        )


def language_shift(base: Sequence, condition: str, n: int, seed: int) -> list:
    """Test environments of a language condition: environment ``j`` is training environment ``j % N``
    with held-out phrasings, or with held-out objects at the same poses (every other value kept)."""
    if condition not in CONDITIONS:
        raise ValueError(f"unknown language condition {condition!r}; valid: {', '.join(CONDITIONS)}")
    parents = [base[j % len(base)] for j in range(n)]
    if any(p.content is None for p in parents):
        check_condition(condition, sorted({p.task for p in parents}))
    layouts = [p.content for p in parents]
    layouts = held_out_phrasings(layouts) if condition == HELD_OUT_PHRASINGS else held_out_objects(layouts, seed)
    return [
        replace(parent, content=layout, split="eval", env_id=f"{parent.task}/{condition}/{j:03d}")
        for j, (parent, layout) in enumerate(zip(parents, layouts, strict=True))
    ]
