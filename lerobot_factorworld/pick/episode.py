"""One compiled pick scene inside :class:`~lerobot_factorworld.envs.factor_env.FactorWorldEnv`.

The pick family's ``make_scene`` builds a :class:`PickScene` for a configuration that holds a pick
layout: the scene is compiled once per (factor values, objects and poses) and every episode resets it
with that episode's target and arrangement offset.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco

from ..envs.runtime import CompiledScene
from ..factors.values import FactorValues, SceneConfig
from .bridge import make_pick_env, reset_pick
from .layout import PickLayout
from .scene import add_pick_objects


class PickScene(CompiledScene):
    """A pick scene: the factors' scene with the layout's objects, simulated by the pick bridge."""

    def __init__(self, task, factors: FactorValues, cameras, quality, image_size, layout: PickLayout) -> None:
        self.layout = layout
        super().__init__(task, factors, cameras, quality, image_size)

    def edit_spec(self, spec: mujoco.MjSpec, factors: FactorValues) -> None:
        add_pick_objects(spec, self.layout.objects, factors.object_texture)

    def make_env(self, model: mujoco.MjModel) -> Any:
        return make_pick_env(self.task, model, self.layout)

    def reset(self, object_offset: Sequence[float], arm_offset: Sequence[float], config: SceneConfig) -> None:
        layout = config.content
        if layout is None or not layout.target:
            raise ValueError("a pick episode needs a configuration whose target is pinned (SceneConfig.for_episode)")
        self.metaworld_obs = reset_pick(self.env, layout.placed(object_offset), layout.target, arm_offset)
