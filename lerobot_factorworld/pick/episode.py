"""One compiled pick scene inside :class:`~lerobot_factorworld.envs.factor_env.FactorWorldEnv`.

``FactorWorldEnv`` builds a :class:`PickScene` instead of its plain scene for a configuration that
holds a pick layout: the scene is compiled once per (factor values, objects and poses) and every
episode resets it with that episode's target and arrangement offset.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..envs.factor_env import _Scene
from ..factors.values import FactorValues, SceneConfig
from .bridge import make_pick_env, reset_pick
from .layout import PickLayout
from .scene import add_pick_objects


class PickScene(_Scene):
    """A pick scene: the factors' scene with the layout's objects, simulated by the pick bridge."""

    def __init__(self, task, factors: FactorValues, cameras, quality, image_size, layout: PickLayout) -> None:
        from ..scene.build import build_spec, robot_frame_offset

        self.task = task
        self.cameras = cameras
        spec = build_spec(task, factors, cameras, quality, image_size)
        add_pick_objects(spec, layout.objects, factors.object_texture)
        self.model = spec.compile()
        self.env = make_pick_env(task, self.model, layout)
        self.rest_shift = 0.0
        self.robot_offset = robot_frame_offset(factors)
        self.image_size = image_size
        self._renderer = None
        self.metaworld_obs = None

    def reset(self, object_offset: Sequence[float], arm_offset: Sequence[float], config: SceneConfig) -> None:
        layout = config.pick
        if layout is None or not layout.target:
            raise ValueError("a pick episode needs a configuration whose target is pinned (SceneConfig.for_episode)")
        self.metaworld_obs = reset_pick(self.env, layout.placed(object_offset), layout.target, arm_offset)
