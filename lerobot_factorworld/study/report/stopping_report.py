"""``report.md`` of an ``eval.episodes=auto`` evaluation: per condition the episodes it used, why it stopped, and
its success rate and gap with their **anytime-valid** intervals (``study/sequential.py``).

Why a report of its own: every other section of a study's report rests on fixed-n intervals (Wilson, Newcombe,
seed-level bootstraps, the claims decided from them), which a data-dependent stopping makes invalid. This one
shows only intervals that hold under the stopping, and says so; the per-episode Parquet and the stages are as
in any study.
"""

from __future__ import annotations

from collections.abc import Sequence

from ...protocol.conditions import TRAIN_SUITE
from ..plan.config import StudyConfig
from ..results.rows import RESULTS_FILE, commits_of
from ..results.stopping import StopRow, stop_rows
from ..sequential import INTERVAL_LABEL
from .markdown import ci

STOP_COLUMNS = ("method", "task", "N", "condition", "episodes", "stopped", "success rate", "interval", "gap",
                "interval of the gap", "decision")  # fmt: skip


def rule_text(cfg: StudyConfig) -> str:
    """The rule in one sentence, with its settings."""
    rule = cfg.eval.stop_rule()
    return (
        f"episodes in blocks of {rule.block} paired reset seeds (seed {cfg.eval.start_seed}+i in every condition), "
        f"at most {rule.max_episodes} per condition; after each block every running shifted condition's paired gap "
        f"(train minus shift, per episode seed) gets a {rule.confidence:.0%} {INTERVAL_LABEL} confidence sequence "
        "(hedged betting, Waudby-Smith and Ramdas 2024), Bonferroni-corrected over the shifted conditions; a "
        f"condition stops when it excludes 0 (decided), lies inside ±{rule.tolerance:g} (within tolerance) or "
        "reaches the budget; train runs as long as any condition does"
    )


def decision(row: StopRow) -> str:
    if row.condition == TRAIN_SUITE:
        return ""
    if row.reason == "decided":
        return "gap > 0" if row.gap_low > 0 else "gap < 0"
    if row.reason == "within tolerance":
        return "no gap beyond the tolerance"
    return "not decided"


def stop_cells(cfg: StudyConfig, rows: Sequence[dict]) -> list[tuple[str, ...]]:
    """The stopping table's cells (:data:`STOP_COLUMNS`), one row per condition: what report.md and report.html
    both show."""
    out = []
    for r in stop_rows(cfg, rows):
        is_train = r.condition == TRAIN_SUITE
        out.append((
            r.method, r.task, str(r.n_train_envs), r.condition, str(r.episodes), r.reason, f"{r.success_rate:.3f}",
            ci(r.success_low, r.success_high, sign=False), "" if is_train else f"{r.gap:+.3f}",
            "" if is_train else ci(r.gap_low, r.gap_high), decision(r),
        ))  # fmt: skip
    return out


def stop_table(cfg: StudyConfig, rows: Sequence[dict]) -> list[str]:
    lines = ["| " + " | ".join(STOP_COLUMNS) + " |", "|---|---|---|---|---:|---|---:|---|---:|---|---|"]
    return lines + ["| " + " | ".join(cells) + " |" for cells in stop_cells(cfg, rows)]


STOPPED_NOTE = (
    "*stopped*: `decided` (the interval of the gap excludes 0), `within tolerance` (it lies inside ±{tolerance:g}), "
    "`budget` ({budget} episodes, neither), `paired` (train: as long as the longest of its conditions; a "
    "condition's gap pairs it with train's first episodes)."
)


def render_auto(cfg: StudyConfig, rows: list[dict], command: str, planned: int, stages: list[str]) -> str:
    """The text of an ``auto`` study's ``report.md`` (``stages``: the "Where episodes fail" lines)."""
    stops = stop_rows(cfg, rows)
    used = sum(r.episodes for r in stops)
    fixed = len(stops) * cfg.eval.max_episodes
    commits = ", ".join(commits_of(rows)) or "not recorded"
    lines = [
        f"# Study `{cfg.name}` (evaluated until decided)",
        "",
        f"Produced by `{command}` ({len({r['step'] for r in rows})} of {planned} evaluations finished). Every number "
        f"below comes from `{RESULTS_FILE}` next to this file; every episode run is in `episodes.parquet`.",
        "",
        f"- Code: {commits}.",
        f"- Evaluation (`eval.episodes=auto`): {rule_text(cfg)}.",
        f"- Episodes used: {used} of the {fixed} a fixed evaluation at the budget would run ({used / fixed:.0%}).",
        f"- Intervals: every interval here is {INTERVAL_LABEL} ({cfg.eval.confidence:.0%}, simultaneous over the "
        "conditions and every look), so it holds at the data-dependent stop. Success rates carry their own "
        "sequences (Bonferroni over train and the shifted conditions). The same columns of the CSV hold these "
        "intervals, not Wilson's or Newcombe's; the fixed-n sections of a study's report (bootstraps, claims, "
        "ordering, plots with error bars) are left out, as this stopping invalidates them. The guarantee is per "
        "checkpoint: it says nothing of other training seeds.",
        "",
        "## How each condition stopped",
        "",
        *stop_table(cfg, rows),
        "",
        STOPPED_NOTE.format(tolerance=cfg.eval.tolerance, budget=cfg.eval.max_episodes),
        "",
        *stages,
    ]
    return "\n".join(lines) + "\n"
