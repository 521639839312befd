"""Level of detail for the robot's meshes: what the ``lod`` render quality adds to ``fast``.

On the software rasteriser (EGL on Mesa's llvmpipe) a frame of a Factor World scene is bound by triangles,
not pixels: the Sawyer's 11 visible meshes hold about 67,000 of them and cost most of a frame. The ``lod``
quality draws them from copies with :data:`LOD_REDUCTION` of their triangles removed by quadric decimation
(``fast-simplification``). Physics never sees the copies:

* a mesh drawn only by render-only geoms (``contype = conaffinity = 0`` on a body with an explicit
  inertial, so they add no mass) gets the simplified data in place;
* a geom that is drawn and also collides (the Sawyer's ``l6`` and ``eGripperBase``) keeps its mesh and all
  its physics and is only hidden (group :data:`HIDDEN_GROUP`); a render-only twin on the same body draws the
  simplified copy.

Trajectories are therefore bit-identical to the other qualities; pixels change a little (measured side by
side with ``scripts/bench_render.py``; table in ``docs/factors.md``).

Each mesh is simplified once: results are kept in this process and on disk, under
``$XDG_CACHE_HOME/lerobot_factorworld/lod/`` (``~/.cache/...`` without it), keyed by the SHA-256 of the
mesh file's bytes, the reduction, the aggressiveness, :data:`LOD_VERSION` and the package's version; a
scene build only reads them.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import os
from pathlib import Path

import mujoco
import numpy as np

from ..assets.mesh import weld
from ..assets.mesh_io import read_stl
from ..core.io import temporary_path

LOD_VERSION = 1
"""Part of every disk-cache key: bump it when the vertex preparation changes, so stale entries are ignored."""

ROBOT_ROOT = "base"  # the Sawyer's root body in Meta-World's scenes
HIDDEN_GROUP = 3  # a geom group MuJoCo does not draw by default (a collision geom's drawn twin replaces it)

LOD_REDUCTION = 0.8
"""Share of each robot mesh's triangles removed (67,000 -> 15,000 drawn triangles in door-open). Measured at
84 and 224 px on door-open and pick-place (``docs/factors.md``): 0.8 keeps the mean pixel change under 1/255
and about 1% of pixels changing by more than 16 levels; 0.9 doubles both for ~15% more speed."""

LOD_AGGRESSIVENESS = 3.0
"""``fast-simplification``'s ``agg``: 3 halves the pixel change of its default (7) at the same triangle count;
at 1 or below it stops short of the target reduction (about half of the triangles stay)."""

LOD_MESHES = ("l0", "eGripperBase", "l1", "head", "base", "l4", "l6", "l5", "l3", "l2", "pedestal")
"""The Sawyer's meshes (names in Meta-World's ``xyz_base`` assets), largest first (13,510 to 2,371 triangles)."""

_simplified: dict[tuple[str, float, float], tuple[np.ndarray, np.ndarray]] = {}
stats = {"simplified": 0, "disk_hits": 0, "memory_hits": 0}
"""Counters (for tests and benchmarks): meshes simplified, read from the disk cache, served from memory."""


def cache_dir() -> Path:
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "lerobot_factorworld" / "lod"


def clear_memory_cache() -> None:
    """Forget the simplified meshes held in this process (the disk cache stays)."""
    _simplified.clear()


def simplified_mesh(
    path: str | Path, reduction: float = LOD_REDUCTION, agg: float = LOD_AGGRESSIVENESS
) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (N, 3) float64, faces (M, 3) int32) of the STL at ``path`` with ``reduction`` of its
    triangles removed; cached in memory and on disk (see the module docstring)."""
    key = (str(Path(path).resolve()), float(reduction), float(agg))
    if key in _simplified:
        stats["memory_hits"] += 1
        return _simplified[key]
    digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()[:32]
    version = importlib.metadata.version("fast-simplification")
    file = cache_dir() / f"{digest}-r{reduction:.4f}-a{agg:g}-v{LOD_VERSION}-fs{version}.npz"
    try:
        with np.load(file) as saved:
            result = (saved["vertices"], saved["faces"])
        stats["disk_hits"] += 1
    except (OSError, KeyError, ValueError):
        result = _simplify(path, reduction, agg)
        stats["simplified"] += 1
        _save(file, result)
    _simplified[key] = result
    return result


def _simplify(path: str | Path, reduction: float, agg: float) -> tuple[np.ndarray, np.ndarray]:
    import fast_simplification  # noqa: PLC0415  (compiled extension, needed only when a cache entry is missing)

    vertices, faces = weld(*read_stl(path))
    points, triangles = fast_simplification.simplify(
        vertices, faces.astype(np.int32), target_reduction=reduction, agg=agg
    )
    return np.asarray(points, np.float64), np.asarray(triangles, np.int32)


def _save(file: Path, mesh: tuple[np.ndarray, np.ndarray]) -> None:
    tmp = temporary_path(file).with_suffix(".npz")
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        np.savez(tmp, vertices=mesh[0], faces=mesh[1])
        tmp.replace(file)
    except OSError:
        pass  # a read-only cache folder: simplify again in the next process, never fail a scene build
    finally:
        tmp.unlink(missing_ok=True)


def apply_lod(
    spec: mujoco.MjSpec,
    meshes: tuple[str, ...] = LOD_MESHES,
    reduction: float = LOD_REDUCTION,
    agg: float = LOD_AGGRESSIVENESS,
) -> list[str]:
    """Draw the robot's ``meshes`` from simplified copies (see the module docstring); returns those swapped.

    Physics is untouched: render-only meshes get the new data in place; a drawn collision geom is hidden
    and a render-only twin on its body draws the copy (``fw_lod_<mesh>``).
    """
    robot = {ROBOT_ROOT, *(b.name for b in spec.body(ROBOT_ROOT).find_all(mujoco.mjtObj.mjOBJ_BODY))}
    users: dict[str, list] = {}
    for geom in spec.geoms:
        if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
            users.setdefault(geom.meshname, []).append(geom)
    swapped = []
    for name in meshes:
        mesh = spec.mesh(name)
        geoms = users.get(name, [])
        if mesh is None or not mesh.file.lower().endswith(".stl") or not geoms:
            continue
        if not all(g.parent.name in robot and bool(g.parent.explicitinertial) for g in geoms):
            continue  # a mesh outside the robot, or one that could add mass: leave it as it is
        vertices, faces = simplified_mesh(_mesh_path(spec, mesh), reduction, agg)
        uservert, userface = vertices.flatten().tolist(), faces.flatten().tolist()
        if all(_render_only(g) for g in geoms):
            mesh.file = ""
            mesh.uservert, mesh.userface = uservert, userface
        else:
            lod_name = f"fw_lod_{name}"
            spec.add_mesh(name=lod_name, uservert=uservert, userface=userface, scale=mesh.scale)
            for geom in geoms:
                if _render_only(geom):
                    geom.meshname = lod_name
                elif geom.group < HIDDEN_GROUP:
                    _add_twin(geom, lod_name)
        swapped.append(name)
    return swapped


def _render_only(geom) -> bool:
    return geom.contype == 0 and geom.conaffinity == 0


def _add_twin(geom, mesh_name: str) -> None:
    """A render-only copy of ``geom`` drawing ``mesh_name``; ``geom`` keeps its physics and is hidden."""
    twin = geom.parent.add_geom(
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=mesh_name,
        pos=geom.pos,
        quat=geom.quat,
        contype=0,
        conaffinity=0,
        group=geom.group,
        mass=0.0,
    )
    twin.rgba = geom.rgba
    twin.material = geom.material
    geom.group = HIDDEN_GROUP


def _mesh_path(spec: mujoco.MjSpec, mesh) -> Path:
    path = Path(mesh.file)
    if path.is_absolute():
        return path
    return Path(spec.modelfiledir) / (spec.meshdir or "") / path
