"""A rerun against the results it repeats: does each cell land within the interval the first run stated?

Two runs of the same step (same key in ``results.csv``'s ``step`` column: the same environments, seeds,
dataset and training settings) on one machine give byte-identical results. On another machine they need
not: torch picks its CPU kernels by instruction set (oneDNN's AVX-512 and AVX2 kernels sum in different
orders), so a checkpoint trained there differs in its last bits and the episodes of a borderline policy
can end differently. What a rerun on another machine must do is land within the stated intervals. This
module matches the two runs' rows by step key and says, per cell, whether the rerun's success rate lies
within the first run's Wilson 95% interval and its gap within the first run's paired (Newcombe) interval;
with both runs' ``episodes.parquet`` rows it also counts the episodes whose outcome and length agree.
Pure functions of the rows: ``factorworld compare-reruns`` reads the files and prints :func:`rerun_lines`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from ...protocol.conditions import TRAIN_SUITE

CELL_LABEL = ("method", "task", "n_train_envs", "seed", "widths", "condition")


@dataclass(frozen=True)
class CellComparison:
    """One step in both runs: the first run's successes with its Wilson interval and gap with its paired
    interval, the rerun's successes and gap, and whether the rerun lies within the first run's intervals
    (``gap_within`` is ``None`` for a ``train`` cell, which has no gap, and a cell whose gap is undefined)."""

    label: tuple
    step: str
    episodes: int
    successes: tuple[int, int]
    interval: tuple[float, float]
    gaps: tuple[float, float]
    gap_interval: tuple[float, float]
    rate_within: bool
    gap_within: bool | None
    same_outcome: int | None = None  # episodes whose success agrees (None: no episode rows for this step)
    same_length: int | None = None  # ... whose length in steps agrees too


@dataclass(frozen=True)
class RerunComparison:
    cells: list[CellComparison]
    only_first: int  # steps of the first run the rerun lacks
    only_rerun: int

    @property
    def within(self) -> int:
        """Cells whose rate and gap (where it has one) both lie within the first run's intervals."""
        return sum(1 for c in self.cells if c.rate_within and c.gap_within is not False)

    @property
    def identical(self) -> int:
        """Cells with the same successes and the same gap."""
        return sum(1 for c in self.cells if c.successes[0] == c.successes[1] and _same(*c.gaps))


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or abs(a - b) < 1e-9


def _inside(value: float, low: float, high: float) -> bool:
    return low - 1e-9 <= value <= high + 1e-9


def compare_reruns(
    first: Sequence[dict],
    rerun: Sequence[dict],
    first_episodes: Iterable[dict] = (),
    rerun_episodes: Iterable[dict] = (),
) -> RerunComparison:
    """Match ``results.csv`` rows of two runs by step key and compare each cell (see the module's docstring);
    episode rows (``episodes.parquet``: ``step``, ``episode_ix``, ``success``, ``n_steps``) add per-episode
    agreement. Raises ``ValueError`` when the runs share no step, or a step has different episode counts."""
    mine = {r["step"]: r for r in first}
    theirs = {r["step"]: r for r in rerun}
    shared = [key for key in mine if key in theirs]
    if not shared:
        raise ValueError(
            "the two runs share no evaluation step (results.csv's `step` column): a rerun repeats the same config"
        )
    episodes_a = _episodes_by_step(first_episodes)
    episodes_b = _episodes_by_step(rerun_episodes)
    cells = []
    for key in shared:
        a, b = mine[key], theirs[key]
        if a["episodes"] != b["episodes"]:
            raise ValueError(f"step {key} has {a['episodes']} episodes in one run and {b['episodes']} in the other")
        shifted = a["condition"] != TRAIN_SUITE and not math.isnan(float(a["gap_ci_low"]))  # a gap with an interval
        same_outcome = same_length = None
        if key in episodes_a and key in episodes_b:
            pairs = [(episodes_a[key][i], episodes_b[key][i]) for i in episodes_a[key] if i in episodes_b[key]]
            same_outcome = sum(1 for x, y in pairs if bool(x["success"]) == bool(y["success"]))
            same_length = sum(
                1 for x, y in pairs if bool(x["success"]) == bool(y["success"]) and x.get("n_steps") == y.get("n_steps")
            )
        cells.append(
            CellComparison(
                label=tuple(a[k] for k in CELL_LABEL),
                step=key,
                episodes=int(a["episodes"]),
                successes=(int(a["successes"]), int(b["successes"])),
                interval=(float(a["ci_low"]), float(a["ci_high"])),
                gaps=(float(a["gap"]), float(b["gap"])) if shifted else (math.nan, math.nan),
                gap_interval=(float(a["gap_ci_low"]), float(a["gap_ci_high"])) if shifted else (math.nan, math.nan),
                rate_within=_inside(float(b["success_rate"]), float(a["ci_low"]), float(a["ci_high"])),
                gap_within=_inside(float(b["gap"]), float(a["gap_ci_low"]), float(a["gap_ci_high"]))
                if shifted
                else None,
                same_outcome=same_outcome,
                same_length=same_length,
            )
        )
    return RerunComparison(cells, only_first=len(mine) - len(shared), only_rerun=len(theirs) - len(shared))


def _episodes_by_step(rows: Iterable[dict]) -> dict[str, dict[int, dict]]:
    out: dict[str, dict[int, dict]] = {}
    for row in rows:
        out.setdefault(row["step"], {})[int(row["episode_ix"])] = row
    return out


def rerun_lines(found: RerunComparison) -> list[str]:
    """``factorworld compare-reruns``'s text: one Markdown row per cell both ran, then the counts; the last line
    is ``within: <cells within>/<cells>``."""
    lines = [
        f"{len(found.cells)} evaluation steps in both; {found.only_first} only in the first, {found.only_rerun} "
        "only in the rerun",
        "",
        "| method | task | N | seed | widths | condition | first | rerun | rate within | gap first [95%] | gap rerun | "
        "gap within | same outcome | same length |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in found.cells:
        gap = "—" if c.gap_within is None else f"{c.gaps[0]:+.2f} [{c.gap_interval[0]:+.2f}, {c.gap_interval[1]:+.2f}]"
        gap_rerun = "—" if c.gap_within is None or math.isnan(c.gaps[1]) else f"{c.gaps[1]:+.2f}"
        lines.append(
            "| " + " | ".join(str(v) for v in c.label) + f" | {c.successes[0]}/{c.episodes} [{c.interval[0]:.2f}, "
            f"{c.interval[1]:.2f}] | {c.successes[1]}/{c.episodes} | {'yes' if c.rate_within else 'NO'} | {gap} | "
            f"{gap_rerun} | {'—' if c.gap_within is None else ('yes' if c.gap_within else 'NO')} | "
            f"{'—' if c.same_outcome is None else c.same_outcome} | {'—' if c.same_length is None else c.same_length} |"
        )
    with_episodes = [c for c in found.cells if c.same_outcome is not None]
    lines += ["", f"identical cells (same successes and gap): {found.identical}/{len(found.cells)}"]
    if with_episodes:
        total = sum(c.episodes for c in with_episodes)
        lines.append(
            f"episodes ending alike: {sum(c.same_outcome for c in with_episodes)}/{total}; "
            f"identically (same length too): {sum(c.same_length for c in with_episodes)}/{total}"
        )
    lines.append(f"within: {found.within}/{len(found.cells)}")
    return lines
