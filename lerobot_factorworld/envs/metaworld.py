"""The only place that touches Meta-World internals: build a task env on our model, reset it.

Meta-World v3 envs load their XML in ``MujocoEnv._initialize_simulation``; a subclass per task class
returns our compiled model instead (:func:`adopted_class`, :func:`adopt`: shared with task families,
whose bridges add only their own methods and state). Resets go through Meta-World's own ``reset_model`` (so its task
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

from collections.abc import Callable, Sequence
from functools import cache
from typing import Any

import mujoco
import numpy as np
from gymnasium.spaces import Box
from metaworld.env_dict import ALL_V3_ENVIRONMENTS

from ..tasks import TaskSpec

_NO_TRUNCATION = 10**9  # Meta-World raises past max_path_length; FactorWorldEnv truncates itself


def adopted_class(metaworld_name: str, prefix: str, methods: Callable[[type], dict[str, Any]]) -> type:
    """A subclass of Meta-World's env class ``metaworld_name`` that simulates a model we compiled
    (``env._factorworld_model``), with ``methods(base)`` overriding the base's (callers cache the class)."""
    base = ALL_V3_ENVIRONMENTS[metaworld_name]

    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        return self._factorworld_model, mujoco.MjData(self._factorworld_model)

    return type(
        f"{prefix}{base.__name__}", (base,), {"_initialize_simulation": _initialize_simulation, **methods(base)}
    )


def adopt(cls: type, model: mujoco.MjModel, goal_space: Box | None = None, **state: Any) -> Any:
    """An instance of an :func:`adopted_class` on ``model``: ``state`` is set before Meta-World's
    ``__init__`` (which resets through the overridden methods), then Meta-World's own randomisation,
    truncation and partial observability are switched off (Factor World draws, truncates and observes)."""
    env = cls.__new__(cls)
    env._factorworld_model = model
    for name, value in state.items():
        setattr(env, name, value)
    env.__init__()
    if goal_space is not None:
        env.goal_space = goal_space
    env._partially_observable = False  # scripted experts read the goal from the state vector
    env.__dict__.pop("sawyer_observation_space", None)
    env._set_task_called = True
    env._freeze_rand_vec = True
    env.max_path_length = _NO_TRUNCATION
    env._factorworld_default_hand = np.array(env.init_config["hand_init_pos"], dtype=np.float64)
    return env


def move_hand(env: Any, arm_offset: Sequence[float]) -> None:
    """Start the gripper of the next reset at Meta-World's default plus ``arm_offset`` (the arm factor)."""
    env.hand_init_pos = env._factorworld_default_hand + np.asarray(arm_offset, dtype=np.float64)


def _plain_methods(base: type) -> dict[str, Any]:
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

    return {"reset_model": reset_model, "evaluate_state": evaluate_state}


@cache
def _env_class(metaworld_name: str) -> type:
    return adopted_class(metaworld_name, "FactorWorld", _plain_methods)


def make_metaworld_env(task: TaskSpec, model: mujoco.MjModel) -> Any:
    """A Meta-World task env (no renderer of its own) simulating ``model``."""
    goal = None if task.goal is None else np.array(task.goal, dtype=np.float64)
    env = adopt(
        _env_class(task.metaworld_name),
        model,
        goal_space=None if goal is None else Box(goal, goal.copy(), dtype=np.float64),
        _factorworld_goal=goal,
        _factorworld_success_radius=task.success_radius,
    )
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
    move_hand(env, arm_offset)
    obs, _ = env.reset()
    return obs


def seeded_reset(env: Any, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Reset ``env`` as LeRobot's env does for ``seed`` (Meta-World's own seeded draw of the object and goal);
    returns Meta-World's state vector and the drawn reset vector. The env is frozen again afterwards, as
    Factor World keeps it."""
    env._freeze_rand_vec, env.seeded_rand_vec = False, True
    try:
        env.seed(seed)
        obs, _ = env.reset()
    finally:
        env._freeze_rand_vec, env.seeded_rand_vec = True, False
    return obs, np.array(env._last_rand_vec, dtype=np.float64)


def reset_frozen_at(env: Any, rand_vec: np.ndarray) -> np.ndarray:
    """Reset ``env`` with its random reset vector frozen at ``rand_vec``; returns Meta-World's state vector."""
    env._last_rand_vec = rand_vec
    obs, _ = env.reset()
    return obs
