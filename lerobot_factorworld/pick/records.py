"""What each evaluated pick episode asked for, and success broken down by it.

An evaluation's episode ``i`` is reset with seed ``start_seed + i`` in its condition's environments, and
a pick episode's target and phrasing are drawn from that seed (:meth:`.layout.PickLayout.for_episode`),
so resetting a physics-only env with the same configurations and seeds recovers every episode's record
exactly, without touching LeRobot's evaluation loop. The study runner stores these records with each
evaluation (``pick`` in its result) and reports success per named object, shape and phrasing.
"""

from __future__ import annotations

import csv
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .catalog import get_object

BREAKDOWN_FILE = "pick_breakdowns.csv"
BREAKDOWN_COLUMNS = ("method", "task", "n_train_envs", "seed", "condition", "by", "value", "episodes", "successes")
BY = ("target", "shape", "template", "instruction")
MARKDOWN_BY = ("target", "shape", "template")  # instructions are many: in the CSV only


def episode_records(configs: Sequence[Any], seeds: Sequence[int], object_pos_width: str | None = None) -> list[dict]:
    """The pick record (instruction, target, template, objects) of the episode reset with each seed;
    ``[]`` when the configurations are not pick configurations."""
    from ..envs.factor_env import FactorWorldEnv

    if not configs or configs[0].pick is None:
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


def study_breakdowns(plan: Any, study_dir: str | Path) -> list[dict]:
    """One row per (finished pick evaluation, breakdown, value) of a study."""
    from ..study.steps import is_done, read_result

    rows = []
    for step in plan.of_kind("eval"):
        if not is_done(step, study_dir):
            continue
        result = read_result(step, study_dir)
        if not result.get("pick"):
            continue
        meta = step.meta
        for by in BY:
            for value, outcomes in breakdown(result["successes"], result["pick"], by).items():
                rows.append(
                    {
                        "method": meta["method"],
                        "task": meta["task"],
                        "n_train_envs": meta["n_train_envs"],
                        "seed": meta["seed"],
                        "condition": meta["condition"],
                        "by": by,
                        "value": value,
                        "episodes": len(outcomes),
                        "successes": sum(outcomes),
                    }
                )
    return rows


def write_study_breakdowns(plan: Any, study_dir: str | Path) -> list[str]:
    """Write ``pick_breakdowns.csv`` next to the study's results and return report.md lines (none when the
    study has no pick evaluation)."""
    rows = study_breakdowns(plan, study_dir)
    path = Path(study_dir) / BREAKDOWN_FILE
    if not rows:
        path.unlink(missing_ok=True)
        return []
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=BREAKDOWN_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "## Pick: success per named object, shape and phrasing",
        "",
        f"Summed over N and seeds, per method; per instruction in `{BREAKDOWN_FILE}`.",
        "",
    ]
    conditions = list(dict.fromkeys(r["condition"] for r in rows))
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        for by in MARKDOWN_BY:
            values = sorted({r["value"] for r in mine if r["by"] == by})
            lines += [f"| {method}: {by} | " + " | ".join(conditions) + " |", "|---" * (len(conditions) + 1) + "|"]
            for value in values:
                cells = []
                for condition in conditions:
                    hits = [r for r in mine if r["by"] == by and r["value"] == value and r["condition"] == condition]
                    k, n = sum(r["successes"] for r in hits), sum(r["episodes"] for r in hits)
                    cells.append(f"{k}/{n}" if n else "")
                lines.append(f"| {value} | " + " | ".join(cells) + " |")
            lines.append("")
    return lines
