"""Task families: what a group of tasks adds to a plain Meta-World task, as one plug-in object.

A task row (:data:`lerobot_factorworld.tasks.TASKS`) names its family (``TaskSpec.family``; ``""`` for a
plain Meta-World task) and, for a plug-in family, where its :class:`TaskFamily` object lives
(``TaskSpec.family_entry_point``, gymnasium-style ``"module:attr"``). Every layer below the family
packages asks :func:`family_of` instead of testing family names, so a new family (or a change to one)
touches its own package and its task rows only.

The base class is the plain Meta-World behaviour: no scene content, nothing extra to sample, no extra
evaluation condition, the compiled scene and expert of the Meta-World task, the measured keep-out.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from functools import cache
from typing import Any, ClassVar

from .tasks import TASKS, TaskSpec, get_task


class TaskFamily:
    """The hooks a task family implements; every default is the plain Meta-World task's behaviour.

    Attributes:
        name: The family's name (``TaskSpec.family``); ``""`` for plain Meta-World tasks.
        content_key: The key a configuration's content is saved under (in saved configurations, env
            ``info`` and study step results); ``""``: the family has no content.
        sampling_options: The ``SamplingOptions`` fields only this family reads.
        keyed_when_set: Those of :attr:`sampling_options` a collection's key holds only when set (options added
            after collections were keyed without them: their keys stay as they were).
        conditions: Evaluation conditions the family adds to the factor shifts.
        episode_measures: Keys of the env's ``info`` whose values at an episode's last step an evaluation records
            for every episode (``measures`` in its result), beside its stage.
        report_entry_point: Where the family's part of a study report lives (``"module:attr"``, a
            ``study.report.family_report.FamilyReport`` above the study); ``""``: the family adds nothing to reports.
    """

    name: ClassVar[str] = ""
    content_key: ClassVar[str] = ""
    sampling_options: ClassVar[tuple[str, ...]] = ()
    keyed_when_set: ClassVar[tuple[str, ...]] = ()
    conditions: ClassVar[tuple[str, ...]] = ()
    episode_measures: ClassVar[tuple[str, ...]] = ()
    report_entry_point: ClassVar[str] = ""

    # --- content: what a configuration of this family holds besides its factors ----------------------

    def content_from_dict(self, data: dict[str, Any]) -> Any:
        raise ValueError(f"tasks of family {self.name!r} take no content, got {sorted(data)}")

    def default_content(self, task: TaskSpec) -> Any:
        """The content of a configuration that gives none (``None``: the family has no content)."""
        return None

    def check_config(self, config: Any) -> Any:
        """The configuration's content, checked and normalised (a dict is parsed, ``None`` defaulted)."""
        content = config.content
        if content is not None:
            kind = getattr(content, "kind", "content")
            owner = getattr(content, "family", "")
            raise ValueError(f"task {config.task!r} takes no {kind} (only the {owner or 'its'} family does)")
        return None

    def instruction(self, config: Any) -> str | None:
        """The configuration's instruction when its content fixes one (``None``: the usual instruction)."""
        return None

    def for_episode(self, content: Any, rng: Any) -> Any:
        """The content of one episode (choices drawn from ``rng``); the plain task draws nothing."""
        return content

    def episode_record(self, content: Any, object_offset: Any) -> dict[str, Any]:
        """What an episode records about its content, stored under :attr:`content_key` (JSON-able)."""
        return {}

    def describe(self, content: Any) -> list[tuple[str, str]]:
        """``(label, text)`` pairs that ``str(SceneConfig)`` shows for the content."""
        return []

    # --- sampling --------------------------------------------------------------------------------------

    def check_sampling(self, options: Any) -> None:
        """Refuse sampling options this family cannot use (only the fields in :attr:`sampling_options`)."""

    def sample_contents(self, task: TaskSpec, n: int, seed: int, split: str, options: Any) -> list[Any]:
        """The content of ``n`` sampled environments (their own seeded stream, apart from the factors')."""
        return [None] * n

    def lookalike_families(self, task: TaskSpec) -> tuple[str, ...]:
        """Asset shape families no distractor is drawn from, besides the scene's own (the family's objects)."""
        return ()

    # --- evaluation conditions -------------------------------------------------------------------------

    def check_condition(self, condition: str, tasks: Sequence[str]) -> None:
        """Refuse a condition of this family for ``tasks`` that are not of it."""
        others = [t for t in tasks if condition not in family_of(t).conditions]
        if others:
            raise ValueError(
                f"condition {condition!r} applies to the {self.name} family only, not to {', '.join(others)}"
            )

    def condition_configs(self, base: Sequence[Any], condition: str, n: int, seed: int) -> list[Any]:
        """The ``n`` test environments of one of :attr:`conditions`, derived from training environments ``base``."""
        raise ValueError(f"unknown condition {condition!r}; valid: {', '.join(self.conditions) or 'none'}")

    # --- scene and simulation ----------------------------------------------------------------------------

    def make_scene(
        self, task: TaskSpec, factors: Any, cameras: Any, quality: str, image_size: Any, content: Any
    ) -> Any:
        """The family's compiled scene (a ``CompiledScene``); ``None``: the plain compiled Meta-World scene."""
        return None

    def scene_key(self, content: Any) -> Any:
        """What of the content the compiled model depends on (scenes are cached by it with the factors)."""
        return None

    def expert(self, task: TaskSpec) -> Any:
        """The family's scripted expert; ``None``: Meta-World's scripted policy of the task."""
        return None

    def keepout(self, task: TaskSpec, clearance: float) -> Any:
        """Table-frame boxes distractors must avoid; ``None``: measured by sweeping the expert."""
        return None

    def stages(self, task: TaskSpec) -> Any:
        """The ordered stages an episode can fail at (``envs.stages.Stages``); ``None``: those of the task's
        kind (object or articulated, ``envs/stages.py``)."""
        return None

    # --- records -----------------------------------------------------------------------------------------

    def episode_records(
        self, configs: Sequence[Any], seeds: Sequence[int], object_pos_width: str | None = None
    ) -> list[dict]:
        """What each evaluated episode (reset with ``seeds``) asked for; ``[]`` for a plain task."""
        return []


PLAIN = TaskFamily()
"""The plain Meta-World family (every task row without ``family_entry_point``)."""


def family_of(task: str | TaskSpec) -> TaskFamily:
    """The family object of a task (a task row or its name)."""
    task = task if isinstance(task, TaskSpec) else get_task(task)
    return _load(task.family_entry_point) if task.family_entry_point else PLAIN


def all_families() -> tuple[TaskFamily, ...]:
    """Every family a task row names (the plain one first), each once."""
    out = [PLAIN]
    for row in TASKS.values():
        family = family_of(row)
        if family not in out:
            out.append(family)
    return tuple(out)


def condition_family(condition: str) -> TaskFamily | None:
    """The family that declares ``condition`` (``None``: not a family condition, e.g. a factor shift)."""
    for family in all_families():
        if condition in family.conditions:
            return family
    return None


@cache
def _load(entry_point: str) -> TaskFamily:
    # The one deliberate dynamic import: family packages sit above every layer that asks for a family, so
    # the rows name them by entry point and nothing below imports them statically (no upward arrow, no cycle).
    module, _, attr = entry_point.partition(":")
    family = getattr(importlib.import_module(module), attr)
    if not isinstance(family, TaskFamily):
        raise TypeError(f"family entry point {entry_point!r} is a {type(family).__name__}, not a TaskFamily")
    return family
