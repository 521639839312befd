"""``FactorWorldEnv``: a gymnasium env for one Factor World task under one or more scene configurations.

Description:
    Wraps Meta-World v3's task logic (dynamics, scripted-expert-compatible state, success test) in a
    scene compiled by :func:`lerobot_factorworld.scene.build.build_model`, and renders its own cameras
    with CPU-friendly settings.

Observation space:
    ``pixels``: dict camera -> uint8 (H, W, 3); ``agent_pos``: float32 (8,) = gripper position and
    finger opening at the current and at the previous step (the paper's proprioception), positions
    in the robot's frame: under a table shift they move by ``table_pos`` as if the table had moved
    (:func:`lerobot_factorworld.scene.build.robot_frame_offset`); the state vector scripted experts
    read (``state_observation``) stays in Meta-World's world frame, which is the table's.
    ``cameras=()`` gives a physics-only env without ``pixels`` (scripted experts, physics tests).
    ``obs="lerobot_metaworld"`` gives LeRobot's ``--env.type=metaworld`` observation instead (``pixels``:
    uint8 (480, 480, 3) from Meta-World's ``corner2`` flipped on both axes; ``agent_pos``: float64 (4,)),
    its seeded episode starts and task texts; ``cameras`` and ``image_size`` are then unused
    (:mod:`lerobot_factorworld.envs.lerobot_obs`).

Action space:
    Box(-1, 1, (4,)): end-effector displacement (x, y, z, 1 cm per unit) and gripper effort.

Rewards:
    1.0 on a step where the task is solved, else 0.0 (Meta-World's shaped reward is in ``info``).

Starting state:
    The configuration picked for the episode (``options["config"]``, ``options["env_index"]``,
    ``seed % len(configs)``, or drawn from the env's RNG) fixes the scene; the object's start offset
    is re-sampled every episode from the reset seed unless the configuration pins ``object_pos``.

Episode end:
    Terminates on success (``terminate_on_success``); truncates after ``max_episode_steps``.

Info:
    ``is_success``, ``factors`` (the values the scene really had, defaults filled in), ``env_id``,
    ``env_index``, ``metaworld_reward``, ``stage`` (the furthest stage the episode has reached, judged from
    Meta-World's own per-step quantities: :mod:`lerobot_factorworld.envs.stages`); for a task family with
    content also the episode's record under the family's ``content_key`` (the pick family's: instruction,
    named object, objects with their poses).
"""

from __future__ import annotations

import contextlib
import copy
import weakref
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import fields, replace
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from ..core.checks import check_image_size
from ..factors.registry import FACTORS, factor_range, support_reason
from ..factors.values import FactorValues, SceneConfig, to_jsonable
from ..families import family_of
from ..scene.build import DEFAULT_HEADLIGHT, DEFAULT_QUALITY, QUALITIES, Quality
from ..scene.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE, check_camera_names
from ..tasks import get_task
from .lerobot_obs import FACTORWORLD_OBS, LEROBOT_METAWORLD_OBS, LeRobotMetaworldObs, check_obs_mode
from .runtime import CompiledScene
from .stages import STAGE_KEY, StageTracker, stages_of

PER_EPISODE_FACTORS = ("object_pos", "arm_pos")  # applied at reset; everything else is compiled in
RESERVED_OPTION_PREFIX = "lerobot_"  # LeRobot's rollout passes {"lerobot_new_rollout": True}
OPTIONS = ("config", "env_index", "factors")
CONTROL_FPS = 80  # Meta-World: timestep 0.0025 s x frame_skip 5 = 12.5 ms per env step


class FactorWorldEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": CONTROL_FPS}

    def __init__(
        self,
        task: str = "pick-place",
        configs: SceneConfig | Sequence[SceneConfig] | None = None,
        *,
        cameras: Sequence[str] | str = DEFAULT_CAMERAS,
        image_size: int | tuple[int, int] = DEFAULT_IMAGE_SIZE,
        quality: Quality = DEFAULT_QUALITY,
        max_episode_steps: int | None = None,
        object_pos_width: str | None = None,
        terminate_on_success: bool = True,
        render_mode: str | None = "rgb_array",
        scene_cache_size: int = 4,
        obs: str = FACTORWORLD_OBS,
    ) -> None:
        self.task_spec = get_task(task)
        self._family = family_of(self.task_spec)
        self.configs = _as_configs(self.task_spec.name, configs)
        self.obs = check_obs_mode(obs)
        self._lerobot = LeRobotMetaworldObs(self.task_spec) if self.obs == LEROBOT_METAWORLD_OBS else None
        if self._lerobot is not None:  # LeRobot's image: Meta-World's own corner2 camera, not one of ours
            cameras, image_size = (), self._lerobot.image_size
        self.cameras = check_camera_names([cameras] if isinstance(cameras, str) else list(cameras), allow_none=True)
        if not self.cameras and self._lerobot is None:
            render_mode = None
        self.image_size = (image_size, image_size) if isinstance(image_size, int) else tuple(image_size)
        check_image_size(self.image_size)
        if quality not in QUALITIES:
            raise ValueError(f"unknown render quality {quality!r}; valid: {', '.join(QUALITIES)}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"unsupported render_mode {render_mode!r}; valid: {self.metadata['render_modes']}")
        self.quality = quality
        self.object_pos_range = factor_range(self.task_spec, "object_pos", object_pos_width)
        self.terminate_on_success = terminate_on_success
        self.render_mode = render_mode
        self._max_episode_steps = int(max_episode_steps or self.task_spec.max_episode_steps)
        self.task = self.task_spec.name
        self.task_description = self.configs[0].task_description
        if self._lerobot is not None:
            self.task_description = self._lerobot.task_description

        h, w = self.image_size
        spaces: dict[str, gym.Space] = {"agent_pos": gym.spaces.Box(-np.inf, np.inf, (8,), dtype=np.float32)}
        if self.cameras:
            spaces["pixels"] = gym.spaces.Dict(
                {cam: gym.spaces.Box(0, 255, (h, w, 3), dtype=np.uint8) for cam in self.cameras}
            )
        self.observation_space = gym.spaces.Dict(spaces) if self._lerobot is None else self._lerobot.observation_space
        self.action_space = gym.spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)

        self._scenes: OrderedDict[tuple, CompiledScene] = OrderedDict()
        # The scenes' renderers are released when the env is collected, or at exit while GL is still loaded,
        # not only by close(): an env left open must not end its script in GL tracebacks.
        weakref.finalize(self, _close_scenes, self._scenes)
        self._scene_cache_size = max(1, scene_cache_size)
        self._scene: CompiledScene | None = None
        self._config: SceneConfig | None = None
        self._steps = 0
        self._last_frame: np.ndarray | None = None
        self._episode_factors: dict[str, Any] = {}
        self._episode_record: dict[str, Any] = {}
        self._env_index = 0
        self.episode_observer: EpisodeObserver | None = None
        """Told of every reset and step of this env (e.g. an evaluation recording stages and frames); None: nobody."""
        self.timer: Callable[[str], contextlib.AbstractContextManager[None]] = _untimed
        """Wraps this env's scene compilation (``scene_compile``) and rendering (``render``), e.g. a study's
        per-step timings (``core.timing.Timings.span``); the default times nothing."""

    # --- gymnasium API ------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        config, index = self._select_config(seed, options or {})
        factors = config.factors
        # The object start is always drawn, even when the condition pins object_pos, so that every draw after
        # it (a pick episode's target and phrasing) is the same for a seed in every condition: paired episodes.
        low, high = self.object_pos_range
        drawn = tuple(float(v) for v in self.np_random.uniform(low, high))
        object_offset = factors.object_pos if factors.object_pos is not None else drawn
        config = config.for_episode(self.np_random)  # a pick episode's target and phrasing; others draw nothing
        scene = self._scene_for(config)
        scene.reset(object_offset, factors.arm_pos or (0.0, 0.0, 0.0), config)
        self._scene, self._config, self._env_index, self._steps = scene, config, index, 0
        self.task_description = config.task_description
        if self._lerobot is not None:  # LeRobot's metaworld episode: Meta-World's seeded start, LeRobot's text
            object_offset = self._start_lerobot_episode(scene, seed, factors)
        self._episode_factors = resolved_factors(config, object_offset)
        self._episode_record = config.episode_record(object_offset)
        self._stage = StageTracker(stages_of(self.task_spec))  # the furthest stage this episode reaches
        obs = self._observe(scene.metaworld_obs)
        info = self._info(success=False, metaworld_reward=0.0, stage=self._stage.name)
        if self.episode_observer is not None:
            self.episode_observer.on_reset(self, seed, obs, info)
        return obs, info

    def step(self, action: np.ndarray):
        if self._scene is None:
            raise RuntimeError("call reset() before step()")
        action = np.asarray(action, dtype=np.float32).reshape(4)
        mw_obs, mw_reward, _, _, mw_info = self._scene.env.step(np.clip(action, -1.0, 1.0))
        self._scene.metaworld_obs = mw_obs
        self._steps += 1
        success = bool(mw_info["success"])
        stage = self._stage.update(mw_info)
        obs = self._observe(mw_obs)
        terminated = success and self.terminate_on_success
        truncated = self._steps >= self._max_episode_steps
        info = self._info(success, float(mw_reward), stage)
        info.update((key, mw_info[key]) for key in self._family.episode_measures)  # e.g. pick: how close it came
        if self.episode_observer is not None:
            self.episode_observer.on_step(self, obs, terminated, truncated, info)
        return obs, float(success), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The first camera's latest frame (already rendered for the observation: no second render)."""
        if self.render_mode is None:
            return None
        if self._last_frame is None:
            raise RuntimeError("call reset() before render()")
        return self._last_frame.copy()

    def close(self) -> None:
        _close_scenes(self._scenes)  # the finalizer stays: scenes of a reset after close are released too
        self._scene = None

    # --- introspection ------------------------------------------------------------------------

    @property
    def model(self):
        """The current scene's ``MjModel`` (after reset)."""
        return None if self._scene is None else self._scene.env.model

    @property
    def data(self):
        return None if self._scene is None else self._scene.env.data

    @property
    def metaworld_env(self):
        """The wrapped Meta-World task env (scripted experts read its state)."""
        return None if self._scene is None else self._scene.env

    @property
    def state_observation(self) -> np.ndarray:
        """Meta-World's 39-dim state vector (object and goal poses): what scripted experts act on."""
        if self._scene is None or self._scene.metaworld_obs is None:
            raise RuntimeError("call reset() first")
        return self._scene.metaworld_obs.copy()

    @property
    def config(self) -> SceneConfig | None:
        return self._config

    @property
    def max_episode_steps(self) -> int:
        """The horizon: steps after which an episode truncates (read-only; LeRobot's evaluation reads the
        same number through ``env.call("_max_episode_steps")``)."""
        return self._max_episode_steps

    @property
    def episode_factors(self) -> dict[str, Any]:
        return dict(self._episode_factors)

    # --- internals ----------------------------------------------------------------------------

    def _select_config(self, seed: int | None, options: dict[str, Any]) -> tuple[SceneConfig, int]:
        unknown = [k for k in options if k not in OPTIONS and not k.startswith(RESERVED_OPTION_PREFIX)]
        if unknown:
            raise ValueError(f"unknown reset option(s) {unknown}; valid options: {', '.join(OPTIONS)}")
        index = -1
        if options.get("config") is not None:
            config = options["config"]
            config = SceneConfig.from_dict(config) if isinstance(config, dict) else config
            if config.task != self.task:
                raise ValueError(f"config is for task {config.task!r} but this env runs {self.task!r}")
        else:
            if options.get("env_index") is not None:
                index = int(options["env_index"])
                if not 0 <= index < len(self.configs):
                    raise ValueError(f"env_index {index} out of range; this env has {len(self.configs)} configs")
            elif seed is not None:
                index = env_index_for_seed(seed, len(self.configs))
            else:
                index = int(self.np_random.integers(len(self.configs)))
            config = self.configs[index]
        if options.get("factors"):
            config = config.with_factors(**options["factors"])
        return config, index

    def _scene_for(self, config: SceneConfig) -> CompiledScene:
        factors = replace(config.factors, **{name: None for name in PER_EPISODE_FACTORS})
        content = config.content
        key = (factors, None if content is None else self._family.scene_key(content))  # what the model depends on
        scene = self._scenes.pop(key, None)
        if scene is None:
            args = (self.task_spec, factors, self.cameras, self.quality, self.image_size)
            with self.timer("scene_compile"):
                scene = self._family.make_scene(*args, content) if content is not None else None
                scene = scene or CompiledScene(*args)  # the family's scene, or the plain Meta-World one
                if self._lerobot is not None:
                    self._lerobot.prepare_scene(scene, factors)
            while len(self._scenes) >= self._scene_cache_size:
                _, old = self._scenes.popitem(last=False)
                old.close()
        self._scenes[key] = scene
        return scene

    def _start_lerobot_episode(
        self, scene: CompiledScene, seed: int | None, factors: FactorValues
    ) -> tuple[float, float]:
        """Start where LeRobot's metaworld env starts the episode of ``seed`` (without a seed: of one drawn from
        this env's generator) and show LeRobot's task text; returns the object's start offset."""
        assert self._lerobot is not None
        episode_seed = seed if seed is not None else int(self.np_random.integers(2**31))
        self.task_description = self._lerobot.task_description
        return self._lerobot.start_episode(scene, episode_seed, factors)

    def _observe(self, mw_obs: np.ndarray) -> dict[str, Any]:
        assert self._scene is not None
        if self._lerobot is not None:
            with self.timer("render"):  # LeRobot's observation is its one camera's frame
                obs = self._lerobot.observe(self._scene, mw_obs)
            self._last_frame = obs["pixels"]
            return obs
        obs: dict[str, Any] = {"agent_pos": self._scene.proprioception(mw_obs)}
        if self.cameras:
            with self.timer("render"):
                obs["pixels"] = self._scene.render_all()
            self._last_frame = obs["pixels"][self.cameras[0]]
        return obs

    def _info(self, success: bool, metaworld_reward: float, stage: str) -> dict[str, Any]:
        assert self._config is not None
        return {
            "is_success": success,
            STAGE_KEY: stage,
            "metaworld_reward": metaworld_reward,
            "factors": dict(self._episode_factors),
            "env_id": self._config.env_id,
            "env_index": self._env_index,
            **copy.deepcopy(self._episode_record),  # fresh per call: users keep what they are given
        }


def env_index_for_seed(seed: int, n_envs: int) -> int:
    """The environment an episode reset with ``seed`` runs in: ``seed % n_envs``.

    LeRobot's ``eval_policy`` resets episode ``i`` with ``start_seed + i`` whatever the batch size, so
    consecutive episodes cycle through the environments: a multiple of ``n_envs`` episodes visits each
    equally (``protocol.coverage.coverage`` checks it), and conditions evaluated from the same start
    seed share their object starts episode by episode.
    """
    return seed % n_envs


def _as_configs(task: str, configs: SceneConfig | Sequence[SceneConfig] | None) -> tuple[SceneConfig, ...]:
    if configs is None:
        return (SceneConfig(task),)
    if isinstance(configs, (SceneConfig, dict)):
        configs = [configs]
    out = tuple(SceneConfig.from_dict(c) if isinstance(c, dict) else c for c in configs)
    if not out:
        raise ValueError("configs must hold at least one SceneConfig")
    wrong = sorted({c.task for c in out if c.task != task})
    if wrong:
        raise ValueError(f"configs for task(s) {wrong} given to a {task!r} env")
    return out


def resolved_factors(config: SceneConfig, object_offset: Sequence[float]) -> dict[str, Any]:
    """The values the scene really has: the configuration with defaults filled in (JSON-able)."""
    f = config.factors
    out: dict[str, Any] = {}
    for field_ in fields(f):
        name = field_.name
        value = getattr(f, name)
        if support_reason(name, config.task):
            out[name] = None
            continue
        if name == "object_pos":
            value = tuple(float(v) for v in object_offset)
        elif value is None:
            value = _DEFAULTS[name]
        out[name] = value
    return {name: to_jsonable(value) for name, value in out.items()}


_DEFAULTS: dict[str, Any] = {
    "arm_pos": (0.0, 0.0, 0.0),
    "camera_pos": (0.0,) * 7,
    "table_pos": (0.0, 0.0, 0.0),
    "object_size": 1.0,
    "object_shape": "default",
    "object_texture": "default",
    "table_texture": "default",
    "floor_texture": "default",
    "light": DEFAULT_HEADLIGHT,
    "distractors": (),
}
assert set(_DEFAULTS) | {"object_pos"} == set(FACTORS)


class EpisodeObserver(Protocol):
    """What an env's ``episode_observer`` is told: each reset (with its seed, ``None`` for an unseeded one) and
    each step, after the env computed them. Set on an instance (``env.unwrapped.episode_observer``), so one
    evaluation's records never see another env's episodes."""

    def on_reset(self, env: FactorWorldEnv, seed: int | None, obs: dict, info: dict) -> None: ...

    def on_step(self, env: FactorWorldEnv, obs: dict, terminated: bool, truncated: bool, info: dict) -> None: ...


def _untimed(name: str) -> contextlib.AbstractContextManager[None]:
    return contextlib.nullcontext()


def _close_scenes(scenes: OrderedDict[tuple, CompiledScene]) -> None:
    """Close every cached scene (their renderers and Meta-World envs) and forget them."""
    for scene in scenes.values():
        scene.close()
    scenes.clear()
