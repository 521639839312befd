"""MjSpec edits that turn Meta-World's pick-place scene into a pick scene.

The puck and the goal marker are removed and each object of the layout is added as a loose body (a
free joint, MuJoCo primitives, the puck's contact settings) standing on the table. Everything else is
:func:`lerobot_factorworld.scene.build.build_spec`'s scene, so every factor composes unchanged: lighting,
textures, cameras, table position (the robot side moves), distractors, arm start.

The object-texture factor gives every pick object the texture's pattern tinted by the object's own
colour (luminance x colour): the instruction may name the colour, so the colour must survive.
"""

from __future__ import annotations

import mujoco
import numpy as np

from ..assets import load_texture
from ..factors.registry import is_rgb, parse_rgb
from ..scene.build import TABLE_CENTER, TEXTURE_SIZE
from .catalog import get_object
from .layout import PlacedObject

PUCK_BODY = "obj"
GOAL_SITE = "goal"
MASS = 0.25  # kg per object
# The puck's contact settings (stiff, high friction): what Meta-World's grasps are tuned to.
CONTACT = {"solimp": [0.99, 0.99, 0.01, 0.5, 2.0], "solref": [0.01, 1.0], "friction": [1.0, 0.1, 0.002], "condim": 4}
TINT_FLOOR = 0.5  # darkest share of the object's colour under a textured pattern
LUMA = np.array([0.299, 0.587, 0.114])  # luminance weights of an RGB colour


def body_name(name: str) -> str:
    return f"pick_{name}"


def joint_name(name: str) -> str:
    return f"pick_{name}_joint"


def add_pick_objects(spec: mujoco.MjSpec, objects: tuple[PlacedObject, ...], texture: str | None) -> None:
    """Replace the puck and goal of a pick-place ``spec`` with ``objects`` at their nominal poses."""
    spec.detach_body(spec.body(PUCK_BODY))
    spec.site(GOAL_SITE).delete()
    for item in objects:
        _add_object(spec, item, texture)


def _add_object(spec: mujoco.MjSpec, item: PlacedObject, texture: str | None) -> None:
    obj = get_object(item.name)
    material = spec.add_material(name=f"{body_name(item.name)}_mat")
    if texture is None:
        material.rgba = [*obj.rgb, 1.0]
    else:
        _tinted_texture(spec, material, texture, obj.rgb)
    pos = TABLE_CENTER + np.array([item.x, item.y, obj.family.half_height])
    body = spec.worldbody.add_body(
        name=body_name(item.name), pos=pos.tolist(), quat=[np.cos(item.yaw / 2), 0.0, 0.0, np.sin(item.yaw / 2)]
    )
    body.info = f"pick object {item.name}"
    body.add_freejoint(name=joint_name(item.name))
    dims = _BUILDERS[obj.shape](body, material.name)
    body.explicitinertial = True
    body.ipos, body.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]  # centre of mass at the object's centre
    body.mass = MASS
    body.inertia = [
        MASS / 12 * (dims[1] ** 2 + dims[2] ** 2),
        MASS / 12 * (dims[0] ** 2 + dims[2] ** 2),
        MASS / 12 * (dims[0] ** 2 + dims[1] ** 2),
    ]


def _tinted_texture(spec: mujoco.MjSpec, material, value: str, rgb: tuple[float, float, float]) -> None:
    if is_rgb(value):  # a flat colour shades the object's own colour by its luminance, as a pattern does
        luminance = float(np.dot(parse_rgb(value), LUMA))
        material.rgba = [*(float(c) * (TINT_FLOOR + (1.0 - TINT_FLOOR) * luminance) for c in rgb), 1.0]
        return
    image = load_texture(value, TEXTURE_SIZE).astype(np.float64) / 255.0
    luminance = image @ LUMA
    shade = TINT_FLOOR + (1.0 - TINT_FLOOR) * luminance
    tinted = np.clip(shade[..., None] * np.asarray(rgb) * 255.0, 0, 255).astype(np.uint8)
    faces = np.ascontiguousarray(np.concatenate([tinted] * 6, axis=0))  # a cube texture: six faces stacked
    name = f"{material.name}_tex"
    tex = spec.add_texture(
        name=name, type=mujoco.mjtTexture.mjTEXTURE_CUBE, width=faces.shape[1], height=faces.shape[0], nchannel=3
    )
    tex.data = faces.tobytes()
    tex.info = f"pick object texture {value}"
    textures = list(material.textures)
    textures[int(mujoco.mjtTextureRole.mjTEXROLE_RGB)] = name
    material.textures = textures
    material.rgba = [1.0, 1.0, 1.0, 1.0]


# --- shapes: each adds its geoms to ``body`` (origin at the object's centre) and returns its box size --------

G = mujoco.mjtGeom


def _geom(body, material: str, kind, size, pos=(0.0, 0.0, 0.0), **extra) -> None:
    params = {**CONTACT, **extra}
    # No geom rgba: a geom colour would override the material's (the object's colour or tinted texture).
    body.add_geom(
        type=kind,
        size=list(size) + [0.0] * (3 - len(size)),
        pos=list(pos),
        material=material,
        group=0,
        contype=1,
        conaffinity=1,
        **params,
    )


def _cube(body, material: str) -> tuple[float, float, float]:
    _geom(body, material, G.mjGEOM_BOX, (0.026, 0.026, 0.026))
    return 0.052, 0.052, 0.052


def _can(body, material: str) -> tuple[float, float, float]:
    _geom(body, material, G.mjGEOM_CYLINDER, (0.026, 0.04))
    return 0.052, 0.052, 0.08


def _ball(body, material: str) -> tuple[float, float, float]:
    # Rolling friction (condim 6) keeps it where it was put when a finger brushes it.
    _geom(body, material, G.mjGEOM_SPHERE, (0.03,), condim=6, friction=[1.0, 0.1, 0.005])
    return 0.06, 0.06, 0.06


def _mug(body, material: str) -> tuple[float, float, float]:
    _geom(body, material, G.mjGEOM_CYLINDER, (0.027, 0.035))
    # A dark opening on top (visual only) and a C-shaped handle on +x.
    body.add_geom(
        type=G.mjGEOM_CYLINDER,
        size=[0.022, 0.001, 0.0],
        pos=[0.0, 0.0, 0.035],
        rgba=[0.08, 0.08, 0.08, 1.0],
        contype=0,
        conaffinity=0,
        group=1,
    )
    for fromto in (
        (0.024, 0, 0.022, 0.046, 0, 0.022),
        (0.046, 0, 0.022, 0.046, 0, -0.022),
        (0.046, 0, -0.022, 0.024, 0, -0.022),
    ):
        _geom(body, material, G.mjGEOM_CAPSULE, (0.0055,), fromto=list(fromto))
    return 0.1, 0.054, 0.07


def _bar(body, material: str) -> tuple[float, float, float]:
    _geom(body, material, G.mjGEOM_BOX, (0.06, 0.018, 0.02))
    return 0.12, 0.036, 0.04


def _dumbbell(body, material: str) -> tuple[float, float, float]:
    for x in (-0.045, 0.045):
        _geom(body, material, G.mjGEOM_SPHERE, (0.022,), pos=(x, 0.0, 0.0), condim=6, friction=[1.0, 0.1, 0.005])
    _geom(body, material, G.mjGEOM_CAPSULE, (0.013,), fromto=[-0.045, 0, 0, 0.045, 0, 0])
    return 0.134, 0.044, 0.044


_BUILDERS = {"cube": _cube, "can": _can, "ball": _ball, "mug": _mug, "bar": _bar, "dumbbell": _dumbbell}
