"""Where an episode fails: the ordered stages of a task, judged from Meta-World's own per-step ``info``.

A success rate says how often a policy fails, not where. Every Meta-World v3 task reports, each step, the
quantities its own reward and success test use (``near_object``, ``grasp_success``, ``obj_to_target``,
``in_place_reward``, ``success``); these definitions turn them into a few ordered stages, so a gap between
conditions comes with its cause (a camera shift that makes the arm miss the object ends episodes at
``none``; one that makes it drop the object ends them at ``grasped``). This module is the one place the
stages are defined; ``docs/study.md`` ("Where episodes fail") documents them.

- Object tasks (a loose object: pick-place, basketball, bin-picking, the pick family):
  ``none`` < ``reached`` < ``grasped`` < ``moved`` < ``succeeded``.
- Articulated tasks (door, drawer, button, faucet, handle, lever, window): ``none`` < ``reached`` < ``moved``
  < ``succeeded`` (their ``grasp_success`` is the gripper's opening or a constant: no grasp stage).

A stage counts when its own test holds at some step; an episode's stage is the last one in the order that
ever did (``none`` if none did). The tests:

- ``reached``: Meta-World's ``near_object`` is 1 (:data:`REACHED_AT`; its radius is the task's own: 3 cm
  for pick-place, 5 cm for buttons, 1 cm for drawer-close and the faucets; door-open's is a reward that
  is 1 with the hand at the handle).
- ``grasped``: Meta-World's ``grasp_success`` (the object held and lifted: 2 cm for pick-place, 3 cm for
  basketball).
- ``moved``: the task's progress quantity (:data:`PROGRESS`; ``obj_to_target`` unless named) covered
  :data:`MOVED_FRACTION` of the way from its value at the episode's first step to its goal value
  (:data:`GOAL_VALUES`: a distance to 0, a reward to 1).
- ``succeeded``: the task's success test (``success``).

A task family may define its own stages (``TaskFamily.stages``; the pick family adds ``reached_other`` and
``wrong_object``). A stage added after evaluations were recorded without it *refines* an older one (``reached_other``
splits ``none``): an evaluation records the stages it tracked (``stage_names`` in its result), and one that
recorded none is counted with the stages it had (:func:`tracked_before`), never with a zero for a stage it could
not see.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any

from ..families import family_of
from ..tasks import TaskSpec, get_task

Info = Mapping[str, Any]  # Meta-World's per-step info of one step
Test = Callable[[Info, Info], bool]  # (this step's info, the episode's first step's info) -> the stage holds

NONE, REACHED, GRASPED, MOVED, SUCCEEDED = "none", "reached", "grasped", "moved", "succeeded"
STAGE_KEY = "stage"  # the env's info key: the furthest stage of the episode so far
REACHED_AT = 1.0  # near_object is a 0/1 flag, except door-open's ready-to-open reward: 1 with the hand at the handle
MOVED_FRACTION = 0.25  # of the way from the start to the goal: the object (or handle, button...) clearly moved
GOAL_VALUES = {"obj_to_target": 0.0, "in_place_reward": 1.0}  # a distance falls to 0, a shaped reward rises to 1
PROGRESS: dict[str, str] = {
    # Tasks whose obj_to_target does not measure the object's progress: door-open reports 0 always, lever-pull
    # the shoulder's distance to the lever. Their in_place_reward does (door angle, lever angle).
    "door-open": "in_place_reward",
    "lever-pull": "in_place_reward",
}


@dataclass(frozen=True)
class Stage:
    """One stage: its name and its test on a step's info (and the episode's first step's, for progress);
    ``refines``: the older stage it splits, for a stage added after evaluations were recorded without it."""

    name: str
    test: Test
    refines: str | None = None


@dataclass(frozen=True)
class Stages:
    """The ordered stages of a task after ``none`` (which holds from the start), the last the furthest."""

    stages: tuple[Stage, ...]

    @property
    def names(self) -> tuple[str, ...]:
        return (NONE, *(s.name for s in self.stages))

    @property
    def refined(self) -> dict[str, str]:
        """``{stage added later: the older stage it splits}``."""
        return {s.name: s.refines for s in self.stages if s.refines is not None}

    def at(self, info: Info, first: Info) -> int:
        """The index (in :attr:`names`) of the furthest stage whose test holds at this step; 0: none."""
        return max((i for i, s in enumerate(self.stages, 1) if s.test(info, first)), default=0)

    def inserted(self, stage: Stage, before: str) -> Stages:
        """These stages with ``stage`` placed right before the one named ``before`` (a family's extra stage)."""
        at = [s.name for s in self.stages].index(before)
        return Stages((*self.stages[:at], stage, *self.stages[at:]))


class StageTracker:
    """The furthest stage of the current episode, updated with every step's info (a new tracker per episode)."""

    def __init__(self, stages: Stages) -> None:
        self.stages = stages
        self._first: Info | None = None
        self._index = 0

    def update(self, info: Info) -> str:
        """Fold in one step's info; the furthest stage so far."""
        if self._first is None:
            self._first = dict(info)
        self._index = max(self._index, self.stages.at(info, self._first))
        return self.name

    @property
    def name(self) -> str:
        return self.stages.names[self._index]


def reached(info: Info, first: Info) -> bool:
    return float(info["near_object"]) >= REACHED_AT


def grasped(info: Info, first: Info) -> bool:
    return bool(info["grasp_success"])


def succeeded(info: Info, first: Info) -> bool:
    return bool(info["success"])


def moved_by(quantity: str) -> Test:
    """``moved`` on ``quantity``: it covered :data:`MOVED_FRACTION` of the way from its first-step value to
    its goal value (never, when it starts at the goal)."""
    goal = GOAL_VALUES[quantity]

    def moved(info: Info, first: Info) -> bool:
        start = float(first[quantity])
        return start != goal and (start - float(info[quantity])) / (start - goal) >= MOVED_FRACTION

    return moved


def kind_stages(task: TaskSpec) -> Stages:
    """The stages of the task's kind: object tasks (a loose object) have a grasp stage, articulated ones not."""
    moved = Stage(MOVED, moved_by(PROGRESS.get(task.name, "obj_to_target")))
    grasp = (Stage(GRASPED, grasped),) if task.object_is_free else ()
    return Stages((Stage(REACHED, reached), *grasp, moved, Stage(SUCCEEDED, succeeded)))


@cache
def stages_of(task: str | TaskSpec) -> Stages:
    """The stages of ``task``: its family's own (``TaskFamily.stages``), else those of its kind."""
    task = task if isinstance(task, TaskSpec) else get_task(task)
    own = family_of(task).stages(task)
    return own if own is not None else kind_stages(task)


def stage_names(task: str | TaskSpec) -> tuple[str, ...]:
    """The stage names of ``task`` in order, ``none`` first and ``succeeded`` last."""
    return stages_of(task).names


def tracked_before(task: str | TaskSpec) -> tuple[str, ...]:
    """The stages of ``task`` an evaluation that did not record its ``stage_names`` tracked: all but those added
    later (a stage that refines another)."""
    later = stages_of(task).refined
    return tuple(name for name in stage_names(task) if name not in later)


def as_tracked(task: str | TaskSpec, stages: list[str], tracked: tuple[str, ...]) -> list[str]:
    """Episodes' stages as an evaluation that tracked only ``tracked`` would have recorded them: a later stage
    it did not track counts as the stage it refines (to pool episodes recorded with and without it)."""
    refined = {name: old for name, old in stages_of(task).refined.items() if name not in tracked}
    return [refined.get(stage, stage) for stage in stages]
