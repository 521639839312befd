"""Run a study: plan the grid, run the steps that are not cached (dependencies first, ``workers`` at
a time, on the chosen executor, with progress bars), then write ``results.csv``, ``episodes.parquet``, plots
and ``report.md``, and push the results to the Hub when asked (``push_to_hub``: one line either way).

A failed step is reported and its dependents are skipped; every other step still runs, so a rerun
only redoes what failed. One run of a study folder at a time (a lock file guards it).

Cached steps made by other code are named, refused or redone first (``stale.py``).
"""

from __future__ import annotations

import fcntl
import os
import shlex
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from tqdm import tqdm

from ..core import machine
from ..core.io import atomic_write_json
from ..datasets.hub import check_hub_token
from .plan.config import StudyConfig, write_run_config
from .plan.cost import describe, fit_cost_model
from .plan.grid import Plan, make_plan
from .plan.profile import profile_text, record_run
from .plan.stale import check_not_stale, rerun_stale, stale_steps, warn_stale
from .report.write import write_report
from .results.episodes import push_results
from .results.eval_results import open_model_pr
from .run.blocks import group_id, is_sequential
from .run.checkpoint import check_checkpoints, fetch_checkpoints
from .run.executors import make_executor, task_units
from .run.options import RunOptions
from .run.result import is_done
from .run.reuse import check_reuse_from, link_reused_steps
from .run.step import KINDS, RUN_CONFIG_FILE, Step

LOCK_FILE = ".lock"
REPORT_LOCK_FILE = ".report.lock"  # one writer of the study's outputs at a time: a run's end or a --report-only
PLAN_FILE = "plan.json"


@dataclass
class StudyOutcome:
    study_dir: Path
    ran: dict[str, int] = field(default_factory=dict)  # steps run now, per kind
    cached: dict[str, int] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)  # step label -> error
    skipped: int = 0  # steps not run because a step they depend on failed
    stale: int = 0  # cached steps made by other code (found before running)
    set_aside: list[Path] = field(default_factory=list)  # old folders of the steps redone (rerun_stale)
    results: Path | None = None
    report: Path | None = None
    plots: list[Path] = field(default_factory=list)
    pushed: bool = False  # the results went to the Hub (push_to_hub)


def inspect_study(cfg: StudyConfig, options: RunOptions) -> str:
    """What ``options`` asks to inspect (``dry_run``, ``profile`` or ``fit_cost``), without running anything: the
    plan's description (steps, cached, cost, power; cached steps made by other code are named on stderr first),
    where the finished steps' time went, or what the refitted cost model found."""
    _check_grid(cfg)
    if not options.inspects:
        raise ValueError("inspect_study needs dry_run, profile or fit_cost; run_study runs the study")
    check_reuse_from(options.reuse_from, cfg.out_dir)
    plan = make_plan(cfg)
    study_dir = Path(cfg.out_dir)
    if options.dry_run:
        warn_stale(options, plan, study_dir, stale_steps(plan, study_dir))
        return describe(cfg, plan, options)
    if options.profile:
        return profile_text(plan, study_dir)
    return fit_cost_model(cfg, plan, study_dir, options)


def _warn_emulated_bf16(plan: Plan, study_dir: Path) -> None:
    """One warning line, before the hours it costs, for trainings at ``speed=fast`` about to run on a CPU whose
    bf16 is emulated; they still run as asked (``speed`` is in their keys, so another value is another training)."""
    slow = [
        s
        for s in plan.of_kind("train")
        if s.inputs.get("device") == "cpu" and s.inputs["policy"].get("speed") == "fast" and not is_done(s, study_dir)
    ]
    here = machine.current()
    if slow and machine.lacks_native_bf16(here):
        print(
            f"warning: {len(slow)} training(s) at speed=fast to run on {machine.describe(here)}, which has no "
            f"AVX-512 BF16 or AMX: {machine.EMULATED_BF16_COST}; speed: default in a method's policy trains "
            "faster here, as other trainings (other keys)",
            file=sys.stderr,
        )


def run_study(cfg: StudyConfig, options: RunOptions | None = None, command: str | None = None) -> StudyOutcome:
    """Run (or resume) the grid ``cfg`` as ``options`` say (default: one local worker). Cached steps made by
    other code are named on stderr first, refused under ``strict``, redone under ``rerun_stale`` (see the module
    docstring). Options that only inspect (``dry_run``, ``profile``, ``fit_cost``) are :func:`inspect_study`'s,
    refused here."""
    _check_grid(cfg)
    options = options or RunOptions()
    if options.model_repo_id and (len(cfg.methods) != 1 or cfg.trained_methods()):
        raise ValueError(
            "model_repo_id opens a pull request with one given checkpoint's results (factorworld profile's); this "
            f"study has {len(cfg.methods)} method(s), {len(cfg.trained_methods())} of them trained here"
        )
    if options.inspects:
        raise ValueError("dry_run, profile and fit_cost run nothing: use inspect_study")
    if options.report_only:
        raise ValueError("report_only runs nothing: use report_study")
    check_reuse_from(options.reuse_from, cfg.out_dir)
    start = time.perf_counter()
    fetch_checkpoints([m.checkpoint for m in cfg.given_methods()])  # before planning: keys hash their files
    plan = make_plan(cfg)
    study_dir = Path(cfg.out_dir)
    cfg.check_weight_files()  # before any step runs: weights are never downloaded
    check_checkpoints(plan.given_evaluations())  # a given checkpoint that cannot run on its env: one line
    if options.push_to_hub:
        check_hub_token()  # before any step runs, not after hours of them
    study_dir.mkdir(parents=True, exist_ok=True)
    command = command or "factorworld study " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    with _lock(study_dir):
        reused = link_reused_steps(plan.steps, study_dir, options.reuse_from)
        if reused:
            folders = ", ".join(options.reuse_from)
            print(f"reused {reused} finished step(s) of {folders} (reuse_from)", file=sys.stderr)
        stale = stale_steps(plan, study_dir)  # under the lock: no other run changes them meanwhile
        check_not_stale(options, stale)  # strict: before any work
        warn_stale(options, plan, study_dir, stale)
        _warn_emulated_bf16(plan, study_dir)
        set_aside = rerun_stale(plan, study_dir, stale) if options.rerun_stale else []
        write_run_config(study_dir / RUN_CONFIG_FILE, {**asdict(cfg), **asdict(options)})  # as a YAML holds them
        atomic_write_json(
            study_dir / PLAN_FILE, [s.to_dict() for s in plan.steps], indent=1, sort_keys=True, default=str
        )
        outcome = _execute(plan, study_dir, options)
        outcome.stale, outcome.set_aside = len(stale), set_aside
        if any(outcome.ran.values()):  # before the report, which states it
            record_run(study_dir, time.perf_counter() - start, options.workers, options.execution, outcome.ran)
        with _lock(study_dir, REPORT_LOCK_FILE, wait=True):
            outcome.results, outcome.report, outcome.plots = write_report(cfg, plan, study_dir, command)
        if options.push_to_hub:
            outcome.pushed = _push(options, outcome)
    return outcome


def report_study(cfg: StudyConfig, options: RunOptions, command: str) -> StudyOutcome:
    """``report_only``: the study's outputs written from its steps finished so far, nothing run. It does not take
    the run's lock: a run of the study in another process (which holds it) only ever adds finished steps, written
    whole. Writing the outputs takes the report lock, which a run's own report takes too, so the two never write
    at once, and the later one reads every step the earlier one did. Cached steps made by other code are named
    (refused under ``strict``) as a run would."""
    _check_grid(cfg)
    if not options.report_only:
        raise ValueError("report_study writes the report of a study's finished steps: it needs report_only")
    plan, study_dir = make_plan(cfg), Path(cfg.out_dir)
    evaluations = plan.evaluations() + plan.curve_points()  # a curve's points are reported before its grid's
    if not any(is_done(step, study_dir) for step in evaluations):
        raise ValueError(
            f"nothing to report: none of this study's {len(evaluations)} evaluations (learning-curve points "
            f"included) has finished in {study_dir}; run the study first (the same command without report_only)"
        )
    stale = stale_steps(plan, study_dir)
    check_not_stale(options, stale)
    warn_stale(options, plan, study_dir, stale)
    outcome = StudyOutcome(study_dir)
    with _lock(study_dir, REPORT_LOCK_FILE, wait=True):
        for kind in KINDS:
            outcome.cached[kind] = sum(1 for step in plan.of_kind(kind) if is_done(step, study_dir))
        outcome.results, outcome.report, outcome.plots = write_report(cfg, plan, study_dir, command)
    return outcome


def _check_grid(cfg: StudyConfig) -> None:
    """A flat study command passed as the grid would run with default options, its own silently dropped; and
    LeRobot's verdict on the policies, which a grid built in code (not read as a :class:`.plan.command.StudyCommand`)
    has not had yet: before any work, as the command's parsing checks them."""
    if isinstance(cfg, RunOptions):
        raise TypeError("pass the grid and the run options apart: run_study(*command.parts()), not the command")
    cfg.check_policies()


def _push(options: RunOptions, outcome: StudyOutcome) -> bool:
    """Push the written results (``push_results``) and print its one line; never half a study's results."""
    if outcome.failed or outcome.skipped:
        print(
            f"warning: nothing pushed to {options.hub_repo_id}: {len(outcome.failed)} step(s) failed; rerun the same "
            "command to finish the study and push it",
            file=sys.stderr,
        )
        return False
    pushed = True
    if options.hub_repo_id:
        pushed, line = push_results(outcome.study_dir, options.hub_repo_id)
        print(line, file=sys.stdout if pushed else sys.stderr, flush=True)
    if options.model_repo_id:
        opened, line = open_model_pr(outcome.study_dir, options.model_repo_id)
        print(line, file=sys.stdout if opened else sys.stderr, flush=True)
        pushed = pushed and opened
    return pushed


def _execute(plan: Plan, study_dir: Path, options: RunOptions) -> StudyOutcome:
    outcome = StudyOutcome(study_dir)
    todo = [s for s in plan.steps if not is_done(s, study_dir)]
    for kind in KINDS:
        total = len(plan.of_kind(kind))
        outcome.cached[kind] = total - sum(1 for s in todo if s.kind == kind)
        outcome.ran[kind] = 0
    if not todo:
        return outcome
    executor = make_executor(
        options.executor, str(study_dir.resolve()), options.workers, options.ray_address, todo, options.execution
    )
    bars = {
        kind: tqdm(total=sum(1 for s in todo if s.kind == kind), desc=f"{kind:7s}", unit="step", position=i)
        for i, kind in enumerate(k for k in KINDS if any(s.kind == k for s in todo))
    }
    done = {s.key for s in plan.steps if is_done(s, study_dir)}
    failed: set[str] = set()
    pending = list(todo)
    running: dict = {}
    try:
        while pending or running:
            for step in _blocked(pending, failed):
                pending.remove(step)
                failed.add(step.key)
                outcome.skipped += 1
                bars[step.kind].update(1)
            ready = [s for s in pending if all(d in done for d in s.deps)]
            ready.sort(key=lambda s: -KINDS.index(s.kind))  # finish cells before starting new ones: early results
            free = max(0, options.workers - len(running))
            for unit in _units(ready, free, grouped=options.execution == "grouped")[:free]:
                for step in unit:
                    pending.remove(step)
                running[executor.submit(unit)] = unit
            if not running:
                break
            for handle in executor.wait_any(list(running)):
                unit = running.pop(handle)
                try:
                    errors = executor.result(handle)
                except Exception as err:  # noqa: BLE001 - the worker died: every step of the task failed
                    errors = {step.key: f"{type(err).__name__}: {err}" for step in unit}
                for step in unit:
                    error = errors.get(step.key, "the worker returned no result for this step")
                    if error is None:
                        done.add(step.key)
                        outcome.ran[step.kind] += 1
                    else:  # reported, dependents skipped, rerun resumes
                        failed.add(step.key)
                        outcome.failed[step.label] = error
                        (step.folder(study_dir)).mkdir(parents=True, exist_ok=True)
                        (step.folder(study_dir) / "error.txt").write_text(error)
                    bars[step.kind].update(1)
    finally:
        executor.shutdown()
        for bar in bars.values():
            bar.close()
    return outcome


def _units(ready: list[Step], free: int, grouped: bool) -> list[list[Step]]:
    """The worker tasks for ``ready``: an ``eval.episodes=auto`` group is one task (its stopping couples its
    conditions: ``run/blocks.py``), the other steps as ``task_units`` makes them."""
    groups: dict[str, list[Step]] = {}
    for step in ready:
        if is_sequential(step):
            groups.setdefault(group_id(step), []).append(step)
    rest = [s for s in ready if not is_sequential(s)]
    return [*groups.values(), *(task_units(rest, free - len(groups), grouped) if rest else [])]


def _blocked(pending: list[Step], failed: set[str]) -> list[Step]:
    return [s for s in pending if any(d in failed for d in s.deps)]


class _lock:
    """An exclusive lock on the study folder (a second concurrent run would race on the same steps), or, with
    ``wait``, on one of its files that writers take in turn (the report's)."""

    def __init__(self, study_dir: Path, name: str = LOCK_FILE, wait: bool = False) -> None:
        self.path, self.wait = study_dir / name, wait

    def __enter__(self):
        self.file = open(self.path, "w")
        try:
            fcntl.flock(self.file, fcntl.LOCK_EX | (0 if self.wait else fcntl.LOCK_NB))
        except BlockingIOError:
            self.file.close()
            raise FileExistsError(f"another run of this study is in progress ({self.path} is locked)") from None
        self.file.write(str(os.getpid()))
        self.file.flush()
        return self

    def __exit__(self, *exc) -> None:
        fcntl.flock(self.file, fcntl.LOCK_UN)
        self.file.close()
