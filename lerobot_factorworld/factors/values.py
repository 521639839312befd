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

from ..tasks import get_task
from .registry import SPLITS, SceneObject, check_factor_names, check_task_support, validate_value

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
        pick: For the ``pick`` family: the objects, their poses, and which one each episode names
            (:class:`lerobot_factorworld.pick.layout.PickLayout`; ``None`` there gives the default
            scene); the instruction then comes from it, never from ``instruction``. ``None`` elsewhere.
    """

    task: str
    factors: FactorValues = field(default_factory=FactorValues)
    instruction: str | None = None
    split: str = "train"
    env_id: str = ""
    pick: Any = None

    def __post_init__(self) -> None:
        task = get_task(self.task)
        object.__setattr__(self, "task", task.name)
        if self.split not in SPLITS:
            raise ValueError(f"unknown split {self.split!r}; valid splits: {', '.join(SPLITS)}")
        if isinstance(self.factors, dict):
            object.__setattr__(self, "factors", FactorValues.from_dict(self.factors))
        check_task_support(task, self.factors.non_default())
        self._check_pick(task.family == "pick")

    def _check_pick(self, is_pick: bool) -> None:
        if not is_pick:
            if self.pick is not None:
                raise ValueError(f"task {self.task!r} takes no pick layout (only the pick family does)")
            return
        from ..pick.layout import PickLayout, default_layout

        if isinstance(self.pick, dict):
            object.__setattr__(self, "pick", PickLayout.from_dict(self.pick))
        elif self.pick is None:
            object.__setattr__(self, "pick", default_layout())
        if not isinstance(self.pick, PickLayout):
            raise ValueError(f"pick must be a PickLayout or a dict, got {type(self.pick).__name__}")
        if self.instruction is not None:
            raise ValueError(
                "a pick configuration's instruction comes from its layout (target and phrasing template); "
                "leave instruction unset"
            )

    @property
    def task_description(self) -> str:
        if self.pick is not None and self.pick.instruction:
            return self.pick.instruction
        return self.instruction or get_task(self.task).instruction

    def for_episode(self, rng: Any) -> SceneConfig:
        """The configuration of one episode: a pick layout's target and phrasing drawn from ``rng`` where
        not pinned (every other configuration is returned unchanged and draws nothing)."""
        return self if self.pick is None else replace(self, pick=self.pick.for_episode(rng))

    def episode_record(self, object_offset: Any) -> dict[str, Any]:
        """What an episode of this (episode) configuration records besides its factors: a pick episode's
        instruction, target and objects (``{"pick": ...}``); nothing for other tasks."""
        if self.pick is None:
            return {}
        from ..pick.layout import episode_record

        return {"pick": episode_record(self.pick, object_offset)}

    def with_factors(self, **values: Any) -> SceneConfig:
        return replace(self, factors=self.factors.set(**values))

    def to_dict(self) -> dict[str, Any]:
        return {
            "task": self.task,
            "factors": self.factors.to_dict(),
            "instruction": self.instruction,
            "split": self.split,
            "env_id": self.env_id,
            **({"pick": self.pick.to_dict()} if self.pick is not None else {}),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SceneConfig:
        unknown = set(data) - {f.name for f in fields(cls)}
        if unknown:
            raise ValueError(f"unknown SceneConfig keys {sorted(unknown)}; valid keys: {[f.name for f in fields(cls)]}")
        values = dict(data)
        values["factors"] = FactorValues.from_dict(values.get("factors") or {})
        return cls(**values)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    def __str__(self) -> str:
        lines = [f"SceneConfig {self.env_id or '(unnamed)'}: task={self.task} split={self.split}"]
        for name, value in self.factors.non_default().items():
            lines.append(f"  {name:15s} {_format(value)}")
        if self.pick is not None:
            lines.append(f"  {'pick objects':15s} {', '.join(self.pick.names)}")
            lines.append(
                f"  {'pick target':15s} {self.pick.target or 'per episode: ' + ', '.join(self.pick.candidates)}"
            )
        if len(lines) == 1:
            lines.append("  (default scene)")
        return "\n".join(lines)


def save_configs(configs: list[SceneConfig] | tuple[SceneConfig, ...], path: str | Path) -> Path:
    """Write configurations as a JSON list (atomically: a crash never leaves half a file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps([c.to_dict() for c in configs], indent=1, sort_keys=True))
    tmp.replace(path)
    return path


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
