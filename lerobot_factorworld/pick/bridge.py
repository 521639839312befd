"""The pick family's only contact with Meta-World internals: Meta-World's pick-place env class, on a pick
scene, adopted through :mod:`lerobot_factorworld.envs.metaworld` like every other task's.

What changes from pick-place:

- ``reset_model`` puts every object at its pose (plus the episode's arrangement offset) on the table;
- the state vector's object slot (what scripted experts read) is the named object's pose, and its goal
  slot the point the named object must be lifted to;
- ``evaluate_state`` judges success on the named object only: its centre must stay at least
  :data:`~.catalog.LIFT_HEIGHT` above where it rested for :data:`~.catalog.HOLD_STEPS` consecutive
  steps, and lifting any other object by :data:`~.catalog.WRONG_LIFT_HEIGHT` first fails the episode
  for good. Meta-World calls it exactly once per step, which is what the hold counter counts. Its info also
  says whether the gripper is near another object (``near_other``, the ``reached_other`` stage) and how close its
  centre has come so far to the named object's centre and to the nearest other one's (``closest_named``,
  ``closest_other``: what an evaluation records of every episode, ``PickFamily.episode_measures``).
"""

from __future__ import annotations

from functools import cache
from typing import Any

import mujoco
import numpy as np
from gymnasium.spaces import Box

from ..envs.metaworld import adopt, adopted_class, move_hand
from ..scene.build import TABLE_CENTER
from ..tasks import TaskSpec
from .catalog import HOLD_STEPS, LIFT_HEIGHT, LIFT_MARGIN, REACH_RADIUS, WRONG_LIFT_HEIGHT, get_object
from .layout import PickLayout, PlacedObject
from .scene import body_name, joint_name

GOAL_BOX = Box(np.array([-1.0, 0.0, 0.0]), np.array([1.0, 1.5, 0.6]), dtype=np.float64)  # where a lift goal can be


def _pick_methods(base: type) -> dict[str, Any]:
    def _get_pos_objects(self) -> np.ndarray:
        return self.data.body(self._pick_target_body).xpos.copy()

    def _get_quat_objects(self) -> np.ndarray:
        return self.data.body(self._pick_target_body).xquat[[1, 2, 3, 0]].copy()  # (x, y, z, w) as Meta-World's

    def _get_id_main_object(self) -> int:
        return int(self.model.body_geomadr[self.model.body(self._pick_target_body).id])

    def reset_model(self) -> np.ndarray:
        self._reset_hand()
        qpos, qvel = self.data.qpos.copy(), self.data.qvel.copy()
        for item in self._pick_objects:
            joint = self.model.joint(joint_name(item.name))
            rest = get_object(item.name).family.half_height
            qpos[joint.qposadr[0] : joint.qposadr[0] + 7] = [
                *(TABLE_CENTER + [item.x, item.y, rest]),
                np.cos(item.yaw / 2),
                0.0,
                0.0,
                np.sin(item.yaw / 2),
            ]
            qvel[joint.dofadr[0] : joint.dofadr[0] + 6] = 0.0
        self.set_state(qpos, qvel)
        self._pick_rest = {
            item.name: float(self.data.body(body_name(item.name)).xpos[2]) for item in self._pick_objects
        }
        target = self.data.body(self._pick_target_body).xpos
        self._target_pos = np.array(
            [target[0], target[1], self._pick_rest[self._pick_target] + LIFT_HEIGHT + LIFT_MARGIN]
        )
        self.obj_init_pos = target.copy()
        self.init_tcp = self.tcp_center
        self.init_left_pad = self.get_body_com("leftpad")
        self.init_right_pad = self.get_body_com("rightpad")
        self._pick_hold, self._pick_wrong = 0, ""
        self._pick_closest = dict.fromkeys(self._pick_rest, np.inf)  # each object's closest gripper distance so far
        return self._get_obs()

    def evaluate_state(self, obs: np.ndarray, action: np.ndarray) -> tuple[float, dict[str, Any]]:
        heights = {
            name: float(self.data.body(body_name(name)).xpos[2]) - rest for name, rest in self._pick_rest.items()
        }
        if not self._pick_wrong:
            lifted = [n for n, h in heights.items() if n != self._pick_target and h >= WRONG_LIFT_HEIGHT]
            self._pick_wrong = lifted[0] if lifted else ""
        self._pick_hold = self._pick_hold + 1 if heights[self._pick_target] >= LIFT_HEIGHT else 0
        success = not self._pick_wrong and self._pick_hold >= HOLD_STEPS
        tcp = self.tcp_center
        tcp_to_obj = float(np.linalg.norm(obs[4:7] - tcp))
        distances = {n: float(np.linalg.norm(self.data.body(body_name(n)).xpos - tcp)) for n in heights}
        tcp_to_other = min((d for n, d in distances.items() if n != self._pick_target), default=np.inf)
        closest = self._pick_closest
        for name, distance in distances.items():
            closest[name] = min(closest[name], distance)
        info = {
            "success": float(success),
            "near_object": float(tcp_to_obj <= REACH_RADIUS),
            "near_other": float(tcp_to_other <= REACH_RADIUS),
            "grasp_success": float(heights[self._pick_target] > 0.01 and self.touching_main_object),
            "grasp_reward": 0.0,
            "in_place_reward": 0.0,
            "obj_to_target": float(np.linalg.norm(obs[4:7] - self._target_pos)),
            "unscaled_reward": float(success),
            "target_height": heights[self._pick_target],
            "wrong_object": self._pick_wrong,
            "closest_named": closest[self._pick_target],  # the gripper's closest approach so far (centres, metres)
            "closest_other": min((d for n, d in closest.items() if n != self._pick_target), default=np.inf),
        }
        return float(success), info

    return {
        "_get_pos_objects": _get_pos_objects,
        "_get_quat_objects": _get_quat_objects,
        "_get_id_main_object": _get_id_main_object,
        "reset_model": reset_model,
        "evaluate_state": evaluate_state,
        "_target_site_config": property(lambda self: []),  # no goal marker in a pick scene
    }


@cache
def _env_class(metaworld_name: str) -> type:
    return adopted_class(metaworld_name, "FactorWorldPick", _pick_methods)


def make_pick_env(task: TaskSpec, model: mujoco.MjModel, layout: PickLayout) -> Any:
    """A Meta-World env simulating the pick scene ``model`` (compiled from ``layout``'s objects)."""
    first = layout.objects[0].name  # the named object until the first episode names one
    return adopt(
        _env_class(task.metaworld_name),
        model,
        goal_space=GOAL_BOX,  # the expert reads the lift goal from the state vector
        _pick_objects=layout.objects,
        _pick_target=first,
        _pick_target_body=body_name(first),
        _pick_rest={},
        _pick_hold=0,
        _pick_wrong="",
    )


def reset_pick(env: Any, objects: tuple[PlacedObject, ...], target: str, arm_offset) -> np.ndarray:
    """Reset with ``objects`` at their episode poses, ``target`` named, the gripper moved by ``arm_offset``."""
    env._pick_objects = objects
    env._pick_target = target
    env._pick_target_body = body_name(target)
    move_hand(env, arm_offset)
    obs, _ = env.reset()
    return obs
