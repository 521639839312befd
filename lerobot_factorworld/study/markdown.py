"""``report.md``: the study's Markdown, every number from the rows of ``results.csv`` through the selectors
of ``aggregate.py`` (the plots draw the same selectors). Task families add their own sections (the
``report_sections`` hook), which read the study's CSV files too."""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

from ..protocol.conditions import TRAIN_SUITE
from .aggregate import (
    factor_ordering,
    gap_per_factor_and_n,
    gap_per_radius,
    pair_rows,
    radius_rows,
    success_per_condition_and_n,
    summary,
)
from .config import StudyConfig
from .metrics import rank_hardest_first, rerank, spearman
from .paper import (
    PAPER_FACTOR_RANKS,
    PAPER_FACTOR_RANKS_STATED,
    PAPER_ORDERING,
    PAPER_PAIR_TOLERANCE,
    PAPER_PAIRS_WITHIN,
)
from .plan import Plan
from .plots import CAPTIONS, PLOTS
from .results import RESULTS_FILE

REPORT_FILE = "report.md"
FAMILY_RESULTS = "results"  # a family's sections after the factor ordering (e.g. next to the paper's table)
FAMILY_DETAILS = "details"  # ... and at the end of the report (e.g. breakdowns per episode record)
MAX_CELL_ROWS = 60


def pm(mean: float, se: float) -> str:
    """``+0.123 ± 0.045`` (``n/a`` without a mean; no ``±`` without a standard error)."""
    if math.isnan(mean):
        return "n/a"
    return f"{mean:+.3f}" + ("" if math.isnan(se) else f" ± {se:.3f}")


def render(
    cfg: StudyConfig,
    plan: Plan,
    rows: list[dict],
    plots: list[Path],
    command: str,
    family_sections: Callable[[str], list[str]] = lambda part: [],
) -> str:
    """The text of ``report.md``; ``family_sections(part)`` gives the task families' own sections
    (``part``: ``FAMILY_RESULTS`` after the factor ordering, ``FAMILY_DETAILS`` at the end)."""
    details = family_sections(FAMILY_DETAILS)  # written first: they name the CSV files they read
    ev = cfg.eval
    training = f"{cfg.train.epochs:g} epochs" if cfg.train.epochs else f"{cfg.train.steps} steps"
    done = len({r["step"] for r in rows})
    total = len(plan.of_kind("eval"))
    lines = [
        f"# Study `{cfg.name}`",
        "",
        f"Produced by `{command}` ({done} of {total} evaluations finished). Every number below comes from "
        f"`{RESULTS_FILE}` next to this file"
        + ("; the breakdowns at the end from the CSV files they name, also next to it." if details else "."),
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
        return "\n".join([*lines, "No evaluation has finished yet."]) + "\n" + "\n".join(details)
    unequal = [r for r in rows if r["episodes"] % r["n_envs"] or r["envs_visited"] != r["n_envs"]]
    if unequal:
        lines += [f"**Coverage:** {len(unequal)} row(s) did not visit their environments equally.", ""]
    lines += _ordering_section(cfg, rows)
    lines += family_sections(FAMILY_RESULTS)
    lines += _gap_table(cfg, rows)
    lines += _pairs_section(cfg, rows)
    lines += _radius_section(cfg, rows)
    lines += _success_table(cfg, rows)
    lines += _cells_table(rows)
    lines += ["## Plots", ""]
    for path in plots:
        lines += [f"![{path.name}]({path.name})", "", CAPTIONS[path.name], ""]
    missing = [p for p in PLOTS if p not in {q.name for q in plots}]
    if missing:
        lines += [f"Not drawn (no data for them in this study): {', '.join(missing)}.", ""]
    return "\n".join(lines) + "\n" + "\n".join(details)


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
            f"| {factor} | {pm(*gaps[factor])} | {ours.get(factor, 'n/a')} | {paper if paper is not None else '—'} |"
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
    if len(shared) >= 2:
        ours_r = dict(zip(shared, rerank([ours[f] for f in shared])))
        paper_r = dict(zip(shared, rerank([PAPER_FACTOR_RANKS[f] for f in shared])))
        differ = [f for f in shared if abs(ours_r[f] - paper_r[f]) >= 1]
        if differ:
            lines.append(
                f"Where they differ (ranks among the {len(shared)} shared factors, 1 = hardest): "
                + "; ".join(f"{f} is ranked {ours_r[f]:g} here and {paper_r[f]:g} in the paper" for f in differ)
                + "."
            )
        else:
            lines.append("The ordering agrees with the paper's (no shared factor moves by a whole rank).")
    lines.append(PAPER_ORDERING)
    lines.append("")
    return lines


def _gap_table(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    stats = gap_per_factor_and_n(rows)
    lines = ["## Gap per factor and N (mean ± SE over seeds, averaged over tasks)", ""]
    header = "| method | condition | " + " | ".join(f"N={n}" for n in cfg.n_train_envs) + " |"
    lines += [header, "|---|---|" + "---|" * len(cfg.n_train_envs)]
    for method in cfg.methods:
        for condition in cfg.conditions():
            cells = [stats.get((method.name, condition, n)) for n in cfg.n_train_envs]
            if any(cells):
                lines.append(
                    f"| {method.name} | {condition} | " + " | ".join(pm(*c[:2]) if c else "n/a" for c in cells) + " |"
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
                    f"| {method.name} | {pair} | {pm(*m[:2]) if m else 'n/a'} | {pm(*i[:2]) if i else 'n/a'} | "
                    f"{sum(undefined)} of {len(undefined)} |"
                )
                if m and not math.isnan(m[0]) and method is cfg.methods[0]:
                    total += 1
                    within += abs(m[0]) <= PAPER_PAIR_TOLERANCE
    lines += [
        "",
        f"{within} of {total} pairs lie within ±6% for {cfg.methods[0].name} (paper: {PAPER_PAIRS_WITHIN}).",
        "",
    ]
    return lines


def _radius_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    if not cfg.radius_factors or not radius_rows(rows, cfg.radius_factors):
        return []
    stats = gap_per_radius(rows, cfg.radius_factors)
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
                f"| {method.name} | {factor} | " + " | ".join(pm(*c[:2]) if c else "n/a" for c in cells) + " |"
            )
    lines.append("")
    return lines


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
    stats = success_per_condition_and_n(rows)
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
