"""``eval.episodes=auto``: the evaluations of one checkpoint run together, block by block of paired seeds, until
the stopping rule (``study/sequential.py``) has stopped every shifted condition; ``train`` runs while any runs.

Why together: a condition's stop depends on ``train``'s outcomes on the same seeds and ``train``'s on every
condition's, so the group is one unit of work (one process, its policy loaded once). Each condition is still its
own step, with its own key (the rule's settings and the group's conditions in it, ``SEQUENTIAL``) and its own
``result.json`` (every episode it ran, and how it stopped under ``SEQUENTIAL``). Every finished block is kept in
the step's folder (``blocks/<first seed>.json``), so an interrupted group resumes at the block it was in; the
results are written only once every condition has stopped, ``train`` last.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...core.io import atomic_write_text
from ...envs.stages import as_tracked, stage_names, tracked_before
from ...protocol.conditions import TRAIN_SUITE
from ..sequential import StopRule, decide, running
from .step import Step

SEQUENTIAL = "sequential"  # an evaluation input (in the key, only with auto): the rule and the group's conditions
GROUP = "sequential_group"  # run entry (not in the key): condition -> key of every step of the group
BLOCKS_DIR = "blocks"
EPISODES_RUN = "episodes_run"  # result entry: the episodes of it this run ran (a resumed group reads the rest back)


def with_stop_rule(steps: list[Step], rule: StopRule) -> list[Step]:
    """The evaluations of one checkpoint (``train`` and its shifted conditions) as one group under ``rule``."""
    evals = [s for s in steps if s.kind == "eval"]
    conditions = sorted(s.meta["condition"] for s in evals if s.meta["condition"] != TRAIN_SUITE)
    settings = {**rule.to_dict(), "conditions": conditions}
    grouped = [Step(s.kind, {**s.inputs, SEQUENTIAL: settings}, s.deps, s.meta) for s in evals]
    keys = {s.meta["condition"]: s.key for s in grouped}
    grouped = [Step(s.kind, s.inputs, s.deps, {**s.meta, "run": {**s.run, GROUP: keys}}) for s in grouped]
    rest = iter(grouped)
    return [next(rest) if s.kind == "eval" else s for s in steps]


def is_sequential(step: Step) -> bool:
    return step.kind == "eval" and SEQUENTIAL in step.inputs


def group_id(step: Step) -> str:
    """The group a sequential evaluation belongs to: its train step's key."""
    return step.run[GROUP][TRAIN_SUITE]


def rule_of(step: Step) -> StopRule:
    return StopRule.from_dict(step.inputs[SEQUENTIAL])


Session = Any  # eval_step.EvalSession: passed in, as worker.py imports both modules
OpenSession = Callable[[Step], Session]
Timed = Callable[[str], contextlib.AbstractContextManager]


def run_group(steps: list[Step], study_dir: Path, open_session: OpenSession, write: Callable, timed: Timed) -> None:
    """Run the group of ``steps`` (some of it may be finished already: it is then reread, never rerun) and write
    each unfinished step's result with ``write(step, result)``; ``open_session(step)`` prepares a condition.
    ``timed(condition)`` encloses all of one condition's own work (preparing it, its episodes, its result), so
    each condition's timings are its own and not the group's."""
    first = steps[0]
    keys: dict[str, str] = first.run[GROUP]
    rule = rule_of(first)
    by_condition = {s.meta["condition"]: s for s in steps}
    folders = {c: Path(study_dir) / "steps" / "eval" / key for c, key in keys.items()}
    start = int(first.inputs["start_seed"])
    outcomes: dict[str, dict[str, list]] = {
        c: {"successes": [], "seeds": [], "stages": [], "lengths": []} for c in keys
    }
    task = first.meta["task"]
    tracked: dict[str, set[tuple[str, ...]]] = {c: set() for c in keys}  # the stages each condition's blocks tracked
    measured: dict[str, list] = {c: [] for c in keys}  # each episode's family measures (None: a block without them)
    sessions: dict[str, Session] = {}
    ran = dict.fromkeys(keys, 0)  # episodes this run ran (not read back from a block): what its cost records
    shifted = [c for c in keys if c != TRAIN_SUITE]
    active = list(keys)
    for begin in range(start, start + rule.max_episodes, rule.block):
        if not active:
            break
        for condition in active:
            block = _read_block(folders[condition], begin)
            if block is None:
                with timed(condition):
                    if condition not in sessions:
                        sessions[condition] = open_session(_step_of(by_condition, condition, folders))
                    session = sessions[condition]
                    successes = session.episodes(begin, rule.block)
                ran[condition] += rule.block
                seeds = list(range(begin, begin + rule.block))
                block = {
                    "successes": successes,
                    "seeds": seeds,
                    "stages": [session.recorder.stages[s] for s in seeds],
                    "lengths": [session.recorder.lengths[s] for s in seeds],
                    "stage_names": list(stage_names(task)),
                }
                if session.recorder.measure_keys:
                    block["measures"] = [session.recorder.measures[s] for s in seeds]
                _write_block(folders[condition], begin, block)
            tracked[condition].add(tuple(block.get("stage_names", tracked_before(task))))  # older blocks: no names
            for name, values in block.items():
                if name in outcomes[condition]:
                    outcomes[condition][name].extend(values)
            measured[condition] += block.get("measures") or [None] * len(block["seeds"])  # older blocks: none
        stops = decide(outcomes[TRAIN_SUITE]["successes"], {c: outcomes[c]["successes"] for c in shifted}, rule)
        active = running(stops)
        active = [TRAIN_SUITE, *active] if active else []
    stops = decide(outcomes[TRAIN_SUITE]["successes"], {c: outcomes[c]["successes"] for c in shifted}, rule)
    for condition in [*shifted, TRAIN_SUITE]:  # train last: once it is written, the whole group is
        step = by_condition.get(condition)
        if step is None:  # finished by an earlier run of the group
            continue
        n = stops[condition].episodes
        own = {name: values[:n] for name, values in outcomes[condition].items()}
        names = _pooled_stage_names(task, tracked[condition])
        with timed(condition):
            if condition not in sessions:
                sessions[condition] = open_session(step)
            stages = as_tracked(task, own["stages"], names)
            measures = measured[condition][:n]
            result = sessions[condition].result(
                own["successes"], own["seeds"], stages, own["lengths"], list(names), measures
            )
        result[SEQUENTIAL] = stops[condition].to_dict()
        result[EPISODES_RUN] = ran[condition]
        write(step, result)


def _pooled_stage_names(task: str, tracked: set[tuple[str, ...]]) -> tuple[str, ...]:
    """The stages a condition's blocks all tracked: their one set, or (blocks of older code among them) the stages
    before any added later, which every block's episodes can be counted in."""
    return next(iter(tracked)) if len(tracked) == 1 else tracked_before(task)


def _step_of(by_condition: dict[str, Step], condition: str, folders: dict[str, Path]) -> Step:
    """A condition's step: one of the unit's, or (finished earlier) the one stored in its folder."""
    if condition in by_condition:
        return by_condition[condition]
    return Step.from_dict(json.loads((folders[condition] / "step.json").read_text()))


def _read_block(folder: Path, begin: int) -> dict[str, list] | None:
    path = folder / BLOCKS_DIR / f"{begin}.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _write_block(folder: Path, begin: int, block: dict[str, list]) -> None:
    (folder / BLOCKS_DIR).mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / BLOCKS_DIR / f"{begin}.json", json.dumps(block))
