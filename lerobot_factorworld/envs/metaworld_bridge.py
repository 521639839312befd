"""The only place that touches Meta-World internals: build a task env on our model, reset it.

Meta-World v3 envs load their XML in ``MujocoEnv._initialize_simulation``; a subclass per task class
returns our compiled model instead. Resets go through Meta-World's own ``reset_model`` (so its task
state, goals and scripted experts stay valid) with the random reset vector frozen to the nominal
start plus the Factor World object offset, and ``hand_init_pos`` set to the arm factor's start.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from typing import Any

import mujoco
import numpy as np

from ..tasks import TaskSpec

_NO_TRUNCATION = 10**9  # Meta-World raises past max_path_length; FactorWorldEnv truncates itself


@cache
def _env_class(metaworld_name: str) -> type:
    from metaworld.env_dict import ALL_V3_ENVIRONMENTS

    base = ALL_V3_ENVIRONMENTS[metaworld_name]

    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        return self._factorworld_model, mujoco.MjData(self._factorworld_model)

    return type(f"FactorWorld{base.__name__}", (base,), {"_initialize_simulation": _initialize_simulation})


def make_metaworld_env(task: TaskSpec, model: mujoco.MjModel) -> Any:
    """A Meta-World task env (no renderer of its own) simulating ``model``."""
    cls = _env_class(task.metaworld_name)
    env = cls.__new__(cls)
    env._factorworld_model = model
    env.__init__()
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
