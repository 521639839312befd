"""The report's "Learning curve" section and ``learning_curve.png`` from ``curve.csv`` (``train.curve_every``):
P_T against training epochs per method and task, pooled over N and seeds, each point with its Wilson 95%
interval, so a training budget is chosen from a measured curve, not a guess; and the differences a reader would
otherwise work out by eye (each checkpoint against the one before, each method against the first), each with
Newcombe's interval."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..results.curve import CURVE_FILE, MACHINES_SEPARATOR, Difference, point_difference, pooled_curve
from .markdown import ci, stage_row
from .plots import draw_intervals, pyplot, save_figure

CURVE_PLOT = "learning_curve.png"
CURVE_CAPTION = (
    "P_T (success on the training environments) against training epochs, per method and task, pooled over N and "
    f"seeds; error bars: the Wilson 95% intervals of the *Learning curve* table (`{CURVE_FILE}`)."
)


def curve_section(
    rows: Sequence[dict[str, Any]], plotted: bool, methods: Sequence[str], budgets: Mapping[str, float] | None = None
) -> list[str]:
    """Markdown lines: the pooled curve as a table (one column per checkpoint), the figure under it, then its
    differences (``methods``: the config's order, whose first method on a task is the one compared against;
    ``budgets``: each method's ``train.epochs``, the checkpoint the grid's evaluations use)."""
    if not rows:
        return []
    pooled = pooled_curve(rows)
    epochs = sorted({p["epochs"] for p in pooled})
    lines = [
        "## Learning curve",
        "",
        f"P_T of each checkpoint the training saved (`train.curve_every`), pooled over N and seeds with its Wilson "
        f"95% interval (episodes of one checkpoint; the spread between seeds is not in it); per cell and seed in "
        f"`{CURVE_FILE}`. {_budget_sentence(pooled, budgets or {})}",
        "",
        "| method | task | " + " | ".join(f"{e:g} epochs" for e in epochs) + " |",
        "|---|---|" + "---|" * len(epochs),
    ]
    by_line: dict[tuple[str, str], dict[float, dict]] = {}
    for point in pooled:
        by_line.setdefault((point["method"], point["task"]), {})[point["epochs"]] = point
    for (method, task), points in by_line.items():
        cells = [
            f"{p['success_rate']:.2f} {ci(p['ci_low'], p['ci_high'], 2, sign=False)} ({p['episodes']})"
            if (p := points.get(e))
            else ""
            for e in epochs
        ]
        lines.append(f"| {method} | {task} | " + " | ".join(cells) + " |")
    lines += ["", "Each cell: P_T [95% interval] (episodes)."]
    if plotted:
        lines += ["", f"![learning curve]({CURVE_PLOT})", "", f"*{CURVE_CAPTION}*"]
    return [*lines, *_differences(by_line, epochs, methods), *_stages(by_line), *_machines(rows), ""]


def _budget_sentence(pooled: Sequence[dict[str, Any]], budgets: Mapping[str, float]) -> str:
    """Which checkpoint the grid's evaluations use: the full budget's, which a curve still training (a chain of
    ``train.extends`` run in parts) has not reached yet, so its last column is not it."""
    reached = {m: max(p["epochs"] for p in pooled if p["method"] == m) for m in {p["method"] for p in pooled}}
    short = {m: e for m, e in reached.items() if m in budgets and e < budgets[m]}
    if not short:
        return "The last column is the checkpoint the grid's evaluations use."
    return (
        "Still training: "
        + "; ".join(
            f"{m} has reached {e:g} of its {budgets[m]:g} epochs, the checkpoint the grid's evaluations use"
            for m, e in sorted(short.items())
        )
        + "."
    )


def _machines(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Which machines trained each cell's checkpoints (``trained_on``), per cell, not pooled: cells of a study run in
    parts may have trained on other machines without any training having moved. One sentence when one machine
    trained them all, else a row per checkpoint, with the machines of its steps since the cell's previous point
    where the curve says (a chain's link: what changed between two points); nothing for a curve.csv that does not
    say."""
    machines = [_names(row, "trained_on") for row in rows]
    if not any(machines):
        return []
    lines = ["", "### Which machines trained the curve", ""]
    if len(set(machines)) == 1 and len(machines[0]) == 1:
        return [*lines, f"One machine trained every checkpoint: {machines[0][0]}."]
    since = any(row.get("trained_since_previous") for row in rows)
    lines += [
        "A training resumed on another machine (`factorworld unpack`) is not byte for byte what one machine would "
        "make where their kernels differ (docs/study.md, *Across machines*); each cell's machines, each once, in the "
        "order they first trained its checkpoint (its training's `trained_on`)"
        + (
            ", and those that trained its steps since the cell's previous point (`trained_since_previous`)"
            if since
            else ""
        )
        + ":",
        "",
        "| method | task | N | seed | epochs | trained on |" + (" since the previous point |" if since else ""),
        "|---|---|---|---|---|---|" + ("---|" if since else ""),
    ]
    for row, names in zip(rows, machines, strict=True):
        cell = " | ".join(str(row.get(c, "")) for c in ("method", "task", "n_train_envs", "seed"))
        extra = f" {'; then '.join(_names(row, 'trained_since_previous')) or 'not recorded'} |" if since else ""
        lines.append(f"| {cell} | {row['epochs']:g} | {'; then '.join(names) or 'not recorded'} |{extra}")
    return lines


def _names(row: dict[str, Any], column: str) -> tuple[str, ...]:
    return tuple(m for m in row.get(column, "").split(MACHINES_SEPARATOR) if m)


def _stages(by_line: dict[tuple[str, str], dict[float, dict]]) -> list[str]:
    """Where each checkpoint's episodes end (the share by furthest stage, as *Where episodes fail* gives the
    grid's), so a curve shows which stage training moves episodes past and where they still stop: one table
    per list of stage names; nothing for a curve.csv without stage counts."""
    tables: dict[tuple[str, ...], list[str]] = {}
    for (method, task), points in by_line.items():
        for epochs, point in sorted(points.items()):
            total = sum(point["stages"].values())
            if not total:  # no stage counts (an older curve.csv), or no episodes
                continue
            names = tuple(point["stages"])
            tables.setdefault(names, []).append(stage_row((method, task, f"{epochs:g}"), point["stages"], names))
    if not tables:
        return []
    lines = [
        "",
        "### Where the curve's episodes end",
        "",
        "The share of each checkpoint's episodes by the furthest stage it reached, pooled like the table above "
        "(the stages of *Where episodes fail*): a checkpoint that gains success shows which stage it moved its "
        "episodes past, and one that levels off shows where its episodes still stop.",
    ]
    for names, rows in tables.items():
        lines += ["", "| method | task | epochs | episodes | " + " | ".join(names) + " |"]
        lines += ["|---|---|---|---|" + "---|" * len(names), *rows]
    return lines


def _differences(
    by_line: dict[tuple[str, str], dict[float, dict]], epochs: list[float], methods: Sequence[str]
) -> list[str]:
    """The curve's differences, each with Newcombe's 95% interval on its own (not corrected for the others): a
    description of where the curve moves, not a verdict. Each is over the cells both points have, paired (episode
    by episode) where both hold their episodes' outcomes, else for independent samples, marked where a table has
    both kinds. A step along a curve is from the curve's own checkpoint before (methods may save at other epochs)."""
    rows = []
    for (method, task), points in by_line.items():
        own = sorted(points)
        steps = {e: point_difference(points[e], points[before]) for before, e in zip(own, own[1:])}
        rows.append((method, "its checkpoint before", task, [steps.get(e) for e in epochs]))
    order = {name: i for i, name in enumerate(methods)}
    first: dict[str, str] = {}
    for method, task in sorted(by_line, key=lambda line: order.get(line[0], len(order))):
        first.setdefault(task, method)
    for (method, task), points in by_line.items():
        if method != first[task]:
            base = by_line[(first[task], task)]
            rows.append((method, first[task], task, [point_difference(points.get(e), base.get(e)) for e in epochs]))
    found = [cell for *_, cells in rows for cell in cells if cell]
    if not found:
        return []
    kinds = {cell.paired for cell in found}
    subsets = any(cell.subset for cell in found)

    def text(cell: Difference | None) -> str:
        if cell is None:
            return ""
        marks = [" (indep.)"] if len(kinds) == 2 and not cell.paired else []
        return difference_text(cell) + "".join(marks) + (SUBSET_MARK if cell.subset else "")

    return [
        "",
        "### Differences along the curve and between methods",
        "",
        "Each checkpoint's P_T minus the checkpoint before it on the same curve, and each method's minus the first "
        f"method's (in the config's order) at the same epochs on the same task, with {_interval_text(kinds)} "
        "(each on its own, not corrected for the others: a description of where the curve moves, not a verdict). "
        "Like the table above, an interval holds the episodes' noise only, not the spread between training seeds, "
        f"so between methods it can be too narrow{_pairing_text(kinds)}{SUBSET_TEXT if subsets else ''}",
        "",
        "| method | against | task | " + " | ".join(f"{e:g} epochs" for e in epochs) + " |",
        "|---|---|---|" + "---|" * len(epochs),
        *(
            f"| {method} | {against} | {task} | " + " | ".join(text(c) for c in cells) + " |"
            for method, against, task, cells in rows
        ),
    ]


def difference_text(difference: Difference) -> str:
    """``+0.17 [+0.01, +0.34]``: a difference of P_T and its interval, as the report's tables give them."""
    return f"{difference.diff:+.2f} {ci(difference.low, difference.high, 2)}"


SUBSET_MARK = " †"
SUBSET_TEXT = (
    " A difference marked † is over the cells (N, seed, widths) both points have: one of them has cells the other "
    "lacks (a curve still training, or a method run on fewer cells), which it leaves out, so it is not the "
    "difference of the two pooled points above."
)


def _interval_text(kinds: set[bool]) -> str:
    if kinds == {False}:
        return "Newcombe's 95% interval for two independent samples"
    if kinds == {True}:
        return "Newcombe's 95% interval for paired samples (episode by episode)"
    return (
        "Newcombe's 95% interval for paired samples (episode by episode), or for two independent samples where a "
        "point lacks its episodes' outcomes or played another number of episodes (marked *indep.*)"
    )


def _pairing_text(kinds: set[bool]) -> str:
    """Why the intervals pair the episodes, or what pairing them would change (an older ``curve.csv``)."""
    if kinds == {False}:
        return (
            "; and the checkpoints play the same episode seeds, so where that makes their outcomes positively "
            "correlated, a paired interval would be narrower."
        )
    return (
        ". Every checkpoint and method plays the same episode seeds in the same training environments, so episode i "
        f"of one point is paired with episode i of the other (their outcomes: `outcomes` in `{CURVE_FILE}`)."
    )


def plot_curve(rows: Sequence[dict[str, Any]], path: Path) -> bool:
    """One line per method and task: pooled P_T against epochs with its Wilson interval."""
    pooled = pooled_curve(rows)
    if not pooled:
        return False
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    for method, task in dict.fromkeys((p["method"], p["task"]) for p in pooled):
        points = [p for p in pooled if (p["method"], p["task"]) == (method, task)]
        found = [(p["success_rate"], p["ci_low"], p["ci_high"]) for p in points]
        draw_intervals(ax, [p["epochs"] for p in points], found, label=f"{method}, {task}", ls="-", ms=4)
    ax.set_xlabel("training epochs")
    ax.set_ylabel("P_T (pooled), 95% interval", fontsize=8)
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=7)
    return save_figure(fig, path)
