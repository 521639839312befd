"""What each evaluated pick episode asked for, and success broken down by it.

An evaluation's episode ``i`` is reset with seed ``start_seed + i`` in its condition's environments, and
a pick episode's target and phrasing are drawn from that seed (:meth:`.layout.PickLayout.for_episode`),
so resetting a physics-only env with the same configurations and seeds recovers every episode's record
exactly, without touching LeRobot's evaluation loop. The study runner stores these records with each
evaluation (``pick`` in its result); :mod:`.report` breaks success down by them (per named object, shape
and phrasing).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from typing import Any

from ..envs.factor_env import FactorWorldEnv
from .catalog import get_object

BY = ("target", "shape", "template", "instruction")


def episode_records(configs: Sequence[Any], seeds: Sequence[int], object_pos_width: str | None = None) -> list[dict]:
    """The pick record (instruction, target, template, objects) of the episode reset with each seed;
    ``[]`` when the configurations are not pick configurations."""
    if not configs or configs[0].content is None:
        return []
    env = FactorWorldEnv(
        configs[0].task, tuple(configs), cameras=(), scene_cache_size=len(configs), object_pos_width=object_pos_width
    )
    try:
        return [env.reset(seed=int(seed))[1]["pick"] for seed in seeds]
    finally:
        env.close()


def breakdown(successes: Sequence[bool], records: Sequence[dict], by: str) -> dict[str, list[bool]]:
    """Outcomes grouped by the named object (``target``), its shape family (``shape``), the phrasing
    template (``template``) or the instruction string itself (``instruction``)."""
    if by not in BY:
        raise ValueError(f"unknown breakdown {by!r}; valid: {', '.join(BY)}")
    groups: dict[str, list[bool]] = defaultdict(list)
    for success, record in zip(successes, records, strict=True):
        key = get_object(record["target"]).shape if by == "shape" else record[by]
        groups[key].append(bool(success))
    return dict(sorted(groups.items()))


MEASURE_BY = ("closest", "named_within")
"""Breakdowns by what the gripper did (an evaluation's ``measures``): which object its centre came closest to, and
how close it came to the named one."""
WITHIN_CM = (3, 6, 10)  # bins of the closest approach to the named object; 3 cm is the ``reached`` radius


def measure_breakdown(successes: Sequence[bool], measures: Sequence[dict | None], by: str) -> dict[str, list[bool]]:
    """Outcomes grouped by the object the gripper's centre came closest to (``closest``: ``named object`` or
    ``another object``) or by how close it came to the named object (``named_within``: ``3 cm``, ``6 cm``,
    ``10 cm``, ``farther``); episodes recorded without measures are left out."""
    if by not in MEASURE_BY:
        raise ValueError(f"unknown breakdown {by!r}; valid: {', '.join(MEASURE_BY)}")
    groups: dict[str, list[bool]] = defaultdict(list)
    for success, measure in zip(successes, measures, strict=True):
        if not measure:
            continue
        named = measure["closest_named"]
        if by == "closest":
            key = "named object" if named <= measure["closest_other"] else "another object"
        else:
            key = next((f"{cm} cm" for cm in WITHIN_CM if named <= cm / 100), "farther")
        groups[key].append(bool(success))
    return dict(sorted(groups.items(), key=lambda item: _bin_order(item[0])))


def _bin_order(key: str) -> tuple[int, str]:
    """The named object before another; bins from the nearest to ``farther``."""
    if key in ("named object", "another object"):
        return (0 if key == "named object" else 1, key)
    return (int(key.split()[0]) if key[0].isdigit() else 10**6, key)
