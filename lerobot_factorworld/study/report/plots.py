"""The study's PNG plots, mirroring the paper's figures for Markdown readers. Each draws what a selector of
``aggregate.py`` gives to a table of the report, with that table's uncertainty: where the table prints a 95%
interval (the seed-level bootstrap, or the pooled success rate's), the error bars are that interval, drawn from
its low to its high end (a percentile interval need not be centred on its point); where it prints a standard
error over seeds, they are that. Each caption (:data:`CAPTIONS`) says which, and names the table."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

from ...protocol.conditions import TRAIN_SUITE
from ...stats.ranks import rank_hardest_first
from ..analysis.study import StudyAnalysis, analyze
from ..paper import PAPER_PAIR_TOLERANCE
from ..plan.config import StudyConfig
from ..results.aggregate import (
    RADIUS_STEP_M,
    Interval,
    gap_against_n,
    gap_per_radius,
    pair_rows,
    pair_summary,
    radius_slopes,
    summary,
    tasks_disagree,
)

BOOTSTRAP_BARS = "error bars: 95% seed-level bootstrap intervals"
CAPTIONS = {
    "gap_vs_n.png": (
        f"Gap against N per factor and over all factors (paper Fig. 3a); {BOOTSTRAP_BARS}, those of the *Gap against "
        "N* table. Drawn when the study has two or more N."
    ),
    "gap_vs_radius.png": (
        "Gap against the radius of camera and table position, mean over tasks and N (paper Fig. 3b); error bars: "
        "± standard error over seeds, as the *Gap versus radius* table prints; the legend gives each line's "
        f"least-squares slope per {RADIUS_STEP_M:g} m with the table's 95% seed-level bootstrap interval."
    ),
    "pairs.png": (
        f"Pairs of the first method, mean over tasks and N (paper Fig. 3c / appendix). Left: the pair metric per "
        f"cell and pooled, {BOOTSTRAP_BARS}, the *Pairs* table's; dashed lines at ±{PAPER_PAIR_TOLERANCE:.0%}; no "
        "point: the harder factor never succeeded. Right: the interaction, error bars ± standard error over "
        "seeds, as the table prints."
    ),
    "methods.png": (
        f"Mean gap per factor (over tasks and N) of each method, hardest first by the first method's gap (paper "
        f"Fig. 5 / appendix); {BOOTSTRAP_BARS} (the first method's: the *Factor ordering* table's)."
    ),
    "ordering_per_task.png": (
        f"Each task's mean gap per factor (over N and seeds), first method; {BOOTSTRAP_BARS}, the *Ordering per "
        "task* table's. Drawn when the tasks rank the factors differently."
    ),
    "success_rates.png": (
        "Success rate per condition ('train' = original), per method and task, pooled over seeds, one series "
        "per N (paper appendix); error bars: the 95% intervals of the *Success per task and N* table (the "
        "seed-level bootstrap's, widened to contain Wilson's; Wilson's with one seed)."
    ),
}
PLOTS = tuple(CAPTIONS)  # file names, in the report's order
DRAWN_WHEN = {  # the plots drawn only in some studies with data for them
    "gap_vs_n.png": "two or more N",
    "ordering_per_task.png": "tasks that rank the factors differently",
}


def pyplot():
    # Deliberately here: matplotlib takes about a second to import and only drawing needs it (not
    # planning, running steps, or a report without rows).
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    return plt


def draw_intervals(ax, xs: Sequence[float], found: Sequence[Interval], horizontal: bool = False, **style) -> None:
    """Points at their estimates with bars from each interval's low to its high end, exact where the interval
    is not centred on its point (NaN intervals draw no bar)."""
    points = [f[0] for f in found]
    lows, highs = [f[1] for f in found], [f[2] for f in found]
    if horizontal:
        (line,) = ax.plot(points, xs, marker="o", ls="none", **style)
        ax.hlines(xs, lows, highs, color=line.get_color(), lw=1.2)
        for end in (lows, highs):
            ax.plot(end, xs, marker="|", ls="none", color=line.get_color(), ms=6)
        return
    (line,) = ax.plot(xs, points, marker="o", **style)
    ax.vlines(xs, lows, highs, color=line.get_color(), lw=1.2)
    for end in (lows, highs):
        ax.plot(xs, end, marker="_", ls="none", color=line.get_color(), ms=8)


def plot_gap_vs_n(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    found = {m.name: gap_against_n(rows, m.name, cfg.shifted_factors()) for m in cfg.methods}
    found = {method: g for method, g in found.items() if g is not None}
    if not found:  # fewer than two N
        return False
    labels = list(dict.fromkeys(label for g in found.values() for label in g.gaps))
    plt = pyplot()
    cols = min(4, len(labels))
    nrows = math.ceil(len(labels) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(3.2 * cols, 2.6 * nrows), sharey=True, squeeze=False)
    ns = sorted({n for g in found.values() for n in g.ns})
    shift = {m: 1.03 ** (j - (len(found) - 1) / 2) for j, m in enumerate(found)}  # methods side by side (log x)
    for ax, label in zip(axes.flat, labels):
        for method, g in found.items():
            if label in g.gaps:
                draw_intervals(ax, [n * shift[method] for n in g.ns], g.gaps[label], label=method)
        ax.set_title(label, fontsize=9)
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks(ns, [str(n) for n in ns])
        ax.axhline(0, color="grey", lw=0.5)
    for ax in list(axes.flat)[len(labels) :]:
        ax.axis("off")
    axes[0][0].set_ylabel("gap P_T - P_F")
    axes[0][0].legend(fontsize=7)
    fig.supxlabel("training environments N (95% bootstrap intervals)")
    return save_figure(fig, path)


def plot_gap_vs_radius(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    stats = gap_per_radius(rows, cfg.radius_factors)  # (method, factor, radius): the radius table's
    if not cfg.radius_factors or not stats:
        return False
    slopes = radius_slopes(rows, cfg.radius_factors)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    for method in cfg.methods:
        for factor in cfg.radius_factors:
            pts = sorted((k[2], v) for k, v in stats.items() if k[:2] == (method.name, factor))
            if not pts:
                continue
            label = f"{factor} ({method.name})"
            slope = slopes.get((method.name, factor))
            if slope:
                p, lo, hi = (v * RADIUS_STEP_M for v in slope)
                label += f": slope {p:+.3f} [{lo:+.3f}, {hi:+.3f}]"
            ax.errorbar(
                [p[0] for p in pts],
                [p[1][0] for p in pts],
                yerr=[_nz(p[1][1]) for p in pts],
                marker="o",
                capsize=3,
                label=label,
            )
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("radius (m)")
    ax.set_ylabel("gap P_T - P_F (± SE)")
    ax.legend(fontsize=7, title=f"slope per {RADIUS_STEP_M:g} m, 95% bootstrap", title_fontsize=7)
    return save_figure(fig, path)


def plot_pairs(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    """Left: the paper's pair metric per cell and pooled with their intervals (undefined ones stay empty);
    right: the interaction, always defined."""
    method = cfg.methods[0].name
    pairs = [p for p in pair_rows(rows) if p["method"] == method]
    names = [p for p in cfg.pair_conditions() if any(r["pair"] == p for r in pairs)]
    boot = pair_summary(rows, method, PAPER_PAIR_TOLERANCE)
    if not names or boot is None:
        return False
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 0.32 * len(names) + 1.6), sharey=True)
    ys = list(range(len(names)))
    nan = (math.nan, math.nan, math.nan)
    for offset, (label, found) in zip((-0.15, 0.15), (("per cell", boot.per_cell), ("pooled", boot.pooled))):
        values = [tuple(100 * v for v in found.get(p, nan)) for p in names]
        draw_intervals(axes[0], [y + offset for y in ys], values, horizontal=True, label=label, ms=4)
    for edge in (-100 * PAPER_PAIR_TOLERANCE, 100 * PAPER_PAIR_TOLERANCE):
        axes[0].axvline(edge, color="grey", lw=0.5, ls="--")
    axes[0].axvline(0, color="grey", lw=0.5)
    axes[0].set_xlabel("(P_A+B - min(P_A, P_B)) / min(P_A, P_B)  [%], 95% bootstrap", fontsize=8)
    axes[0].legend(fontsize=7)
    inter = summary(pairs, "interaction", ["pair"])
    vals = [inter.get((p,), (math.nan, math.nan, 0)) for p in names]
    axes[1].barh(ys, [v[0] for v in vals], xerr=[_nz(v[1]) for v in vals], capsize=2, height=0.6)
    axes[1].axvline(0, color="grey", lw=0.5)
    axes[1].set_xlabel("gap(A+B) - gap(A) - gap(B)  (± SE over seeds)", fontsize=8)
    axes[0].set_yticks(ys, names, fontsize=7)
    axes[0].invert_yaxis()
    fig.suptitle(f"pairs ({method}), mean over tasks and N; no point: the harder factor never succeeded", fontsize=8)
    return save_figure(fig, path)


def plot_methods(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    found = {name: b.intervals() for name, b in analysis.gap_bootstraps.items()}
    found = {method: intervals for method, intervals in found.items() if intervals}
    if not found:
        return False
    first = next(iter(found.values()))
    ranks = rank_hardest_first({f: v[0] for f, v in first.items()})
    factors = sorted(
        dict.fromkeys(f for intervals in found.values() for f in intervals), key=lambda f: ranks.get(f, math.inf)
    )
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(0.55 * len(factors) * max(1, len(found)) / 2 + 3.5, 3.2))
    width = 0.6 / len(found)
    nan = (math.nan, math.nan, math.nan)
    for j, (method, intervals) in enumerate(found.items()):
        xs = [i + (j - (len(found) - 1) / 2) * width for i in range(len(factors))]
        draw_intervals(ax, xs, [intervals.get(f, nan) for f in factors], label=method, ls="none", ms=5)
    ax.set_xticks(range(len(factors)), factors, rotation=30, fontsize=7)
    ax.set_ylabel("gap (mean over tasks and N)\n95% bootstrap interval", fontsize=8)
    ax.axhline(0, color="grey", lw=0.5)
    ax.legend(fontsize=7)
    return save_figure(fig, path)


def plot_ordering_per_task(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    factors = cfg.shifted_factors()
    if len(cfg.tasks) < 2 or len(factors) < 2:
        return False
    method = cfg.methods[0].name
    orderings = {t: b for t, b in analysis.task_orderings.items() if b.names}
    if len(orderings) < 2 or not tasks_disagree(orderings):
        return False
    pooled = analysis.shifted_bootstrap
    ranks = rank_hardest_first(dict(zip(pooled.names, pooled.point.tolist())))
    shown = sorted(dict.fromkeys(f for b in orderings.values() for f in b.names), key=lambda f: ranks.get(f, math.inf))
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(0.5 * len(shown) * len(orderings) / 2 + 3.5, 3.2))
    width = 0.7 / len(orderings)
    nan = (math.nan, math.nan, math.nan)
    for j, (task, b) in enumerate(orderings.items()):
        intervals = b.intervals()
        own = rank_hardest_first({f: v[0] for f, v in intervals.items()})
        xs = [i + (j - (len(orderings) - 1) / 2) * width for i in range(len(shown))]
        order = " > ".join(sorted(own, key=own.get)[:3])
        draw_intervals(ax, xs, [intervals.get(f, nan) for f in shown], label=f"{task} ({order}, ...)", ls="none", ms=5)
    ax.set_xticks(range(len(shown)), shown, rotation=30, fontsize=7)
    ax.set_ylabel("gap (mean over N)\n95% bootstrap interval", fontsize=8)
    ax.axhline(0, color="grey", lw=0.5)
    ax.legend(fontsize=7, title=f"{method}: each task's hardest factors", title_fontsize=7)
    return save_figure(fig, path)


def plot_success_rates(rows, cfg: StudyConfig, path: Path, analysis: StudyAnalysis) -> bool:
    pooled = analysis.per_task_success  # the "Success per task and N" table's
    if not pooled:
        return False
    conditions = [TRAIN_SUITE, *cfg.factors]
    panels = [(m.name, t) for m in cfg.methods for t in cfg.tasks if any(k[:2] == (m.name, t) for k in pooled)]
    ns = [n for n in cfg.n_train_envs if any(k[2] == n for k in pooled)]
    plt = pyplot()
    cols = min(3, len(panels))
    nrows = math.ceil(len(panels) / cols)
    fig, axes = plt.subplots(
        nrows, cols, figsize=(0.45 * len(conditions) * cols + 1.5 * cols, 3 * nrows), sharey=True, squeeze=False
    )
    width = 0.6 / len(ns)
    for ax, (method, task) in zip(axes.flat, panels):
        for j, n in enumerate(ns):
            shown = [i for i, c in enumerate(conditions) if (method, task, n, c) in pooled]
            found = []
            for i in shown:
                k, total, low, high = pooled[(method, task, n, conditions[i])]
                found.append((k / total, low, high))
            xs = [i + (j - (len(ns) - 1) / 2) * width for i in shown]
            draw_intervals(ax, xs, found, label=f"N = {n}", ls="none", ms=4)
        ax.set_xticks(range(len(conditions)), ["original" if c == TRAIN_SUITE else c for c in conditions])
        ax.tick_params(axis="x", labelrotation=35, labelsize=7)
        ax.set_title(f"{method}, {task}", fontsize=9)
        ax.set_ylim(-0.05, 1.05)
    for ax in list(axes.flat)[len(panels) :]:
        ax.axis("off")
    axes[0][0].set_ylabel("success rate (pooled over seeds)\n95% interval", fontsize=8)
    axes[0][0].legend(fontsize=7)
    return save_figure(fig, path)


def _nz(v: float) -> float:
    return 0.0 if v is None or math.isnan(v) else v


def save_figure(fig, path: Path) -> bool:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    pyplot().close(fig)
    return True


# each plotter draws from the rows and their analysis (what it shares with report.md and report.html)
PLOTTERS: dict[str, Callable[[Sequence[dict], StudyConfig, Path, StudyAnalysis], bool]] = {
    "gap_vs_n.png": plot_gap_vs_n,
    "gap_vs_radius.png": plot_gap_vs_radius,
    "pairs.png": plot_pairs,
    "methods.png": plot_methods,
    "ordering_per_task.png": plot_ordering_per_task,
    "success_rates.png": plot_success_rates,
}


def write_plots(
    rows: Sequence[dict], cfg: StudyConfig, study_dir: Path, analysis: StudyAnalysis | None = None
) -> list[Path]:
    """Draw every plot there is data for into ``study_dir`` (stale ones removed); the paths drawn. ``analysis``:
    the rows' (``write.py`` builds it once for every view; built here when not given)."""
    analysis = analyze(cfg, rows) if analysis is None else analysis
    drawn = []
    for name in PLOTS:
        path = study_dir / name
        path.unlink(missing_ok=True)
        if rows and PLOTTERS[name](rows, cfg, path, analysis):
            drawn.append(path)
    return drawn
