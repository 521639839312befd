"""The study's PNG plots, mirroring the paper's figures; each draws what a selector of ``aggregate.py``
gives, the same numbers as the report's table of that quantity."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

from ..protocol.conditions import TRAIN_SUITE
from .aggregate import (
    gap_per_factor,
    gap_per_factor_and_n,
    gap_per_radius,
    pair_rows,
    success_per_condition_and_n,
    summary,
)
from .config import StudyConfig

CAPTIONS = {
    "gap_vs_n.png": "Gap versus N per factor (paper Fig. 3a).",
    "gap_vs_radius.png": "Gap versus radius of camera and table position (paper Fig. 3b).",
    "pairs.png": "Pair metric for every pair (paper Fig. 3c / appendix); dashed lines at ±6%.",
    "methods.png": "Methods compared per factor (paper Fig. 5 / appendix).",
    "success_rates.png": "Raw success rates, train ('original') and per factor (paper appendix).",
}
PLOTS = tuple(CAPTIONS)  # file names, in the report's order


def _plt():
    # Deliberately here: matplotlib takes about a second to import and only drawing needs it (not
    # planning, running steps, or a report without rows).
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    return plt


def plot_gap_vs_n(rows, cfg: StudyConfig, path: Path) -> bool:
    stats = gap_per_factor_and_n(rows)
    if not stats:
        return False
    plt = _plt()
    cols = min(4, len(cfg.factors))
    nrows = math.ceil(len(cfg.factors) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(3.2 * cols, 2.6 * nrows), sharey=True, squeeze=False)
    for ax, factor in zip(axes.flat, cfg.factors):
        for method in cfg.methods:
            xs = [n for n in cfg.n_train_envs if (method.name, factor, n) in stats]
            ys = [stats[(method.name, factor, n)][0] for n in xs]
            es = [_nz(stats[(method.name, factor, n)][1]) for n in xs]
            ax.errorbar(xs, ys, yerr=es, marker="o", capsize=3, label=method.name)
        ax.set_title(factor, fontsize=9)
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks(cfg.n_train_envs, [str(n) for n in cfg.n_train_envs])
        ax.axhline(0, color="grey", lw=0.5)
    for ax in list(axes.flat)[len(cfg.factors) :]:
        ax.axis("off")
    axes[0][0].set_ylabel("gap P_T - P_F")
    axes[0][0].legend(fontsize=7)
    fig.supxlabel("training environments N")
    return _save(fig, path)


def plot_gap_vs_radius(rows, cfg: StudyConfig, path: Path) -> bool:
    stats = gap_per_radius(rows, cfg.radius_factors, per_n=True)
    if not cfg.radius_factors or not stats:
        return False
    plt = _plt()
    fig, axes = plt.subplots(1, len(cfg.n_train_envs), figsize=(3.4 * len(cfg.n_train_envs), 2.8), squeeze=False)
    for ax, n in zip(axes[0], cfg.n_train_envs):
        for method in cfg.methods:
            for factor in cfg.radius_factors:
                pts = sorted((k[3], v) for k, v in stats.items() if k[:3] == (method.name, factor, n))
                if pts:
                    ax.errorbar(
                        [p[0] for p in pts],
                        [p[1][0] for p in pts],
                        yerr=[_nz(p[1][1]) for p in pts],
                        marker="o",
                        capsize=3,
                        label=f"{factor} ({method.name})",
                    )
        ax.set_title(f"N = {n}", fontsize=9)
        ax.set_xlabel("radius (m)")
    axes[0][0].set_ylabel("gap P_T - P_F")
    axes[0][0].legend(fontsize=7)
    return _save(fig, path)


def plot_pairs(rows, cfg: StudyConfig, path: Path) -> bool:
    """Left: the paper's pair metric (undefined bars stay empty); right: the interaction, always defined."""
    pairs = [p for p in pair_rows(rows) if p["method"] == cfg.methods[0].name]
    names = cfg.pair_conditions()
    if not pairs or not names:
        return False
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 0.28 * len(names) * len(cfg.n_train_envs) + 1.4), sharey=True)
    height = 0.8 / len(cfg.n_train_envs)
    for ax, value, scale, label in (
        (axes[0], "pair_metric", 100, "(P_A+B - min(P_A, P_B)) / min(P_A, P_B)  [%]"),
        (axes[1], "interaction", 1, "gap(A+B) - gap(A) - gap(B)"),
    ):
        stats = summary(pairs, value, ["pair", "n_train_envs"])
        for j, n in enumerate(cfg.n_train_envs):
            vals = [stats.get((p, n), (math.nan, math.nan, 0)) for p in names]
            ax.barh(
                [i + j * height for i in range(len(names))],
                [scale * v[0] for v in vals],
                height=height,
                xerr=[scale * _nz(v[1]) for v in vals],
                capsize=2,
                label=f"N = {n}",
            )
        ax.axvline(0, color="grey", lw=0.5)
        ax.set_xlabel(label, fontsize=8)
    for edge in (-6, 6):
        axes[0].axvline(edge, color="grey", lw=0.5, ls="--")
    axes[0].set_yticks([i + 0.4 - height / 2 for i in range(len(names))], names, fontsize=7)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"pairs ({cfg.methods[0].name}); empty bar: the harder factor never succeeded", fontsize=8)
    return _save(fig, path)


def plot_methods(rows, cfg: StudyConfig, path: Path) -> bool:
    stats = gap_per_factor(rows, cfg.factors)
    if not stats:
        return False
    plt = _plt()
    fig, ax = plt.subplots(figsize=(1.1 * len(cfg.factors) * max(1, len(cfg.methods)) / 2 + 3, 3))
    width = 0.8 / len(cfg.methods)
    for j, method in enumerate(cfg.methods):
        vals = [stats.get((method.name, f), (math.nan, math.nan, 0)) for f in cfg.factors]
        ax.bar(
            [i + j * width for i in range(len(cfg.factors))],
            [v[0] for v in vals],
            width=width,
            yerr=[_nz(v[1]) for v in vals],
            capsize=2,
            label=method.name,
        )
    ax.set_xticks([i + 0.4 - width / 2 for i in range(len(cfg.factors))], cfg.factors, rotation=30, fontsize=7)
    ax.set_ylabel("gap (mean over N and tasks)")
    ax.axhline(0, color="grey", lw=0.5)
    ax.legend(fontsize=7)
    return _save(fig, path)


def plot_success_rates(rows, cfg: StudyConfig, path: Path) -> bool:
    stats = success_per_condition_and_n(rows)
    if not stats:
        return False
    plt = _plt()
    fig, axes = plt.subplots(1, len(cfg.methods), figsize=(4 * len(cfg.methods), 3), squeeze=False, sharey=True)
    for ax, method in zip(axes[0], cfg.methods):
        for condition in [TRAIN_SUITE, *cfg.factors]:
            xs = [n for n in cfg.n_train_envs if (method.name, condition, n) in stats]
            ax.errorbar(
                xs,
                [stats[(method.name, condition, n)][0] for n in xs],
                yerr=[_nz(stats[(method.name, condition, n)][1]) for n in xs],
                marker="o",
                capsize=3,
                label="original" if condition == TRAIN_SUITE else condition,
                lw=2.5 if condition == TRAIN_SUITE else 1,
            )
        ax.set_title(method.name, fontsize=9)
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks(cfg.n_train_envs, [str(n) for n in cfg.n_train_envs])
        ax.set_ylim(-0.05, 1.05)
        ax.set_xlabel("N")
    axes[0][0].set_ylabel("success rate")
    axes[0][0].legend(fontsize=6)
    return _save(fig, path)


def _nz(v: float) -> float:
    return 0.0 if v is None or math.isnan(v) else v


def _save(fig, path: Path) -> bool:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _plt().close(fig)
    return True


PLOTTERS: dict[str, Callable[[Sequence[dict], StudyConfig, Path], bool]] = {
    "gap_vs_n.png": plot_gap_vs_n,
    "gap_vs_radius.png": plot_gap_vs_radius,
    "pairs.png": plot_pairs,
    "methods.png": plot_methods,
    "success_rates.png": plot_success_rates,
}


def write_plots(rows: Sequence[dict], cfg: StudyConfig, study_dir: Path) -> list[Path]:
    """Draw every plot there is data for into ``study_dir`` (stale ones removed); the paths drawn."""
    drawn = []
    for name in PLOTS:
        path = study_dir / name
        path.unlink(missing_ok=True)
        if rows and PLOTTERS[name](rows, cfg, path):
            drawn.append(path)
    return drawn
