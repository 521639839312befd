"""The pick family's part of a study report (its ``report_sections`` hook): success next to the paper's
real-robot table, and success per named object, shape and phrasing.

Every number comes from a CSV file next to ``report.md``: the real-robot table from the study's
``results.csv`` rows, the breakdowns from ``pick_breakdowns.csv``, which is written once from the
evaluations' episode records (:mod:`.records`) and read back to draw the tables.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..core.io import atomic_write_text
from ..protocol.conditions import TRAIN_SUITE
from ..study.aggregate import main_grid
from ..study.config import StudyConfig
from ..study.markdown import FAMILY_DETAILS, FAMILY_RESULTS
from ..study.metrics import spearman, wilson_interval
from ..study.paper import PAPER_REAL_ROBOT
from ..study.results import Evaluation, csv_text
from ..tasks import get_task
from .records import BY, breakdown

FAMILY = "pick"  # the family's name and the key of its episode records in an evaluation's result
BREAKDOWN_FILE = "pick_breakdowns.csv"
BREAKDOWN_COLUMNS = ("method", "task", "n_train_envs", "seed", "condition", "by", "value", "episodes", "successes")
MARKDOWN_BY = ("target", "shape", "template")  # instructions are many: in the CSV only


def report_sections(
    cfg: StudyConfig, rows: Sequence[dict], evaluations: Sequence[Evaluation], study_dir: str | Path, part: str
) -> list[str]:
    """The pick sections of ``report.md`` at ``part`` (the study's ``FAMILY_RESULTS`` or ``FAMILY_DETAILS``)."""
    if part == FAMILY_RESULTS:
        return real_robot_section(cfg, rows)
    if part == FAMILY_DETAILS:
        path = write_breakdowns(evaluations, study_dir)
        return breakdown_section(read_breakdowns(path)) if path else []
    raise ValueError(f"unknown report part {part!r}; valid: {FAMILY_RESULTS}, {FAMILY_DETAILS}")


# --- next to the paper's real-robot table ---------------------------------------------------------


def pooled_success(rows: Sequence[dict], method: str, condition: str) -> tuple[int, int]:
    """(successes, episodes) of ``method`` in ``condition`` over the pick family's rows of the main grid,
    pooled over tasks, N and seeds."""
    cell = [r for r in main_grid(rows) if _is_pick(r["task"]) and r["method"] == method and r["condition"] == condition]
    return sum(r["successes"] for r in cell), sum(r["episodes"] for r in cell)


def real_robot_section(cfg: StudyConfig, rows: Sequence[dict]) -> list[str]:
    """The pick family's rows next to the paper's real-robot table (success pooled over N and seeds)."""
    if not any(_is_pick(r["task"]) for r in main_grid(rows)):
        return []
    lines = [
        "## Pick next to the paper's real-robot table",
        "",
        "Success pooled over tasks of the pick family, N and seeds (Wilson 95% interval); the paper's numbers are "
        "RT-1 on a real robot, 12 trials per factor (section 5.1).",
        "",
        "| method | condition | paper (real robot) | successes | success rate [Wilson 95%] |",
        "|---|---|---|---|---|",
    ]
    for method in cfg.methods:
        rates = {}
        for condition in [TRAIN_SUITE, *cfg.conditions()]:
            k, n = pooled_success(rows, method.name, condition)
            if not n:
                continue
            low, high = wilson_interval(k, n)
            name, paper = PAPER_REAL_ROBOT.get(condition, (condition, None))
            rates[condition] = k / n
            lines.append(
                f"| {method.name} | {name} (`{condition}`) | {'—' if paper is None else f'{paper:.1f}%'} | {k}/{n} | "
                f"{k / n:.2f} [{low:.2f}, {high:.2f}] |"
            )
        shifted = [c for c in rates if c != TRAIN_SUITE and PAPER_REAL_ROBOT.get(c, ("", None))[1] is not None]
        rho = spearman({c: rates[c] for c in shifted}, {c: PAPER_REAL_ROBOT[c][1] for c in shifted})
        if not math.isnan(rho):
            lines += [
                "",
                f"{method.name}: Spearman correlation of the {len(shifted)} shifted conditions' success rates with the "
                f"paper's real-robot ones: **{rho:+.2f}** (easiest first here: "
                + ", ".join(sorted(shifted, key=lambda c: -rates[c]))
                + "; in the paper: "
                + ", ".join(sorted(shifted, key=lambda c: -PAPER_REAL_ROBOT[c][1]))
                + ").",
            ]
        lines.append("")
    return lines


def _is_pick(task: str) -> bool:
    return get_task(task).family == FAMILY


# --- per named object, shape and phrasing ---------------------------------------------------------


def breakdown_rows(evaluations: Sequence[Evaluation]) -> list[dict]:
    """One row per (finished pick evaluation, breakdown, value): episodes and successes."""
    rows = []
    for evaluation in evaluations:
        records = evaluation.result.get(FAMILY)
        if not records:
            continue
        labels = evaluation.labels
        for by in BY:
            for value, outcomes in breakdown(evaluation.result["successes"], records, by).items():
                rows.append(
                    {
                        **{k: labels[k] for k in ("method", "task", "n_train_envs", "seed", "condition")},
                        "by": by,
                        "value": value,
                        "episodes": len(outcomes),
                        "successes": sum(outcomes),
                    }
                )
    return rows


def write_breakdowns(evaluations: Sequence[Evaluation], study_dir: str | Path) -> Path | None:
    """Write ``pick_breakdowns.csv`` into the study folder (removed when no evaluation has pick records);
    its path, or ``None``."""
    rows = breakdown_rows(evaluations)
    path = Path(study_dir) / BREAKDOWN_FILE
    if not rows:
        path.unlink(missing_ok=True)
        return None
    return atomic_write_text(path, csv_text(rows, BREAKDOWN_COLUMNS))


def read_breakdowns(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a ``pick_breakdowns.csv`` (counts as integers)."""
    with open(path, newline="") as f:
        return [{**r, "episodes": int(r["episodes"]), "successes": int(r["successes"])} for r in csv.DictReader(f)]


def breakdown_section(rows: Sequence[dict]) -> list[str]:
    """Tables of success per named object, shape and phrasing template and condition, summed over N and
    seeds, per method."""
    if not rows:
        return []
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
