"""Cached steps made by other code. Before anything runs, the cached steps of the plan are checked
against the current code: a step whose recorded provenance has another source hash, or none (made
before provenance was recorded), is *stale*.
One ``warning:`` line names them (kinds, counts, commits, a few labels) and says when the current code
has uncommitted changes; ``strict`` refuses to run instead, ``rerun_stale`` redoes them together with
every cached step that depends on one (its dataset or checkpoint is remade by the current code, so
what was computed from the old one no longer matches it). Redone steps' folders are moved aside to
``steps/<kind>/<key>.stale-<commit>``, never deleted: the old results stay readable.
"""

from __future__ import annotations

import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from ...core import provenance
from ...core.provenance import UNKNOWN, Provenance
from ..run.options import RunOptions
from ..run.result import is_done, provenance_of, read_result
from ..run.step import Step
from .grid import Plan

STALE_SUFFIX = ".stale-"  # a redone step's old folder: steps/<kind>/<key>.stale-<commit>
STALE_LABELS = 3  # step labels the stale line names


@dataclass(frozen=True)
class Stale:
    """A cached step of the plan made by other code than the current one."""

    step: Step
    made_by: Provenance | None  # None: made before provenance was recorded

    @property
    def name(self) -> str:
        return self.made_by.name if self.made_by else UNKNOWN


def stale_steps(plan: Plan, study_dir: Path, now: Provenance | None = None) -> list[Stale]:
    """The finished steps of ``plan`` whose code differs from ``now`` (default: the current code) by source
    hash, or that recorded none, in plan order."""
    now = now or provenance.current()
    out = []
    for step in plan.steps:
        if is_done(step, study_dir):
            made_by = provenance_of(read_result(step, study_dir))
            if made_by is None or made_by.source_hash != now.source_hash:
                out.append(Stale(step, made_by))
    return out


def dependents(plan: Plan, keys: set[str]) -> list[Step]:
    """The steps of ``plan`` that depend, directly or through others, on the steps ``keys`` (plan order is
    dependency order, so one pass finds them all)."""
    affected, out = set(keys), []
    for step in plan.steps:
        if step.key not in affected and any(d in affected for d in step.deps):
            affected.add(step.key)
            out.append(step)
    return out


def stale_summary(stale: list[Stale], now: Provenance) -> str:
    """``12 cached steps were made by other code than the current, a963569: collect x2 at 826fe54, ...
    (e.g. <label>; <label>; <label>; +9 more)``."""
    groups = Counter((s.step.kind, s.name) for s in stale)  # plan order: collect, train, eval
    counts = ", ".join(f"{kind} x{n} at {name}" for (kind, name), n in groups.items())
    labels = "; ".join(s.step.label for s in stale[:STALE_LABELS])
    more = f"; +{len(stale) - STALE_LABELS} more" if len(stale) > STALE_LABELS else ""
    were = "step was" if len(stale) == 1 else "steps were"
    return f"{len(stale)} cached {were} made by other code than the current, {now.name}: {counts} (e.g. {labels}{more})"


def check_not_stale(options: RunOptions, stale: list[Stale]) -> None:
    """``strict``: refuse (one line) when cached steps of the plan were made by other code."""
    if options.strict and stale:
        raise ValueError(
            f"{stale_summary(stale, provenance.current())}; --strict=true refuses to mix them with steps of the "
            "current code: --rerun_stale=true redoes them, or choose another out_dir"
        )


def provenance_warning(options: RunOptions, plan: Plan, study_dir: Path, stale: list[Stale]) -> str | None:
    """The one ``warning:`` line before a run: the cached steps made by other code and what happens to
    them, and whether the steps run now come from a tree with uncommitted changes; ``None`` when neither."""
    now = provenance.current()
    parts = []
    redo = {s.step.key for s in stale}
    if stale and options.rerun_stale:
        also = [s for s in dependents(plan, redo) if is_done(s, study_dir)]
        parts.append(
            f"{stale_summary(stale, now)}; --rerun_stale=true: they and the {len(also)} cached step(s) depending "
            f"on them are redone (old folders kept as steps/<kind>/<key>{STALE_SUFFIX}<commit>)"
        )
    elif stale:
        parts.append(f"{stale_summary(stale, now)}; --rerun_stale=true redoes them, --strict=true refuses")
    to_run = any(not is_done(s, study_dir) for s in plan.steps) or (bool(stale) and options.rerun_stale)
    if now.clean is False and to_run:
        parts.append(
            f"the current code, {now.name}, has uncommitted changes: steps run now are not reproducible from a commit"
        )
    return "warning: " + "; ".join(parts) if parts else None


def warn_stale(options: RunOptions, plan: Plan, study_dir: Path, stale: list[Stale]) -> None:
    line = provenance_warning(options, plan, study_dir, stale)
    if line:
        print(line, file=sys.stderr, flush=True)


def rerun_stale(plan: Plan, study_dir: Path, stale: list[Stale]) -> list[Path]:
    """Move the folders of the ``stale`` steps and of every cached step depending on them aside (to
    ``<key>.stale-<commit>``, the commit that made each), so that they run again; returns the new folders.
    Dependents go first: an interruption leaves no cached step whose inputs are gone."""
    known = {s.step.key: s.made_by for s in stale}  # read before: no second read of their results
    redo = [s.step for s in stale] + dependents(plan, set(known))
    order = {s.key: i for i, s in enumerate(plan.steps)}
    moved = []
    for step in sorted(redo, key=lambda s: -order[s.key]):
        if is_done(step, study_dir):
            made_by = known[step.key] if step.key in known else provenance_of(read_result(step, study_dir))
            moved.append(_move_aside(step.folder(study_dir), made_by.revision(short=True) if made_by else UNKNOWN))
    return moved


def _move_aside(folder: Path, revision: str) -> Path:
    """Rename ``folder`` to ``<name>.stale-<revision>`` (``-2``, ``-3``, ... when that exists already)."""
    target = folder.with_name(f"{folder.name}{STALE_SUFFIX}{revision}")
    n = 1
    while target.exists():
        n += 1
        target = folder.with_name(f"{folder.name}{STALE_SUFFIX}{revision}-{n}")
    folder.rename(target)
    return target
