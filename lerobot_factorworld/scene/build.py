"""Pure scene builder: (task, factor values, render settings) -> compiled ``MjModel``.

Every factor except the per-episode ones (object and arm start positions, set at reset) is an
``MjSpec`` edit applied to Meta-World's unmodified task XML, so factors compose without overwriting
each other and a scene never inherits edits from a previous one.

Table position is implemented by moving the robot, its cameras and the floor by the opposite offset:
relative geometry is identical to moving the table and everything on it, while the task's own
world-frame logic (object and goal positions, mocap bounds, success tests) stays valid untouched.
The world frame is therefore the table's; the robot's own readings are expressed in the robot's
frame (:func:`robot_frame_offset`), so that the robot sees the table move as in the public code.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Literal

import mujoco
import numpy as np

from ..assets import load_mesh, load_texture
from ..assets.scenes import VISIBLE_GROUPS, metaworld_xml
from ..core.checks import check_choice
from ..factors.registry import is_rgb, parse_rgb
from ..factors.values import FactorValues, SceneObject
from ..tasks import TaskSpec, get_task
from .cameras import CAMERAS, DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE
from .lod import apply_lod

Quality = Literal["fast", "full", "lod"]
QUALITIES = ("fast", "full", "lod")
DEFAULT_QUALITY: Quality = "fast"  # every default quality of Factor World's own observation derives from this one
"""Render qualities. A quality is part of a dataset's recorded settings, so data of different qualities never mix.

* ``fast`` (the default): Meta-World's scene without shadows, multisampling or reflections, which dominate
  the software rasteriser's cost;
* ``full``: Meta-World's own settings (4096x4096 shadow map, 4x multisampling, reflective materials);
* ``lod``: ``fast`` with the robot's meshes drawn from simplified copies (:mod:`.lod`, 80% fewer triangles):
  trades a small pixel change (mean under 1/255, about 1% of pixels off by more than 16 levels) for ~2x
  faster frames on the software rasteriser; physics and trajectories identical to ``fast``.
"""

TABLE_CENTER = np.array([0.0, 0.6, 0.0])  # world position of the table top's centre (body ``tablelink``)
ROBOT_ROOT = "base"
FLOOR_GEOM = "floor"
TABLE_MATERIAL = "table_wood"
FLOOR_MATERIAL = "basic_floor"
TEXTURE_SIZE = 128
DEFAULT_HEADLIGHT = (0.4, 0.4)  # Meta-World's headlight (ambient, diffuse)


@dataclass(frozen=True)
class ObjectGeometry:
    """Facts about a task's manipulated object in its default scene (for size and shape edits)."""

    extent: float  # largest bounding-box side of the object's collision geometry, metres
    dims: tuple[float, float, float]  # its bounding-box sides along x, y, z
    bottom: float  # lowest point of that geometry relative to the root body origin (z, metres)
    mass: float  # total mass of the object's subtree, kg


def load_task_spec(task: TaskSpec) -> mujoco.MjSpec:
    return mujoco.MjSpec.from_file(metaworld_xml(task))


@cache
def object_geometry(task_name: str) -> ObjectGeometry:
    """Measure the object in the task's unmodified scene (cached: the XML never changes)."""
    task = get_task(task_name)
    model = load_task_spec(task).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    root = model.body(task.object_bodies[0]).id
    lows, highs = [], []
    for g in subtree_geoms(model, task.object_bodies):
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        corners = geom_world_corners(model, data, g)
        lows.append(corners.min(axis=0))
        highs.append(corners.max(axis=0))
    low, high = np.min(lows, axis=0), np.max(highs, axis=0)
    mass = float(model.body_subtreemass[root])
    dims = tuple(float(d) for d in high - low)
    return ObjectGeometry(float(max(dims)), dims, float(low[2] - data.xpos[root][2]), mass)


def build_model(
    task: str | TaskSpec,
    factors: FactorValues,
    cameras: tuple[str, ...] = DEFAULT_CAMERAS,
    quality: Quality = DEFAULT_QUALITY,
    image_size: tuple[int, int] = (DEFAULT_IMAGE_SIZE, DEFAULT_IMAGE_SIZE),
) -> mujoco.MjModel:
    """Compile the scene of ``task`` under ``factors`` (``image_size`` is (height, width))."""
    return build_spec(task, factors, cameras, quality, image_size).compile()


def build_spec(
    task: str | TaskSpec,
    factors: FactorValues,
    cameras: tuple[str, ...] = DEFAULT_CAMERAS,
    quality: Quality = DEFAULT_QUALITY,
    image_size: tuple[int, int] = (DEFAULT_IMAGE_SIZE, DEFAULT_IMAGE_SIZE),
) -> mujoco.MjSpec:
    task = task if isinstance(task, TaskSpec) else get_task(task)
    if quality not in QUALITIES:
        raise ValueError(f"unknown render quality {quality!r}; valid: {', '.join(QUALITIES)}")
    spec = load_task_spec(task)
    _add_cameras(spec, cameras, factors.camera_pos)
    if factors.table_pos is not None:
        _move_robot_side(spec, -robot_frame_offset(factors))
    ambient, diffuse = factors.light if factors.light is not None else DEFAULT_HEADLIGHT
    spec.visual.headlight.ambient = [ambient] * 3
    spec.visual.headlight.diffuse = [diffuse] * 3
    if factors.table_texture is not None:
        _retexture_material(spec, TABLE_MATERIAL, factors.table_texture, cube=True)
    if factors.floor_texture is not None:
        _retexture_material(spec, FLOOR_MATERIAL, factors.floor_texture, cube=False)
    if factors.object_shape is not None or factors.object_size is not None:
        _reshape_object(spec, task, factors.object_shape, factors.object_size or 1.0)
    if factors.object_texture is not None:
        material = _add_material(spec, "fw_object", factors.object_texture, cube=True)
        for geom in _visible_geoms(spec, task.object_bodies):
            geom.material = material
            geom.rgba = _geom_rgba(factors.object_texture)  # not the task's own tint (the upstream red-puck bug)
    for i, item in enumerate(factors.distractors or ()):
        _add_scene_object(spec, f"fw_distractor{i}", item)
    _set_render_quality(spec, quality, image_size)
    return spec


def robot_frame_offset(factors: FactorValues) -> np.ndarray:
    """What to add to a world (= table frame) position to express it in the robot's frame.

    The robot's frame is the world frame of the unshifted scene, carried along with the robot base.
    Since the table factor moves the robot side by ``-table_pos``, a point fixed in the world sits at
    ``+table_pos`` from where it would be for the robot: exactly as if the table had moved.
    """
    return np.zeros(3) if factors.table_pos is None else np.asarray(factors.table_pos, dtype=np.float64)


def resting_height_shift(task: TaskSpec, factors: FactorValues) -> float:
    """How much higher the object's origin must start so a resized/reshaped object rests as before."""
    if factors.object_size is None:
        return 0.0
    geometry = object_geometry(task.name)
    return -geometry.bottom * (factors.object_size - 1.0)


# --- cameras and the robot side -----------------------------------------------------------------


def _add_cameras(spec: mujoco.MjSpec, names: tuple[str, ...], delta: tuple[float, ...] | None) -> None:
    for name in names:
        cam = CAMERAS[name]
        pos = np.asarray(cam.pos, float)
        quat = cam.quat()
        if delta is not None:
            pos = pos + np.asarray(delta[:3])
            quat = quat + np.asarray(delta[3:])
            quat /= np.linalg.norm(quat)
        spec.worldbody.add_camera(name=name, pos=pos.tolist(), quat=quat.tolist(), fovy=cam.fovy)


def _move_robot_side(spec: mujoco.MjSpec, offset: np.ndarray) -> None:
    """Shift the robot, the floor and every world-fixed camera by ``offset``."""
    body = spec.body(ROBOT_ROOT)
    body.pos = (np.asarray(body.pos) + offset).tolist()
    floor = spec.geom(FLOOR_GEOM)
    floor.pos = (np.asarray(floor.pos) + offset).tolist()
    for cam in spec.worldbody.cameras:
        cam.pos = (np.asarray(cam.pos) + offset).tolist()


# --- textures -----------------------------------------------------------------------------------


def _texture_data(name: str, cube: bool) -> tuple[int, int, bytes]:
    image = np.ascontiguousarray(load_texture(name, TEXTURE_SIZE), dtype=np.uint8)
    if cube:  # MuJoCo stores a cube texture as six square faces stacked vertically
        image = np.concatenate([image] * 6, axis=0)
    return image.shape[1], image.shape[0], image.tobytes()


def _add_texture(spec: mujoco.MjSpec, name: str, value: str, cube: bool) -> str:
    width, height, data = _texture_data(value, cube)
    kind = mujoco.mjtTexture.mjTEXTURE_CUBE if cube else mujoco.mjtTexture.mjTEXTURE_2D
    texture = spec.add_texture(name=name, type=kind, width=width, height=height, nchannel=3)
    texture.data = data
    texture.info = f"factor texture {value}"
    return name


def _add_material(spec: mujoco.MjSpec, name: str, value: str, cube: bool) -> str:
    material = spec.add_material(name=name)
    _paint(spec, material, value, cube)
    return name


def _paint(spec: mujoco.MjSpec, material, value: str, cube: bool) -> None:
    textures = list(material.textures)
    role = int(mujoco.mjtTextureRole.mjTEXROLE_RGB)
    if is_rgb(value):
        material.rgba = [*parse_rgb(value), 1.0]
        textures[role] = ""
    else:
        material.rgba = [1.0, 1.0, 1.0, 1.0]
        textures[role] = _add_texture(spec, f"{material.name}_tex", value, cube)
    material.textures = textures


def _geom_rgba(value: str) -> list[float]:
    """The colour of a geom painted with texture ``value``: MuJoCo draws a geom whose rgba is not its default
    in that rgba, not in its material's, so white under an image (the texture's own colours) and the colour
    itself for a flat ``rgb:`` one."""
    return [*parse_rgb(value), 1.0] if is_rgb(value) else [1.0, 1.0, 1.0, 1.0]


def _retexture_material(spec: mujoco.MjSpec, material_name: str, value: str, cube: bool) -> None:
    _paint(spec, spec.material(material_name), value, cube)


# --- object size and shape ----------------------------------------------------------------------


def _reshape_object(spec: mujoco.MjSpec, task: TaskSpec, shape: str | None, scale: float) -> None:
    geometry = object_geometry(task.name)
    geoms = _subtree_spec_geoms(spec, task.object_bodies)
    if shape is None:
        _scale_subtree(spec, task.object_bodies, scale)
        return
    mesh = load_mesh(shape)
    main = next((g for g in geoms if g.name == "objGeom"), None) or next(g for g in geoms if g.contype or g.conaffinity)
    root = spec.body(task.object_bodies[0])
    keep_mass = not root.explicitinertial
    for geom in geoms:
        if geom is not main:
            geom.delete()
    # Fit the new shape to the old object's bounding box, so the grasp height and width (and what the
    # scripted expert assumes about them) stay the same: shape varies, size does not.
    fit = np.asarray(geometry.dims) * scale / np.maximum(np.ptp(mesh.vertices, axis=0), 1e-6)
    spec.add_mesh(
        name="fw_object_mesh",
        uservert=(mesh.vertices * fit).astype(np.float64).flatten().tolist(),
        userface=mesh.faces.flatten().tolist(),
    )
    # Keep the main geom in its own body (Meta-World reads it by name); express the new pose in the
    # root body's frame by removing the offsets of the bodies between them.
    offset = np.zeros(3)
    body = main.parent
    while body.name != root.name:
        offset += np.asarray(body.pos)
        body = body.parent
    main.type = mujoco.mjtGeom.mjGEOM_MESH
    main.meshname = "fw_object_mesh"
    main.pos = (np.array([0.0, 0.0, geometry.bottom * scale]) - offset).tolist()
    main.quat = [1.0, 0.0, 0.0, 0.0]
    if keep_mass:
        main.mass = geometry.mass
    if main.group not in VISIBLE_GROUPS:
        # A hidden collision geom (its group may be the only one counted for inertia): add a massless
        # visible twin rather than moving it to a rendered group.
        twin = main.parent.add_geom(
            name="fw_object_visual",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname="fw_object_mesh",
            pos=main.pos,
            contype=0,
            conaffinity=0,
            group=1,
            mass=0.0,
        )
        twin.rgba = [0.8, 0.3, 0.2, 1.0]
    else:
        main.rgba = [0.8, 0.3, 0.2, 1.0]


def _scale_subtree(spec: mujoco.MjSpec, roots: tuple[str, ...], scale: float) -> None:
    scaled_meshes: set[str] = set()
    for body in _subtree_bodies(spec, roots):
        if body.name not in roots:
            body.pos = (np.asarray(body.pos) * scale).tolist()
        if body.explicitinertial:
            body.inertia = (np.asarray(body.inertia) * scale**2).tolist()
            body.ipos = (np.asarray(body.ipos) * scale).tolist()
        for geom in body.geoms:
            geom.pos = (np.asarray(geom.pos) * scale).tolist()
            if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
                if geom.meshname not in scaled_meshes:
                    mesh = spec.mesh(geom.meshname)
                    mesh.scale = (np.asarray(mesh.scale) * scale).tolist()
                    scaled_meshes.add(geom.meshname)
            else:
                geom.size = (np.asarray(geom.size) * scale).tolist()
        for site in body.sites:
            site.pos = (np.asarray(site.pos) * scale).tolist()
            site.size = (np.asarray(site.size) * scale).tolist()


# --- distractors --------------------------------------------------------------------------------


def _add_scene_object(spec: mujoco.MjSpec, name: str, item: SceneObject) -> None:
    mesh = load_mesh(item.shape)
    spec.add_mesh(
        name=f"{name}_mesh",
        uservert=(mesh.vertices * item.size).astype(np.float64).flatten().tolist(),
        userface=mesh.faces.flatten().tolist(),
    )
    material = _add_material(spec, f"{name}_mat", item.texture, cube=True)
    pos = TABLE_CENTER + np.array([item.x, item.y, 0.0])
    body = spec.worldbody.add_body(name=name, pos=pos.tolist(), quat=[np.cos(item.yaw / 2), 0, 0, np.sin(item.yaw / 2)])
    body.info = f"distractor {item.shape}"
    body.add_geom(
        name=f"{name}_geom",
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=f"{name}_mesh",
        material=material,
        rgba=_geom_rgba(item.texture),
        contype=1,
        conaffinity=1,
        condim=3,
        group=0,
    )


# --- rendering ----------------------------------------------------------------------------------


def _set_render_quality(spec: mujoco.MjSpec, quality: Quality, image_size: tuple[int, int]) -> None:
    height, width = image_size
    spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, width)
    spec.visual.global_.offheight = max(spec.visual.global_.offheight, height)
    if quality == "full":
        return
    if quality == "lod":
        apply_lod(spec)  # the robot's meshes are most of a frame's triangles
    # CPU rendering: shadows and multisampling dominate llvmpipe's cost (~10x); reflections add more.
    spec.visual.quality.shadowsize = 0
    spec.visual.quality.offsamples = 0
    for light in spec.lights:
        light.castshadow = False
    for material in spec.materials:
        material.reflectance = 0.0


# --- spec/model traversal helpers ---------------------------------------------------------------


def _subtree_bodies(spec: mujoco.MjSpec, roots: tuple[str, ...]) -> list:
    out = []
    for root in roots:
        body = spec.body(root)
        if body is None:
            raise ValueError(f"object body {root!r} not found in the task's scene")
        out.append(body)
        out.extend(body.find_all(mujoco.mjtObj.mjOBJ_BODY))
    return out


def _subtree_spec_geoms(spec: mujoco.MjSpec, roots: tuple[str, ...]) -> list:
    return [geom for body in _subtree_bodies(spec, roots) for geom in body.geoms]


def _visible_geoms(spec: mujoco.MjSpec, roots: tuple[str, ...]) -> list:
    return [g for g in _subtree_spec_geoms(spec, roots) if g.group in VISIBLE_GROUPS and g.rgba[3] > 0]


def subtree_geoms(model: mujoco.MjModel, roots: Sequence[str]) -> list[int]:
    """The geoms of the bodies named ``roots`` and of every body below them."""
    root_ids = {model.body(r).id for r in roots}
    out = []
    for g in range(model.ngeom):
        b = int(model.geom_bodyid[g])
        while b and b not in root_ids:
            b = int(model.body_parentid[b])
        if b in root_ids:
            out.append(g)
    return out


def geom_world_corners(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    center, half = model.geom_aabb[g][:3], model.geom_aabb[g][3:]
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    local = center + signs * half
    return data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T


def check_quality(quality: str) -> None:
    check_choice("quality", quality, QUALITIES)
