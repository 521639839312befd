"""``CompiledScene``: one compiled Factor World scene at run time, a Meta-World task env on our model
plus a renderer for our cameras.

:class:`~lerobot_factorworld.envs.factor_env.FactorWorldEnv` keeps a few of them (one per distinct
compiled model) and resets the one an episode needs. A task family's scene (built by its
``TaskFamily.make_scene``) subclasses it and overrides the three steps that differ: :meth:`edit_spec`
(add the family's content to the scene), :meth:`make_env` (the family's Meta-World bridge) and
:meth:`reset`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from ..factors.values import FactorValues, SceneConfig
from ..scene.build import build_spec, resting_height_shift, robot_frame_offset
from ..scene.renderer import SharedContextRenderer
from ..tasks import TaskSpec
from .metaworld import make_metaworld_env, reset_metaworld

_GL_CONTEXTS_CREATED = False


def gl_context_created() -> bool:
    """Whether this process has created a MuJoCo render context (forking it would share GL state)."""
    return _GL_CONTEXTS_CREATED


class CompiledScene:
    """One compiled scene: a Meta-World task env on our model, plus a renderer for our cameras.

    Attributes:
        model: The compiled ``MjModel``.
        env: The Meta-World task env simulating it (scripted experts read its state).
        metaworld_obs: Meta-World's latest 39-dim state vector (after :meth:`reset`).
    """

    def __init__(self, task: TaskSpec, factors: FactorValues, cameras, quality, image_size) -> None:
        self.task = task
        self.cameras = cameras
        self.image_size = image_size
        spec = build_spec(task, factors, cameras, quality, image_size)
        self.edit_spec(spec, factors)
        self.model = spec.compile()
        self.env = self.make_env(self.model)
        self.rest_shift = resting_height_shift(task, factors)
        self.robot_offset = robot_frame_offset(factors)
        self._renderer: SharedContextRenderer | None = None
        self.metaworld_obs: np.ndarray | None = None

    def edit_spec(self, spec: mujoco.MjSpec, factors: FactorValues) -> None:
        """Edit the factors' scene before it is compiled (a family adds its content); the plain scene: none."""

    def make_env(self, model: mujoco.MjModel) -> Any:
        """The Meta-World env simulating ``model``."""
        return make_metaworld_env(self.task, model)

    def reset(self, object_offset: Sequence[float], arm_offset: Sequence[float], config: SceneConfig) -> None:
        self.metaworld_obs = reset_metaworld(self.env, self.task, object_offset, arm_offset, self.rest_shift)

    def proprioception(self, mw_obs: np.ndarray) -> np.ndarray:
        """``agent_pos`` from Meta-World's state: gripper xyz and opening, now and one step before,
        with positions moved from the world (table) frame into the robot's frame."""
        state = np.concatenate([mw_obs[0:4], mw_obs[18:22]])
        state[[0, 1, 2, 4, 5, 6]] += np.tile(self.robot_offset, 2)
        return state.astype(np.float32)

    def render_all(self) -> dict[str, np.ndarray]:
        if self._renderer is None:
            global _GL_CONTEXTS_CREATED
            h, w = self.image_size
            # one GL context per thread for every scene: a new one per scene cost ~0.3 s (scene/renderer.py)
            self._renderer = SharedContextRenderer(self.model, height=h, width=w)
            _GL_CONTEXTS_CREATED = True
        frames = {}
        for cam in self.cameras:
            self._renderer.update_scene(self.env.data, camera=cam)
            frames[cam] = self._renderer.render()
        return frames

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self.env.close()
