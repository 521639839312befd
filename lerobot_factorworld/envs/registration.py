"""gymnasium ids ``FactorWorld/<task>-v0``, one per row of :data:`lerobot_factorworld.tasks.TASKS`."""

from __future__ import annotations

import gymnasium as gym

from ..tasks import TASKS

ENTRY_POINT = "lerobot_factorworld.envs.factor_env:FactorWorldEnv"


def register_envs() -> None:
    """Register every task (idempotent). ``FactorWorldEnv`` truncates itself at the task horizon."""
    for task in TASKS.values():
        if task.gym_id not in gym.registry:
            gym.register(id=task.gym_id, entry_point=ENTRY_POINT, kwargs={"task": task.name}, disable_env_checker=True)
