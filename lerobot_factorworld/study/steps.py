"""Content-hashed study steps: collect (scripted demos), train (``lerobot-train``), eval (LeRobot's
``eval_policy_all`` on the ``factorworld`` env, as ``lerobot-eval`` does).

A step's key hashes its kind, its inputs and the keys of the steps it depends on, so a change to one
setting changes the keys of exactly the steps that depend on it. Inputs hold what changes results
(settings, the versions of the packages that compute them, the dataset format, weight files' content);
settings documented not to change results (workers, evaluation batch size and threads, where a weights
file lies) travel in ``meta["run"]`` instead. Each step works in ``<study>/steps/<kind>/<key>/`` and
counts as done only once its ``result.json`` is written (atomically, last): an interrupted step is
redone, a finished one is never redone. Results name their files relative to the study folder, so a
moved study folder still resumes.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from .. import __version__  # the package root registers the env and policy types (in a fresh worker too)
from ..core.io import atomic_write_text
from ..families import family_of
from ..protocol.conditions import TRAIN_SUITE, fingerprint
from ..protocol.coverage import coverage
from ..protocol.sampling import SamplingOptions
from .inputs import CollectInputs, EvalInputs, TrainInputs

KINDS = ("collect", "train", "eval")
STEP_FORMAT = 2  # bump when a step's meaning changes: every key changes with it (2: versions, content hashes)
RESULT_FILE = "result.json"
INPUTS_FILE = "step.json"
LOG_FILE = "log.txt"
DATA_DIR = "data"
TRAIN_DIR = "train"
CHECKPOINT = "checkpoints/last/pretrained_model"
RUN = "run"  # meta entry: how to run a step, without changing its results (not in the key, not in labels)
RESULT_PATHS = ("root", "checkpoint")  # result entries that name files: stored relative to the study folder
DISTRIBUTION = "lerobot_env_factorworld"
VERSIONED = ("lerobot", "torch", "mujoco", "metaworld")  # packages whose version changes what a step computes


@functools.cache
def versions() -> dict[str, str]:
    """The versions in every step's key: this project's and those of the packages that compute results.

    A code change without a version bump is not detected (bump ``STEP_FORMAT`` or the package version).
    """
    out = {"lerobot_factorworld": _version(DISTRIBUTION, __version__)}
    out.update({name: _version(name, "unknown") for name in VERSIONED})
    return out


def _version(distribution: str, default: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return default


@functools.cache
def _sha256(path: str, size: int, mtime_ns: int) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def file_fingerprint(path: str | Path) -> str | None:
    """``sha256:<hex>`` of a file's content (cached per size and mtime), ``None`` when it is not a file."""
    path = Path(path)
    if not path.is_file():
        return None
    stat = path.stat()
    return "sha256:" + _sha256(str(path.resolve()), stat.st_size, stat.st_mtime_ns)


@dataclass(frozen=True)
class Step:
    """One unit of work. ``inputs`` (JSON-able) and ``deps`` decide ``key``; ``meta`` only labels it."""

    kind: str
    inputs: dict[str, Any]
    deps: tuple[str, ...] = ()
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def key(self) -> str:
        payload = {"format": STEP_FORMAT, "kind": self.kind, "inputs": self.inputs, "deps": list(self.deps)}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    @property
    def label(self) -> str:
        return f"{self.kind} " + " ".join(f"{k}={v}" for k, v in self.meta.items() if k != RUN)

    @property
    def run(self) -> dict[str, Any]:
        """How to run this step (worker count, batch size, threads, paths): never changes its results."""
        return self.meta.get(RUN, {})

    def folder(self, study_dir: str | Path) -> Path:
        return Path(study_dir) / "steps" / self.kind / self.key

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "inputs": self.inputs, "deps": list(self.deps), "meta": self.meta, "key": self.key}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Step:
        return cls(data["kind"], data["inputs"], tuple(data["deps"]), data.get("meta", {}))


def is_done(step: Step, study_dir: str | Path) -> bool:
    return (step.folder(study_dir) / RESULT_FILE).is_file()


def read_result(step_or_folder: Step | Path, study_dir: str | Path | None = None) -> dict[str, Any]:
    """A step's result, its paths (``root``, ``checkpoint``) absolute under the study folder it is in now."""
    folder = step_or_folder.folder(study_dir) if isinstance(step_or_folder, Step) else Path(step_or_folder)
    result = json.loads((folder / RESULT_FILE).read_text())
    base = folder.parents[2]  # <study>/steps/<kind>/<key>
    return {k: str(_absolute(v, base)) if k in RESULT_PATHS and v else v for k, v in result.items()}


def _absolute(value: str, study_dir: Path) -> Path:
    """A stored path made absolute: relative ones (this format) are under ``study_dir``; an absolute one
    (older results) is re-rooted there when the study folder has moved since."""
    path = Path(value)
    if not path.is_absolute():
        return study_dir / path
    if path.exists():
        return path
    parts = path.parts
    for i in range(len(parts) - 2, -1, -1):
        if parts[i] == "steps" and parts[i + 1] in KINDS:
            return study_dir.joinpath(*parts[i:])
    return path


def _portable(result: dict[str, Any], study_dir: Path) -> dict[str, Any]:
    """The result with its paths relative to the study folder (where they lie inside it)."""
    out = dict(result)
    for key in RESULT_PATHS:
        if out.get(key):
            path = Path(out[key])
            with contextlib.suppress(ValueError):
                out[key] = path.resolve().relative_to(study_dir.resolve()).as_posix()
    return out


def run_step(step_data: dict[str, Any], study_dir: str) -> dict[str, Any]:
    """Run one step (in a worker process or a Ray task) and return its result. Idempotent."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    step = Step.from_dict(step_data)
    folder = step.folder(study_dir)
    if (folder / RESULT_FILE).is_file():
        return read_result(folder)
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / INPUTS_FILE, json.dumps(step.to_dict(), indent=1, sort_keys=True))
    deps = [_dep_folder(study_dir, key) for key in step.deps]
    start = time.perf_counter()
    with _output_to(folder / LOG_FILE):  # progress bars of collection and evaluation go to the step's log
        result = RUNNERS[step.kind](step, folder, deps)
    result["seconds"] = round(time.perf_counter() - start, 2)
    stored = _portable(result, Path(study_dir))
    atomic_write_text(folder / RESULT_FILE, json.dumps(stored, indent=1, sort_keys=True))
    return result


@contextlib.contextmanager
def _output_to(path: Path):
    """Send this process's stdout and stderr (Python and C level) to ``path`` for the duration."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with open(path, "a") as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)


def _dep_folder(study_dir: str, key: str) -> Path:
    for kind in KINDS:
        folder = Path(study_dir) / "steps" / kind / key
        if (folder / RESULT_FILE).is_file():
            return folder
    raise RuntimeError(f"step {key} that this step depends on has not finished")


def _dep_of_kind(deps: list[Path], kind: str) -> Path:
    return next(d for d in deps if d.parent.name == kind)


# --- collect ------------------------------------------------------------------------------------


def collect_config(inputs: CollectInputs | dict[str, Any], root: Path, key: str, workers: int = 1):
    """The ``factorworld collect`` settings of a collect step."""
    # Deliberately here: the collection module imports LeRobot (about 2 s), which planning and reporting
    # never need.
    from ..datasets.collect import CollectConfig  # noqa: PLC0415

    if not isinstance(inputs, CollectInputs):
        inputs = CollectInputs.from_dict(inputs)
    sampling = SamplingOptions(
        widths=dict(inputs.widths), n_distractors=inputs.n_distractors, **dict(inputs.family_options)
    )
    return CollectConfig(
        task=inputs.task,
        factors=list(inputs.train_factors),
        n_envs=inputs.n_envs,
        demos=inputs.demos,
        seed=inputs.seed,
        cameras=inputs.cameras,
        image_size=inputs.image_size,
        action_noise=inputs.action_noise,
        max_episode_steps=inputs.max_episode_steps,
        use_videos=inputs.use_videos,
        root=str(root),
        repo_id=f"local/factorworld_{key}",
        workers=workers,
        mode="new",
        sampling=sampling,
    )


def _run_collect(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    # Deliberately here: LeRobot's dataset code (seconds to import), only in the process that collects.
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

    from ..datasets.collect import SIDECAR, collect  # noqa: PLC0415

    root = folder / DATA_DIR
    cfg = collect_config(step.inputs, root, step.key, step.run.get("workers", 1))
    if (root / SIDECAR).is_file():  # merged before an interruption: nothing left to do
        meta = LeRobotDatasetMetadata(cfg.repo_id, root=root)
        return {
            "root": str(root),
            "repo_id": cfg.repo_id,
            "episodes": meta.total_episodes,
            "frames": meta.total_frames,
            "failures": {},
        }
    report = collect(cfg)
    return {
        "root": str(root),
        "repo_id": cfg.repo_id,
        "episodes": report.episodes,
        "frames": report.frames,
        "failures": report.failures,
    }


# --- train --------------------------------------------------------------------------------------


def policy_args(policy: dict[str, Any], prefix: str = "--policy") -> list[str]:
    """``{type: bc, augmentation: shift}`` -> ``["--policy.type=bc", "--policy.augmentation=shift"]``."""
    args = []
    for name, value in policy.items():
        if isinstance(value, dict):
            args += policy_args(value, f"{prefix}.{name}")
        else:
            text = json.dumps(value) if isinstance(value, (list, bool)) or value is None else str(value)
            args.append(f"{prefix}.{name}={text}")
    return args


def train_steps(inputs: TrainInputs, frames: int) -> int:
    """Gradient steps: ``steps``, or ``ceil(epochs * frames / batch_size)`` when ``epochs`` is set."""
    if inputs.epochs is None:
        return int(inputs.steps)
    return max(1, math.ceil(inputs.epochs * frames / inputs.batch_size))


def _run_train(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    data = read_result(_dep_of_kind(deps, "collect"))
    inputs = TrainInputs.from_dict(step.inputs)
    policy = step.run.get("policy", inputs.policy)  # absolute paths; the key holds their content hashes
    extra_args = step.run.get("extra_args", list(inputs.extra_args))
    steps = train_steps(inputs, data["frames"])
    out = folder / TRAIN_DIR
    if out.exists():  # an interrupted run: LeRobot refuses an existing output_dir, start over
        shutil.rmtree(out)
    cmd = [
        sys.executable,
        "-m",
        "lerobot.scripts.lerobot_train",
        *policy_args(policy),
        f"--policy.device={inputs.device}",
        "--policy.push_to_hub=false",
        f"--dataset.repo_id={data['repo_id']}",
        f"--dataset.root={data['root']}",
        f"--steps={steps}",
        f"--batch_size={inputs.batch_size}",
        f"--seed={inputs.seed}",
        "--num_workers=0",
        f"--save_freq={steps}",
        f"--log_freq={max(1, steps // 10)}",
        "--wandb.enable=false",
        f"--output_dir={out}",
        *extra_args,
    ]
    threads = str(inputs.threads)
    env = {**os.environ, "OMP_NUM_THREADS": threads, "MKL_NUM_THREADS": threads, "TOKENIZERS_PARALLELISM": "false"}
    with open(folder / LOG_FILE, "a") as log:
        log.write(" ".join(cmd) + "\n")
        log.flush()
        proc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=folder)
    if proc.returncode != 0:
        tail = (folder / LOG_FILE).read_text()[-2000:]
        raise RuntimeError(f"lerobot-train failed (exit {proc.returncode}); log {folder / LOG_FILE}:\n{tail}")
    checkpoint = out / CHECKPOINT
    if not checkpoint.is_dir():
        raise RuntimeError(f"lerobot-train finished without a checkpoint at {checkpoint}")
    return {"checkpoint": str(checkpoint), "steps": steps}


# --- eval ---------------------------------------------------------------------------------------


def eval_env_config(collect: CollectInputs, data_root: str, inputs: EvalInputs):
    """The ``factorworld`` env config of one condition: its ``train`` condition is the dataset's."""
    # Deliberately here: the env config subclasses LeRobot's (about 4 s to import); planning never needs it.
    from ..adapters.env_config import FactorWorldEnvConfig  # noqa: PLC0415

    is_train = inputs.condition == TRAIN_SUITE
    n_test_envs = {} if is_train else {"n_test_envs": inputs.n_test_envs}  # train: the dataset's own
    return FactorWorldEnvConfig(
        task=collect.task,
        cameras=collect.cameras,
        image_size=collect.image_size,
        episode_length=inputs.max_episode_steps,
        dataset_root=data_root,
        shifts=[] if is_train else [inputs.condition],
        include_train=is_train,
        **n_test_envs,
    )


def _run_eval(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    # Deliberately here: torch and LeRobot's evaluation stack (seconds to import), only in the process
    # that evaluates.
    import torch  # noqa: PLC0415
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415
    from lerobot.envs.factory import make_env, make_env_pre_post_processors  # noqa: PLC0415
    from lerobot.policies.factory import make_policy, make_pre_post_processors  # noqa: PLC0415
    from lerobot.scripts.lerobot_eval import eval_policy_all  # noqa: PLC0415
    from lerobot.utils.import_utils import register_third_party_plugins  # noqa: PLC0415
    from lerobot.utils.random_utils import set_seed  # noqa: PLC0415

    register_third_party_plugins()  # as lerobot-eval does: Factor World's env and policy types, and any other plugin

    inputs, run = EvalInputs.from_dict(step.inputs), step.run
    torch.set_num_threads(run.get("threads", 1))
    collect_folder = _dep_of_kind(deps, "collect")
    collect_inputs = CollectInputs.from_dict(json.loads((collect_folder / INPUTS_FILE).read_text())["inputs"])
    data = read_result(collect_folder)
    checkpoint = read_result(_dep_of_kind(deps, "train"))["checkpoint"]
    env_cfg = eval_env_config(collect_inputs, data["root"], inputs)
    task = env_cfg.task_names[0]
    configs = env_cfg.suites(task)[inputs.condition]

    policy_cfg = PreTrainedConfig.from_pretrained(checkpoint)
    policy_cfg.pretrained_path = Path(checkpoint)
    policy_cfg.device = _eval_device(inputs.device)
    set_seed(inputs.start_seed)
    policy = make_policy(cfg=policy_cfg, env_cfg=env_cfg)
    preprocessor, postprocessor = make_pre_post_processors(
        policy_cfg=policy_cfg,
        pretrained_path=checkpoint,
        preprocessor_overrides={"device_processor": {"device": str(policy_cfg.device)}},
    )
    env_pre, env_post = make_env_pre_post_processors(env_cfg=env_cfg, policy_cfg=policy_cfg)
    envs = make_env(env_cfg, n_envs=run.get("batch_size", 1), use_async_envs=False)
    with torch.no_grad():
        info = eval_policy_all(
            envs,
            policy,
            env_pre,
            env_post,
            preprocessor,
            postprocessor,
            n_episodes=inputs.episodes,
            max_episodes_rendered=0,
            start_seed=inputs.start_seed,
        )
    successes = [bool(s) for s in info["per_task"][0]["metrics"]["successes"]]
    seeds = [inputs.start_seed + i for i in range(len(successes))]
    cover = coverage(seeds, len(configs))
    width = env_cfg.sampling.widths.get("object_pos")
    result = {
        "condition": inputs.condition,
        "successes": successes,
        "seeds": seeds,
        "n_envs": len(configs),
        "envs_visited": cover.visited,
        "equal_visits": cover.equal,
        "fingerprint": fingerprint(configs, width),
        "checkpoint": checkpoint,
    }
    family = family_of(task)
    if family.content_key:  # what every episode asked for (e.g. instruction, named object), for breakdowns
        result[family.content_key] = family.episode_records(configs, seeds, width)
    return result


def _eval_device(device: str) -> str:
    """``eval.device``, refused when this machine lacks it (rather than silently running elsewhere)."""
    import torch  # noqa: PLC0415 - deliberately here: only the evaluating process needs torch (seconds to import)

    if device.startswith("cuda") and not torch.cuda.is_available():
        raise RuntimeError(f"eval.device={device} but this machine has no CUDA device; use --eval.device=cpu")
    if device == "mps" and not torch.backends.mps.is_available():
        raise RuntimeError("eval.device=mps but this machine has no MPS device; use --eval.device=cpu")
    return device


RUNNERS = {"collect": _run_collect, "train": _run_train, "eval": _run_eval}
