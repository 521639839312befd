"""``factorworld profile``: the generalization profile of an existing LeRobot checkpoint, a study with one
method that names the checkpoint (``MethodConfig.checkpoint``) and therefore no collection and no training.

The checkpoint is evaluated on the unshifted ``train`` condition and under each factor (pairs and the radius
sweep optional) on paired episode seeds, with the study's steps, cache, executors and outputs (``report.md``,
``results.csv``, plots, ``episodes.parquet``): :meth:`ProfileConfig.study` is the whole translation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ...envs.lerobot_obs import FACTORWORLD_OBS
from ...factors.registry import PAPER_STUDY_FACTORS, WIDTHS
from ...families import family_of
from ...protocol.sampling import SamplingOptions
from ...scene.build import DEFAULT_QUALITY
from ..run.checkpoint import local_folder, read_policy_config, training_dataset
from ..run.options import RunOptions
from .collect_settings import CollectSettings
from .config import HUB_BENCHMARK, StudyConfig
from .eval_settings import EvalSettings
from .method_config import MethodConfig

DEFAULT_METHOD = "checkpoint"  # the method's name when the checkpoint's config names no policy type


@dataclass
class ProfilePolicy:
    """The checkpoint (LeRobot's ``--policy.path`` spelling).

    Attributes:
        path: A LeRobot ``pretrained_model`` folder (``config.json``, ``model.safetensors``, processor files), or
            a Hub model id, fetched only when the Hub can be reached.
        name: Its method name in the results (default: its policy type, e.g. ``bc``).
    """

    path: str = ""
    name: str = ""


@dataclass
class ProfileEnv:
    """How the env observes, which must be how the checkpoint was trained to observe (checked before any work).

    Attributes:
        obs: ``factorworld`` (``cameras`` at ``image_size``, 8-number state) or ``lerobot_metaworld`` (LeRobot's
            ``--env.type=metaworld`` observation: docs/lerobot_metaworld.md).
        cameras: Comma-separated cameras (``factorworld`` only; default: the dataset's, else ``front``).
        image_size: Square image side in pixels (``factorworld`` only; default: the dataset's, else 84).
    """

    obs: str = FACTORWORLD_OBS
    cameras: str | None = None
    image_size: int | None = None


@dataclass
class ProfileConfig:
    """``factorworld profile --policy.path=<checkpoint> --task=<task> [...]``.

    Attributes:
        policy: The checkpoint and its name in the results.
        env: The observation it was trained with.
        task: The task (``factorworld tasks``).
        factors: Single-factor conditions (default: the paper's seven).
        pairs: Pair conditions: ``[all]`` or a list of ``a+b``.
        radius_factors: Factors of the radius sweep (``camera_pos``, ``table_pos``).
        radius_widths: Widths of the sweep (narrow / medium / wide).
        dataset_root: The Factor World dataset the checkpoint was trained on: ``train`` is then its training
            environments (N, factors, seed and sampling read from its ``meta/factorworld.json``, and with
            ``env.obs=factorworld`` its cameras, image size and render quality; settings given as well must
            agree). Default: the dataset the checkpoint's ``train_config.json`` names, when it is a
            Factor World dataset on this machine (``factorworld collect`` + ``lerobot-train``); otherwise the
            defaults below.
        n_train_envs: Environments of the unshifted ``train`` condition (default 5, or 1 with
            ``env.obs=lerobot_metaworld``: Meta-World's own scene, as ``lerobot-eval --env.obs=lerobot_metaworld``).
        train_factors: Factors varied across those environments (default the paper's seven, or none with
            ``env.obs=lerobot_metaworld``).
        seed: Seed of the environment sampling (default 0; the ``seed`` column of the results; a checkpoint has
            no training seed).
        eval: Episodes, test environments per shifted condition, ``start_seed`` (episode ``i`` is reset with
            ``start_seed + i`` in every condition), step limit, device, batch size, threads.
        name: Study name in the results and the report.
        out_dir: Folder of the outputs and the cached evaluations.
        workers: Evaluations run at once.
        dry_run: Print the plan and its cost, run nothing.
        push_to_hub: Push ``episodes.parquet`` and ``results.csv`` with a card to ``hub_repo_id`` afterwards.
        hub_repo_id: ``user/name`` of that dataset repo.
        model_repo_id: ``user/name`` of the checkpoint's model repo: with ``push_to_hub``, a pull request adds
            ``.eval_results/factorworld.yaml`` and the per-episode Parquet to it.
        hub_benchmark: The Hub benchmark dataset (``user/name``) the ``.eval_results`` entries name.
    """

    policy: ProfilePolicy = field(default_factory=ProfilePolicy)
    env: ProfileEnv = field(default_factory=ProfileEnv)
    task: str = ""
    factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    pairs: list[str] = field(default_factory=list)
    radius_factors: list[str] = field(default_factory=list)
    radius_widths: list[str] = field(default_factory=lambda: list(WIDTHS))
    dataset_root: str | None = None
    n_train_envs: int | None = None
    train_factors: list[str] | None = None
    seed: int | None = None
    eval: EvalSettings = field(default_factory=EvalSettings)
    name: str = "profile"
    out_dir: str = "outputs/profile"
    workers: int = 1
    dry_run: bool = False
    push_to_hub: bool = False
    hub_repo_id: str | None = None
    model_repo_id: str | None = None
    hub_benchmark: str = HUB_BENCHMARK

    def __post_init__(self) -> None:
        if not self.policy.path:
            raise ValueError("factorworld profile needs --policy.path=<a pretrained_model folder or a Hub model id>")
        if not self.task:
            raise ValueError("factorworld profile needs --task=<task> (factorworld tasks lists them)")
        self._study = self._make_study()  # every setting checked now, as the study checks its own

    def study(self) -> StudyConfig:
        """The study this profile is: one method naming the checkpoint, one task, one seed."""
        return self._study

    def _make_study(self) -> StudyConfig:
        # Deliberately here: the env config imports LeRobot (seconds); it resolves the train condition's
        # defaults for the observation and checks the task, cameras and image size as lerobot-eval would.
        from ...adapters.env_config import FactorWorldEnvConfig  # noqa: PLC0415

        view = {"cameras": self.env.cameras, "image_size": self.env.image_size}
        if self.dataset_root is None and self.env.obs == FACTORWORLD_OBS:
            self.dataset_root = training_dataset(local_folder(self.policy.path))
        env = FactorWorldEnvConfig(
            task=self.task,
            obs=self.env.obs,
            dataset_root=self.dataset_root,
            n_train_envs=self.n_train_envs,
            train_factors=self.train_factors,
            seed=self.seed,
            **{name: value for name, value in view.items() if value is not None},  # unset: the env's default
        )
        if len(env.task_names) != 1:
            raise ValueError(f"factorworld profile takes one task, got {self.task!r}")
        # Factor World's observation renders at the dataset's quality; LeRobot's at Meta-World's own (the default)
        own_quality = env.quality if env.obs == FACTORWORLD_OBS else DEFAULT_QUALITY
        name = self.policy.name or _default_name(self.policy.path)
        method = MethodConfig(name=name, checkpoint=self.policy.path, obs=self.env.obs)
        return StudyConfig(
            name=self.name,
            out_dir=self.out_dir,
            tasks=env.task_names,
            n_train_envs=[env.n_train_envs],
            seeds=[env.seed],
            train_factors=list(env.train_factors),
            factors=list(self.factors),
            pairs=list(self.pairs),
            radius_factors=list(self.radius_factors),
            radius_widths=list(self.radius_widths),
            methods=[method],
            collect=_collect_settings(env.task_names[0], env.cameras, env.image_size, env.sampling, own_quality),
            eval=self.eval,
            hub_benchmark=self.hub_benchmark,
        )

    def options(self) -> RunOptions:
        """How the profile's study runs (what its command line says)."""
        return RunOptions(
            workers=self.workers,
            dry_run=self.dry_run,
            push_to_hub=self.push_to_hub,
            hub_repo_id=self.hub_repo_id,
            model_repo_id=self.model_repo_id,
        )


def _collect_settings(
    task: str, cameras: str, image_size: int, sampling: SamplingOptions, quality: str = DEFAULT_QUALITY
) -> CollectSettings:
    """The study settings that sample ``train``'s environments as ``sampling`` does and render them at
    ``quality`` (a dataset's, or the defaults); sampling a study cannot express is refused in one line."""
    defaults, widths = SamplingOptions(), dict(sampling.widths)
    object_pos_width = widths.pop("object_pos", CollectSettings.object_pos_width)
    other = [f"widths.{name}={width}" for name, width in widths.items()]
    other += [f"{name}={getattr(sampling, name)}" for name in ("texture_folder", "shape_folder", "asset_split")
              if getattr(sampling, name) != getattr(defaults, name)]  # fmt: skip
    if other:
        raise ValueError(
            f"the training environments were sampled with {', '.join(other)}, which a profile cannot reproduce; "
            "evaluate the checkpoint with lerobot-eval --env.type=factorworld --env.dataset_root=<its dataset>"
        )
    return CollectSettings(
        cameras=cameras,
        image_size=image_size,
        object_pos_width=object_pos_width,
        n_distractors=sampling.n_distractors,
        rgb_fraction=sampling.rgb_fraction,
        n_objects=sampling.n_objects if "n_objects" in family_of(task).sampling_options else None,
        template=(sampling.template or None) if "template" in family_of(task).sampling_options else None,
        quality=quality,
    )


def _default_name(path: str) -> str:
    """The checkpoint's policy type (``bc``, ``act``, ...) when it is here to read, else ``checkpoint``."""
    folder = local_folder(path)
    return str(read_policy_config(folder).get("type") or DEFAULT_METHOD) if folder is not None else DEFAULT_METHOD
