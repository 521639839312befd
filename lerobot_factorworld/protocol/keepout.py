"""Where distractors may stand: the table minus everything the task's expert sweeps through.

A distractor must not block the task, so the keep-out area is measured, not guessed: the scripted
expert is run (physics only, no noise) from the extreme object offsets the task allows, and every
step records the footprint of each non-robot body (objects, doors, drawers, windows as they move)
and of the gripper whenever it is low enough to hit a distractor. One box per (start, body) is kept.
Computed once per task and process, in the table frame.
"""

from __future__ import annotations

import itertools
from functools import cache

import mujoco
import numpy as np

from ..envs.factor_env import FactorWorldEnv
from ..experts import expert_action, expert_policy
from ..factors.registry import DISTRACTOR_SIZE, factor_range, get_factor
from ..factors.values import FactorValues, SceneConfig
from ..families import family_of
from ..scene.build import FLOOR_GEOM, ROBOT_ROOT, TABLE_CENTER, geom_world_corners
from ..tasks import get_task

SCENERY_BODIES = ("tablelink", "RetainingWall", "mocap")  # static scenery distractors may touch
GRIPPER_BODIES = ("hand", "rightclaw", "leftclaw", "rightpad", "leftpad")
CLEARANCE = 0.03  # metres kept free around everything the expert sweeps
LOW_MARGIN = 0.05  # the gripper counts as "low" below the tallest distractor plus this
SWEEP_STEPS = 300


@cache
def keepout_boxes(task_name: str) -> np.ndarray:
    """(k, 4) boxes [xmin, ymin, xmax, ymax] in the table frame that distractors must not overlap."""
    task = get_task(task_name)
    boxes = family_of(task).keepout(task, CLEARANCE)  # a family's own area (pick: its whole workspace)
    if boxes is not None:
        return boxes
    widest = list(get_factor("object_pos").ranges)[-1]
    low, high = factor_range(task, "object_pos", widest)
    starts = [(0.0, 0.0), *itertools.product((low[0], high[0]), (low[1], high[1]))]
    env = FactorWorldEnv(task.name, [SceneConfig(task.name, FactorValues(object_pos=s)) for s in starts], cameras=())
    policy = expert_policy(task)
    swept: list[np.ndarray] = []
    try:
        for index in range(len(starts)):
            env.reset(seed=0, options={"env_index": index})
            tracked = _tracked_geoms(env.model)
            sweep = {body: np.array([np.inf, np.inf, -np.inf, -np.inf]) for body in tracked}
            for _ in range(SWEEP_STEPS):
                _record(env.model, env.data, tracked, sweep)
                _, _, terminated, _, _ = env.step(expert_action(policy, env.state_observation))
                if terminated:
                    break
            _record(env.model, env.data, tracked, sweep)
            swept.extend(box for box in sweep.values() if np.isfinite(box).all())
    finally:
        env.close()
    out = np.asarray(swept, dtype=np.float64)
    out[:, [0, 2]] -= TABLE_CENTER[0]
    out[:, [1, 3]] -= TABLE_CENTER[1]
    out[:, :2] -= CLEARANCE
    out[:, 2:] += CLEARANCE
    return out


def _tracked_geoms(model: mujoco.MjModel) -> dict[int, tuple[list[int], bool]]:
    """root body -> (its geoms, is_gripper) for every moving or task body that is not scenery."""
    robot = model.body(ROBOT_ROOT).id
    scenery = {model.body(name).id for name in SCENERY_BODIES if _has_body(model, name)}
    gripper = {model.body(name).id for name in GRIPPER_BODIES if _has_body(model, name)}
    tracked: dict[int, tuple[list[int], bool]] = {}
    for g in range(model.ngeom):
        body = int(model.geom_bodyid[g])
        root = _root_body(model, body)
        if body in gripper:
            tracked.setdefault(-body, ([], True))[0].append(g)
        elif root not in (0, robot) and root not in scenery and model.geom(g).name != FLOOR_GEOM:
            tracked.setdefault(root, ([], False))[0].append(g)
    return tracked


def _record(model, data, tracked, sweep) -> None:
    low_z = DISTRACTOR_SIZE[1] + LOW_MARGIN
    for key, (geoms, is_gripper) in tracked.items():
        corners = np.concatenate([geom_world_corners(model, data, g) for g in geoms])
        if is_gripper and corners[:, 2].min() > low_z:
            continue
        box = sweep[key]
        box[:2] = np.minimum(box[:2], corners[:, :2].min(axis=0))
        box[2:] = np.maximum(box[2:], corners[:, :2].max(axis=0))


def _has_body(model: mujoco.MjModel, name: str) -> bool:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) >= 0


def _root_body(model: mujoco.MjModel, b: int) -> int:
    while b and model.body_parentid[b] != 0:
        b = int(model.body_parentid[b])
    return b
