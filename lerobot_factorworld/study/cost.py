"""The ``--dry-run`` text and its rough cost model: wall-clock hours of the steps still to run, under a
few machine profiles. Every constant is a stated, measured assumption; the model overestimates (see
docs/study.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..tasks import get_task
from .config import StudyConfig
from .inputs import CollectInputs, EvalInputs, TrainInputs
from .plan import Plan
from .steps import Step, is_done

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
    """Typical scripted-demo length of ``task`` (its row's ``demo_steps``, measured)."""
    return get_task(task).demo_steps


def cameras_of(collect: CollectInputs) -> int:
    return len([c for c in str(collect.cameras).split(",") if c.strip()])


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
        collect = CollectInputs.from_dict(step.inputs)
        frames = collect.demos * expert_episode_steps(collect.task)
        return STEP_OVERHEAD_S["collect"] + frames * COLLECT_FRAME_S, 0.0
    collect = CollectInputs.from_dict(plan_index[step.deps[-1]].inputs)
    if step.kind == "train":
        return STEP_OVERHEAD_S["train"], _train_seconds(TrainInputs.from_dict(step.inputs), collect)
    train = TrainInputs.from_dict(plan_index[step.deps[0]].inputs)
    return _eval_cost(EvalInputs.from_dict(step.inputs), train, collect)


def _train_seconds(train: TrainInputs, collect: CollectInputs) -> float:
    frames = collect.demos * expert_episode_steps(collect.task)
    steps = train.steps or train.epochs * frames / train.batch_size
    samples = steps * train.batch_size
    policy = train.policy
    seconds = samples * TRAIN_SAMPLE_S.get(policy["type"], 0.02)
    encoder = frozen_encoder(policy)
    if encoder:
        seconds += encoder_runs(policy, frames, samples) * cameras_of(collect) * ENCODER_FRAME_S[encoder]
    return seconds


def _eval_cost(ev: EvalInputs, train: TrainInputs, collect: CollectInputs) -> tuple[float, float]:
    horizon = ev.max_episode_steps or get_task(collect.task).max_episode_steps
    sim_steps = ev.episodes * horizon * EVAL_EPISODE_FRACTION
    cpu_s = STEP_OVERHEAD_S["eval"] + sim_steps * SIM_STEP_S
    encoder = frozen_encoder(train.policy)
    encoder_s = sim_steps * cameras_of(collect) * ENCODER_FRAME_S[encoder] if encoder else 0.0
    if str(ev.device).startswith("cuda"):
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
        + (f" + {len(cfg.family_conditions())} language" if cfg.family_conditions() else "")
        + f"; radius runs: {len(cfg.radius_variants())}"
    )
    lines.append("  estimated wall time of the steps to run (rough model in study/cost.py):")
    for name, hours in estimate(plan, todo).items():
        lines.append(f"    {name:40s} {hours:10.1f} h" if hours >= 1 else f"    {name:40s} {hours * 60:10.0f} min")
    missing = cfg.missing_weight_files()
    if missing:
        lines.append(f"  not startable yet, weights file(s) not found: {'; '.join(missing)}")
    return "\n".join(lines)
