"""``factorworld collect``: scripted demonstrations of Factor World environments as a LeRobotDataset.

Work is split into jobs (one environment, up to ``episodes_per_shard`` demos) run by worker
processes. Each job writes its own small LeRobotDataset in a staging folder and only renames it from
``<job>.tmp`` to ``<job>`` after ``finalize()``: a crashed worker or a full disk can only lose the
job in progress, and a re-run resumes from the finished jobs. When every job is done the shards are
merged with LeRobot's ``aggregate_datasets`` (which keeps the factor columns) into ``root``.
"""

from __future__ import annotations

import importlib
import json
import os
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from multiprocessing import get_all_start_methods, get_context
from pathlib import Path
from typing import Any

import numpy as np
from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE
from tqdm import tqdm

from ..assets.library import check_asset_folders
from ..core.checks import (
    check_at_least,
    check_choice,
    check_folder_target,
    check_image_size,
    check_repo_id,
    check_seed,
    check_std,
    split_list,
)
from ..core.io import atomic_write_text
from ..core.splits import check_split
from ..core.timing import Timings
from ..envs import runtime
from ..envs.factor_env import CONTROL_FPS, FactorWorldEnv
from ..experts import DEFAULT_ACTION_NOISE, Episode, expert_policy, rollout
from ..factors.registry import PAPER_STUDY_FACTORS, check_factors
from ..factors.values import SceneConfig
from ..protocol.sampling import SamplingOptions, sample_configs, unset_options
from ..protocol.sidecar import SIDECAR
from ..scene.build import DEFAULT_QUALITY, check_quality
from ..scene.cameras import DEFAULT_CAMERAS_SETTING, DEFAULT_IMAGE_SIZE, check_cameras
from ..tasks import check_tasks
from .card import write_card
from .hub import check_push_settings, push_dataset
from .merge import write_stats_in_feature_order
from .schema import ENV_ID_COLUMN, SPLIT_COLUMN, encode_episode, encode_factors, frame_features
from .version import DATA_VERSION, DATA_VERSION_KEY, data_version, describe_data_version

MODES = ("new", "overwrite", "append")
PLAN_FILE = "plan.json"
JOB_RESULT_FILE = "factorworld_job.json"
# Settings that do not change what gets collected (so they may differ on resume).
RUN_ONLY_SETTINGS = ("workers", "mode", "push_to_hub", "private", "episodes_per_shard", "start_method")


@dataclass
class CollectConfig:
    """``factorworld collect``: scripted demos -> LeRobotDataset (v3) with per-episode factor values.

    Attributes:
        task: Task name, or a comma-separated list (one dataset, per-episode instruction).
        factors: Factors varied across the environments (default: the paper's seven).
        n_envs: Number of environments N per task.
        demos: Total successful demos per task (spread evenly over the environments).
        demos_per_env: If set, demos per environment instead of ``demos``.
        split: Asset split the environments draw from (``train`` or ``eval``).
        seed: Seed of the environments and of every episode (object start, action noise).
        cameras: Comma-separated cameras, each stored as ``observation.images.<camera>``.
        image_size: Square image side in pixels.
        quality: Rendering quality (``fast``, ``full`` or ``lod``: ``scene.build.QUALITIES``); recorded with the
            dataset, so frames of different qualities never mix.
        action_noise: Std of the Gaussian noise added to the expert's actions (default: the public Factor World's, ``experts.DEFAULT_ACTION_NOISE``).
        end_on_success: End episodes at the first success (else run to ``max_episode_steps``).
        max_episode_steps: Step limit per episode (``None``: the task's horizon).
        max_attempts: Attempts per demo before it is reported as failed.
        use_videos: Store images as MP4 video (default) or as PNG images in parquet.
        root: Output dataset folder.
        repo_id: Dataset id (``user/name``), used by LeRobot and for the Hub.
        workers: Worker processes (0: all cores).
        episodes_per_shard: Demos per job; a crash loses at most one job per worker.
        start_method: How workers start: ``auto`` (``fork`` when this process has no GL context, else
            ``forkserver``), or ``fork`` / ``forkserver`` / ``spawn``.
        mode: ``new`` (refuses to touch a different existing dataset; resumes an identical one),
            ``overwrite`` (deletes what is at ``root``), ``append`` (adds these demos to it).
        push_to_hub: Push with LeRobot's mechanism (card, tags) when done; a Hub ``repo_id`` (not
            ``local/...``) and a Hugging Face token are checked before collecting.
        private: Push as a private dataset (only with ``push_to_hub``).
        sampling: How factor values are drawn (``--sampling.n_distractors=2``, ``--sampling.texture_folder=...``,
            ``--sampling.rgb_fraction=0.5``: the share of textures that are flat RGB colours); recorded with the data.
    """

    task: str = "pick-place"
    factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    n_envs: int = 5
    demos: int = 20
    demos_per_env: int | None = None
    split: str = "train"
    seed: int = 0
    cameras: str = DEFAULT_CAMERAS_SETTING
    image_size: int = DEFAULT_IMAGE_SIZE
    quality: str = DEFAULT_QUALITY
    action_noise: float = DEFAULT_ACTION_NOISE
    end_on_success: bool = True
    max_episode_steps: int | None = None
    max_attempts: int = 3
    use_videos: bool = True
    root: str = "outputs/datasets/factorworld_pick-place"
    repo_id: str = "local/factorworld_pick-place"
    workers: int = 0
    episodes_per_shard: int = 20
    start_method: str = "auto"
    mode: str = "new"
    push_to_hub: bool = False
    private: bool = False
    sampling: SamplingOptions = field(default_factory=SamplingOptions)

    def __post_init__(self) -> None:
        """Refuse every invalid setting here, when it is parsed: before any worker starts or data is touched."""
        check_factors(self.factors, check_tasks(self.task))
        check_at_least("n_envs", self.n_envs, 1)
        if self.demos_per_env is None:
            check_at_least("demos", self.demos, 1)
            if self.demos < self.n_envs:
                raise ValueError(f"demos ({self.demos}) must be at least n_envs ({self.n_envs}): one per environment")
        else:
            check_at_least("demos_per_env", self.demos_per_env, 1)
        check_split(self.split)
        check_asset_folders(self.sampling.texture_folder, self.sampling.shape_folder)
        check_seed(self.seed)
        check_cameras(self.cameras)
        check_image_size(self.image_size)
        check_quality(self.quality)
        check_std("action_noise", self.action_noise)
        if self.max_episode_steps is not None:
            check_at_least("max_episode_steps", self.max_episode_steps, 1)
        check_at_least("max_attempts", self.max_attempts, 1)
        root = check_folder_target(self.root, "root")
        check_folder_target(staging_dir(root), "root's staging folder")
        check_repo_id(self.repo_id)
        check_push_settings(self.repo_id, self.push_to_hub, self.private)
        check_at_least("workers", self.workers, 0)
        check_at_least("episodes_per_shard", self.episodes_per_shard, 1)
        check_choice("start_method", self.start_method, ("auto", *get_all_start_methods()))
        check_choice("mode", self.mode, MODES)

    @property
    def task_names(self) -> list[str]:
        return check_tasks(self.task)

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(split_list(self.cameras))

    def fingerprint(self) -> dict[str, Any]:
        """The settings that determine the collected data, with the version of what the data means."""
        settings = asdict(self)
        for key in (*RUN_ONLY_SETTINGS, "root"):
            settings.pop(key)
        for key in unset_options(self.sampling):  # an option added later, unset: recorded as before it existed
            settings["sampling"].pop(key)
        return {**settings, DATA_VERSION_KEY: DATA_VERSION}


@dataclass(frozen=True)
class Job:
    """Demos ``demo_indices`` of environment ``env_index`` of ``task``."""

    job_id: str
    task: str
    task_index: int
    env_index: int
    config: dict
    demo_indices: tuple[int, ...]


@dataclass
class CollectReport:
    root: Path
    episodes: int
    frames: int
    failures: dict[str, int]
    seconds: float
    timings: dict[str, float] = field(default_factory=dict)  # where the time went (seconds; jobs' summed)


def plan_jobs(cfg: CollectConfig) -> list[Job]:
    """Every job of the collection, in a deterministic order."""
    jobs = []
    for task_index, task in enumerate(cfg.task_names):
        configs = sample_configs(task, cfg.n_envs, cfg.seed, cfg.split, cfg.factors, cfg.sampling)
        for env_index, config in enumerate(configs):
            if cfg.demos_per_env is not None:
                count = cfg.demos_per_env
            else:
                count = cfg.demos // cfg.n_envs + (1 if env_index < cfg.demos % cfg.n_envs else 0)
            demos = tuple(range(count))
            for part, start in enumerate(range(0, count, cfg.episodes_per_shard)):
                jobs.append(
                    Job(
                        f"{task}__env{env_index:03d}__part{part:03d}",
                        task,
                        task_index,
                        env_index,
                        config.to_dict(),
                        demos[start : start + cfg.episodes_per_shard],
                    )
                )
    return jobs


def episode_seed(cfg_seed: int, task_index: int, env_index: int, demo: int, attempt: int) -> int:
    return int(np.random.SeedSequence([cfg_seed, task_index, env_index, demo, attempt]).generate_state(1)[0])


def staging_dir(root: Path) -> Path:
    return root.parent / f"{root.name}.parts"


def collect(cfg: CollectConfig) -> CollectReport:
    """Run (or resume) a collection and merge it into ``cfg.root``."""
    start = time.perf_counter()
    timings = Timings()
    _quiet_encoder()
    root = Path(cfg.root).resolve()
    parts = staging_dir(root)
    try:  # sampling the environments checks the asset folders and the distractor layout: before touching data
        jobs = plan_jobs(cfg)
    except RuntimeError as err:
        raise ValueError(str(err)) from err
    _prepare(cfg, root, parts)
    done = {job.job_id for job in jobs if (parts / job.job_id / JOB_RESULT_FILE).is_file()}
    todo = [job for job in jobs if job.job_id not in done]
    for stale in parts.glob("*.tmp"):  # a job interrupted by a crash: redo it from scratch
        shutil.rmtree(stale)
    total = sum(len(job.demo_indices) for job in todo)
    workers = max(1, min(cfg.workers or os.cpu_count() or 1, len(todo)))  # a process per job at most
    errors: dict[str, str] = {}
    if todo:
        settings = asdict(cfg)
        with tqdm(total=total, desc="collecting demos", unit="demo") as bar:
            if workers == 1:
                for job in todo:
                    try:
                        run_job(job, settings, str(parts))
                    except Exception as err:  # e.g. a full disk: keep the finished shards, report
                        errors[job.job_id] = repr(err)
                        break
                    bar.update(len(job.demo_indices))
            else:
                pool_start = time.perf_counter()
                context = _worker_context(cfg.start_method)
                timings.add("worker_start", time.perf_counter() - pool_start)
                with ProcessPoolExecutor(workers, mp_context=context, initializer=_worker_init) as pool:
                    futures = {pool.submit(run_job, job, settings, str(parts)): job for job in todo}
                    for future in as_completed(futures):
                        job = futures[future]
                        try:
                            future.result()
                        except Exception as err:  # a worker died: keep going, report, resume later
                            errors[job.job_id] = repr(err)
                        bar.update(len(job.demo_indices))
    if errors:
        raise RuntimeError(
            f"{len(errors)} job(s) failed and were not merged (finished jobs are kept in {parts}; "
            f"re-run the same command to resume): {errors}"
        )
    results = [json.loads((parts / job.job_id / JOB_RESULT_FILE).read_text()) for job in jobs]
    for job, result in zip(jobs, results, strict=True):
        if job.job_id not in done:  # jobs run now (resumed ones were timed by the run that did them)
            timings.update(result.get("timings", {}))
    failures = {f"{r['task']}/{r['env_id']}": r["failures"] for r in results if r["failures"]}
    with timings.span("merge"):
        episodes, frames = _merge(cfg, root, parts, jobs, results)
    if cfg.push_to_hub:
        push_dataset(root, cfg.repo_id, private=cfg.private)
    return CollectReport(root, episodes, frames, failures, time.perf_counter() - start, timings.as_dict())


WORKER_PRELOAD = "lerobot_factorworld.datasets.worker_preload"


def _worker_context(start_method: str):
    """How worker processes start. ``auto``: ``fork`` on Linux when this process holds no GL context
    (workers then inherit LeRobot and MuJoCo already imported: no per-worker import, seconds each),
    else ``forkserver`` preloaded with those modules (safe with GL contexts and torch threads)."""
    if start_method == "auto":
        start_method = "fork" if sys.platform == "linux" and not runtime.gl_context_created() else "forkserver"
    context = get_context(start_method)
    if start_method == "forkserver":
        context.set_forkserver_preload([WORKER_PRELOAD])
    elif start_method == "fork":
        importlib.import_module(WORKER_PRELOAD)  # imported once here, inherited by every worker
    return context


def _worker_init() -> None:
    # One llvmpipe thread per process: workers already use every core between them.
    os.environ.setdefault("LP_NUM_THREADS", "1")
    _quiet_encoder()


def _quiet_encoder() -> None:
    os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 otherwise prints its whole configuration per video


def _prepare(cfg: CollectConfig, root: Path, parts: Path) -> None:
    """Refuse to mix different settings; resume identical ones; overwrite or append on request.

    Every refusal happens before anything on disk is changed."""
    fingerprint = cfg.fingerprint()
    plan_path = parts / PLAN_FILE
    holds_data = root.is_dir() and any(root.iterdir())
    previous = _read_sidecar(root) if holds_data else None
    if holds_data and previous is None:
        raise FileExistsError(
            f"{root} is not empty and holds no factorworld dataset (no {SIDECAR}); nothing was changed. "
            "Choose another --root (a new or empty folder)"
        )
    staged = json.loads(plan_path.read_text()) if plan_path.is_file() else None
    if cfg.mode != "overwrite":
        _check_data_version(previous, f"{root} holds", "collect into another --root or pass --mode=overwrite")
        _check_data_version(staged, f"the unfinished collection staged in {parts} is", "pass --mode=overwrite")
    if cfg.mode == "append" and previous is not None:
        _check_appendable(previous["settings"], fingerprint, root)
    if cfg.mode == "overwrite":
        for path in (root, parts):
            if path.exists():
                shutil.rmtree(path)
    elif holds_data and cfg.mode == "new" and not plan_path.is_file():
        if previous.get("settings") != fingerprint:
            diff = _settings_diff(previous.get("settings", {}), fingerprint)
            raise FileExistsError(
                f"{root} already holds a dataset collected with other settings ({diff}); nothing was changed. "
                "Pass --mode=overwrite to replace it or --mode=append to add these demos to it."
            )
        if not list(parts.glob("*")):
            raise FileExistsError(f"{root} is already complete with these settings; use --mode=append to add more")
    if staged is not None and cfg.mode != "overwrite":
        if staged["settings"] != fingerprint:
            raise FileExistsError(
                f"an unfinished collection with other settings is staged in {parts} "
                f"({_settings_diff(staged['settings'], fingerprint)}); re-run it with its settings to finish it, "
                "or pass --mode=overwrite to discard it"
            )
    parts.mkdir(parents=True, exist_ok=True)
    atomic_write_text(plan_path, json.dumps({"settings": fingerprint, "mode": cfg.mode}, indent=1, sort_keys=True))


def _check_data_version(recorded: dict | None, what: str, fix: str) -> None:
    """Never mix data whose columns mean different things (e.g. ``observation.state`` in another frame)."""
    if recorded is None:
        return
    version = data_version(recorded["settings"])
    if version != DATA_VERSION:
        raise FileExistsError(
            f"{what} {describe_data_version(version)}, but this version of lerobot_factorworld writes "
            f"{describe_data_version(DATA_VERSION)}; nothing was changed. Data of two versions never mix: {fix}"
        )


# What an appended collection must share: the features (LeRobot's ``aggregate_datasets`` needs them identical)
# and the render quality (the side-car records one for the whole dataset, and evaluation renders it).
SCHEMA_SETTINGS = ("cameras", "image_size", "use_videos", "quality")


def _check_appendable(old: dict, new: dict, root: Path) -> None:
    """Check now, not after the collection, that the new frames can join the old (``SCHEMA_SETTINGS``); a side-car
    that does not record its quality is taken at its word for the rest."""
    keys = [k for k in SCHEMA_SETTINGS if k != "quality" or "quality" in old]
    old_schema = {k: split_list(old.get(k)) if k == "cameras" else old.get(k) for k in keys}
    new_schema = {k: split_list(new[k]) if k == "cameras" else new[k] for k in keys}
    if old_schema != new_schema:
        raise FileExistsError(
            f"cannot append to {root}: its frames were made otherwise ({_settings_diff(old_schema, new_schema)}); "
            f"nothing was changed. Appending needs the same {', '.join(SCHEMA_SETTINGS)}"
        )


def _settings_diff(old: dict, new: dict) -> str:
    keys = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
    return ", ".join(f"{k}: {old.get(k)!r} -> {new.get(k)!r}" for k in keys) or "unknown settings"


def run_job(job: Job, settings: dict, parts_dir: str) -> dict:
    """Collect one job's demos into ``<parts>/<job_id>`` (atomically). Runs in a worker process."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: PLC0415  heavy (seconds): only a collecting worker needs it

    timings = Timings()
    job_start = time.perf_counter()
    worker = {"push_to_hub": False, "private": False}  # the main process pushes (and checked the token)
    cfg = CollectConfig(**{**settings, **worker, "sampling": SamplingOptions(**settings["sampling"])})
    parts = Path(parts_dir)
    tmp, final = parts / f"{job.job_id}.tmp", parts / job.job_id
    if tmp.exists():
        shutil.rmtree(tmp)
    config = SceneConfig.from_dict(job.config)
    cameras, size = cfg.camera_names, (cfg.image_size, cfg.image_size)
    env = FactorWorldEnv(
        job.task,
        config,
        cameras=cameras,
        image_size=cfg.image_size,
        quality=cfg.quality,
        max_episode_steps=cfg.max_episode_steps,
        terminate_on_success=cfg.end_on_success,
        object_pos_width=cfg.sampling.widths.get("object_pos"),  # recorded with the data (sampling settings)
        scene_cache_size=1,
    )
    policy = expert_policy(job.task)
    dataset = LeRobotDataset.create(
        repo_id=f"local/{job.job_id}",
        fps=CONTROL_FPS,
        features=frame_features(cameras, size, cfg.use_videos),
        root=tmp,
        robot_type="sawyer",
        use_videos=cfg.use_videos,
    )
    episode_columns: dict[str, Any] = {}
    original_save = dataset.meta.save_episode

    def save_with_factors(episode_index, episode_length, episode_tasks, episode_stats, episode_metadata):
        return original_save(
            episode_index, episode_length, episode_tasks, episode_stats, {**episode_metadata, **episode_columns}
        )

    dataset.meta.save_episode = save_with_factors
    episodes, failures = [], 0
    timings.add("setup", time.perf_counter() - job_start)
    try:
        # timed, unchanged: the scene's compilation and rendering inside the expert's rollouts
        with (
            timings.wrap(runtime.CompiledScene, "__init__", "env_build"),
            timings.wrap(runtime.CompiledScene, "render_all", "render"),
        ):
            for demo in job.demo_indices:
                for attempt in range(cfg.max_attempts):
                    seed = episode_seed(cfg.seed, job.task_index, job.env_index, demo, attempt)
                    with timings.span("expert_physics"):  # less the compilation and rendering inside
                        episode = rollout(env, policy, seed, cfg.action_noise)
                    if episode.success:
                        break
                    failures += 1
                else:
                    continue
                with timings.span("write_frames"):
                    for frame in episode_frames(episode, env.task_description):
                        dataset.add_frame(frame)
                episode_columns.clear()
                episode_columns.update(
                    {
                        ENV_ID_COLUMN: config.env_id,
                        SPLIT_COLUMN: config.split,
                        **encode_factors(episode.info["factors"]),
                    }
                )
                # the episode's instruction (and a family's record of what it asked for)
                episode_columns.update(encode_episode(episode.info, env.task_description, env.task))
                episode_columns["factorworld/seed"] = seed
                episode_columns["factorworld/demo"] = demo
                with timings.span("save_episode"):  # image / video encoding and the episode's parquet
                    dataset.save_episode()
                episodes.append({"demo": demo, "seed": seed, "length": len(episode)})
    finally:
        with timings.span("finalize"):
            dataset.finalize()
        env.close()
    result = {
        "job_id": job.job_id,
        "task": job.task,
        "env_id": config.env_id,
        "episodes": episodes,
        "failures": failures,
        "config": job.config,
        "timings": timings.as_dict(),
    }
    atomic_write_text(tmp / JOB_RESULT_FILE, json.dumps(result, indent=1))
    if final.exists():
        shutil.rmtree(final)
    tmp.rename(final)  # the job counts as done only once its shard is complete
    return result


def episode_frames(episode: Episode, task_description: str) -> list[dict]:
    """LeRobot frames of an expert episode: each observation with the action taken from it."""
    frames = []
    for obs, action in zip(episode.observations, episode.actions, strict=True):
        frame = {f"{OBS_IMAGES}.{cam}": image for cam, image in obs["pixels"].items()}
        frame.update({OBS_STATE: obs["agent_pos"], ACTION: action, "task": task_description})
        frames.append(frame)
    return frames


def _merge(cfg: CollectConfig, root: Path, parts: Path, jobs: list[Job], results: list[dict]) -> tuple[int, int]:
    # heavy (seconds): settings are checked before LeRobot's dataset stack is imported
    from lerobot.datasets.aggregate import aggregate_datasets  # noqa: PLC0415
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

    sources = [parts / job.job_id for job, r in zip(jobs, results, strict=True) if r["episodes"]]
    repo_ids = [f"local/{path.name}" for path in sources]
    if cfg.mode == "append" and root.exists():
        sources.insert(0, root)
        repo_ids.insert(0, cfg.repo_id)
    if not sources:
        raise RuntimeError("no successful demo was collected; nothing to write (see the failures per environment)")
    merged = root.parent / f"{root.name}.merging"
    if merged.exists():
        shutil.rmtree(merged)
    aggregate_datasets(repo_ids, cfg.repo_id, roots=sources, aggr_root=merged)
    write_stats_in_feature_order(merged)
    environments = [r["config"] for r in results]
    failures = {r["job_id"]: r["failures"] for r in results}
    history = []
    previous = _read_sidecar(root) if cfg.mode == "append" else None
    if previous is not None:  # appended: keep what the earlier collections recorded
        environments = previous["environments"] + environments
        failures = {**previous["failures"], **failures}
        history = [*previous.get("history", []), previous["settings"]]
    unique = sorted({json.dumps(c, sort_keys=True) for c in environments})
    sidecar = {
        "settings": cfg.fingerprint(),
        "history": history,
        "environments": [json.loads(c) for c in unique],
        "failures": failures,
    }
    atomic_write_text(merged / SIDECAR, json.dumps(sidecar, indent=1, sort_keys=True))
    # Swap in the merged dataset only now: until here the previous dataset (if any) is untouched.
    backup = root.parent / f"{root.name}.previous"
    if root.exists():
        root.rename(backup)
    merged.rename(root)
    if backup.exists():
        shutil.rmtree(backup)
    shutil.rmtree(parts)
    meta = LeRobotDatasetMetadata(cfg.repo_id, root=root)
    write_card(meta)
    return meta.total_episodes, meta.total_frames


def _read_sidecar(root: Path) -> dict | None:
    path = root / SIDECAR
    return json.loads(path.read_text()) if path.is_file() else None
