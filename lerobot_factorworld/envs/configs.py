"""LeRobot env type ``factorworld``: ``lerobot-eval --env.type=factorworld ...``.

``create_envs`` returns one suite per evaluation condition, so ``eval_info.json`` reports success per
condition: ``train`` (the N training environments) and one suite per shifted factor or pair (test
environments drawn from the held-out split), e.g. ``--env.shifts='[camera_pos,light+distractors]'``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

import gymnasium as gym
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE

from ..factors.registry import PAPER_STUDY_FACTORS
from ..factors.sampling import SamplingOptions
from ..tasks import get_task
from .factor_env import CONTROL_FPS, FactorWorldEnv

AGENT_POS_DIM = 8
ACTION_DIM = 4


@EnvConfig.register_subclass("factorworld")
@dataclass
class FactorWorldEnvConfig(EnvConfig):
    """Factor World for LeRobot.

    Attributes:
        task: One task or a comma-separated list (each becomes a task id within every suite).
        cameras: Comma-separated camera names (see ``factorworld cameras``); each gives
            ``observation.images.<camera>``.
        image_size: Square image side in pixels.
        quality: ``fast`` (CPU-friendly, default) or ``full`` (Meta-World's shadows and multisampling).
        episode_length: Step limit; ``None`` uses each task's horizon.
        n_train_envs: Number of training environments N.
        train_factors: Factors varied across the training environments (default: the paper's seven).
        shifts: Evaluation conditions besides ``train``: factor names or pairs ``a+b``.
        n_test_envs: Test environments per shifted condition (the paper uses 100).
        seed: Seed of the environment sampling (episode seeds come from ``--seed``).
        include_train: Also evaluate on the training environments (needed for the generalization gap).
        configs_path: JSON file of training configurations (``factorworld sample`` writes one) to use
            instead of sampling them.
        sampling: How factor values are drawn (``--env.sampling.widths='{camera_pos: wide}'``, ...).
    """

    task: str = "pick-place"
    fps: int = CONTROL_FPS
    cameras: str = "front"
    image_size: int = 84
    quality: str = "fast"
    episode_length: int | None = None
    n_train_envs: int = 5
    train_factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    shifts: list[str] = field(default_factory=list)
    n_test_envs: int = 100
    seed: int = 0
    include_train: bool = True
    configs_path: str | None = None
    sampling: SamplingOptions = field(default_factory=SamplingOptions)
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in self.task_names:
            get_task(name)
        self.features = {
            ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(ACTION_DIM,)),
            "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(AGENT_POS_DIM,)),
        }
        self.features_map = {ACTION: ACTION, "agent_pos": OBS_STATE}
        for cam in self.camera_names:
            self.features[f"pixels/{cam}"] = PolicyFeature(
                type=FeatureType.VISUAL, shape=(self.image_size, self.image_size, 3)
            )
            self.features_map[f"pixels/{cam}"] = f"{OBS_IMAGES}.{cam}"
        if not self.include_train and not self.shifts:
            raise ValueError("nothing to evaluate: include_train=false and no shifts given")

    @property
    def task_names(self) -> list[str]:
        return [t.strip() for t in (self.task or "").split(",") if t.strip()]

    @property
    def camera_names(self) -> tuple[str, ...]:
        from ..scene.cameras import check_camera_names

        return check_camera_names([c.strip() for c in self.cameras.split(",") if c.strip()])

    @property
    def gym_kwargs(self) -> dict:
        return {
            "cameras": self.camera_names,
            "image_size": self.image_size,
            "quality": self.quality,
            "max_episode_steps": self.episode_length,
        }

    def suites(self, task: str) -> dict:
        """Evaluation conditions -> scene configurations for ``task``."""
        from ..factors.values import load_configs
        from ..study.plan import TRAIN_SUITE, evaluation_suites

        train_configs = None
        if self.configs_path:
            train_configs = [c for c in load_configs(self.configs_path) if c.task == get_task(task).name]
            if not train_configs:
                raise ValueError(f"{self.configs_path} holds no configuration for task {task!r}")
        suites = evaluation_suites(
            task,
            self.n_train_envs,
            self.train_factors,
            self.shifts,
            self.n_test_envs,
            self.seed,
            self.sampling,
            train_configs,
        )
        if not self.include_train:
            suites.pop(TRAIN_SUITE)
        return suites

    def create_envs(self, n_envs: int, use_async_envs: bool = False) -> dict[str, dict[int, gym.vector.VectorEnv]]:
        vector_cls = gym.vector.AsyncVectorEnv if (use_async_envs and n_envs > 1) else gym.vector.SyncVectorEnv
        extra = {"context": "forkserver"} if vector_cls is gym.vector.AsyncVectorEnv else {}
        out: dict[str, dict[int, gym.vector.VectorEnv]] = {}
        for task_id, task in enumerate(self.task_names):
            for suite, configs in self.suites(task).items():
                make = partial(FactorWorldEnv, task, tuple(configs), **self.gym_kwargs)
                out.setdefault(suite, {})[task_id] = vector_cls(
                    [make] * n_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP, **extra
                )
        return out
