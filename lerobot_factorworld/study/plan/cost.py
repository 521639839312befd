"""The ``--dry-run`` text and its cost model: wall-clock time of the steps still to run, under a few
machine profiles, with constants fitted from a finished study's measured timings.

The model. A step costs a fixed part plus a part proportional to its work, in seconds on one CPU core:

- collect: ``collect.fixed_s + frames * collect.frame_s``, frames = demos x the task's measured demo
  length (``TaskSpec.demo_steps``);
- train: ``train.fixed_s + steps * batch_size * train.sample_s[policy type]`` (plus a frozen encoder's
  backbone passes, ``ENCODER_FRAME_S``); the per-sample part is what a GPU takes over (``GPU_TRAIN_SPEEDUP``);
- eval: ``eval.fixed_s + episodes * horizon * eval.episode_fraction[task] * eval.sim_step_s`` (plus the
  encoder's passes), the fraction being the mean episode length over the horizon (successes end early).

The fixed parts hold what a step pays besides its work (imports in a fresh worker, process start,
policy and environment set-up, dataset merging, checkpoint saving), so they depend on ``execution``;
the constants are those of the execution they were fitted with. The wall time is then a simulation of
the runner's schedule on one machine (on a cluster: the work over its slots): ``slots`` workers take ready tasks, evaluations first, then trainings, then
collections (``executors.task_units``: with ``grouped``, one task per checkpoint's evaluations), plus
``study_s`` (planning, pool start-up and report writing). ``cost_model.json`` next to this file holds the
constants and where they were fitted (study, commit, date, execution, measured wall time);
``factorworld study --config_path=X --fit_cost=true`` refits them from the finished steps of study X
(their ``timings``, ``study/plan/profile.py``) and rewrites it.
"""

from __future__ import annotations

import datetime
import heapq
import json
from collections import deque
from pathlib import Path
from typing import Any

from ...core import provenance
from ...core.io import atomic_write_json
from ...envs.lerobot_obs import LEROBOT_METAWORLD_OBS
from ...scene.build import DEFAULT_QUALITY
from ...tasks import get_task, step_limit
from ..run.blocks import EPISODES_RUN
from ..run.checkpoint import GIVEN_CHECKPOINT, checkpoint_problems, local_folder, read_policy_config
from ..run.executors import task_units
from ..run.inputs import CollectInputs, EnvInputs, EvalInputs, TrainInputs
from ..run.options import RunOptions
from ..run.result import TIMINGS, is_done
from ..run.reuse import reusable_steps
from ..run.step import KINDS, Step, evaluated
from ..run.train_schedule import epoch_frames
from .config import StudyConfig
from .grid import Plan
from .power import power_lines
from .profile import finished_timings, last_run

COST_MODEL_FILE = Path(__file__).with_name("cost_model.json")
# Measured separately (not refitted from a study's timings): a frozen pretrained encoder of bc adds one
# backbone pass per image it has not cached (training) or sees (evaluation). Measured 2026-11-23 on the
# 2-core machine: forward of the randomly initialised backbone, its own resizing to 224 px included, batch 8
# of 84 px images, one thread, no gradient, best of 3 rounds; other jobs shared the machine (load average
# 4.3), so these may be up to 2x high.
ENCODER_FRAME_S = {"lite0": 0.032, "r3m_rn50": 0.086, "clip_rn50": 0.115}
# A step of --env.obs=lerobot_metaworld (480 x 480, quality full) on the 2-core machine: 137 ms median per rendered
# step in scripts/compare_lerobot_metaworld.py (2026-11-25, cores shared; docs/lerobot_metaworld.md), rounded up
# for the policy's share; not refitted by --fit_cost.
LEROBOT_METAWORLD_STEP_S = 0.15
FEATURE_CACHE_FRAMES = 100_000  # bc's default feature_cache_size (frames whose frozen features are kept)
# One datacentre GPU vs one CPU core for these small image policies' whole training step: an assumption. Their model
# updates alone measured 156x (bc conv) and 92x (rt1 small) on an H200 against one thread of its host (docs/rt1.md,
# "On a GPU"); a lerobot-train step also loads its batch on the CPU, which that leaves out, so it bounds this from above.
GPU_TRAIN_SPEEDUP = 30.0
DEFAULT_SAMPLE_S = 0.02  # a policy type the fit has not seen
DEFAULT = "default"  # the episode fraction of a task the fit has not seen
CLUSTER_SLOTS = 16  # beyond one machine's slots the estimate is the throughput bound, not a simulated schedule
PROFILES = {
    # name: (parallel CPU slots, parallel GPU training slots)
    "one CPU machine (2 cores)": (2, 0),
    "one GPU machine (1 GPU, 16 cores)": (16, 1),
    "Ray cluster (8 machines x 16 cores)": (128, 0),
}
# What a step's timings hold per unit of work (the rest of its total is its fixed part).
PER_WORK = {
    "collect": ("env_build", "render", "expert_physics", "write_frames", "save_episode"),
    "train": ("data", "update"),
    "eval": ("scene_compile", "render", "env_reset", "env_step", "policy", "rollout_other"),
}


def load_model(path: Path = COST_MODEL_FILE) -> dict[str, Any]:
    """The cost model's constants (``cost_model.json``)."""
    return json.loads(Path(path).read_text())


def expert_episode_steps(task: str) -> int:
    """Typical scripted-demo length of ``task`` (its row's ``demo_steps``, measured)."""
    return get_task(task).demo_steps


def cameras_of(env: CollectInputs | EnvInputs) -> int:
    return len([c for c in str(env.cameras).split(",") if c.strip()])


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


def step_cost(step: Step, plan_index: dict[str, Step], model: dict[str, Any]) -> tuple[float, float]:
    """(fixed seconds, seconds of work a GPU takes over) of a training step; (seconds, 0) of the others,
    or (seconds on CPU, encoder seconds a GPU takes over) of an evaluation on a GPU."""
    if step.kind == "collect":
        collect = CollectInputs.from_dict(step.inputs)
        frames = collect.demos * expert_episode_steps(collect.task)
        return model["collect"]["fixed_s"] + frames * model["collect"]["frame_s"], 0.0
    if step.kind == "eval" and not step.deps:  # a given checkpoint: its config says which policy it is
        inputs = EvalInputs.from_dict(step.inputs)
        return _eval_cost(inputs, given_policy(step), inputs.environments, model)
    if step.kind == "train":  # the task's own dataset first (deps[0]), then other tasks' (extra_tasks)
        collects = [CollectInputs.from_dict(plan_index[d].inputs) for d in step.deps if plan_index[d].kind == "collect"]
        return model["train"]["fixed_s"], _train_seconds(TrainInputs.from_dict(step.inputs), collects, model)
    collect = CollectInputs.from_dict(plan_index[step.deps[-1]].inputs)
    train = TrainInputs.from_dict(plan_index[step.deps[0]].inputs)
    return _eval_cost(EvalInputs.from_dict(step.inputs), train.policy, collect, model)


def _train_seconds(train: TrainInputs, collects: list[CollectInputs], model: dict[str, Any]) -> float:
    """Seconds of a training's work on ``collects`` (the task's own dataset first, then other tasks' merged in)."""
    frames = [c.demos * expert_episode_steps(c.task) for c in collects]
    done = train.extends or 0  # a training that continues a shorter one trains only the rest (and under a pass more)
    steps = (
        (train.steps - done)
        if train.epochs is None
        else (train.epochs - done) * epoch_frames(train, frames) / train.batch_size
    )
    samples = steps * train.batch_size
    policy = train.policy
    seconds = samples * model["train"]["sample_s"].get(policy["type"], DEFAULT_SAMPLE_S)
    encoder = frozen_encoder(policy)
    if encoder:
        seconds += encoder_runs(policy, sum(frames), samples) * cameras_of(collects[0]) * ENCODER_FRAME_S[encoder]
    return seconds


def episode_fraction(model: dict[str, Any], task: str) -> float:
    fractions = model["eval"]["episode_fraction"]
    return fractions.get(task, fractions[DEFAULT])


def given_policy(step: Step) -> dict[str, Any]:
    """A given checkpoint's policy settings, from its ``config.json`` (``{}`` while it is not here)."""
    folder = local_folder(step.run[GIVEN_CHECKPOINT])
    return read_policy_config(folder) if folder is not None else {}


def _eval_cost(
    ev: EvalInputs, policy: dict[str, Any], env: CollectInputs | EnvInputs, model: dict[str, Any]
) -> tuple[float, float]:
    """An evaluation's cost: the same model for a trained and a given checkpoint, but for a step of LeRobot's
    observation (a 480 px frame with shadows, not the small frames the constant was fitted on)."""
    horizon = step_limit(env.task, ev.max_episode_steps)
    sim_steps = ev.episodes * horizon * episode_fraction(model, env.task)
    step_s = model["eval"]["sim_step_s"]
    if isinstance(env, EnvInputs) and env.obs == LEROBOT_METAWORLD_OBS:
        step_s = max(step_s, LEROBOT_METAWORLD_STEP_S)
    cpu_s = model["eval"]["fixed_s"] + sim_steps * step_s
    encoder = frozen_encoder(policy)
    encoder_s = sim_steps * cameras_of(env) * ENCODER_FRAME_S[encoder] if encoder else 0.0
    if str(ev.device).startswith("cuda"):
        return cpu_s, encoder_s
    return cpu_s + encoder_s, 0.0


def step_costs(plan: Plan, steps: list[Step], model: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """:func:`step_cost` of each of ``steps``, by key: computed once for every profile an estimate simulates."""
    index = {s.key: s for s in plan.steps}
    return {s.key: step_cost(s, index, model) for s in steps}


def simulate(
    plan: Plan,
    steps: list[Step],
    slots: int,
    gpus: int,
    grouped: bool,
    model: dict[str, Any],
    costs: dict[str, tuple[float, float]] | None = None,
) -> float:
    """Seconds until ``steps`` (with the rest of ``plan`` done) finish on ``slots`` workers (and ``gpus``
    GPUs taking training's per-sample work), scheduled as the runner does: ready evaluations first, then
    trainings, then collections, each task on one worker. ``costs``: :func:`step_costs`, if already known."""
    costs = costs if costs is not None else step_costs(plan, steps, model)
    todo = {s.key for s in steps}
    cost = {}
    for s in steps:
        fixed, accelerated = costs[s.key]
        on_gpu = s.kind == "train" and gpus > 0
        cost[s.key] = (fixed + (accelerated / GPU_TRAIN_SPEEDUP if on_gpu else accelerated), on_gpu)
    waiting = {s.key: sum(1 for d in s.deps if d in todo) for s in steps}
    dependents: dict[str, list[Step]] = {}
    for s in steps:
        for d in s.deps:
            dependents.setdefault(d, []).append(s)
    ready = {kind: deque() for kind in KINDS}
    for s in steps:
        if not waiting[s.key]:
            ready[s.kind].append(s)
    now, running, free_gpus, events = 0.0, 0, gpus, []
    order = 0
    while True:
        free = slots - running
        if free > 0:
            picked = 0
            units = task_units(_front(ready, free + gpus, grouped), free, grouped)
            for unit in units:
                if picked >= free:
                    break
                on_gpu = any(cost[s.key][1] for s in unit)
                if on_gpu and free_gpus == 0:
                    continue
                for s in unit:
                    ready[s.kind].remove(s)
                free_gpus -= on_gpu
                running += 1
                picked += 1
                order += 1
                heapq.heappush(events, (now + sum(cost[s.key][0] for s in unit), order, unit, on_gpu))
        if not events:
            return now
        now, _, unit, on_gpu = heapq.heappop(events)
        running -= 1
        free_gpus += on_gpu
        for s in unit:
            for child in dependents.get(s.key, []):
                waiting[child.key] -= 1
                if not waiting[child.key]:
                    ready[child.kind].append(child)


def _front(ready: dict[str, deque], units: int, grouped: bool) -> list[Step]:
    """The ready steps in the runner's order (evaluations, trainings, collections), as far as the first
    ``units`` tasks reach (all of a checkpoint's ready evaluations when ``grouped``)."""
    out: list[Step] = []
    seen: set[str] = set()
    for kind in reversed(KINDS):
        for step in ready[kind]:
            unit = evaluated(step) if grouped and kind == "eval" else step.key
            if unit not in seen:
                if len(seen) >= units:
                    return out
                seen.add(unit)
            out.append(step)
    return out


def estimate(
    plan: Plan, steps: list[Step], execution: str = "grouped", model: dict[str, Any] | None = None
) -> dict[str, float]:
    """Wall-clock hours of ``steps`` under each profile (a simulation of the runner's schedule)."""
    model = model or load_model()
    grouped = execution == "grouped"
    costs = step_costs(plan, steps, model)
    out = {}
    for name, (slots, gpus) in PROFILES.items():
        if not steps:
            out[name] = 0.0
        elif slots > CLUSTER_SLOTS:  # a cluster: its throughput bound, the work spread over its slots
            out[name] = sum(sum(cost) for cost in costs.values()) / slots / 3600
        else:
            out[name] = (model["study_s"] + simulate(plan, steps, slots, gpus, grouped, model, costs)) / 3600
    return out


def _extension_lines(plan: Plan, todo: list[Step]) -> list[str]:
    """The trainings that continue a shorter one (``train.extends``): what each trains, and whether it is to run."""
    out = []
    for step in plan.of_kind("train"):
        inputs = TrainInputs.from_dict(step.inputs)
        if inputs.extends is None:
            continue
        unit, budget = ("epochs", inputs.epochs) if inputs.epochs is not None else ("steps", inputs.steps)
        state = "to run" if step in todo else "cached"
        out.append(
            f"  continues: {step.meta.get('method', '?')} {inputs.extends:g} -> {budget:g} {unit} (trains only the "
            f"{budget - inputs.extends:g} new {unit}, from the last pass's end saved before {inputs.extends:g}; {state})"
        )
    return out


def describe(cfg: StudyConfig, plan: Plan, options: RunOptions) -> str:
    """The ``--dry-run`` text: steps per kind, how many are cached (here or in ``options.reuse_from``), the cost
    estimate at ``options.execution``."""
    study_dir = Path(cfg.out_dir)
    lines = [f"study {cfg.name!r} in {study_dir}"]
    reused = reusable_steps(plan.steps, study_dir, options.reuse_from)
    todo = [s for s in plan.steps if not is_done(s, study_dir) and s.key not in reused]
    for kind, total in plan.counts().items():
        cached = total - sum(1 for s in todo if s.kind == kind)
        from_others = sum(1 for s in plan.of_kind(kind) if s.key in reused)
        also = f" ({from_others} in reuse_from)" if from_others else ""
        lines.append(f"  {kind:8s} {total:6d} steps, {cached:6d} cached{also}, {total - cached:6d} to run")
    lines.append(
        f"  grid: {len(cfg.methods)} method(s) x {len(cfg.tasks)} task(s) x N {cfg.n_train_envs} x {len(cfg.seeds)} seed(s); "
        f"conditions: train + {len(cfg.shifted_factors())} factors + {len(cfg.pair_conditions())} pairs"
        + (f" + {len(cfg.family_conditions())} language" if cfg.family_conditions() else "")
        + f"; radius runs: {len(cfg.radius_variants())}"
        + (
            "; learning curve: a checkpoint every "
            + ", ".join(f"{cfg.train_for(m).curve_every:g} epochs ({m.name})" for m in cfg.curve_methods())
            + f", {len(plan.curve_points())} more evaluations on train"
            if plan.curve_points()
            else ""
        )
    )
    lines += _extension_lines(plan, todo)
    model = load_model()
    fitted = model.get("fitted_on", {})
    lines.append(
        f"  estimated wall time of the steps to run (cost model in study/plan/cost.py, fitted on the "
        f"{fitted.get('study', '?')!r} study, {fitted.get('date', '?')}, execution {options.execution}):"
    )
    for name, hours in estimate(plan, todo, options.execution, model).items():
        lines.append(f"    {name:40s} {hours:10.1f} h" if hours >= 1 else f"    {name:40s} {hours * 60:10.0f} min")
    if cfg.collect.other_quality:
        lines.append(
            f"    (the model renders at {DEFAULT_QUALITY}; at {cfg.collect.quality} frames cost "
            + (
                "about half as much, docs/factors.md)"
                if cfg.collect.quality == "lod"
                else "about 7x more, docs/lerobot_metaworld.md)"
            )
        )
    lines += power_lines(cfg)  # what the plan's episode and seed counts can resolve
    missing = cfg.missing_weight_files()
    if missing:
        lines.append(f"  not startable yet, weights file(s) not found: {'; '.join(missing)}")
    problems = checkpoint_problems(plan.given_evaluations())
    if problems:
        lines.append(f"  not startable yet, checkpoint(s): {'; '.join(problems)}")
    return "\n".join(lines)


# --- refitting the constants from a finished study ---------------------------------------------


def fit_constants(plan: Plan, study_dir: str | Path) -> dict[str, Any]:
    """The constants that reproduce the finished steps' measured timings: per kind, the work part's seconds
    per unit of work summed over the steps (frames, samples, environment steps) and the fixed part as the
    mean of what is left of each step's total; the mean episode length over the horizon per task; and
    ``study_s``, the last run's wall time less the simulated schedule of its steps."""
    index = {s.key: s for s in plan.steps}
    finished = finished_timings(plan, study_dir)
    if not finished:
        raise ValueError(f"no finished step with timings in {study_dir}: run the study first")
    work: dict[str, float] = {k: 0.0 for k in KINDS}
    units: dict[str, float] = {k: 0.0 for k in KINDS}
    fixed: dict[str, list[float]] = {k: [] for k in KINDS}
    samples: dict[str, list[float]] = {}
    steps_run: dict[str, list[float]] = {}
    for step, result in finished:
        t = result[TIMINGS]
        variable = sum(t.get(name, 0.0) for name in PER_WORK[step.kind])
        fixed[step.kind].append(t["total"] - variable)
        if step.kind == "collect":
            work["collect"] += variable
            units["collect"] += result["frames"]
        elif step.kind == "train":
            kind = TrainInputs.from_dict(step.inputs).policy["type"]
            n = (result["steps"] - result.get("resumed_from", 0)) * TrainInputs.from_dict(step.inputs).batch_size
            samples.setdefault(kind, []).extend([variable, n])
        else:
            inputs = EvalInputs.from_dict(step.inputs)
            env = inputs.environments or CollectInputs.from_dict(index[step.deps[-1]].inputs)
            task = env.task
            horizon = step_limit(task, inputs.max_episode_steps)
            work["eval"] += variable
            units["eval"] += result.get("env_steps", 0)
            # the episodes whose environment steps it counted: under auto, not its budget, and not the blocks a
            # resumed group read back (EPISODES_RUN); none, and it says nothing of the episodes' length
            ran = result.get(EPISODES_RUN, len(result.get("successes", ())) or inputs.episodes)
            if ran:
                steps_run.setdefault(task, []).extend([result.get("env_steps", 0), ran * horizon])
    old = load_model()
    model = json.loads(json.dumps(old))  # kinds a study did not run keep their constants
    for kind in KINDS:
        if fixed[kind]:
            model[kind]["fixed_s"] = round(sum(fixed[kind]) / len(fixed[kind]), 3)
    if units["collect"]:
        model["collect"]["frame_s"] = round(work["collect"] / units["collect"], 5)
    for kind, pairs in samples.items():
        model["train"]["sample_s"][kind] = round(sum(pairs[0::2]) / sum(pairs[1::2]), 6)
    if units["eval"]:
        model["eval"]["sim_step_s"] = round(work["eval"] / units["eval"], 5)
    for task, pairs in steps_run.items():
        model["eval"]["episode_fraction"][task] = round(sum(pairs[0::2]) / sum(pairs[1::2]), 3)
    run = last_run(study_dir)
    if run is not None:
        steps = [s for s, _ in finished]
        model["study_s"] = 0.0
        simulated = simulate(plan, steps, run["workers"], 0, run["execution"] == "grouped", model)
        model["study_s"] = round(max(0.0, run["wall_s"] - simulated), 1)
    return model


def fit_cost_model(
    cfg: StudyConfig, plan: Plan, study_dir: str | Path, options: RunOptions, path: Path = COST_MODEL_FILE
) -> str:
    """Refit the constants from study ``cfg``'s finished steps, write them to ``path`` with where they were
    fitted, and return what changed and the model's estimate of the whole study next to its wall time. Only from
    a study rendered at the default quality: the model's frame costs are that quality's."""
    if cfg.collect.other_quality:
        raise ValueError(
            f"--fit_cost refits the model of {DEFAULT_QUALITY} rendering; this study renders at "
            f"{cfg.collect.quality}: fit it on a study at {DEFAULT_QUALITY}"
        )
    old = load_model(path) if Path(path).is_file() else load_model()
    model = fit_constants(plan, study_dir)
    run = last_run(study_dir) or {}
    model["fitted_on"] = {
        "study": cfg.name,
        "out_dir": str(cfg.out_dir),
        "commit": provenance.current().revision(short=True),
        "date": datetime.date.today().isoformat(),
        "execution": run.get("execution", options.execution),
        "workers": run.get("workers", options.workers),
        "wall_s": run.get("wall_s"),
    }
    atomic_write_json(path, model, indent=1, sort_keys=True)
    lines = [f"wrote {path}"]
    for kind in (*KINDS, "study_s"):
        lines.append(f"  {kind}: {json.dumps(old.get(kind))} -> {json.dumps(model[kind])}")
    whole = estimate(plan, list(plan.steps), model["fitted_on"]["execution"], model)
    wall = run.get("wall_s")
    cpu = whole[next(iter(PROFILES))] * 3600
    measured = f"{wall:.0f} s measured" if wall else "no measured wall time"
    lines.append(
        f"  this study from scratch on {run.get('workers', options.workers)} workers: {cpu:.0f} s estimated, {measured}"
    )
    return "\n".join(lines)
