"""Value types: what one environment configuration holds, as plain frozen data (no MuJoCo).

A :class:`SceneConfig` is a value: it can be compared, hashed, printed, saved to JSON and loaded
back. ``None`` for a factor means "the task's default scene" (for ``object_pos``: re-randomised every
episode from the reset seed, as in the paper).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields, is_dataclass, replace
from pathlib import Path
from typing import Any

from ..core.io import atomic_write_json
from ..core.splits import check_split
from ..families import family_of
from ..tasks import get_task
from .registry import SceneObject, check_factor_names, check_task_support, validate_value

__all__ = [
    "FactorValues",
    "SceneConfig",
    "SceneObject",
    "load_configs",
    "save_configs",
    "to_jsonable",
]

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class FactorValues:
    """One value per factor of variation; ``None`` keeps the task's default scene."""

    object_pos: Vec2 | None = None
    arm_pos: Vec3 | None = None
    camera_pos: tuple[float, ...] | None = None
    table_pos: Vec3 | None = None
    object_size: float | None = None
    object_shape: str | None = None
    object_texture: str | None = None
    table_texture: str | None = None
    floor_texture: str | None = None
    light: Vec2 | None = None
    distractors: tuple[SceneObject, ...] | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            object.__setattr__(self, f.name, validate_value(f.name, value))

    def set(self, **values: Any) -> FactorValues:
        """A copy with some factors replaced (validated like the constructor)."""
        check_factor_names(values)
        return replace(self, **values)

    def non_default(self) -> dict[str, Any]:
        """The factors that differ from the default scene."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}

    def to_dict(self) -> dict[str, Any]:
        return {name: to_jsonable(value) for name, value in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FactorValues:
        check_factor_names(data)
        values = dict(data)
        if values.get("distractors") is not None:
            values["distractors"] = tuple(
                item if isinstance(item, SceneObject) else SceneObject(**item) for item in values["distractors"]
            )
        return cls(**values)


@dataclass(frozen=True)
class SceneConfig:
    """One Factor World environment: a task plus one value per factor.

    Attributes:
        task: Task name (see :data:`lerobot_factorworld.tasks.TASKS`).
        factors: The factor values.
        instruction: Language instruction; ``None`` uses the task's own.
        split: Asset split the values were drawn from (``train`` or ``eval``); metadata only.
        env_id: Identifier of this environment within a study, e.g. ``pick-place/train/003``.
        content: What the task's family adds to the scene (:mod:`lerobot_factorworld.families`), saved under
            the family's ``content_key`` (the ``pick`` family: the objects, their poses and which one each
            episode names; ``None`` there gives the family's default). ``None`` for a plain Meta-World task.
    """

    task: str
    factors: FactorValues = field(default_factory=FactorValues)
    instruction: str | None = None
    split: str = "train"
    env_id: str = ""
    content: Any = None

    def __post_init__(self) -> None:
        task = get_task(self.task)
        object.__setattr__(self, "task", task.name)
        check_split(self.split)
        if isinstance(self.factors, dict):
            object.__setattr__(self, "factors", FactorValues.from_dict(self.factors))
        check_task_support(task, self.factors.non_default())
        object.__setattr__(self, "content", family_of(task).check_config(self))

    @property
    def task_description(self) -> str:
        return family_of(self.task).instruction(self) or self.instruction or get_task(self.task).instruction

    def for_episode(self, rng: Any) -> SceneConfig:
        """The configuration of one episode: the family's per-episode choices (a pick layout's target and
        phrasing) drawn from ``rng`` where not pinned (a plain task's configuration is returned unchanged
        and draws nothing)."""
        if self.content is None:
            return self
        return replace(self, content=family_of(self.task).for_episode(self.content, rng))

    def episode_record(self, object_offset: Any) -> dict[str, Any]:
        """What an episode of this (episode) configuration records besides its factors, under the family's
        content key (a pick episode's instruction, target and objects: ``{"pick": ...}``); nothing for
        other tasks."""
        family = family_of(self.task)
        if self.content is None or not family.content_key:
            return {}
        return {family.content_key: family.episode_record(self.content, object_offset)}

    def with_factors(self, **values: Any) -> SceneConfig:
        return replace(self, factors=self.factors.set(**values))

    def to_dict(self) -> dict[str, Any]:
        key = family_of(self.task).content_key
        return {
            "task": self.task,
            "factors": self.factors.to_dict(),
            "instruction": self.instruction,
            "split": self.split,
            "env_id": self.env_id,
            **({key: self.content.to_dict()} if self.content is not None else {}),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SceneConfig:
        values = dict(data)
        key = family_of(values["task"]).content_key if "task" in values else ""
        valid = [f.name for f in fields(cls) if f.name != "content"] + ([key] if key else [])
        unknown = set(values) - set(valid)
        if unknown:
            raise ValueError(f"unknown SceneConfig keys {sorted(unknown)}; valid keys: {valid}")
        if key and key in values:
            values["content"] = values.pop(key)
        values["factors"] = FactorValues.from_dict(values.get("factors") or {})
        return cls(**values)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    def __str__(self) -> str:
        lines = [f"SceneConfig {self.env_id or '(unnamed)'}: task={self.task} split={self.split}"]
        for name, value in self.factors.non_default().items():
            lines.append(f"  {name:15s} {_format(value)}")
        if self.content is not None:
            lines.extend(f"  {label:15s} {text}" for label, text in family_of(self.task).describe(self.content))
        if len(lines) == 1:
            lines.append("  (default scene)")
        return "\n".join(lines)


def save_configs(configs: list[SceneConfig] | tuple[SceneConfig, ...], path: str | Path) -> Path:
    """Write configurations as a JSON list (atomically: a crash never leaves half a file)."""
    return atomic_write_json(path, [c.to_dict() for c in configs], indent=1, sort_keys=True)


def load_configs(path: str | Path) -> list[SceneConfig]:
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no configuration file at {path}")
    data = json.loads(path.read_text())
    if isinstance(data, dict):
        data = [data]
    return [SceneConfig.from_dict(item) for item in data]


def to_jsonable(value: Any) -> Any:
    """Tuples -> lists and dataclasses (``SceneObject``) -> dicts, recursively."""
    if is_dataclass(value):
        value = asdict(value)
    if isinstance(value, (tuple, list)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {k: to_jsonable(v) for k, v in value.items()}
    return value


def _format(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, SceneObject):
        return f"{value.shape}@({value.x:+.3f},{value.y:+.3f}) size={value.size:.3f} tex={value.texture}"
    if isinstance(value, tuple) and value and isinstance(value[0], SceneObject):
        return "; ".join(_format(v) for v in value)
    if isinstance(value, tuple):
        return "(" + ", ".join(_format(v) for v in value) + ")"
    return str(value)
