"""The ``pick`` family as a plug-in: :data:`PICK_FAMILY`, named by the pick task row's ``family_entry_point``.

Every hook delegates to the module that owns the fact: layouts (:mod:`.layout`), their sampling and the
language conditions (:mod:`.sampling`), the scene (:mod:`.episode`), the expert (:mod:`.expert`) and the
per-episode records (:mod:`.records`); its report part is ``family_reports/pick.py``, above the study.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..envs.stages import NONE, REACHED, SUCCEEDED, Stage, Stages, kind_stages
from ..families import TaskFamily
from ..tasks import TaskSpec
from .catalog import DEFAULT_OBJECTS, LOOKALIKE_FAMILIES, MAX_OBJECTS, MIN_OBJECTS
from .episode import PickScene
from .expert import PickExpert
from .layout import PickLayout, default_layout, episode_record, workspace_keepout
from .records import episode_records
from .sampling import CONDITIONS, check_condition, check_fixed_template, language_shift, sample_layouts


def lifted_another(info: dict[str, Any], first: dict[str, Any]) -> bool:
    return bool(info["wrong_object"])


def reached_another(info: dict[str, Any], first: dict[str, Any]) -> bool:
    return float(info["near_other"]) >= 1.0


REACHED_OTHER = Stage("reached_other", reached_another, refines=NONE)
"""The gripper reached another object than the named one (within ``catalog.REACH_RADIUS`` of its centre) and
never the named one: a wrong choice that lifted nothing. It splits ``none`` (added after pick evaluations were
recorded without it: those count it as ``none``)."""
WRONG_OBJECT = Stage("wrong_object", lifted_another)
"""Another object than the named one was lifted first (``bridge.py``): the episode can no longer succeed. It
ranks above every progress stage, being the episode's cause of failure, and below success, which it rules out."""


class PickFamily(TaskFamily):
    """Language-conditioned picking among several named objects (docs/pick.md)."""

    name = "pick"
    content_key = "pick"
    sampling_options = ("n_objects", "template")
    keyed_when_set = ("template",)
    conditions = CONDITIONS
    episode_measures = ("closest_named", "closest_other")  # how close the gripper came, to tell choice from reach
    report_entry_point = "lerobot_factorworld.family_reports.pick:PICK_REPORT"
    n_objects = (MIN_OBJECTS, DEFAULT_OBJECTS, MAX_OBJECTS)
    """Objects per pick scene: fewest, default, most (``--sampling.n_objects``)."""

    def content_from_dict(self, data: dict[str, Any]) -> PickLayout:
        return PickLayout.from_dict(data)

    def default_content(self, task: TaskSpec) -> PickLayout:
        return default_layout()

    def check_config(self, config: Any) -> PickLayout:
        content = config.content
        if isinstance(content, dict):
            content = PickLayout.from_dict(content)
        elif content is None:
            content = default_layout()
        if not isinstance(content, PickLayout):
            raise ValueError(f"pick must be a PickLayout or a dict, got {type(content).__name__}")
        if config.instruction is not None:
            raise ValueError(
                "a pick configuration's instruction comes from its layout (target and phrasing template); "
                "leave instruction unset"
            )
        return content

    def instruction(self, config: Any) -> str | None:
        return config.content.instruction if config.content is not None else None

    def for_episode(self, content: PickLayout, rng: np.random.Generator) -> PickLayout:
        return content.for_episode(rng)

    def episode_record(self, content: PickLayout, object_offset: Any) -> dict[str, Any]:
        return episode_record(content, object_offset)

    def describe(self, content: PickLayout) -> list[tuple[str, str]]:
        return [
            ("pick objects", ", ".join(content.names)),
            ("pick target", content.target or "per episode: " + ", ".join(content.candidates)),
        ]

    def check_sampling(self, options: Any) -> None:
        low, _, high = self.n_objects
        if not low <= options.n_objects <= high:
            raise ValueError(f"n_objects must be in [{low}, {high}], got {options.n_objects}")
        check_fixed_template(options.template)

    def sample_contents(self, task: TaskSpec, n: int, seed: int, split: str, options: Any) -> list[PickLayout]:
        # The objects on the table and what episodes name: their own seeded stream.
        return sample_layouts(n, seed, split, options.n_objects, options.template)

    def lookalike_families(self, task: TaskSpec) -> tuple[str, ...]:
        return LOOKALIKE_FAMILIES

    def check_condition(self, condition: str, tasks: Sequence[str]) -> None:
        check_condition(condition, tasks)

    def condition_configs(self, base: Sequence[Any], condition: str, n: int, seed: int) -> list[Any]:
        return language_shift(base, condition, n, seed)

    def make_scene(
        self, task: TaskSpec, factors: Any, cameras: Any, quality: str, image_size: Any, content: PickLayout
    ) -> PickScene:
        return PickScene(task, factors, cameras, quality, image_size, content)

    def scene_key(self, content: PickLayout) -> Any:
        return content.objects  # the compiled model holds the objects at their poses; targets vary per episode

    def expert(self, task: TaskSpec) -> PickExpert:
        return PickExpert()

    def keepout(self, task: TaskSpec, clearance: float) -> np.ndarray:
        # Objects change per environment: keep the whole pick workspace free.
        return np.array([workspace_keepout(clearance)], dtype=np.float64)

    def stages(self, task: TaskSpec) -> Stages:
        return kind_stages(task).inserted(REACHED_OTHER, before=REACHED).inserted(WRONG_OBJECT, before=SUCCEEDED)

    def episode_records(
        self, configs: Sequence[Any], seeds: Sequence[int], object_pos_width: str | None = None
    ) -> list[dict]:
        return episode_records(configs, seeds, object_pos_width)


PICK_FAMILY = PickFamily()
"""The pick family's plug-in object (``family_entry_point="lerobot_factorworld.pick.family:PICK_FAMILY"``)."""
