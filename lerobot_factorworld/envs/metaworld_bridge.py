"""The only place that touches Meta-World internals: build a task env on our model, reset it.

Meta-World v3 envs load their XML in ``MujocoEnv._initialize_simulation``; a subclass per task class
returns our compiled model instead. Resets go through Meta-World's own ``reset_model`` (so its task
state, goals and scripted experts stay valid) with the random reset vector frozen to the nominal
start plus the Factor World object offset, and ``hand_init_pos`` set to the arm factor's start.

A task row may redefine the goal and the success radius (the public Factor World's pick-place): the
goal is moved after Meta-World's own reset (which keeps its sampled goal 15 cm from the object and
would loop forever on a frozen vector closer than that), the goal space is narrowed to it so that
Meta-World's observation clipping keeps it, and success is re-tested on Meta-World's own
``obj_to_target`` distance. The shaped reward (version ``v2``) reads the goal every step, so it
follows too.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from typing import Any

import mujoco
import numpy as np
from gymnasium.spaces import Box

from ..tasks import TaskSpec

_NO_TRUNCATION = 10**9  # Meta-World raises past max_path_length; FactorWorldEnv truncates itself


@cache
def _env_class(metaworld_name: str) -> type:
    from metaworld.env_dict import ALL_V3_ENVIRONMENTS

    base = ALL_V3_ENVIRONMENTS[metaworld_name]

    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        return self._factorworld_model, mujoco.MjData(self._factorworld_model)

    def reset_model(self) -> np.ndarray:
        obs = base.reset_model(self)
        goal = self._factorworld_goal
        if goal is None:
            return obs
        self._target_pos = goal.copy()
        for site, pos in self._target_site_config:  # the goal marker, where the task draws one
            self.model.site(site).pos = pos
            self._set_pos_site(site, pos)
        return self._get_obs()  # the state vector now carries the moved goal

    def evaluate_state(self, obs: np.ndarray, action: np.ndarray) -> tuple[float, dict[str, Any]]:
        reward, info = base.evaluate_state(self, obs, action)
        radius = self._factorworld_success_radius
        if radius is not None:
            info["success"] = float(info["obj_to_target"] <= radius)
        return reward, info

    return type(
        f"FactorWorld{base.__name__}",
        (base,),
        {
            "_initialize_simulation": _initialize_simulation,
            "reset_model": reset_model,
            "evaluate_state": evaluate_state,
        },
    )


def make_metaworld_env(task: TaskSpec, model: mujoco.MjModel) -> Any:
    """A Meta-World task env (no renderer of its own) simulating ``model``."""
    cls = _env_class(task.metaworld_name)
    env = cls.__new__(cls)
    env._factorworld_model = model
    env._factorworld_goal = None if task.goal is None else np.array(task.goal, dtype=np.float64)
    env._factorworld_success_radius = task.success_radius
    env.__init__()
    if env._factorworld_goal is not None:
        env.goal_space = Box(env._factorworld_goal, env._factorworld_goal.copy(), dtype=np.float64)
    env._partially_observable = False  # scripted experts read the goal from the state vector
    env.__dict__.pop("sawyer_observation_space", None)
    env._set_task_called = True
    env._freeze_rand_vec = True
    env.max_path_length = _NO_TRUNCATION
    env._factorworld_default_hand = np.array(env.init_config["hand_init_pos"], dtype=np.float64)
    env._factorworld_nominal = _nominal_rand_vec(task, env._random_reset_space)
    return env


def _nominal_rand_vec(task: TaskSpec, space: Any) -> np.ndarray:
    """The centre of Meta-World's random reset range (object first), or the task's declared start."""
    nominal = (space.low + space.high) / 2.0
    if task.nominal_object_xy is not None:
        nominal[:2] = task.nominal_object_xy
    return nominal


def reset_metaworld(
    env: Any,
    task: TaskSpec,
    object_offset: Sequence[float],
    arm_offset: Sequence[float],
    rest_shift: float = 0.0,
) -> np.ndarray:
    """Reset ``env`` with the object moved by ``object_offset`` and the gripper by ``arm_offset``."""
    rand_vec = env._factorworld_nominal.copy()
    rand_vec[:2] += np.asarray(object_offset, dtype=np.float64)
    if task.object_is_free:
        rand_vec[2] += rest_shift
    env._last_rand_vec = rand_vec
    env.hand_init_pos = env._factorworld_default_hand + np.asarray(arm_offset, dtype=np.float64)
    obs, _ = env.reset()
    return obs
