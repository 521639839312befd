"""The pick family's part of a study report (:data:`PICK_REPORT`, named by ``PickFamily.report_entry_point``):
success next to the paper's real-robot table, and success per named object, shape and phrasing.

Every number comes from a CSV file next to ``report.md``: the real-robot table from the study's
``results.csv`` rows, the breakdowns from ``pick_breakdowns.csv``, which a study that ran writes from the
evaluations' episode records (``pick/records.py``, :meth:`PickReport.write_report_files`) and every report reads back, so a
report regenerated from the committed CSV files (``factorworld report``) has the same tables.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..core.io import atomic_write_text, read_table
from ..pick.records import BY, MEASURE_BY, breakdown, measure_breakdown
from ..protocol.conditions import TRAIN_SUITE
from ..stats.ranks import spearman
from ..study.paper import PAPER_REAL_ROBOT
from ..study.plan.config import StudyConfig
from ..study.report.family_report import FamilyReport
from ..study.report.markdown import FAMILY_DETAILS, FAMILY_RESULTS, ci
from ..study.results.aggregate import main_grid, pooled_rho_interval, pooled_success
from ..study.results.rows import Evaluation, csv_text
from ..tasks import get_task

FAMILY = "pick"  # the family's name and the key of its episode records in an evaluation's result
BREAKDOWN_FILE = "pick_breakdowns.csv"
BREAKDOWN_COLUMNS = ("method", "task", "n_train_envs", "seed", "condition", "by", "value", "episodes", "successes")
MARKDOWN_BY = ("target", "shape", "template")  # instructions are many: in the CSV only


class PickReport(FamilyReport):
    """The pick family's report part: ``pick_breakdowns.csv`` and the sections that read it."""

    report_files = (BREAKDOWN_FILE,)

    def write_report_files(
        self, cfg: StudyConfig, evaluations: Sequence[Evaluation], study_dir: str | Path
    ) -> list[Path]:
        """``pick_breakdowns.csv`` from the finished evaluations' episode records."""
        path = write_breakdowns(evaluations, study_dir)
        return [path] if path else []

    def report_sections(self, cfg: StudyConfig, rows: Sequence[dict], study_dir: str | Path, part: str) -> list[str]:
        """The pick sections of ``report.md`` at ``part`` (the study's ``FAMILY_RESULTS`` or ``FAMILY_DETAILS``),
        from ``rows`` and the ``pick_breakdowns.csv`` in ``study_dir`` (none: no breakdown section)."""
        if part == FAMILY_RESULTS:
            return real_robot_section(cfg, rows)
        if part == FAMILY_DETAILS:
            path = Path(study_dir) / BREAKDOWN_FILE
            return breakdown_section(read_breakdowns(path)) if path.is_file() else []
        raise ValueError(f"unknown report part {part!r}; valid: {FAMILY_RESULTS}, {FAMILY_DETAILS}")


# --- next to the paper's real-robot table ---------------------------------------------------------


def real_robot_section(cfg: StudyConfig, rows: Sequence[dict]) -> list[str]:
    """The pick family's rows next to the paper's real-robot table: success per method and condition,
    pooled over the family's tasks, N and training seeds, with an interval that accounts for the seeds."""
    pick = [r for r in main_grid(rows) if _is_pick(r["task"])]
    if not pick:
        return []
    pooled = pooled_success(pick, ["method", "condition"])
    seeds = len({r["seed"] for r in pick})
    lines = [
        "## Pick next to the paper's real-robot table",
        "",
        f"Success pooled over tasks of the pick family, N and the {seeds} training seed(s); the 95% interval is the "
        "seed-level bootstrap's (training seeds resampled, then episodes within each seed's cells), widened where "
        "needed to contain the Wilson interval of the pooled episodes (with one seed: the Wilson interval). The "
        "paper's numbers are RT-1 on a real robot, 12 trials per new value of a factor (2 in each of 6 tasks), 24-36 "
        "per factor (section 5.1).",
        "",
        "| method | condition | paper (real robot) | successes | success rate [95%, seeds pooled: bootstrap] |",
        "|---|---|---|---|---|",
    ]
    orderings: list[str] = []  # each method's Spearman line, under the one table of every method
    for method in cfg.methods:
        rates = {}
        for condition in [TRAIN_SUITE, *cfg.conditions()]:
            cell = pooled.get((method.name, condition))
            if cell is None:
                continue
            k, n, low, high = cell
            name, paper = PAPER_REAL_ROBOT.get(condition, (condition, None))
            rates[condition] = k / n
            lines.append(
                f"| {method.name} | {name} (`{condition}`) | {'—' if paper is None else f'{paper:.1f}%'} | {k}/{n} | "
                f"{k / n:.2f} {ci(low, high, digits=2, sign=False)} |"
            )
        orderings += _ordering_lines(method.name, rates, [r for r in pick if r["method"] == method.name])
    return [*lines, *orderings, ""]


def _ordering_lines(method: str, rates: dict[str, float], rows: Sequence[dict]) -> list[str]:
    """Spearman's rho of the shifted conditions' success rates with the paper's real-robot ones, with its
    seed-bootstrap interval (``rows``: the method's pick rows)."""
    shifted = [c for c in rates if c != TRAIN_SUITE and PAPER_REAL_ROBOT.get(c, ("", None))[1] is not None]
    paper = {c: PAPER_REAL_ROBOT[c][1] for c in shifted}
    rho = spearman({c: rates[c] for c in shifted}, paper)
    if math.isnan(rho):
        return []
    low, high = pooled_rho_interval(rows, "condition", paper)
    return [
        "",
        f"{method}: Spearman correlation of the {len(shifted)} shifted conditions' success rates with the "
        f"paper's real-robot ones: **{rho:+.2f}**, 95% interval {ci(low, high, digits=2)} (bootstrap) "
        "(easiest first here: "
        + ", ".join(sorted(shifted, key=lambda c: -rates[c]))
        + "; in the paper: "
        + ", ".join(sorted(shifted, key=lambda c: -PAPER_REAL_ROBOT[c][1]))
        + ").",
    ]


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
        successes, measures = evaluation.result["successes"], evaluation.result.get("measures")
        groups = [(by, breakdown(successes, records, by)) for by in BY]
        if measures:  # what the gripper did, where the evaluation recorded it
            groups += [(by, measure_breakdown(successes, measures, by)) for by in MEASURE_BY]
        for by, grouped in groups:
            for value, outcomes in grouped.items():
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
    """The rows of a ``pick_breakdowns.csv`` (counts as integers); a file that is not one is refused in one line."""
    return read_table(path, BREAKDOWN_COLUMNS, integers=("n_train_envs", "seed", "episodes", "successes"))


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
    if any(r["by"] in MEASURE_BY for r in rows):
        lines[-1:-1] = [
            "`closest`: the object the gripper's centre came closest to during the episode; `named_within`: how close "
            "it came to the named object's centre (`3 cm` is the `reached` radius; an episode at `none` that went to "
            "the named object shows in `6 cm` or `10 cm`).",
            "",
        ]
    conditions = list(dict.fromkeys(r["condition"] for r in rows))
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        for by in (*MARKDOWN_BY, *MEASURE_BY):
            values = list(dict.fromkeys(r["value"] for r in mine if r["by"] == by))  # in the CSV's (bin) order
            if by not in MARKDOWN_BY and not values:
                continue
            values = values if by in MEASURE_BY else sorted(values)
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


PICK_REPORT = PickReport()
"""The pick family's report part (``report_entry_point="lerobot_factorworld.family_reports.pick:PICK_REPORT"``)."""
