"""The study grid as steps: one dataset per (task, N, seed, widths), one training run per method on it,
one evaluation per condition of each checkpoint; and a rough cost model for ``--dry-run``.

What goes into a step's inputs (hence its key) is what changes its results; see ``steps.py``."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..datasets.version import DATA_VERSION
from ..factors.registry import get_factor
from ..tasks import get_task
from .conditions import TRAIN_SUITE
from .config import StudyConfig, map_arg_paths, map_policy_paths
from .steps import RUN, Step, file_fingerprint, is_done, versions

DEFAULT_WIDTHS = "default"


@dataclass(frozen=True)
class Plan:
    steps: tuple[Step, ...]  # in dependency order: every step comes after the steps it depends on

    def of_kind(self, kind: str) -> list[Step]:
        return [s for s in self.steps if s.kind == kind]

    def counts(self) -> Counter:
        return Counter(s.kind for s in self.steps)


def widths_label(widths: dict[str, str]) -> str:
    """``{"camera_pos": "medium"}`` -> ``camera_pos=medium``; the main grid -> ``default``."""
    return ",".join(f"{k}={v}" for k, v in sorted(widths.items())) or DEFAULT_WIDTHS


def make_plan(cfg: StudyConfig) -> Plan:
    """Every step of the study, deduplicated by key (a dataset is shared by all methods)."""
    variants: list[tuple[dict[str, str], list[str]]] = [({}, cfg.conditions())]
    variants += [({factor: width}, [factor]) for factor, width in cfg.radius_variants()]
    steps: dict[str, Step] = {}
    for task in cfg.tasks:
        for widths, conditions in variants:
            for n in cfg.n_train_envs:
                for seed in cfg.seeds:
                    cell = {"task": task, "n_train_envs": n, "seed": seed, "widths": widths_label(widths)}
                    collect = _collect_step(cfg, task, n, seed, widths, cell)
                    steps.setdefault(collect.key, collect)
                    for method in cfg.methods:
                        train = _train_step(cfg, method.policy, seed, collect, {"method": method.name, **cell})
                        steps.setdefault(train.key, train)
                        for condition in [TRAIN_SUITE, *conditions]:
                            ev = _eval_step(cfg, condition, train, collect, {"method": method.name, **cell})
                            steps.setdefault(ev.key, ev)
    order = {"collect": 0, "train": 1, "eval": 2}
    return Plan(tuple(sorted(steps.values(), key=lambda s: order[s.kind])))


def _collect_step(cfg: StudyConfig, task: str, n: int, seed: int, widths: dict[str, str], cell: dict) -> Step:
    c = cfg.collect
    inputs = {
        "task": task,
        "n_envs": n,
        "seed": seed,
        "train_factors": sorted(cfg.train_factors),  # each factor has its own RNG: the order changes nothing
        "demos": c.demos_for(task),
        "cameras": c.cameras,
        "image_size": c.image_size,
        "use_videos": c.use_videos,
        "action_noise": c.action_noise,
        "max_episode_steps": c.max_episode_steps,
        "n_distractors": c.n_distractors,
        "widths": {"object_pos": c.object_pos_width, **widths},
        "data_version": DATA_VERSION,
        "versions": versions(),
    }
    n_objects = c.n_objects_for(task)
    if n_objects is not None:  # pick family: objects per scene
        inputs["n_objects"] = n_objects
    return Step("collect", inputs, (), {**cell, RUN: {"workers": c.workers}})


def _train_step(cfg: StudyConfig, policy: dict[str, Any], seed: int, collect: Step, labels: dict) -> Step:
    """Training of one method on one dataset; weight files enter the key by content, not by location."""
    t = cfg.train
    inputs = {
        "policy": keyed_policy(policy),
        "seed": seed,
        "steps": t.steps if t.epochs is None else None,
        "epochs": t.epochs,
        "batch_size": t.batch_size,
        "threads": t.threads,
        "device": t.device,
        "extra_args": keyed_args(t.extra_args),
        "versions": versions(),
    }
    run = {"policy": policy, "extra_args": list(t.extra_args)}
    return Step("train", inputs, (collect.key,), {**labels, RUN: run})


def _eval_step(cfg: StudyConfig, condition: str, train: Step, collect: Step, labels: dict) -> Step:
    """One condition of one checkpoint; batch size and threads do not change results (kept out of the key),
    and ``train`` (the dataset's own environments) does not depend on ``n_test_envs``."""
    ev = cfg.eval
    inputs = {
        "condition": condition,
        "episodes": ev.episodes,
        "start_seed": ev.start_seed,
        "max_episode_steps": ev.max_episode_steps,
        "device": ev.device,
        "versions": versions(),
    }
    if condition != TRAIN_SUITE:
        inputs["n_test_envs"] = ev.n_test_envs
    run = {"batch_size": ev.batch_size, "threads": ev.threads}
    return Step("eval", inputs, (train.key, collect.key), {**labels, "condition": condition, RUN: run})


def _keyed_path(value: str) -> str:
    """A path setting as the key sees it: an existing file by its content hash, anything else as given."""
    return file_fingerprint(value) or value


def keyed_policy(policy: dict[str, Any]) -> dict[str, Any]:
    """Policy settings for the key: every path-like setting naming a file replaced by its content hash."""
    return map_policy_paths(policy, _keyed_path)


def keyed_args(args: list[str]) -> list[str]:
    """``lerobot-train`` flags for the key: path-like values naming a file replaced by its content hash."""
    return map_arg_paths(args, _keyed_path)


# --- cost model ---------------------------------------------------------------------------------
# Rough, stated assumptions (measured on the 2-core CPU machine unless noted):
SIM_STEP_S = 0.025  # one 84x84 rendered env step with a small policy (measured 15-25 ms + policy)
COLLECT_FRAME_S = 0.05  # one demo frame: render, expert, LeRobotDataset writing and merging (measured 0.035-0.07 s)
STEP_OVERHEAD_S = {"collect": 15.0, "train": 20.0, "eval": 10.0}  # process start, imports, dataset/policy load
TRAIN_SAMPLE_S = {
    "rt1": 0.02,
    "bc": 0.006,
    "act": 0.01,
}  # seconds per training sample on one CPU core (bc: 1 thread, batch 32; the conv encoder and head)
# A frozen pretrained encoder of bc adds one backbone pass per image it has not cached (training) or sees
# (evaluation). Measured 2026-11-23 on the 2-core machine: forward of the randomly initialised backbone,
# its own resizing to 224 px included, batch 8 of 84 px images, one thread, no gradient, best of 3 rounds;
# other jobs shared the machine (load average 4.3), so these may be up to 2x high.
ENCODER_FRAME_S = {"lite0": 0.032, "r3m_rn50": 0.086, "clip_rn50": 0.115}
FEATURE_CACHE_FRAMES = 100_000  # bc's default feature_cache_size (frames whose frozen features are kept)
GPU_TRAIN_SPEEDUP = 30.0  # one datacentre GPU vs one CPU core for these small image policies
EVAL_EPISODE_FRACTION = 0.6  # mean episode length / horizon (successes end early, failures run to the limit)
PROFILES = {
    # name: (parallel CPU slots, parallel GPU training slots, rendering speed-up vs the 2-core machine)
    "one CPU machine (2 cores)": (2, 0, 1.0),
    "one GPU machine (1 GPU, 16 cores)": (16, 1, 1.0),
    "Ray cluster (8 machines x 16 cores)": (128, 0, 1.0),
}


def expert_episode_steps(task: str) -> int:
    """Typical scripted-demo length (measured: pick-place ~50, door-open ~85, pick ~85, bin-picking ~120 steps)."""
    return {"pick-place": 50, "door-open": 85, "pick": 85, "bin-picking": 120, "handle-press": 30}.get(task, 100)


def cameras_of(collect: Step) -> int:
    return len([c for c in str(collect.inputs["cameras"]).split(",") if c.strip()])


def frozen_encoder(policy: dict[str, Any]) -> str | None:
    """The frozen pretrained encoder of a ``bc`` policy (``lite0``, ``r3m_rn50``, ``clip_rn50``), if any."""
    encoder = policy.get("encoder", "conv") if policy.get("type") == "bc" else None
    return encoder if encoder in ENCODER_FRAME_S else None


def encoder_runs(policy: dict[str, Any], frames: int, samples: float) -> float:
    """Backbone passes of a training run: with ``augmentation: none`` the feature cache computes each frame
    once while it holds them all (an LRU of ``feature_cache_size`` frames otherwise hits cache/frames of
    the draws); with augmentation every sample is new pixels."""
    cache = int(policy.get("feature_cache_size", FEATURE_CACHE_FRAMES))
    if policy.get("augmentation", "none") != "none" or cache == 0 or samples <= min(frames, cache):
        return samples
    if frames <= cache:
        return frames
    return cache + (samples - cache) * (1 - cache / frames)


def step_cost(step: Step, plan_index: dict[str, Step]) -> tuple[float, float]:
    """(CPU seconds, seconds on one CPU core of work a GPU takes over) of one step.

    The second part is training, and evaluation's frozen encoder when ``eval.device`` is a GPU.
    """
    if step.kind == "collect":
        frames = step.inputs["demos"] * expert_episode_steps(step.inputs["task"])
        return STEP_OVERHEAD_S["collect"] + frames * COLLECT_FRAME_S, 0.0
    collect = plan_index[step.deps[-1]]
    if step.kind == "train":
        return STEP_OVERHEAD_S["train"], _train_seconds(step, collect)
    return _eval_cost(step, plan_index[step.deps[0]], collect)


def _train_seconds(step: Step, collect: Step) -> float:
    frames = collect.inputs["demos"] * expert_episode_steps(collect.inputs["task"])
    steps = step.inputs["steps"] or step.inputs["epochs"] * frames / step.inputs["batch_size"]
    samples = steps * step.inputs["batch_size"]
    policy = step.inputs["policy"]
    seconds = samples * TRAIN_SAMPLE_S.get(policy["type"], 0.02)
    encoder = frozen_encoder(policy)
    if encoder:
        seconds += encoder_runs(policy, frames, samples) * cameras_of(collect) * ENCODER_FRAME_S[encoder]
    return seconds


def _eval_cost(step: Step, train: Step, collect: Step) -> tuple[float, float]:
    horizon = step.inputs["max_episode_steps"] or get_task(collect.inputs["task"]).max_episode_steps
    sim_steps = step.inputs["episodes"] * horizon * EVAL_EPISODE_FRACTION
    cpu_s = STEP_OVERHEAD_S["eval"] + sim_steps * SIM_STEP_S
    encoder = frozen_encoder(train.inputs["policy"])
    encoder_s = sim_steps * cameras_of(collect) * ENCODER_FRAME_S[encoder] if encoder else 0.0
    if str(step.inputs.get("device", "cpu")).startswith("cuda"):
        return cpu_s, encoder_s
    return cpu_s + encoder_s, 0.0


def estimate(plan: Plan, steps: list[Step]) -> dict[str, float]:
    """Wall-clock hours of ``steps`` under each profile (CPU work spread over slots; training on GPU where there is one)."""
    index = {s.key: s for s in plan.steps}
    cpu_s, gpu_able_s = 0.0, 0.0
    for step in steps:
        seconds, accelerated = step_cost(step, index)
        cpu_s += seconds
        gpu_able_s += accelerated
    out = {}
    for name, (slots, gpus, speed) in PROFILES.items():
        train_s = gpu_able_s / GPU_TRAIN_SPEEDUP / gpus if gpus else gpu_able_s / slots
        out[name] = (cpu_s / slots / speed + train_s) / 3600
    return out


def describe(cfg: StudyConfig, plan: Plan) -> str:
    """The ``--dry-run`` text: steps per kind, how many are cached, the cost estimate."""
    study_dir = Path(cfg.out_dir)
    lines = [f"study {cfg.name!r} in {study_dir}"]
    todo = [s for s in plan.steps if not is_done(s, study_dir)]
    for kind, total in plan.counts().items():
        cached = total - sum(1 for s in todo if s.kind == kind)
        lines.append(f"  {kind:8s} {total:6d} steps, {cached:6d} cached, {total - cached:6d} to run")
    lines.append(
        f"  grid: {len(cfg.methods)} method(s) x {len(cfg.tasks)} task(s) x N {cfg.n_train_envs} x {len(cfg.seeds)} seed(s); "
        f"conditions: train + {len(cfg.shifted_factors())} factors + {len(cfg.pair_conditions())} pairs"
        + (f" + {len(cfg.language_conditions())} language" if cfg.language_conditions() else "")
        + f"; radius runs: {len(cfg.radius_variants())}"
    )
    lines.append("  estimated wall time of the steps to run (rough model in study/plan.py):")
    for name, hours in estimate(plan, todo).items():
        lines.append(f"    {name:40s} {hours:10.1f} h" if hours >= 1 else f"    {name:40s} {hours * 60:10.0f} min")
    missing = cfg.missing_weight_files()
    if missing:
        lines.append(f"  not startable yet, weights file(s) not found: {'; '.join(missing)}")
    return "\n".join(lines)


def radius_of(widths: str, factor: str) -> float | None:
    """The paper's radius (m) of ``factor`` in a run with ``widths`` (``default`` = the factor's default width)."""
    from .config import RADII_M

    if widths == DEFAULT_WIDTHS:
        return RADII_M.get(get_factor(factor).default_width)
    parts = dict(p.split("=") for p in widths.split(","))
    return RADII_M.get(parts.get(factor, get_factor(factor).default_width))
