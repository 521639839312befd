"""Where a study's time went: the ``timings`` every finished step records in its ``result.json``
(seconds per component, ``total`` its own wall time), summed per kind of step and component.

``factorworld study --config_path=X --profile=true`` prints :func:`profile_text` (nothing is run), the
report's "Where the time went" section is :func:`profile_markdown`, and the ``--dry-run`` cost model is
refitted from the same numbers (``cost.py``). Timings never enter a step's key or ``results.csv``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...core.io import atomic_write_json
from ..run.result import RESULT_FILE, TIMINGS
from ..run.step import KINDS, Step
from .grid import Plan

RUN_FILE = "run_timing.json"  # the last run of the study folder: wall seconds, workers, execution, steps run
TOTAL = "total"

# What each component means, per kind (components a step did not record are left out of the table).
COMPONENTS = {
    "collect": {
        "imports": "imports in the worker (paid once per worker process)",
        "worker_start": "start of collection worker processes",
        "setup": "per job: config, environment object, empty dataset",
        "env_build": "scene compilation (MjSpec -> model, Meta-World env)",
        "render": "rendering the cameras",
        "expert_physics": "scripted expert and physics (the rollout less the two above)",
        "write_frames": "adding frames to the dataset (image writing)",
        "save_episode": "saving episodes (encoding, parquet)",
        "finalize": "closing each job's dataset",
        "merge": "merging the jobs' datasets into one",
    },
    "train": {
        "imports": "imports in the worker (in-process training, once per worker)",
        "startup_save": "process start and imports (subprocess), dataset and policy set-up, checkpoint",
        "data": "data loading (LeRobot's data_s x steps)",
        "update": "forward, backward, optimizer (LeRobot's updt_s x steps)",
        "merge": "merging the task's dataset with other tasks' (extra_tasks)",
    },
    "eval": {
        "imports": "imports in the worker (paid once per worker process)",
        "policy_load": "policy and processors from the checkpoint (once per group when grouped)",
        "env_build": "vector environment and its processors",
        "scene_compile": "scenes compiled at the episodes' resets",
        "render": "rendering the cameras (and creating each scene's renderer)",
        "env_reset": "environment resets less compilation and rendering",
        "env_step": "environment steps less rendering (physics, Meta-World)",
        "policy": "policy inference (select_action)",
        "rollout_other": "LeRobot's rollout loop: pre/post-processing, bookkeeping",
        "records": "episode records, coverage, fingerprint",
    },
}


@dataclass(frozen=True)
class ComponentRow:
    kind: str
    component: str  # a component name, "other" (the step's total less its components) or "total"
    count: int  # steps that recorded it
    seconds: float  # summed over those steps
    share: float  # of all steps' summed wall time (``total``)

    @property
    def mean(self) -> float:
        return self.seconds / self.count if self.count else 0.0


def finished_timings(plan: Plan, study_dir: str | Path) -> list[tuple[Step, dict[str, Any]]]:
    """(step, result) of every finished step of ``plan`` that recorded timings, in plan order."""
    out = []
    for step in plan.steps:
        path = step.folder(study_dir) / RESULT_FILE
        if path.is_file():
            result = json.loads(path.read_text())
            if result.get(TIMINGS):
                out.append((step, result))
    return out


def component_rows(plan: Plan, study_dir: str | Path) -> list[ComponentRow]:
    """Per kind: every component's count, summed and mean seconds and share of the summed step time; then
    ``other`` (a step's total less its components) and the kind's ``total``."""
    finished = finished_timings(plan, study_dir)
    grand = sum(r[TIMINGS].get(TOTAL, 0.0) for _, r in finished) or 1.0
    rows: list[ComponentRow] = []
    for kind in KINDS:
        results = [r[TIMINGS] for s, r in finished if s.kind == kind]
        if not results:
            continue
        names = [n for n in COMPONENTS[kind] if any(n in t for t in results)]
        names += sorted({n for t in results for n in t} - set(names) - {TOTAL})
        for name in names:
            values = [t[name] for t in results if name in t]
            rows.append(ComponentRow(kind, name, len(values), sum(values), sum(values) / grand))
        other = sum(t.get(TOTAL, 0.0) - sum(v for n, v in t.items() if n != TOTAL) for t in results)
        rows.append(ComponentRow(kind, "other", len(results), other, other / grand))
        total = sum(t.get(TOTAL, 0.0) for t in results)
        rows.append(ComponentRow(kind, TOTAL, len(results), total, total / grand))
    return rows


def record_run(study_dir: str | Path, wall_s: float, workers: int, execution: str, ran: dict[str, int]) -> None:
    """Remember the wall time of a run that ran steps (the profile and the cost model's fit read it)."""
    atomic_write_json(
        Path(study_dir) / RUN_FILE,
        {"wall_s": round(wall_s, 2), "workers": workers, "execution": execution, "ran": ran},
        indent=1,
        sort_keys=True,
    )


def last_run(study_dir: str | Path) -> dict[str, Any] | None:
    path = Path(study_dir) / RUN_FILE
    return json.loads(path.read_text()) if path.is_file() else None


def _run_line(study_dir: str | Path, rows: list[ComponentRow]) -> str:
    steps_s = sum(r.seconds for r in rows if r.component == TOTAL)
    run = last_run(study_dir)
    if run is None:
        return f"summed step time {steps_s:.1f} s (no run's wall time recorded)"
    busy = steps_s / (run["wall_s"] * run["workers"]) if run["wall_s"] else 0.0
    ran = ", ".join(f"{n} {k}" for k, n in run["ran"].items())
    return (
        f"last run: {run['wall_s']:.1f} s wall with {run['workers']} worker(s), execution {run['execution']} "
        f"(ran {ran}); summed step time {steps_s:.1f} s, workers busy {busy:.0%} of the run"
    )


def profile_text(plan: Plan, study_dir: str | Path) -> str:
    """The ``--profile`` table: per kind and component, steps, summed and mean seconds, share."""
    rows = component_rows(plan, study_dir)
    if not rows:
        return f"no finished step with timings in {study_dir}"
    lines = [_run_line(study_dir, rows), "share: of the summed wall time of all finished steps"]
    lines.append(f"{'kind':8s} {'component':16s} {'steps':>5s} {'total s':>9s} {'mean s':>8s} {'share':>6s}")
    for r in rows:
        lines.append(f"{r.kind:8s} {r.component:16s} {r.count:5d} {r.seconds:9.1f} {r.mean:8.2f} {r.share:6.1%}")
    return "\n".join(lines)


def profile_markdown(plan: Plan, study_dir: str | Path) -> list[str]:
    """The report's "Where the time went" section (empty when no finished step recorded timings)."""
    rows = component_rows(plan, study_dir)
    if not rows:
        return []
    lines = [
        "## Where the time went",
        "",
        _run_line(study_dir, rows) + " (`factorworld study --config_path=... --profile=true` prints this table).",
        "",
        "| kind | component | steps | total s | mean s | share of step time |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        name = f"**{r.component}**" if r.component == TOTAL else r.component
        lines.append(f"| {r.kind} | {name} | {r.count} | {r.seconds:.1f} | {r.mean:.2f} | {r.share:.1%} |")
    return [*lines, ""]
