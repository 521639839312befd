"""The study grid as steps: one dataset per (task, N, seed, widths), one training run per method on it,
one evaluation per condition of each checkpoint; and a rough cost model for ``--dry-run``."""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

from ..factors.registry import get_factor
from ..tasks import get_task
from .conditions import TRAIN_SUITE
from .config import StudyConfig
from .steps import Step, is_done

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
                        train = Step(
                            "train",
                            {"policy": method.policy, "seed": seed, **_train_inputs(cfg)},
                            (collect.key,),
                            {"method": method.name, **cell},
                        )
                        steps.setdefault(train.key, train)
                        for condition in [TRAIN_SUITE, *conditions]:
                            ev = Step(
                                "eval",
                                {"condition": condition, **asdict(cfg.eval)},
                                (train.key, collect.key),
                                {"method": method.name, **cell, "condition": condition},
                            )
                            steps.setdefault(ev.key, ev)
    order = {"collect": 0, "train": 1, "eval": 2}
    return Plan(tuple(sorted(steps.values(), key=lambda s: order[s.kind])))


def _collect_step(cfg: StudyConfig, task: str, n: int, seed: int, widths: dict[str, str], cell: dict) -> Step:
    c = cfg.collect
    inputs = {
        "task": task,
        "n_envs": n,
        "seed": seed,
        "train_factors": list(cfg.train_factors),
        "demos": c.demos_for(task),
        "cameras": c.cameras,
        "image_size": c.image_size,
        "use_videos": c.use_videos,
        "action_noise": c.action_noise,
        "max_episode_steps": c.max_episode_steps,
        "n_distractors": c.n_distractors,
        "widths": {"object_pos": c.object_pos_width, **widths},
    }
    return Step("collect", inputs, (), {**cell, "collect_workers": c.workers})


def _train_inputs(cfg: StudyConfig) -> dict:
    t = cfg.train
    return {
        "steps": t.steps if t.epochs is None else None,
        "epochs": t.epochs,
        "batch_size": t.batch_size,
        "threads": t.threads,
        "device": t.device,
        "extra_args": list(t.extra_args),
    }


# --- cost model ---------------------------------------------------------------------------------
# Rough, stated assumptions (measured on the 2-core CPU machine unless noted):
SIM_STEP_S = 0.025  # one 84x84 rendered env step with a small policy (measured 15-25 ms + policy)
COLLECT_FRAME_S = 0.05  # one demo frame: render, expert, LeRobotDataset writing and merging (measured 0.035-0.07 s)
STEP_OVERHEAD_S = {"collect": 15.0, "train": 20.0, "eval": 10.0}  # process start, imports, dataset/policy load
TRAIN_SAMPLE_S = {
    "rt1": 0.02,
    "bc": 0.006,
    "act": 0.01,
}  # seconds per training sample on one CPU core (bc: 1 thread, batch 32)
GPU_TRAIN_SPEEDUP = 30.0  # one datacentre GPU vs one CPU core for these small image policies
EVAL_EPISODE_FRACTION = 0.6  # mean episode length / horizon (successes end early, failures run to the limit)
PROFILES = {
    # name: (parallel CPU slots, parallel GPU training slots, rendering speed-up vs the 2-core machine)
    "one CPU machine (2 cores)": (2, 0, 1.0),
    "one GPU machine (1 GPU, 16 cores)": (16, 1, 1.0),
    "Ray cluster (8 machines x 16 cores)": (128, 0, 1.0),
}


def expert_episode_steps(task: str) -> int:
    """Typical scripted-demo length (measured: pick-place ~50, door-open ~85, bin-picking ~120 steps)."""
    return {"pick-place": 50, "door-open": 85, "bin-picking": 120, "handle-press": 30}.get(task, 100)


def step_cost(step: Step, plan_index: dict[str, Step]) -> tuple[float, float]:
    """(CPU seconds, GPU-able training samples) of one step."""
    if step.kind == "collect":
        frames = step.inputs["demos"] * expert_episode_steps(step.inputs["task"])
        return STEP_OVERHEAD_S["collect"] + frames * COLLECT_FRAME_S, 0.0
    collect = plan_index[step.deps[-1]]
    if step.kind == "train":
        frames = collect.inputs["demos"] * expert_episode_steps(collect.inputs["task"])
        steps = step.inputs["steps"] or step.inputs["epochs"] * frames / step.inputs["batch_size"]
        return STEP_OVERHEAD_S["train"], steps * step.inputs["batch_size"]
    horizon = step.inputs["max_episode_steps"] or get_task(collect.inputs["task"]).max_episode_steps
    return STEP_OVERHEAD_S["eval"] + step.inputs["episodes"] * horizon * EVAL_EPISODE_FRACTION * SIM_STEP_S, 0.0


def estimate(plan: Plan, steps: list[Step]) -> dict[str, float]:
    """Wall-clock hours of ``steps`` under each profile (CPU work spread over slots; training on GPU where there is one)."""
    index = {s.key: s for s in plan.steps}
    cpu_s, train_samples_s = 0.0, 0.0
    for step in steps:
        seconds, samples = step_cost(step, index)
        cpu_s += seconds
        if samples:
            policy = index[step.key].inputs["policy"]["type"]
            train_samples_s += samples * TRAIN_SAMPLE_S.get(policy, 0.02)
    out = {}
    for name, (slots, gpus, speed) in PROFILES.items():
        train_s = train_samples_s / GPU_TRAIN_SPEEDUP / gpus if gpus else train_samples_s / slots
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
        f"conditions: train + {len(cfg.factors)} factors + {len(cfg.pair_conditions())} pairs; "
        f"radius runs: {len(cfg.radius_variants())}"
    )
    lines.append("  estimated wall time of the steps to run (rough model in study/plan.py):")
    for name, hours in estimate(plan, todo).items():
        lines.append(f"    {name:40s} {hours:10.1f} h" if hours >= 1 else f"    {name:40s} {hours * 60:10.0f} min")
    return "\n".join(lines)


def radius_of(widths: str, factor: str) -> float | None:
    """The paper's radius (m) of ``factor`` in a run with ``widths`` (``default`` = the factor's default width)."""
    from .config import RADII_M

    if widths == DEFAULT_WIDTHS:
        return RADII_M.get(get_factor(factor).default_width)
    parts = dict(p.split("=") for p in widths.split(","))
    return RADII_M.get(parts.get(factor, get_factor(factor).default_width))
