"""Where distractors may stand: the table minus every task fixture, the object's start region and goal.

Computed once per task from its default compiled scene (no rendering), in the table frame.
"""

from __future__ import annotations

from functools import cache

import mujoco
import numpy as np

from ..factors.registry import get_factor
from ..tasks import get_task
from .build import FLOOR_GEOM, ROBOT_ROOT, TABLE_CENTER, load_task_spec, object_geometry

SCENERY_BODIES = ("tablelink", "RetainingWall", "mocap")  # static scenery distractors may touch
CLEARANCE = 0.03  # metres kept free around fixtures, the object's start region and the goal


@cache
def keepout_boxes(task_name: str) -> np.ndarray:
    """(k, 4) boxes [xmin, ymin, xmax, ymax] in the table frame that distractors must not overlap."""
    task = get_task(task_name)
    model = load_task_spec(task).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    robot = model.body(ROBOT_ROOT).id
    scenery = {model.body(name).id for name in SCENERY_BODIES if _has_body(model, name)}
    boxes = []
    for g in range(model.ngeom):
        root = _root_body(model, int(model.geom_bodyid[g]))
        if root == robot or root in scenery or root == 0 or model.geom(g).name == FLOOR_GEOM:
            continue
        boxes.append(_xy_box(model, data, g))
    # The object's start region under the widest object-position range, plus its size.
    low, high = get_factor("object_pos").widest
    from ..envs.metaworld_bridge import nominal_object_xy

    centre = np.asarray(nominal_object_xy(task))
    half = object_geometry(task.name).extent / 2
    boxes.append([centre[0] + low[0] - half, centre[1] + low[1] - half, centre[0] + high[0] + half, centre[1] + high[1] + half])
    for s in range(model.nsite):
        if model.site(s).name == "goal":
            x, y = data.site_xpos[s][:2]
            boxes.append([x - 0.04, y - 0.04, x + 0.04, y + 0.04])
    out = np.asarray(boxes, dtype=np.float64)
    out[:, [0, 2]] -= TABLE_CENTER[0]
    out[:, [1, 3]] -= TABLE_CENTER[1]
    out[:, :2] -= CLEARANCE
    out[:, 2:] += CLEARANCE
    return out


def _has_body(model: mujoco.MjModel, name: str) -> bool:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) >= 0


def _root_body(model: mujoco.MjModel, b: int) -> int:
    while b and model.body_parentid[b] != 0:
        b = int(model.body_parentid[b])
    return b


def _xy_box(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> list[float]:
    from .build import _geom_world_corners

    corners = _geom_world_corners(model, data, g)
    return [*corners[:, :2].min(axis=0), *corners[:, :2].max(axis=0)]
