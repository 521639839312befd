"""How each condition of an ``eval.episodes=auto`` evaluation stopped, read back from ``results.csv`` rows alone
(so ``factorworld report`` states it without step folders): episodes used, why it stopped, its success rate and
gap with their anytime-valid intervals (the rows' interval columns hold those under ``auto``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ...protocol.conditions import TRAIN_SUITE
from ...stats.stopping import BUDGET, DECIDED, REASONS, WITHIN_TOLERANCE
from ..plan.config import StudyConfig
from ..sequential import PAIRED, StopRule


@dataclass(frozen=True)
class StopRow:
    """One condition of one checkpoint under the rule."""

    method: str
    task: str
    n_train_envs: int
    widths: str
    condition: str
    episodes: int
    reason: str  # decided / within tolerance / budget, paired (train), running (an unfinished group)
    success_rate: float
    success_low: float
    success_high: float
    gap: float
    gap_low: float
    gap_high: float


def reason_of(row: dict, rule: StopRule) -> str:
    """Why a row's condition stopped, from its interval, the tolerance and the budget (the rule's own tests)."""
    if row["condition"] == TRAIN_SUITE:
        return PAIRED
    low, high = row["gap_ci_low"], row["gap_ci_high"]
    if math.isnan(low) or math.isnan(high):
        return "running"
    if low > 0 or high < 0:
        return REASONS[DECIDED]
    if low >= -rule.tolerance and high <= rule.tolerance:
        return REASONS[WITHIN_TOLERANCE]
    return REASONS[BUDGET] if row["episodes"] >= rule.max_episodes else "running"


def stop_rows(cfg: StudyConfig, rows: Sequence[dict]) -> list[StopRow]:
    """Every row of an ``auto`` study as its stop, in the rows' order."""
    rule = cfg.eval.stop_rule()
    return [
        StopRow(
            r["method"],
            r["task"],
            int(r["n_train_envs"]),
            r["widths"],
            r["condition"],
            int(r["episodes"]),
            reason_of(r, rule),
            r["success_rate"],
            r["ci_low"],
            r["ci_high"],
            r["gap"],
            r["gap_ci_low"],
            r["gap_ci_high"],
        )  # fmt: skip
        for r in rows
    ]
