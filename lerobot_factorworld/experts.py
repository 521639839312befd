"""Meta-World's scripted experts for Factor World tasks (they act on the simulator state, not pixels),
and :func:`rollout`, the one expert episode loop that collection, the expert tables and the tests share."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import metaworld.policies as metaworld_policies
import numpy as np

from .families import family_of
from .tasks import TaskSpec, get_task


def expert_policy(task: str | TaskSpec) -> Any:
    """The Meta-World v3 scripted policy of ``task`` (e.g. ``SawyerDoorOpenV3Policy`` for door-open), or
    its family's own expert (``TaskFamily.expert``)."""
    task = task if isinstance(task, TaskSpec) else get_task(task)
    own = family_of(task).expert(task)
    if own is not None:
        return own
    name = "Sawyer" + "".join(part.capitalize() for part in task.name.split("-")) + "V3Policy"
    return getattr(metaworld_policies, name)()


def expert_action(
    policy: Any, state: np.ndarray, rng: np.random.Generator | None = None, noise_std: float = 0.0
) -> np.ndarray:
    """One expert action, optionally with Gaussian noise (demonstrations use :data:`DEFAULT_ACTION_NOISE`)."""
    action = np.asarray(policy.get_action(state), dtype=np.float32)
    if noise_std > 0:
        if rng is None:
            raise ValueError("noise needs a seeded rng for reproducibility")
        action = action + rng.normal(0.0, noise_std, size=action.shape).astype(np.float32)
    return np.clip(action, -1.0, 1.0)


DEFAULT_ACTION_NOISE = 0.002  # std of the demonstrations' action noise (the public Factor World's)
NOISE_STREAM = 0  # spawn key of the action-noise stream under an episode seed


def noise_rng(seed: int) -> np.random.Generator:
    """The expert's action-noise stream for the episode reset with ``seed``.

    ``env.reset(seed=seed)`` seeds the env's own generator (object start) with ``SeedSequence(seed)``;
    the noise comes from a spawned child of that sequence, a statistically independent stream, so the
    noise never repeats the numbers that placed the object.
    """
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(NOISE_STREAM,)))


Act = Callable[[Any, np.ndarray, np.random.Generator, float], np.ndarray]
"""How an action is chosen: ``act(policy, state, noise_rng, noise_std)`` (:func:`expert_action` by default)."""


@dataclass
class Episode:
    """One rolled-out episode: ``observations[t]`` is what the policy saw when it chose ``actions[t]``;
    ``info`` is the env's info after the last step (``info["is_success"]``)."""

    observations: list[dict[str, Any]] = field(default_factory=list)
    actions: list[np.ndarray] = field(default_factory=list)
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return bool(self.info.get("is_success", False))

    def __len__(self) -> int:
        return len(self.actions)


def rollout(
    env: Any,
    policy: Any,
    seed: int,
    noise_std: float = 0.0,
    *,
    act: Act = expert_action,
    max_steps: int | None = None,
    after_step: Callable[[Any], None] | None = None,
) -> Episode:
    """One expert episode as ``factorworld collect`` runs it: ``env`` reset with ``seed``, actions from
    ``act`` on Meta-World's state with noise from :func:`noise_rng` (``seed``), until the env terminates,
    truncates or ``max_steps`` (default: the env's horizon) is reached. ``after_step(env)`` runs after
    every step (e.g. to record the simulator state)."""
    obs, info = env.reset(seed=seed)
    rng = noise_rng(seed)
    episode = Episode(info=info)
    for _ in range(env.max_episode_steps if max_steps is None else max_steps):
        action = act(policy, env.state_observation, rng, noise_std)
        episode.observations.append(obs)
        episode.actions.append(action)
        obs, _, terminated, truncated, episode.info = env.step(action)
        if after_step is not None:
            after_step(env)
        if terminated or truncated:
            break
    return episode
