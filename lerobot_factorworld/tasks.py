"""The Factor World task list: one frozen row per task, the single source of truth for task facts.

Every row names the Meta-World v3 environment and scripted expert it wraps, the natural-language
instruction, and what the task's *object* is, so that object factors (texture, size, shape, position)
act on every task and not only on pick-place.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from .core.checks import split_list


@dataclass(frozen=True)
class TaskSpec:
    """Static facts about one Factor World task.

    Attributes:
        name: Factor World task name (Meta-World name without the ``-v3`` suffix).
        instruction: Natural-language instruction given to language-conditioned policies.
        object_bodies: Root bodies of the manipulated object; their whole subtree is "the object"
            (its visual geoms take the object texture).
        object_is_free: Whether the object is a loose rigid body (free joint). Only loose objects can
            be resized or reshaped without changing the task's mechanics.
        max_episode_steps: Horizon used for evaluation and collection (Meta-World's own cap is 500).
        demo_steps: Typical length of a scripted demo (measured; the study's dry-run cost model uses it).
        nominal_object_xy: The object's nominal start (x, y) when it is not the centre of Meta-World's
            random reset range: pick-place and basketball need the object at least 0.15 m from the goal.
        reshapeable: Whether the object-shape factor applies: the task's scripted expert still solves
            it with other object shapes (measured; basketball's and bin-picking's experts do not).
        limits: Per-factor boxes ``(factor, (low, high))`` where this task stays solvable by its
            scripted expert (bin walls, reach, the hoop's size); the factor's ranges are intersected
            with them and explicit values outside them are rejected.
        object_family: The shape family (:func:`lerobot_factorworld.assets.asset_family`) the loose
            object looks like: no distractor is drawn from it, and the family split keeps it in train
            (the default scene shows it). Empty for fixtures: their look-alikes are the families of the
            Meta-World meshes their scene shows (the faucet's head and base, the drawer, the door handle),
            read from the scene by :func:`lerobot_factorworld.assets.scenes.scene_shape_families`.
        goal: A fixed goal position (world frame, which is the table's) replacing the one Meta-World
            samples; ``None`` keeps Meta-World's goal at the centre of its range.
        success_radius: Object-to-goal distance (metres) that counts as success, replacing Meta-World's
            threshold; only for tasks whose success test is ``obj_to_target <= radius``.
        family: The task family's name (``pick``: several named objects, one instruction per episode);
            empty for a plain Meta-World task.
        family_entry_point: Where the family's :class:`~lerobot_factorworld.families.TaskFamily` object
            lives (``"module:attr"``, loaded by :func:`lerobot_factorworld.families.family_of`); empty for
            a plain Meta-World task.
        metaworld_base: The Meta-World task whose scene and env class the family builds on (empty: the
            task's own name).
        unsupported: ``(factor, reason)`` pairs: factors that do not apply to this task, and why.
    """

    name: str
    instruction: str
    object_bodies: tuple[str, ...]
    object_is_free: bool = False
    max_episode_steps: int = 500
    demo_steps: int = 100
    nominal_object_xy: tuple[float, float] | None = None
    reshapeable: bool = False
    limits: tuple[tuple[str, tuple[tuple[float, ...], tuple[float, ...]]], ...] = ()
    object_family: str = ""
    goal: tuple[float, float, float] | None = None
    success_radius: float | None = None
    family: str = ""
    family_entry_point: str = ""
    metaworld_base: str = ""
    unsupported: tuple[tuple[str, str], ...] = ()

    def limit(self, factor: str) -> tuple[tuple[float, ...], tuple[float, ...]] | None:
        return dict(self.limits).get(factor)

    @property
    def metaworld_name(self) -> str:
        return f"{self.metaworld_base or self.name}-v3"

    @property
    def gym_id(self) -> str:
        return f"FactorWorld/{self.name}-v0"


_ROWS = (
    TaskSpec(
        "pick-place",
        "pick up the puck and place it at the blue goal",
        ("obj",),
        True,
        nominal_object_xy=(0.0, 0.6),
        reshapeable=True,
        object_family="cylinder",  # the puck
        # The public Factor World's pick-place: the goal lies on the table in front of the puck (where a
        # goal-blind scripted policy ends up) and success is within 3 cm; Meta-World's goal floats in the
        # air at y 0.8..0.9 with a 7 cm radius.
        goal=(-0.005, 0.40, 0.02),
        success_radius=0.03,
        demo_steps=50,
    ),
    TaskSpec(
        "basketball",
        "dunk the basketball into the hoop",
        ("bsktball",),
        True,
        nominal_object_xy=(0.0, 0.6),
        limits=(("object_size", ((0.7,), (1.1,))),),
        object_family="ellipsoid",  # a ball
    ),
    TaskSpec(
        "bin-picking",
        "move the block from the red bin into the blue bin",
        ("obj",),
        True,
        limits=(("object_pos", ((-0.05, -0.04), (0.05, 0.04))), ("object_size", ((0.8,), (1.3,)))),
        demo_steps=120,
        object_family="box",  # a cube
    ),
    TaskSpec("button-press", "press the button from the front", ("box",)),
    TaskSpec("button-press-topdown", "press the button from the top", ("box",)),
    TaskSpec("button-press-topdown-wall", "reach over the wall and press the button from the top", ("box",)),
    TaskSpec(
        "button-press-wall",
        "reach around the wall and press the button",
        ("box",),
        limits=(("object_pos", ((-0.05, -0.025), (0.05, 0.075))),),
    ),
    TaskSpec("door-lock", "lock the door by turning the lock", ("door",)),
    TaskSpec(
        "door-open", "open the door", ("door",), limits=(("object_pos", ((-0.05, -0.03), (0.1, 0.075))),), demo_steps=85
    ),
    TaskSpec("door-unlock", "unlock the door by turning the lock", ("door",)),
    TaskSpec(
        "drawer-close", "push the drawer closed", ("drawer",), limits=(("object_pos", ((-0.1, -0.075), (0.1, 0.02))),)
    ),
    TaskSpec("drawer-open", "pull the drawer open", ("drawer",)),
    TaskSpec("faucet-close", "turn the faucet handle to close it", ("faucetBase",)),
    TaskSpec("faucet-open", "turn the faucet handle to open it", ("faucetBase",)),
    TaskSpec("handle-press", "press the handle down", ("box",), demo_steps=30),
    TaskSpec("handle-pull", "pull the handle up", ("box",)),
    TaskSpec("handle-pull-side", "pull the side handle up", ("box",)),
    TaskSpec("lever-pull", "pull the lever", ("lever",), limits=(("object_pos", ((-0.1, -0.06), (0.1, 0.075))),)),
    TaskSpec("window-close", "slide the window closed", ("window",)),
    TaskSpec("window-open", "slide the window open", ("window",)),
    # Language-conditioned picking among several objects (the paper's real-robot task), on pick-place's
    # table: the family plug-in lerobot_factorworld/pick/ (its catalog reads this row's facts).
    TaskSpec(
        "pick",
        "pick up the named object",  # shown by `factorworld tasks`; every episode gets its own instruction
        (),
        True,
        # The scripted expert needs about 80 steps (docs/pick.md's expert table: 80-86 on average).
        max_episode_steps=200,
        demo_steps=85,
        family="pick",
        family_entry_point="lerobot_factorworld.pick.family:PICK_FAMILY",
        metaworld_base="pick-place",
        unsupported=tuple(
            (
                factor,
                "pick objects are told apart by shape family and colour, which the instruction names; "
                "resizing or reshaping them would change what the instruction refers to",
            )
            for factor in ("object_size", "object_shape")
        ),
    ),
)

TASKS: dict[str, TaskSpec] = {row.name: row for row in _ROWS}
"""All tasks by name, in the order of the public Factor World README."""


def get_task(name: str) -> TaskSpec:
    """Look a task up by name; accepts the Meta-World ``-v3`` spelling too."""
    key = name.removesuffix("-v3")
    if key not in TASKS:
        raise ValueError(f"unknown task {name!r}; valid tasks: {', '.join(TASKS)}")
    return TASKS[key]


def step_limit(task: str, limit: int | None = None) -> int:
    """An episode's step limit: ``limit`` when set, else the task's horizon (``max_episode_steps``)."""
    return limit or get_task(task).max_episode_steps


def check_tasks(task: str | Sequence[str] | None) -> list[str]:
    """Task names (comma-separated) -> canonical names; at least one, each once."""
    names = [get_task(name).name for name in split_list(task)]
    if not names:
        raise ValueError(f"no task given; valid tasks: {', '.join(TASKS)}")
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"task(s) {', '.join(duplicates)} given more than once")
    return names
