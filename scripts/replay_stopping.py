"""Replay ``eval.episodes=auto``'s stopping rule (lerobot_factorworld/stats/stopping.py, its settings in
study/sequential.py) on committed episodes.

For every cell (method, task, N, seed, widths) of each study's ``docs/results/<study>/episodes.parquet`` that has a
``train`` condition and shifted ones on the same episode seeds, the rule runs over the episodes in seed order, in
blocks of ``--block``, capped at the committed count (the budget), Bonferroni over the cell's shifted conditions.
It prints the share of the committed episodes the rule would have run (train as long as its longest condition)
and compares each condition's decision with the fixed-n analysis of the same cell on all committed episodes: a gap
with its sign, or none, from Newcombe's paired 95% interval uncorrected (as results.csv has it) and corrected
(Bonferroni over the cell's shifted conditions: the family-wise guarantee the rule gives, without its stopping).
Shown as ``fixed:<uncorrected>/<corrected>``. A cell that two studies share (the same episodes) counts once in
the last line.

    python scripts/replay_stopping.py [--block 5] [--tolerance 0.1] [--confidence 0.95] [study ...]
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path
from statistics import NormalDist
from typing import NamedTuple

import pyarrow.parquet as pq

from lerobot_factorworld.stats.proportions import paired_gap
from lerobot_factorworld.study.sequential import StopRule, decide

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
CELL = ("method", "task", "n_train_envs", "seed", "widths")
DEFAULT_STUDIES = ("f1_ordering", "f2_gap_vs_n_pick-place", "f2_gap_vs_n_door-open", "f2_gap_vs_n_400_demos",
                   "f2_gap_vs_n_400_demos_n5_20", "learning_curve", "learning_curve_n20",
                   "learning_curve_bin-picking_500")  # fmt: skip


def cells(study: str) -> dict[tuple, dict[str, list[tuple[int, bool]]]]:
    """cell -> condition -> [(episode seed, success)] in seed order, from the study's committed Parquet."""
    table = pq.read_table(RESULTS / study / "episodes.parquet", columns=[*CELL, "condition", "episode_seed", "success"])
    out: dict[tuple, dict[str, list[tuple[int, bool]]]] = {}
    for row in table.to_pylist():
        key = tuple(row[c] for c in CELL)
        out.setdefault(key, {}).setdefault(row["condition"], []).append((row["episode_seed"], row["success"]))
    for conditions in out.values():
        for episodes in conditions.values():
            episodes.sort()
    return out


def fixed_decision(train: list[bool], shifted: list[bool], conditions: int = 1) -> str:
    """Newcombe's paired 95% interval's decision, Bonferroni-corrected over ``conditions``."""
    z = NormalDist().inv_cdf(1 - 0.05 / (2 * conditions))
    gap, low, high = paired_gap(train, shifted, z=z)
    return "+" if low > 0 else "-" if high < 0 else "none"


class Cell(NamedTuple):
    """One replayed cell: its identity (key and outcomes: a cell two studies share is one), its episodes."""

    identity: tuple
    used: int  # episodes the rule would run
    committed: int
    agreement: Counter  # (rule, fixed-n uncorrected) -> conditions
    corrected: Counter  # (rule, fixed-n corrected) -> conditions


def replay(study: str, block: int, tolerance: float, confidence: float) -> tuple[list[str], list[Cell]]:
    lines: list[str] = []
    replayed: list[Cell] = []
    for key, conditions in cells(study).items():
        train = conditions.get("train")
        shifted = {c: e for c, e in conditions.items() if c != "train"}
        label = "/".join(str(k) for k in key)
        if train is None or not shifted:
            lines.append(f"  {label}: no shifted condition on train's seeds: nothing to stop")
            continue
        n = len(train)
        if any([s for s, _ in e] != [s for s, _ in train] for e in shifted.values()) or n % block:
            lines.append(f"  {label}: conditions not on the same {n} seeds (or not in blocks of {block}): skipped")
            continue
        rule = StopRule(block=block, max_episodes=n, tolerance=tolerance, confidence=confidence)
        t = [ok for _, ok in train]
        stops = decide(t, {c: [ok for _, ok in e] for c, e in shifted.items()}, rule)
        cell_used = sum(s.episodes for s in stops.values())
        agreement, corrected = Counter(), Counter()
        parts = []
        for condition, stop in stops.items():
            if condition == "train":
                continue
            rule_says = ("+" if stop.gap_low > 0 else "-") if stop.reason == "decided" else "none"
            fixed = fixed_decision(t, [ok for _, ok in shifted[condition]])
            strict = fixed_decision(t, [ok for _, ok in shifted[condition]], len(shifted))
            agreement[(rule_says, fixed)] += 1
            corrected[(rule_says, strict)] += 1
            short = {"decided": "dec", "within tolerance": "tol", "budget": "bud"}[stop.reason]
            said = "" if rule_says == "none" else rule_says
            parts.append(f"{condition} {stop.episodes} {short}{said} fixed:{fixed}/{strict}")
        lines.append(f"  {label}: {cell_used}/{n * (len(shifted) + 1)} episodes; train {stops['train'].episodes}; "
                     + "; ".join(parts))  # fmt: skip
        identity = (key, tuple(t), tuple((c, tuple(ok for _, ok in e)) for c, e in sorted(shifted.items())))
        replayed.append(Cell(identity, cell_used, n * (len(shifted) + 1), agreement, corrected))
    return lines, replayed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("studies", nargs="*", default=list(DEFAULT_STUDIES))
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--tolerance", type=float, default=0.1)
    parser.add_argument("--confidence", type=float, default=0.95)
    args = parser.parse_args()
    print(
        f"replay of eval.episodes=auto: block {args.block}, tolerance {args.tolerance:g}, confidence "
        f"{args.confidence:g} (anytime-valid, Bonferroni over each cell's shifted conditions); budget = the "
        "committed episodes per condition; fixed-n = Newcombe's paired 95% interval on all of them, uncorrected / "
        "corrected (Bonferroni over the cell's shifted conditions)"
    )
    unique: dict[tuple, Cell] = {}
    for study in args.studies:
        lines, replayed = replay(study, args.block, args.tolerance, args.confidence)
        used, committed = sum(c.used for c in replayed), sum(c.committed for c in replayed)
        print(f"\n{study}: " + (f"{used}/{committed} episodes ({used / committed:.1%})" if committed else "no cells"))
        print("\n".join(lines))
        if committed:
            print("  " + _agreement_lines(replayed))
        unique.update({cell.identity: cell for cell in replayed})
    cells = list(unique.values())
    used, committed = sum(c.used for c in cells), sum(c.committed for c in cells)
    if not committed:
        print("\nall: no cell to replay")
        return
    print(
        f"\nall ({len(cells)} distinct cells): {used}/{committed} episodes ({used / committed:.1%}); "
        + _agreement_lines(cells)
    )


def _agreement_lines(cells: list[Cell]) -> str:
    return "; ".join(
        f"against fixed-n {name}: {_agreement_line(sum((getattr(c, field) for c in cells), Counter()))}"
        for name, field in (("uncorrected", "agreement"), ("corrected", "corrected"))
    )


def _agreement_line(agreement: Counter) -> str:
    """Decisions per (rule, fixed-n): + / - a gap with its sign, none."""
    same = sum(v for (r, f), v in agreement.items() if r == f)
    conditions = sum(agreement.values())
    missed = sum(v for (r, f), v in agreement.items() if r == "none" and f != "none")
    extra = sum(v for (r, f), v in agreement.items() if r != "none" and f == "none")
    opposite = sum(v for (r, f), v in agreement.items() if "none" not in (r, f) and r != f)
    decided_fixed = sum(v for (r, f), v in agreement.items() if f != "none")
    return (
        f"conditions {conditions}: same decision {same}; fixed-n decided {decided_fixed}, of which the rule decided "
        f"{decided_fixed - missed} (missed {missed}); the rule decided where fixed-n did not {extra}; opposite signs "
        f"{opposite}"
    )


if __name__ == "__main__":
    main()
