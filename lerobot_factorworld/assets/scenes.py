"""Which built-in assets each task's default scene shows, read from the task's Meta-World XML.

Meta-World paints its fixtures with its own textures (the wall's bricks, the door's metal) and builds them
from its own meshes (the faucet's head, the bin, the hoop), and those files are in the built-in pools too.
Reading them from the scene itself, not from a hand-kept list, is what three rules rely on:

* the family split keeps in ``train`` every texture family a default scene shows
  (:func:`~lerobot_factorworld.assets.library.seen_families`): a factor a study does not vary keeps its
  default, so that look is seen in training whatever the split;
* no distractor comes from a shape family the task's scene shows (:func:`scene_shape_families`): no second
  hoop, bin, faucet head or button next to the task's own;
* a sampled table texture avoids the textures of the task's object when the object keeps its own
  (:attr:`SceneAssets.object_textures`): no table of the door's metal.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
from metaworld.env_dict import ALL_V3_ENVIRONMENTS

from ..families import family_of
from ..tasks import TaskSpec, get_task
from .library import METAWORLD_MESH_FAMILIES, METAWORLD_TEXTURE_FAMILIES, asset_family, metaworld_assets_dir

VISIBLE_GROUPS = (0, 1, 2)  # geom groups MuJoCo renders by default


def metaworld_xml(task: TaskSpec) -> str:
    """The Meta-World XML file of ``task``'s scene (of its ``metaworld_base`` for a task family)."""
    cls = ALL_V3_ENVIRONMENTS[task.metaworld_name]
    return cls.model_name.fget(None)  # the property only joins a constant path


@dataclass(frozen=True)
class SceneAssets:
    """Built-in asset names (``metaworld:...``, sorted) on the visible geoms of a task's default scene.

    Attributes:
        textures: Textures of every visible material (table, floor, robot, fixtures, walls).
        meshes: Meshes of the built-in shape pool (:data:`METAWORLD_MESH_FAMILIES`) that visible geoms use;
            the robot's and the table's meshes are not in the pool.
        object_textures: The textures of the task's object (``TaskSpec.object_bodies``): what the object
            shows while the object-texture factor keeps its default.
        object_meshes: The ``meshes`` of the task's object (what an object-shape value replaces).
    """

    textures: tuple[str, ...]
    meshes: tuple[str, ...]
    object_textures: tuple[str, ...]
    object_meshes: tuple[str, ...]


@functools.cache
def scene_assets(task_name: str) -> SceneAssets:
    """Parse the task's Meta-World XML (no compilation: ~10 ms per task once Meta-World is imported)."""
    task = get_task(task_name)
    xml = Path(metaworld_xml(task))
    spec = mujoco.MjSpec.from_file(str(xml))
    object_bodies = set()
    for root in task.object_bodies:
        body = spec.body(root)
        object_bodies |= {body.name, *(b.name for b in body.find_all(mujoco.mjtObj.mjOBJ_BODY))}
    textures, meshes, object_textures, object_meshes = set(), set(), set(), set()
    for geom in spec.geoms:
        material = spec.material(geom.material) if geom.material else None
        if geom.group not in VISIBLE_GROUPS or geom.rgba[3] <= 0 or (material is not None and material.rgba[3] <= 0):
            continue
        on_object = geom.parent.name in object_bodies
        if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
            name = _builtin_name(xml, spec.meshdir, spec.mesh(geom.meshname).file)
            meshes.add(name)
            if on_object:
                object_meshes.add(name)
        for texture in material.textures if material is not None else ():
            file = spec.texture(texture).file if texture else ""
            if file:
                name = _builtin_name(xml, spec.texturedir, file)
                textures.add(name)
                if on_object:
                    object_textures.add(name)
    return SceneAssets(
        _in_pool(textures, METAWORLD_TEXTURE_FAMILIES),
        _in_pool(meshes, METAWORLD_MESH_FAMILIES),
        _in_pool(object_textures, METAWORLD_TEXTURE_FAMILIES),
        _in_pool(object_meshes, METAWORLD_MESH_FAMILIES),
    )


def _in_pool(names: set[str], pool: Mapping[str, str]) -> tuple[str, ...]:
    """The names among ``names`` that are in a built-in pool (its Meta-World paths), sorted."""
    return tuple(sorted(n for n in names if n.removeprefix("metaworld:") in pool))


def _builtin_name(xml: Path, asset_dir: str, file: str) -> str:
    """``metaworld:<path inside metaworld/assets>`` of a file an XML names (relative to the main file's
    folder, as MuJoCo resolves it), or its absolute path when it lies elsewhere."""
    path = Path(os.path.normpath(xml.parent / asset_dir / file))
    try:
        return f"metaworld:{path.relative_to(metaworld_assets_dir()).as_posix()}"
    except ValueError:
        return str(path)


def scene_texture_families(task_name: str) -> tuple[str, ...]:
    """Families of the textures the task's default scene shows (sorted)."""
    return tuple(sorted({asset_family(n) for n in scene_assets(task_name).textures}))


def scene_shape_families(task_name: str, object_family: str | None = None) -> tuple[str, ...]:
    """Shape families the task's scene shows (sorted): of its built-in meshes (the fixtures' parts), of its
    loose object (``object_family`` when the object was reshaped, else ``TaskSpec.object_family``) and of a
    task family's objects (``TaskFamily.lookalike_families``). No distractor is drawn from them."""
    task, shown = get_task(task_name), scene_assets(task_name)
    meshes = set(shown.meshes) - (set(shown.object_meshes) if object_family is not None else set())
    own = object_family if object_family is not None else task.object_family
    lookalike = family_of(task).lookalike_families(task)
    families = {asset_family(n) for n in meshes} | set(lookalike) | ({own} if own else set())
    return tuple(sorted(families))
