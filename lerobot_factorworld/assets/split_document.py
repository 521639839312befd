"""The generator of ``asset_splits.json``, the single source of the built-in train/eval asset splits.

Kept apart from the asset loader (:mod:`.library`), which only reads the file: writing it needs the task
rows and their Meta-World scenes (the families the default scenes show stay in ``train``), reading it
does not. ``scripts/make_asset_splits.py`` writes the file; the tests check it is up to date.
"""

from __future__ import annotations

from typing import Any

from ..core.splits import SPLITS
from ..tasks import TASKS
from .library import (
    ASSET_SPLITS,
    KINDS,
    SPLITS_SEED,
    TRAIN_FRACTION,
    AssetKind,
    builtin_split,
    check_kind,
    jsonable,
    splits_digest,
)
from .scenes import scene_texture_families


def scene_seen_families(kind: AssetKind) -> tuple[str, ...]:
    """Built-in families the default scenes show, which the family split always puts in ``train``.

    A factor a study does not vary keeps its default, so these are seen in training whatever the split.
    Textures: the families of every texture any task's default scene shows, read from the scenes
    (:func:`~lerobot_factorworld.assets.scenes.scene_assets`: the table's wood, the floor's tiles, the
    robot's and fixtures' metal, the walls' bricks). Shapes: the families of the tasks' loose objects
    (:attr:`~lerobot_factorworld.tasks.TaskSpec.object_family`: the puck is a cylinder, ...), which the
    object-shape factor replaces; a fixture's meshes need no place here, because no distractor of its task
    is drawn from their families (:func:`~lerobot_factorworld.assets.scenes.scene_shape_families`).
    Holding any of them out would put a training look in the evaluation split.
    """
    if check_kind(kind) == "texture":
        seen = {family for task in TASKS for family in scene_texture_families(task)}
    else:
        seen = {task.object_family for task in TASKS.values() if task.object_family}
    return tuple(sorted(seen))


def builtin_splits_document(seed: int = SPLITS_SEED) -> dict[str, Any]:
    """The content of ``asset_splits.json``: both split modes, recomputed from the code's built-in pools."""
    seen = {kind: scene_seen_families(kind) for kind in KINDS}  # type: ignore[arg-type]
    lists = {mode: {kind: builtin_split(mode, kind, seed, seen[kind]) for kind in KINDS} for mode in ASSET_SPLITS}  # type: ignore[arg-type]
    return {
        "generator": "scripts/make_asset_splits.py",
        "seed": seed,
        "train_fraction": dict(TRAIN_FRACTION),
        "seen_families": {kind: list(families) for kind, families in seen.items()},
        "counts": {
            mode: {kind: {s: len(d["names"][s]) for s in SPLITS} for kind, d in by_kind.items()}
            for mode, by_kind in lists.items()
        },
        "splits": jsonable(lists),
        "sha256": splits_digest(lists),
    }
