"""LeRobot env type ``factorworld``: ``lerobot-eval --env.type=factorworld ...``.

``create_envs`` returns one suite per evaluation condition, so ``eval_info.json`` reports success per
condition: ``train`` (the N training environments) and one suite per shifted factor or pair (test
environments drawn from the held-out split), e.g. ``--env.shifts='[camera_pos,light+distractors]'``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import partial

import gymnasium as gym
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_IMAGE, OBS_IMAGES, OBS_STATE

from ..assets.library import check_asset_folders
from ..core.checks import check_at_least, check_image_size, check_input_file, check_seed
from ..envs.factor_env import CONTROL_FPS, FactorWorldEnv
from ..envs.lerobot_obs import (
    FACTORWORLD_OBS,
    IMAGE_SIZE,
    LEROBOT_METAWORLD_OBS,
    STATE_DIM,
    check_lerobot_task,
    check_obs_mode,
)
from ..factors.registry import PAPER_STUDY_FACTORS, check_factors
from ..factors.values import load_configs
from ..protocol.conditions import (
    PAIR_SEPARATOR,
    TRAIN_SUITE,
    check_condition,
    evaluation_suites,
    is_family_condition,
    parse_shift,
)
from ..protocol.coverage import checked_vector_env
from ..protocol.sampling import SamplingOptions
from ..protocol.sidecar import check_against_dataset, read_dataset_condition
from ..scene.build import DEFAULT_QUALITY, check_quality
from ..scene.cameras import DEFAULT_CAMERAS_SETTING, DEFAULT_IMAGE_SIZE, check_cameras
from ..tasks import check_tasks, get_task

logger = logging.getLogger(__name__)

AGENT_POS_DIM = 8
ACTION_DIM = 4
DEFAULT_N_TRAIN_ENVS = 5
DEFAULT_ENV_SEED = 0
DEFAULT_CAMERAS = DEFAULT_CAMERAS_SETTING  # the scene default, as the command line spells it
OBS_QUALITY = {FACTORWORLD_OBS: DEFAULT_QUALITY, LEROBOT_METAWORLD_OBS: "full"}  # full: Meta-World's own pixels
LEROBOT_IMAGE_FEATURE = "pixels/top"  # LeRobot's metaworld config names its corner2 image so


@EnvConfig.register_subclass("factorworld")
@dataclass
class FactorWorldEnvConfig(EnvConfig):
    """Factor World for LeRobot.

    Attributes:
        task: One task or a comma-separated list (each becomes a task id within every suite).
        cameras: Comma-separated camera names (see ``factorworld cameras``); each gives
            ``observation.images.<camera>``. Default ``front``, or the dataset's (``dataset_root``).
        image_size: Square image side in pixels. Default 84, or the dataset's.
        quality: ``fast`` (CPU-friendly, the default with ``obs=factorworld``), ``full`` (Meta-World's shadows and
            multisampling, the default with ``obs=lerobot_metaworld``) or ``lod`` (``fast`` with simplified robot
            meshes: ~2x faster frames, slightly different pixels). With ``dataset_root``, the dataset's (one
            given must agree): the ``train`` condition then renders the frames the policy was trained on.
        episode_length: Step limit; ``None`` uses each task's horizon.
        n_train_envs: Number of training environments N (default 5, or the dataset's).
        train_factors: Factors varied across the training environments (default: the paper's seven, or
            the dataset's).
        shifts: Evaluation conditions besides ``train``: factor names or pairs ``a+b``; for the ``pick``
            family also ``held_out_phrasings`` and ``held_out_objects`` (docs/pick.md).
        n_test_envs: Test environments per shifted condition (the paper uses 100; a multiple of N keeps
            every test environment paired with the training environment it derives from).
        seed: Seed of the environment sampling (default 0, or the dataset's; episode seeds come from
            ``--seed``). A condition's test environments depend only on this seed and its factor names.
        dataset_root: A Factor World dataset (``factorworld collect``) whose training environments are the
            ``train`` condition: N, factors, seed, sampling widths, cameras, image size and render quality are
            read from its ``meta/factorworld.json``; settings given explicitly must agree with it.
        include_train: Also evaluate on the training environments (needed for the generalization gap).
        configs_path: JSON file of training configurations (``factorworld sample`` writes one) to use
            instead of sampling them.
        sampling: How factor values are drawn (``--env.sampling.widths='{camera_pos: wide}'``,
            ``--env.sampling.rgb_fraction=0.5``: the share of flat-colour textures, ...); ``widths.object_pos``
            (narrow / medium) is also the range of the per-episode object start. With ``dataset_root`` they are
            the dataset's: sampling settings given (other than the defaults) must agree with them.
        obs: ``factorworld`` (default: ``cameras`` at ``image_size``, 8-number state) or ``lerobot_metaworld``:
            exactly LeRobot's ``--env.type=metaworld`` features (480 x 480 ``corner2`` image as
            ``observation.image``, 4-number ``observation.state``), episode starts and task texts, so a
            checkpoint trained there evaluates here unchanged (docs/lerobot_metaworld.md). Its ``train``
            condition defaults to Meta-World's unshifted scene (``n_train_envs=1``, ``train_factors=[]``).
    """

    task: str = "pick-place"
    fps: int = CONTROL_FPS
    cameras: str | None = None
    image_size: int | None = None
    quality: str | None = None
    episode_length: int | None = None
    n_train_envs: int | None = None
    train_factors: list[str] | None = None
    shifts: list[str] = field(default_factory=list)
    n_test_envs: int = 100
    seed: int | None = None
    dataset_root: str | None = None
    include_train: bool = True
    configs_path: str | None = None
    sampling: SamplingOptions = field(default_factory=SamplingOptions)
    obs: str = FACTORWORLD_OBS
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_obs_mode(self.obs)
        self._resolve_train_condition()  # with dataset_root: its cameras, image size and quality unless given
        self.cameras = DEFAULT_CAMERAS if self.cameras is None else self.cameras
        self.image_size = DEFAULT_IMAGE_SIZE if self.image_size is None else self.image_size
        self.quality = OBS_QUALITY[self.obs] if self.quality is None else self.quality
        self._validate()
        if self.obs == LEROBOT_METAWORLD_OBS:
            self.features, self.features_map = lerobot_metaworld_features()
        else:
            self.features, self.features_map = self._factorworld_features()

    def _factorworld_features(self) -> tuple[dict[str, PolicyFeature], dict[str, str]]:
        """One ``observation.images.<camera>`` per camera and the 8-number state."""
        features = {
            ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(ACTION_DIM,)),
            "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(AGENT_POS_DIM,)),
        }
        features_map = {ACTION: ACTION, "agent_pos": OBS_STATE}
        for cam in self.camera_names:
            features[f"pixels/{cam}"] = PolicyFeature(
                type=FeatureType.VISUAL, shape=(self.image_size, self.image_size, 3)
            )
            features_map[f"pixels/{cam}"] = f"{OBS_IMAGES}.{cam}"
        return features, features_map

    def _validate(self) -> None:
        """Refuse bad settings when the config is parsed, so ``lerobot-eval`` fails before building a policy."""
        tasks = check_tasks(self.task)
        check_cameras(self.cameras)
        check_image_size(self.image_size)
        check_quality(self.quality)
        if self.fps != CONTROL_FPS:
            raise ValueError(f"fps is fixed by the simulator's control rate ({CONTROL_FPS}), got {self.fps}")
        if self.episode_length is not None:
            check_at_least("episode_length", self.episode_length, 1)
        check_at_least("n_train_envs", self.n_train_envs, 1)
        check_at_least("n_test_envs", self.n_test_envs, 1)
        check_seed(self.seed)
        check_asset_folders(self.sampling.texture_folder, self.sampling.shape_folder)
        check_factors(self.train_factors, tasks, "train_factors")
        conditions = [PAIR_SEPARATOR.join(parse_shift(shift)) for shift in self.shifts]
        for condition in conditions:
            if is_family_condition(condition):  # a task family's own (pick: held-out phrasings / objects)
                check_condition(condition, tasks)
                continue
            check_factors(condition.split(PAIR_SEPARATOR), tasks, f"shift {condition!r}")
        if len(set(conditions)) != len(conditions):
            raise ValueError(f"shifts lists a condition more than once: {self.shifts}")
        if not self.include_train and not self.shifts:
            raise ValueError("nothing to evaluate: include_train=false and no shifts given")
        if self.configs_path:
            self._check_configs_file(tasks)
        if self.obs == LEROBOT_METAWORLD_OBS:
            self._check_lerobot_settings(tasks)

    def _check_lerobot_settings(self, tasks: list[str]) -> None:
        """LeRobot's observation fixes the camera and image size; only Meta-World tasks have LeRobot twins."""
        if self.cameras != DEFAULT_CAMERAS or self.image_size != DEFAULT_IMAGE_SIZE:
            raise ValueError(
                f"obs={LEROBOT_METAWORLD_OBS} fixes the camera (corner2) and image size ({IMAGE_SIZE}); "
                f"leave cameras and image_size unset (got cameras={self.cameras}, image_size={self.image_size})"
            )
        for task in tasks:
            spec = get_task(task)
            check_lerobot_task(spec)
            if spec.goal is not None:
                logger.warning(
                    "factorworld: task %s is Factor World's definition (goal %s, success within %s m), not "
                    "Meta-World's %s that LeRobot's metaworld env runs: a checkpoint trained there solves a "
                    "different task here",
                    task,
                    spec.goal,
                    spec.success_radius,
                    spec.metaworld_name,
                )

    def _check_configs_file(self, tasks: list[str]) -> None:
        path = check_input_file(self.configs_path, "configs_path")
        try:
            configs = load_configs(path)
        except (ValueError, KeyError, TypeError) as err:
            raise ValueError(f"configs_path {path} holds no valid configurations ({err})") from None
        missing = [task for task in tasks if not any(c.task == task for c in configs)]
        if missing:
            raise ValueError(f"configs_path {path} holds no configuration for task(s) {', '.join(missing)}")

    def _resolve_train_condition(self) -> None:
        """Fill N, factors, seed and sampling from ``dataset_root`` (refusing disagreements) or the defaults; with
        ``obs=factorworld`` also the cameras, image size and quality its frames were rendered with (LeRobot's
        observation fixes its own: a LeRobot checkpoint evaluated on a dataset's environments keeps it)."""
        if self.configs_path and self.dataset_root:
            raise ValueError(
                "give dataset_root or configs_path, not both: each defines the training environments "
                f"(dataset_root={self.dataset_root}, configs_path={self.configs_path})"
            )
        if self.dataset_root is None:
            lerobot = self.obs == LEROBOT_METAWORLD_OBS  # a LeRobot checkpoint's training scene: the unshifted one
            default_n, default_factors = (1, []) if lerobot else (DEFAULT_N_TRAIN_ENVS, list(PAPER_STUDY_FACTORS))
            self.n_train_envs = default_n if self.n_train_envs is None else self.n_train_envs
            self.train_factors = default_factors if self.train_factors is None else self.train_factors
            self.seed = DEFAULT_ENV_SEED if self.seed is None else self.seed
            return
        dataset = read_dataset_condition(self.dataset_root)
        explicit_sampling = None if self.sampling == SamplingOptions() else self.sampling
        requested = {
            "n_train_envs": self.n_train_envs,
            "train_factors": self.train_factors,
            "seed": self.seed,
            "sampling": explicit_sampling,
        }
        own_frames = self.obs == FACTORWORLD_OBS  # the dataset's frames are what this observation renders
        if own_frames:
            cameras = None if self.cameras is None else check_cameras(self.cameras)
            requested.update(quality=self.quality, cameras=cameras, image_size=self.image_size)
        check_against_dataset(dataset, requested)
        for name in self.task_names:
            dataset.train_configs(name)  # raises when the dataset holds no environment of this task
        self.n_train_envs, self.train_factors, self.seed = dataset.n_envs, list(dataset.factors), dataset.seed
        self.sampling = dataset.sampling
        if not own_frames:
            return
        if dataset.quality is not None:
            self.quality = dataset.quality
        if dataset.cameras is not None:
            self.cameras = ",".join(dataset.cameras)
        if dataset.image_size is not None:
            self.image_size = dataset.image_size

    @property
    def task_names(self) -> list[str]:
        return check_tasks(self.task)

    @property
    def camera_names(self) -> tuple[str, ...]:
        return check_cameras(self.cameras)

    @property
    def gym_kwargs(self) -> dict:
        return {
            "cameras": self.camera_names,
            "image_size": self.image_size,
            "quality": self.quality,
            "max_episode_steps": self.episode_length,
            "object_pos_width": self.sampling.widths.get("object_pos"),
            "obs": self.obs,
        }

    def suites(self, task: str) -> dict:
        """Evaluation conditions -> scene configurations for ``task``."""
        train_configs = None
        if self.dataset_root:
            train_configs = read_dataset_condition(self.dataset_root).train_configs(get_task(task).name)
        elif self.configs_path:
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
        n_train = len(suites[TRAIN_SUITE])
        if len(suites) > 1 and self.n_test_envs % n_train:
            logger.warning(
                "factorworld: test environment j derives from training environment j %% %d; n_test_envs=%d is not "
                "a multiple of %d, so the training environments are unequally represented in the shifted "
                "conditions and their gaps are not paired environment by environment",
                n_train,
                self.n_test_envs,
                n_train,
            )
        if not self.include_train:
            suites.pop(TRAIN_SUITE)
        return suites

    def create_envs(self, n_envs: int, use_async_envs: bool = False) -> dict[str, dict[int, gym.vector.VectorEnv]]:
        base_cls = gym.vector.AsyncVectorEnv if (use_async_envs and n_envs > 1) else gym.vector.SyncVectorEnv
        extra = {"context": "forkserver"} if base_cls is gym.vector.AsyncVectorEnv else {}
        vector_cls = checked_vector_env(base_cls)  # logs how the seeded episodes covered the environments
        out: dict[str, dict[int, gym.vector.VectorEnv]] = {}
        for task_id, task in enumerate(self.task_names):
            for suite, configs in self.suites(task).items():
                make = partial(FactorWorldEnv, task, tuple(configs), **self.gym_kwargs)
                vec = vector_cls([make] * n_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP, **extra)
                vec.setup_coverage(f"{task}/{suite}", len(configs))
                out.setdefault(suite, {})[task_id] = vec
        return out


def lerobot_metaworld_features() -> tuple[dict[str, PolicyFeature], dict[str, str]]:
    """The features and map of LeRobot 0.6.1's ``MetaworldEnv`` config (``obs_type=pixels_agent_pos``),
    key for key, so ``env_to_policy_features`` gives a LeRobot Meta-World checkpoint its own inputs."""
    features = {
        ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(ACTION_DIM,)),
        "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(STATE_DIM,)),
        LEROBOT_IMAGE_FEATURE: PolicyFeature(type=FeatureType.VISUAL, shape=(IMAGE_SIZE, IMAGE_SIZE, 3)),
    }
    features_map = {ACTION: ACTION, "agent_pos": OBS_STATE, "top": OBS_IMAGE, LEROBOT_IMAGE_FEATURE: OBS_IMAGE}
    return features, features_map
