"""Meta-World's scripted experts for Factor World tasks (they act on the simulator state, not pixels)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .tasks import TaskSpec, get_task


def expert_policy(task: str | TaskSpec) -> Any:
    """The Meta-World v3 scripted policy of ``task`` (e.g. ``SawyerDoorOpenV3Policy`` for door-open), or
    the family's own expert (``pick``: :class:`lerobot_factorworld.pick.expert.PickExpert`)."""
    import metaworld.policies as policies

    task = task if isinstance(task, TaskSpec) else get_task(task)
    if task.family == "pick":
        from .pick.expert import PickExpert

        return PickExpert()
    name = "Sawyer" + "".join(part.capitalize() for part in task.name.split("-")) + "V3Policy"
    return getattr(policies, name)()


def expert_action(
    policy: Any, state: np.ndarray, rng: np.random.Generator | None = None, noise_std: float = 0.0
) -> np.ndarray:
    """One expert action, optionally with Gaussian noise (the public Factor World used std 0.002)."""
    action = np.asarray(policy.get_action(state), dtype=np.float32)
    if noise_std > 0:
        if rng is None:
            raise ValueError("noise needs a seeded rng for reproducibility")
        action = action + rng.normal(0.0, noise_std, size=action.shape).astype(np.float32)
    return np.clip(action, -1.0, 1.0)
