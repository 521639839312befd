"""Study outputs: ``results.csv`` (one row per method x task x N x widths x condition x seed), PNG plots
mirroring the paper's figures, and ``report.md``. Everything is derived from the finished eval steps,
so a rerun or a resumed study rewrites the same files (no duplicated rows)."""

from __future__ import annotations

import csv
import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from pathlib import Path

from .conditions import PAIR_SEPARATOR, TRAIN_SUITE
from .config import RADIUS_FACTORS, StudyConfig
from .metrics import (
    PAPER_FACTOR_RANKS,
    PAPER_FACTOR_RANKS_STATED,
    PAPER_REAL_ROBOT,
    interaction,
    mean_se,
    pair_metric,
    paired_gap,
    rank_hardest_first,
    spearman,
    wilson_interval,
)
from .plan import DEFAULT_WIDTHS, Plan, radius_of
from .steps import is_done, read_result

RESULTS_FILE = "results.csv"
REPORT_FILE = "report.md"
RESULT_COLUMNS = (
    "study",  # study name
    "method",  # method name from the config
    "policy",  # LeRobot policy type
    "task",
    "n_train_envs",  # N
    "seed",  # environment-sampling and training seed
    "widths",  # sampling widths of the run: "default" or e.g. "camera_pos=medium" (radius sweep)
    "condition",  # "train", a factor, or a pair "a+b"
    "n_factors",  # shifted factors: 0 (train), 1, 2
    "radius_m",  # radius of camera_pos / table_pos in this run (single-factor rows of those factors)
    "n_envs",  # environments of the condition (N for train, n_test_envs otherwise)
    "episodes",
    "successes",
    "success_rate",
    "ci_low",  # Wilson 95% interval of success_rate
    "ci_high",
    "train_success_rate",  # P_T of the same checkpoint on the same episode seeds
    "gap",  # P_T - P_F (0 for train)
    "gap_ci_low",  # Newcombe paired 95% interval of gap
    "gap_ci_high",
    "envs_visited",  # environments the episodes visited (all, equally, unless flagged in report.md)
    "fingerprint",  # hash of the condition's environments (configurations and object-start width)
    "step",  # key of the eval step (steps/eval/<key>/)
)
PLOTS = ("gap_vs_n.png", "gap_vs_radius.png", "pairs.png", "methods.png", "success_rates.png")


def result_rows(cfg: StudyConfig, plan: Plan, study_dir: str | Path) -> list[dict]:
    """``results.csv`` rows of every finished evaluation, in plan order."""
    policies = {m.name: m.policy["type"] for m in cfg.methods}
    done = {s.key: read_result(s, study_dir) for s in plan.of_kind("eval") if is_done(s, study_dir)}
    train_outcomes = {}
    for step in plan.of_kind("eval"):
        if step.key in done and step.meta["condition"] == TRAIN_SUITE:
            train_outcomes[step.deps[0]] = done[step.key]
    rows = []
    for step in plan.of_kind("eval"):
        if step.key not in done:
            continue
        res, meta = done[step.key], step.meta
        train = train_outcomes.get(step.deps[0])
        k, n = sum(res["successes"]), len(res["successes"])
        low, high = wilson_interval(k, n)
        gap = gap_low = gap_high = p_train = math.nan
        condition = meta["condition"]
        if train is not None and train["seeds"] == res["seeds"]:
            p_train = sum(train["successes"]) / len(train["successes"])
            if condition == TRAIN_SUITE:
                gap = 0.0  # by construction: no interval
            else:
                gap, gap_low, gap_high = paired_gap(train["successes"], res["successes"])
        factors = [] if condition == TRAIN_SUITE else condition.split(PAIR_SEPARATOR)
        radius = radius_of(meta["widths"], factors[0]) if len(factors) == 1 and factors[0] in RADIUS_FACTORS else None
        rows.append(
            {
                "study": cfg.name,
                "method": meta["method"],
                "policy": policies.get(meta["method"], ""),
                "task": meta["task"],
                "n_train_envs": meta["n_train_envs"],
                "seed": meta["seed"],
                "widths": meta["widths"],
                "condition": condition,
                "n_factors": len(factors),
                "radius_m": radius,
                "n_envs": res["n_envs"],
                "episodes": n,
                "successes": k,
                "success_rate": k / n if n else math.nan,
                "ci_low": low,
                "ci_high": high,
                "train_success_rate": p_train,
                "gap": gap,
                "gap_ci_low": gap_low,
                "gap_ci_high": gap_high,
                "envs_visited": res["envs_visited"],
                "fingerprint": res["fingerprint"],
                "step": step.key,
            }
        )
    return rows


def write_results(rows: Sequence[dict], path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".csv.tmp")
    with open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=RESULT_COLUMNS, lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _fmt(row[k]) for k in RESULT_COLUMNS})
    tmp.replace(path)
    return path


def _fmt(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, float):
        return f"{value:.6f}"
    return str(value)


# --- aggregation --------------------------------------------------------------------------------


def per_seed(rows: Iterable[dict], value: str, keys: Sequence[str]) -> dict[tuple, dict[int, float]]:
    """``value`` averaged over tasks (and any column not in ``keys``), per group of ``keys`` and seed."""
    acc: dict[tuple, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        v = row[value]
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        acc[tuple(row[k] for k in keys)][row["seed"]].append(float(v))
    return {g: {s: sum(vs) / len(vs) for s, vs in seeds.items()} for g, seeds in acc.items()}


def summary(rows: Iterable[dict], value: str, keys: Sequence[str]) -> dict[tuple, tuple[float, float, int]]:
    """Per group: (mean over seeds, standard error over seeds, number of seeds)."""
    return {g: (*mean_se(list(s.values())), len(s)) for g, s in per_seed(rows, value, keys).items()}


def pair_rows(rows: Sequence[dict]) -> list[dict]:
    """Pair metric and interaction per method x task x N x seed x pair (main grid)."""
    index = {
        (r["method"], r["task"], r["n_train_envs"], r["seed"], r["condition"]): r
        for r in rows
        if r["widths"] == DEFAULT_WIDTHS
    }
    out = []
    for key, row in index.items():
        if row["n_factors"] != 2:
            continue
        a, b = row["condition"].split(PAIR_SEPARATOR)
        ra, rb = index.get((*key[:4], a)), index.get((*key[:4], b))
        if ra is None or rb is None:
            continue
        out.append(
            {
                "method": key[0],
                "task": key[1],
                "n_train_envs": key[2],
                "seed": key[3],
                "pair": row["condition"],
                "pair_metric": pair_metric(row["success_rate"], ra["success_rate"], rb["success_rate"]),
                "interaction": interaction(row["gap"], ra["gap"], rb["gap"]),
            }
        )
    return out


def factor_ordering(rows: Sequence[dict], method: str, factors: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Mean gap (over N, tasks; mean and SE over seeds) per single factor of the main grid, for ``method``."""
    single = [r for r in rows if r["method"] == method and r["widths"] == DEFAULT_WIDTHS and r["condition"] in factors]
    stats = summary(single, "gap", ["condition"])
    return {f: stats[(f,)][:2] for f in factors if (f,) in stats}


# --- plots --------------------------------------------------------------------------------------


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_gap_vs_n(rows, cfg: StudyConfig, path: Path) -> bool:
    stats = summary([r for r in rows if r["widths"] == DEFAULT_WIDTHS], "gap", ["method", "condition", "n_train_envs"])
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
    radius_rows = [r for r in rows if r["radius_m"] is not None and r["condition"] in cfg.radius_factors]
    stats = summary(radius_rows, "gap", ["method", "condition", "n_train_envs", "radius_m"])
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
    stats = summary(
        [r for r in rows if r["widths"] == DEFAULT_WIDTHS and r["n_factors"] == 1], "gap", ["method", "condition"]
    )
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
    stats = summary(
        [r for r in rows if r["widths"] == DEFAULT_WIDTHS and r["n_factors"] <= 1],
        "success_rate",
        ["method", "condition", "n_train_envs"],
    )
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
    import matplotlib.pyplot as plt

    plt.close(fig)
    return True


# --- report.md ----------------------------------------------------------------------------------


def write_report(cfg: StudyConfig, plan: Plan, study_dir: str | Path, command: str) -> tuple[Path, Path, list[Path]]:
    """Write ``results.csv``, the plots and ``report.md``; returns their paths."""
    study_dir = Path(study_dir)
    rows = result_rows(cfg, plan, study_dir)
    csv_path = write_results(rows, study_dir / RESULTS_FILE)
    plotters = (plot_gap_vs_n, plot_gap_vs_radius, plot_pairs, plot_methods, plot_success_rates)
    plots = []
    for name, plotter in zip(PLOTS, plotters):
        path = study_dir / name
        path.unlink(missing_ok=True)
        if rows and plotter(rows, cfg, path):
            plots.append(path)
    text = _markdown(cfg, plan, rows, plots, command)
    from ..pick.records import write_study_breakdowns

    text += "\n".join(write_study_breakdowns(plan, study_dir))  # pick tasks: per object and phrasing
    report = study_dir / REPORT_FILE
    report.write_text(text)
    return csv_path, report, plots


def _pm(mean: float, se: float) -> str:
    if math.isnan(mean):
        return "n/a"
    return f"{mean:+.3f}" + ("" if math.isnan(se) else f" ± {se:.3f}")


def _markdown(cfg: StudyConfig, plan: Plan, rows: list[dict], plots: list[Path], command: str) -> str:
    ev = cfg.eval
    training = f"{cfg.train.epochs:g} epochs" if cfg.train.epochs else f"{cfg.train.steps} steps"
    done = len({r["step"] for r in rows})
    total = len(plan.of_kind("eval"))
    lines = [
        f"# Study `{cfg.name}`",
        "",
        f"Produced by `{command}` ({done} of {total} evaluations finished). Every number below comes from "
        f"`{RESULTS_FILE}` next to this file.",
        "",
        f"- Grid: methods {', '.join(m.name for m in cfg.methods)}; tasks {', '.join(cfg.tasks)}; "
        f"N {cfg.n_train_envs}; seeds {cfg.seeds}; {cfg.collect.demos} demos per dataset"
        + (f" (per task: {cfg.collect.demos_per_task})" if cfg.collect.demos_per_task else "")
        + f"; training {training} at batch {cfg.train.batch_size}.",
        f"- Evaluation: {ev.episodes} episodes per condition and checkpoint (episode i reset with seed "
        f"{ev.start_seed}+i in every condition, so object starts are paired), {ev.n_test_envs} test environments "
        "per shifted condition drawn from the held-out split, the N training environments for `train`.",
        "- Success rates carry Wilson 95% intervals; gaps P_T - P_F carry Newcombe's paired 95% intervals (in "
        "the CSV). Aggregates below: mean over tasks (and over N where stated) per seed, then mean ± standard "
        "error over seeds"
        + (
            "."
            if len(cfg.seeds) > 1
            else " (one seed here: no standard error is shown, and the plots' error bars are absent, not zero)."
        ),
        "",
    ]
    if not rows:
        return "\n".join([*lines, "No evaluation has finished yet."]) + "\n"
    unequal = [r for r in rows if r["episodes"] % r["n_envs"] or r["envs_visited"] != r["n_envs"]]
    if unequal:
        lines += [f"**Coverage:** {len(unequal)} row(s) did not visit their environments equally.", ""]
    lines += _ordering_section(cfg, rows)
    lines += _real_robot_section(cfg, rows)
    lines += _gap_table(cfg, rows)
    lines += _pairs_section(cfg, rows)
    lines += _radius_section(cfg, rows)
    lines += _success_table(cfg, rows)
    lines += _cells_table(rows)
    lines += ["## Plots", ""]
    captions = {
        "gap_vs_n.png": "Gap versus N per factor (paper Fig. 3a).",
        "gap_vs_radius.png": "Gap versus radius of camera and table position (paper Fig. 3b).",
        "pairs.png": "Pair metric for every pair (paper Fig. 3c / appendix); dashed lines at ±6%.",
        "methods.png": "Methods compared per factor (paper Fig. 5 / appendix).",
        "success_rates.png": "Raw success rates, train ('original') and per factor (paper appendix).",
    }
    for path in plots:
        lines += [f"![{path.name}]({path.name})", "", captions[path.name], ""]
    missing = [p for p in PLOTS if p not in {q.name for q in plots}]
    if missing:
        lines += [f"Not drawn (no data for them in this study): {', '.join(missing)}.", ""]
    return "\n".join(lines) + "\n"


def _ordering_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    method = cfg.methods[0].name
    gaps = factor_ordering(rows, method, cfg.factors)
    ours = rank_hardest_first({f: v[0] for f, v in gaps.items()})
    rho = spearman(ours, PAPER_FACTOR_RANKS)
    lines = [
        f"## Factor ordering ({method}, mean gap over tasks and N)",
        "",
        "| factor | gap (mean ± SE over seeds) | our rank | paper rank |",
        "|---|---|---|---|",
    ]
    for factor in sorted(gaps, key=lambda f: ours.get(f, 99)):
        paper = PAPER_FACTOR_RANKS.get(factor)
        lines.append(
            f"| {factor} | {_pm(*gaps[factor])} | {ours.get(factor, 'n/a')} | {paper if paper is not None else '—'} |"
        )
    shared = [f for f in ours if f in PAPER_FACTOR_RANKS]
    lines.append("")
    if math.isnan(rho):
        lines.append(
            f"Spearman correlation with the paper's ordering: not computed ({len(shared)} shared factors; "
            "it needs at least 3 with distinct gaps)."
        )
    else:
        stated = spearman(ours, PAPER_FACTOR_RANKS_STATED)
        lines.append(
            f"Spearman correlation with the paper's ordering over {len(shared)} factors: **{rho:+.2f}** "
            f"(with only what the paper's text states, the four hard factors tied: {stated:+.2f})."
        )
    from .metrics import _rerank

    if len(shared) >= 2:
        ours_r = dict(zip(shared, _rerank([ours[f] for f in shared])))
        paper_r = dict(zip(shared, _rerank([PAPER_FACTOR_RANKS[f] for f in shared])))
        differ = [f for f in shared if abs(ours_r[f] - paper_r[f]) >= 1]
        if differ:
            lines.append(
                f"Where they differ (ranks among the {len(shared)} shared factors, 1 = hardest): "
                + "; ".join(f"{f} is ranked {ours_r[f]:g} here and {paper_r[f]:g} in the paper" for f in differ)
                + "."
            )
        else:
            lines.append("The ordering agrees with the paper's (no shared factor moves by a whole rank).")
    lines.append(
        "The paper's ordering (section 5.1, Fig. 3a): camera position = object texture > table position = "
        "table texture > floor (background) > lighting = distractors. Its text states the coarser order "
        "(table texture, camera position, and their look-alikes object texture and table position) > "
        "background > lighting, distractors; the split of the four hard factors into two tiers is our "
        "reading of Fig. 3a."
    )
    lines.append("")
    return lines


def _real_robot_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    """The pick family's rows next to the paper's real-robot table (success pooled over N and seeds)."""
    from ..tasks import get_task

    pick = [r for r in rows if get_task(r["task"]).family == "pick" and r["widths"] == DEFAULT_WIDTHS]
    if not pick:
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
            cell = [r for r in pick if r["method"] == method.name and r["condition"] == condition]
            if not cell:
                continue
            k, n = sum(r["successes"] for r in cell), sum(r["episodes"] for r in cell)
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


def _gap_table(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    stats = summary([r for r in rows if r["widths"] == DEFAULT_WIDTHS], "gap", ["method", "condition", "n_train_envs"])
    lines = ["## Gap per factor and N (mean ± SE over seeds, averaged over tasks)", ""]
    header = "| method | condition | " + " | ".join(f"N={n}" for n in cfg.n_train_envs) + " |"
    lines += [header, "|---|---|" + "---|" * len(cfg.n_train_envs)]
    for method in cfg.methods:
        for condition in cfg.conditions():
            cells = [stats.get((method.name, condition, n)) for n in cfg.n_train_envs]
            if any(cells):
                lines.append(
                    f"| {method.name} | {condition} | " + " | ".join(_pm(*c[:2]) if c else "n/a" for c in cells) + " |"
                )
    lines.append("")
    return lines


def _pairs_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    pairs = pair_rows(rows)
    if not pairs:
        return []
    metric = summary(pairs, "pair_metric", ["method", "pair"])
    inter = summary(pairs, "interaction", ["method", "pair"])
    lines = [
        "## Pairs (mean ± SE over seeds, averaged over tasks and N)",
        "",
        "Pair metric = (P_A+B - min(P_A, P_B)) / min(P_A, P_B) (the paper's; undefined when the harder factor "
        "never succeeds); interaction = gap(A+B) - gap(A) - gap(B).",
        "",
        "A cell (task x N x seed) whose harder factor never succeeded has no pair metric; such cells are "
        "left out of the mean, and the last column counts them: a pair with many undefined cells is among "
        "the hardest, whatever its mean says.",
        "",
        "| method | pair | pair metric | interaction | cells without a pair metric |",
        "|---|---|---|---|---|",
    ]
    cells: dict[tuple, list[bool]] = defaultdict(list)
    for row in pairs:
        cells[(row["method"], row["pair"])].append(math.isnan(row["pair_metric"]))
    within = total = 0
    for method in cfg.methods:
        for pair in cfg.pair_conditions():
            m = metric.get((method.name, pair))
            i = inter.get((method.name, pair))
            undefined = cells.get((method.name, pair), [])
            if m or i or undefined:
                lines.append(
                    f"| {method.name} | {pair} | {_pm(*m[:2]) if m else 'n/a'} | {_pm(*i[:2]) if i else 'n/a'} | "
                    f"{sum(undefined)} of {len(undefined)} |"
                )
                if m and not math.isnan(m[0]) and method is cfg.methods[0]:
                    total += 1
                    within += abs(m[0]) <= 0.06
    lines += ["", f"{within} of {total} pairs lie within ±6% for {cfg.methods[0].name} (paper: 16 of 21).", ""]
    return lines


def _radius_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    radius_rows = [r for r in rows if r["radius_m"] is not None and r["condition"] in cfg.radius_factors]
    if not cfg.radius_factors or not radius_rows:
        return []
    stats = summary(radius_rows, "gap", ["method", "condition", "radius_m"])
    radii = sorted({k[2] for k in stats})
    lines = [
        "## Gap versus radius (mean ± SE over seeds, averaged over tasks and N)",
        "",
        "| method | factor | " + " | ".join(f"{r:g} m" for r in radii) + " |",
        "|---|---|" + "---|" * len(radii),
    ]
    for method in cfg.methods:
        for factor in cfg.radius_factors:
            cells = [stats.get((method.name, factor, r)) for r in radii]
            lines.append(
                f"| {method.name} | {factor} | " + " | ".join(_pm(*c[:2]) if c else "n/a" for c in cells) + " |"
            )
    lines.append("")
    return lines


MAX_CELL_ROWS = 60


def _cells_table(rows: list[dict]) -> list[str]:
    """Every row with its intervals, when there are few enough to read (else: see results.csv)."""
    if len(rows) > MAX_CELL_ROWS:
        return [f"Per-cell results with intervals: {len(rows)} rows in `{RESULTS_FILE}`.", ""]
    lines = [
        "## Every cell (success rate with Wilson 95% interval; gap with Newcombe's paired 95% interval)",
        "",
        "| method | task | N | seed | widths | condition | successes | success rate | gap |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        gap = "—" if r["n_factors"] == 0 else f"{r['gap']:+.2f} [{r['gap_ci_low']:+.2f}, {r['gap_ci_high']:+.2f}]"
        lines.append(
            f"| {r['method']} | {r['task']} | {r['n_train_envs']} | {r['seed']} | {r['widths']} | {r['condition']} | "
            f"{r['successes']}/{r['episodes']} | {r['success_rate']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}] | {gap} |"
        )
    lines.append("")
    return lines


def _success_table(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    stats = summary(
        [r for r in rows if r["widths"] == DEFAULT_WIDTHS], "success_rate", ["method", "condition", "n_train_envs"]
    )
    lines = [
        "## Success rates (mean ± SE over seeds, averaged over tasks)",
        "",
        "| method | condition | " + " | ".join(f"N={n}" for n in cfg.n_train_envs) + " |",
        "|---|---|" + "---|" * len(cfg.n_train_envs),
    ]
    for method in cfg.methods:
        for condition in [TRAIN_SUITE, *cfg.conditions()]:
            cells = [stats.get((method.name, condition, n)) for n in cfg.n_train_envs]
            if any(cells):
                lines.append(
                    f"| {method.name} | {condition} | "
                    + " | ".join(
                        f"{c[0]:.2f}" + ("" if math.isnan(c[1]) else f" ± {c[1]:.2f}") if c else "n/a" for c in cells
                    )
                    + " |"
                )
    lines.append("")
    return lines
