"""``report.md``: the study's Markdown, every number from the rows of ``results.csv`` through the selectors
of ``aggregate.py`` (the plots draw the same selectors). Task families add their own sections (the
``report_sections`` hook), which read the study's CSV files too."""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path

from ...core.provenance import UNKNOWN
from ...envs.lerobot_obs import FACTORWORLD_OBS
from ...protocol.conditions import TRAIN_SUITE
from ...stats.bootstrap import BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED
from ...stats.ranks import rank_hardest_first, rerank, spearman
from ...tasks import step_limit
from ..analysis.study import StudyAnalysis, analyze
from ..paper import (
    PAPER_FACTOR_GROUPS,
    PAPER_FACTOR_RANKS,
    PAPER_FACTOR_RANKS_STATED,
    PAPER_ORDERING,
    PAPER_PAIR_TOLERANCE,
    PAPER_PAIRS_WITHIN,
)
from ..plan.config import StudyConfig
from ..plan.method_config import MethodConfig
from ..results.aggregate import (
    ALL_FACTORS,
    RADIUS_STEP_M,
    FactorGapBootstrap,
    factor_ordering,
    gap_against_n,
    gap_per_factor_and_n,
    gap_per_radius,
    main_grid,
    method_gap_differences,
    method_rho_differences,
    method_success_differences,
    pair_bands,
    pair_rows,
    pair_summary,
    radius_rows,
    radius_slopes,
    shared_cell_count,
    success_per_condition_and_n,
    summary,
)
from ..results.rows import RESULTS_FILE, commit_name
from ..run.inputs import MERGED_FRAMES
from .claims_markdown import claims_section, ordering_sentence
from .plots import CAPTIONS, DRAWN_WHEN, PLOTS

REPORT_FILE = "report.md"
FAMILY_RESULTS = "results"  # a family's sections after the factor ordering (e.g. next to the paper's table)
FAMILY_DETAILS = "details"  # ... and at the end of the report (e.g. breakdowns per episode record)
MAX_CELL_ROWS = 60


def pm(mean: float, se: float) -> str:
    """``+0.123 ± 0.045`` (``n/a`` without a mean; no ``±`` without a standard error)."""
    if math.isnan(mean):
        return "n/a"
    return f"{mean:+.3f}" + ("" if math.isnan(se) else f" ± {se:.3f}")


def ci(low: float, high: float, digits: int = 3, sign: bool = True) -> str:
    """``[-0.012, +0.345]`` (``[n/a]`` without an interval)."""
    if math.isnan(low) or math.isnan(high):
        return "[n/a]"
    fmt = f"{{:{'+' if sign else ''}.{digits}f}}"
    return f"[{fmt.format(low)}, {fmt.format(high)}]"


BOOTSTRAP_NOTE = (
    f"95% intervals marked *bootstrap* are seed-level bootstraps ({BOOTSTRAP_RESAMPLES} resamples from the fixed "
    f"seed {BOOTSTRAP_SEED}, so a rebuilt report is identical): each resample draws the training seeds with "
    "replacement, then each drawn cell's episodes with replacement (its successes are binomial at its own rate), "
    "each cell from a generator seeded by its identity (method, task, N, widths, condition), so a cell has the same "
    "interval in every table and report that holds it with the same seeds, and recomputes the summary; the interval is the 2.5-97.5 percentile. Train and shifted cells are resampled "
    "independently (only counts are in the CSV), so gap intervals are somewhat wide; with S seeds a resample can "
    "only take a few distinct seed sets (10 for 3 seeds), so with few seeds they are rough. A percentile interval "
    "of a rank correlation or a count need not contain its point estimate: resampling breaks the point's ties and "
    "adds noise."
)


def render(
    cfg: StudyConfig,
    rows: list[dict],
    plots: list[Path],
    command: str,
    planned: int,
    family_sections: Callable[[str], list[str]] = lambda part: [],
    analysis: StudyAnalysis | None = None,
    finding_studies: Sequence[str] = (),
) -> str:
    """The text of ``report.md`` from the rows of ``results.csv`` (``planned``: the plan's evaluations);
    ``family_sections(part)`` gives the task families' own sections (``part``: ``FAMILY_RESULTS`` after the
    factor ordering, ``FAMILY_DETAILS`` at the end); ``analysis``: ``rows``' analysis, claims included
    (``analysis.study.analyze``, which ``write.py`` builds once for every view; built here when not given);
    ``finding_studies``: the other studies of its finding
    they were corrected with."""
    details = family_sections(FAMILY_DETAILS)
    ev = cfg.eval
    training = _training_text(cfg)
    done = len({r["step"] for r in rows})
    lines = [
        f"# Study `{cfg.name}`",
        "",
        f"Produced by `{command}` ({done} of {planned} evaluations finished). Every number below comes from "
        f"`{RESULTS_FILE}` next to this file"
        + ("; the breakdowns at the end from the CSV files they name, also next to it." if details else "."),
        "",
        *([commit_line(rows), ""] if rows else []),
        f"- Grid: methods {', '.join(m.name for m in cfg.methods)}; tasks {', '.join(cfg.tasks)}; "
        f"N {cfg.n_train_envs}; seeds {cfg.seeds}"
        + (
            f"; {cfg.collect.demos} demos per dataset"
            + (f" (per task: {cfg.collect.demos_per_task})" if cfg.collect.demos_per_task else "")
            if cfg.trained_methods()
            else ""
        )
        + f"; textures a flat RGB colour with probability {cfg.collect.effective_rgb_fraction:g}, else an image"
        + (f"; rendered at quality {cfg.collect.quality}" if _renders_at_another_quality(cfg) else "")
        + (f"; training {training}." if cfg.trained_methods() else "."),
        *_given_lines(cfg, rows),
        *_extra_data_lines(cfg),
        f"- Evaluation: {ev.episodes} episodes per condition and checkpoint (episode i reset with seed "
        f"{ev.start_seed}+i in every condition, so object starts are paired), {ev.n_test_envs} test environments "
        "per shifted condition drawn from the held-out split, the N training environments for `train`; an "
        f"episode ends at success or after {_step_limits(cfg)}.",
        "- Success rates carry Wilson 95% intervals; gaps P_T - P_F carry Newcombe's paired 95% intervals (in "
        "the CSV). Aggregates below: mean over tasks (and over N where stated) per seed, then mean ± standard "
        "error over seeds"
        + (
            "."
            if len(cfg.seeds) > 1
            else " (one seed here: no standard error is shown, and the plots' error bars are absent, not zero)."
        ),
        f"- {BOOTSTRAP_NOTE}",
        "",
    ]
    if not rows:
        # a curve still training (the grid's evaluations use its last checkpoint): its points so far come below
        curve = any(line.startswith("## Learning curve") for line in details)
        waiting = "No evaluation of the grid has finished yet" + (
            "; the learning curve below has its points so far.\n" if curve else "."
        )
        return "\n".join([*lines, waiting]) + "\n" + "\n".join(details)
    unequal = [r for r in rows if r["episodes"] % r["n_envs"] or r["envs_visited"] != r["n_envs"]]
    if unequal:
        lines += [f"**Coverage:** {len(unequal)} row(s) did not visit their environments equally.", ""]
    analysis = analyze(cfg, rows) if analysis is None else analysis
    lines += _ordering_section(cfg, rows, analysis)
    lines += claims_section(list(analysis.verdicts), cfg.finding, finding_studies)
    lines += _ordering_per_task_section(cfg, rows, analysis)
    lines += family_sections(FAMILY_RESULTS)
    lines += _gap_table(cfg, rows)
    lines += _gap_against_n_section(cfg, rows)
    lines += _methods_section(cfg, rows)
    lines += _pairs_section(cfg, rows)
    lines += _radius_section(cfg, rows)
    lines += _success_table(cfg, rows)
    lines += _per_task_table(cfg, rows, analysis)
    lines += _stages_section(cfg, analysis)
    lines += _cells_table(rows)
    lines += ["## Plots", ""]
    for path in plots:
        lines += [f"![{path.name}]({path.name})", "", CAPTIONS[path.name], ""]
    missing = [p for p in PLOTS if p not in {q.name for q in plots}]
    if missing:
        no_data = [p for p in missing if p not in DRAWN_WHEN]
        why = [f"{', '.join(no_data)} (no data for them in this study)"] if no_data else []
        why += [f"{p} (drawn only with {DRAWN_WHEN[p]})" for p in missing if p in DRAWN_WHEN]
        lines += [f"Not drawn: {'; '.join(why)}.", ""]
    return "\n".join(lines) + "\n" + "\n".join(details)


def commit_line(rows: Sequence[dict]) -> str:
    """``Numbers made at commit(s): 826fe54 (6 rows), commit not recorded (2 rows)``, in row order (the
    ``commit`` column through ``results.commit_name``; a CSV made before it was recorded has none)."""
    counts = Counter(commit_name(row) for row in rows)  # one entry per distinct code
    return "Numbers made at commit(s): " + ", ".join(
        f"{'commit not recorded' if commit == UNKNOWN else commit} ({n} row{'s' if n != 1 else ''})"
        for commit, n in counts.items()
    )


def _extra_data_lines(cfg: StudyConfig) -> list[str]:
    """The methods trained with other tasks' demos joined to each task's (``extra_tasks``)."""
    lines = []
    for m in cfg.trained_methods():
        if m.extra_tasks:
            demos = f"{m.extra_demos} demos each" if m.extra_demos else "as many demos as those tasks' own datasets"
            lines.append(
                f"- Out-of-domain data: {m.name} trains on each task's dataset plus the datasets of "
                f"{', '.join(m.extra_tasks)} (other than the task itself) in the same cell, {demos}; its in-task "
                + (
                    "demos and passes over them are those of the same method without them (its epochs count every "
                    "merged frame, so it takes proportionally more gradient steps)."
                    if m.epochs_over == MERGED_FRAMES
                    else "demos and gradient steps are those of the same method without them."
                )
            )
    return lines


def _step_limits(cfg: StudyConfig) -> str:
    """``200 steps``, ``200 steps (bin-picking: 500)`` or ``the task's step limit (pick-place: 500, ...)``."""
    limits = {task: step_limit(task, cfg.eval.max_steps_for(task)) for task in cfg.tasks}
    if len(set(limits.values())) == 1:
        return f"{next(iter(limits.values()))} steps"
    common = cfg.eval.max_episode_steps
    if common is None:
        return "the task's step limit (" + ", ".join(f"{t}: {n}" for t, n in limits.items()) + ")"
    others = ", ".join(f"{t}: {n}" for t, n in limits.items() if n != common)
    return f"{common} steps ({others})"


def _given_lines(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    """The given checkpoints (methods evaluated as they are): where they are, what they observe, and what
    ``train`` and ``seed`` mean for them."""
    given = cfg.given_methods()
    if not given:
        return []
    policies = {r["method"]: r["policy"] for r in rows}
    names = "; ".join(f"{m.name} (`{policies.get(m.name) or '?'}`, `{m.checkpoint}`, obs={m.obs})" for m in given)
    return [
        f"- Given checkpoint(s), evaluated as they are (no collection, no training): {names}. Their `train` is the "
        f"N environments sampled varying {', '.join(cfg.train_factors) or 'no factor (the unshifted scene)'}, "
        f"and they are evaluated at the first seed only, {cfg.seeds[0]} (it samples the environments; a given "
        "checkpoint has no training seed)."
    ]


def _training_text(cfg: StudyConfig) -> str:
    """``60 epochs at batch 32``; per method where methods train differently (their own ``train``)."""

    def text(method: MethodConfig) -> str:
        t = cfg.train_for(method)
        return (f"{t.epochs:g} epochs" if t.epochs else f"{t.steps} steps") + f" at batch {t.batch_size}"

    texts = {m.name: text(m) for m in cfg.trained_methods()}
    if len(set(texts.values())) <= 1:
        return next(iter(texts.values()), "")
    return ", ".join(f"{name} {value}" for name, value in texts.items())


def _ordering_section(cfg: StudyConfig, rows: list[dict], analysis: StudyAnalysis) -> list[str]:
    if not cfg.factors:  # e.g. a profile of the `train` condition alone
        return []
    method = cfg.methods[0].name
    gaps = factor_ordering(rows, method, cfg.factors)
    ours = rank_hardest_first({f: v[0] for f, v in gaps.items()})
    rho = spearman(ours, PAPER_FACTOR_RANKS)
    bootstrap = analysis.gap_bootstraps[method]  # one resampling for every interval below
    lines = [
        f"## Factor ordering ({method}, mean gap over tasks and N)",
        "",
        "| " + " | ".join(ORDERING_COLUMNS) + " |",
        "|---|---|---|---|---|",
        *("| " + " | ".join(row) + " |" for row in ordering_rows(gaps, bootstrap)),
    ]
    shared = [f for f in ours if f in PAPER_FACTOR_RANKS]
    lines.append("")
    if math.isnan(rho):
        lines.append(
            f"Spearman correlation with the paper's ordering: not computed ({len(shared)} shared factors; "
            "it needs at least 3 with distinct gaps)."
        )
    else:
        stated = spearman(ours, PAPER_FACTOR_RANKS_STATED)
        rho_ci = bootstrap.rho_interval(PAPER_FACTOR_RANKS)
        stated_ci = bootstrap.rho_interval(PAPER_FACTOR_RANKS_STATED)
        lines.append(
            f"Spearman correlation with the paper's ordering over {len(shared)} factors: **{rho:+.2f}**, "
            f"95% interval {ci(*rho_ci, digits=2)} (bootstrap) (with only what the paper's text states, the four "
            f"hard factors tied: {stated:+.2f}, {ci(*stated_ci, digits=2)})."
        )
    if len(shared) >= 2:
        ours_r = dict(zip(shared, rerank([ours[f] for f in shared])))
        paper_r = dict(zip(shared, rerank([PAPER_FACTOR_RANKS[f] for f in shared])))
        differ = [f for f in shared if abs(ours_r[f] - paper_r[f]) >= 1]
        if differ:
            lines.append(
                f"Point ranks that differ (among the {len(shared)} shared factors, 1 = hardest; ranks are not verdicts): "
                + "; ".join(f"{f} is ranked {ours_r[f]:g} here and {paper_r[f]:g} in the paper" for f in differ)
                + "."
            )
    trained = [m.name for m in cfg.methods]
    for other, (own, diff) in method_rho_differences(rows, trained, cfg.factors, PAPER_FACTOR_RANKS).items():
        lines.append(
            f"{other}'s ordering: Spearman {own[0]:+.2f} {ci(*own[1:], digits=2)} with the paper's, {diff[0]:+.2f} "
            f"{ci(*diff[1:], digits=2)} against {method}'s (bootstrap; one resampling of both, on the "
            f"{shared_cell_count(rows, [method, other])} cells (task, N, seed, condition) both have)."
        )
    sentence = ordering_sentence(list(analysis.verdicts))
    if sentence:
        lines.append(sentence)
    lines.append(PAPER_ORDERING)
    lines.append("")
    return lines + _resolved_factors(bootstrap, method, sorted(gaps, key=lambda f: ours.get(f, 99)))


ORDERING_COLUMNS = ("factor", "gap (mean ± SE over seeds)", "95% interval (bootstrap)", "our rank", "paper rank")


def ordering_rows(gaps: dict[str, tuple[float, float]], bootstrap: FactorGapBootstrap) -> list[tuple[str, ...]]:
    """The factor ordering table's cells (:data:`ORDERING_COLUMNS`), hardest first, as report.md and report.html
    print them: ``gaps`` from ``aggregate.factor_ordering``, the intervals from the same rows' ``bootstrap``."""
    ours = rank_hardest_first({f: v[0] for f, v in gaps.items()})
    intervals = bootstrap.intervals()
    out = []
    for factor in sorted(gaps, key=lambda f: ours.get(f, 99)):
        paper = PAPER_FACTOR_RANKS.get(factor)
        interval = ci(*intervals[factor][1:]) if factor in intervals else "[n/a]"
        out.append(
            (
                factor,
                pm(*gaps[factor]),
                interval,
                str(ours.get(factor, "n/a")),
                str(paper if paper is not None else "—"),
            )
        )
    return out


def _ordering_per_task_section(cfg: StudyConfig, rows: list[dict], analysis: StudyAnalysis) -> list[str]:
    """Each task's own ordering (the first method's mean gap per factor, its rank and Spearman's rho with the
    paper's), so a pooled ordering that one task makes is seen as such."""
    tasks = [t for t in cfg.tasks if any(r["task"] == t for r in rows)]
    if len(tasks) < 2 or len(cfg.shifted_factors()) < 2:
        return []
    method = cfg.methods[0].name
    per_task = analysis.task_orderings
    other_methods = _method_rho_rows_per_task(cfg, rows, tasks)
    lines = [
        f"## Ordering per task ({method})",
        "",
        "Each task's mean gap per factor (over N and seeds) with its 95% bootstrap interval and its rank among the "
        "factors (1 = hardest); the Spearman row is rho with the paper's ranks"
        + (
            f"; below it, each other method's rho and that rho minus {method}'s (one bootstrap of both per task)."
            if other_methods
            else "."
        ),
        "",
        "| factor | " + " | ".join(tasks) + " | paper rank |",
        "|---|" + "---|" * (len(tasks) + 1),
    ]
    intervals = {t: b.intervals() for t, b in per_task.items()}
    ranks = {t: rank_hardest_first({f: v[0] for f, v in intervals[t].items()}) for t in tasks}
    for factor in cfg.shifted_factors():
        cells = []
        for t in tasks:
            found = intervals[t].get(factor)
            cells.append(f"{found[0]:+.3f} {ci(*found[1:])} ({ranks[t][factor]:g})" if found else "n/a")
        paper = PAPER_FACTOR_RANKS.get(factor)
        lines.append(f"| {factor} | " + " | ".join(cells) + f" | {paper if paper is not None else '—'} |")
    rhos = []
    for t in tasks:
        rhos.append(_rho_cell((spearman(ranks[t], PAPER_FACTOR_RANKS), *per_task[t].rho_interval(PAPER_FACTOR_RANKS))))
    lines += ["| Spearman with the paper | " + " | ".join(rhos) + " | |"]
    return lines + other_methods + [""]


def _method_rho_rows_per_task(cfg: StudyConfig, rows: list[dict], tasks: list[str]) -> list[str]:
    """Per method after the first, two rows of the per-task table: its Spearman with the paper and that rho minus
    the first method's, each task's interval from one bootstrap of the two methods on that task's rows, over the
    factors both have there (so whether an augmentation moves the ordering is read per task, not only pooled)."""
    first, *others = [m.name for m in cfg.methods]
    lines = []
    for other in others:
        found = [
            method_rho_differences(
                [r for r in rows if r["task"] == t], [first, other], cfg.shifted_factors(), PAPER_FACTOR_RANKS
            ).get(other)
            for t in tasks
        ]
        if not any(found):
            continue
        own = [_rho_cell(f[0] if f else None) for f in found]
        lines.append(f"| Spearman with the paper, {other} | " + " | ".join(own) + " | |")
        lines.append(f"| {other} minus {first} | " + " | ".join(_rho_cell(f[1] if f else None) for f in found) + " | |")
    return lines


def _rho_cell(interval: tuple[float, float, float] | None) -> str:
    """``+0.55 [+0.31, +0.68]``; ``n/a`` without rows, or where rho is undefined (every gap tied)."""
    if interval is None or math.isnan(interval[0]):
        return "n/a"
    return f"{interval[0]:+.2f} {ci(*interval[1:], digits=2)}"


def _resolved_factors(bootstrap: FactorGapBootstrap, method: str, hardest_first: list[str]) -> list[str]:
    """Which factors' mean gaps the study tells apart: per factor, the easier factors whose difference to it has
    a 95% bootstrap interval above 0, and those it is not resolved from."""
    if len(hardest_first) < 2:
        return []
    differences = bootstrap.differences()
    lines = [
        f"### Which factors are resolved from each other ({method})",
        "",
        "A factor's gap is resolved from another's here when the 95% bootstrap interval of the difference of their "
        "mean gaps (one bootstrap for all factors, so what their cells share is kept) excludes 0. This table describes; "
        "it is not corrected for the many comparisons and has no t-interval over seeds: the verdicts are in "
        "*The paper's claims*.",
        "",
        "| factor (hardest first) | larger than (difference, 95% interval) | not resolved from |",
        "|---|---|---|",
    ]
    both = {**differences, **{(b, a): (-p, -high, -low) for (a, b), (p, low, high) in differences.items()}}
    for factor in hardest_first:
        larger, unresolved = [], []
        for other in (f for f in hardest_first if (factor, f) in both):  # factors with a defined gap
            point, low, high = both[(factor, other)]
            if low > 0:
                larger.append(f"{other} {point:+.3f} {ci(low, high)}")
            elif high >= 0:
                unresolved.append(other)
        lines.append(f"| {factor} | {'; '.join(larger) or '—'} | {', '.join(unresolved) or '—'} |")
    lines.append("")
    return lines


def _gap_table(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    stats = gap_per_factor_and_n(rows)
    if not stats:
        return []
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
    lines += ["", *_partial_methods_note(cfg, rows)]
    return lines


def _partial_methods_note(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    """A line for the averaged tables when a method ran on part of the first method's (task, N, seed) cells: its
    averages are over its own cells, so its row and the first's average different tasks or seeds; the comparisons
    (*Methods against*, the claims) use the cells both have."""
    first = cfg.methods[0].name
    cells_of = {m.name: {(r["task"], r["n_train_envs"], r["seed"]) for r in main_grid(rows) if r["method"] == m.name}
                for m in cfg.methods}  # fmt: skip
    partial = [
        f"{m} on {len(own & cells_of[first])} of {first}'s {len(cells_of[first])} (task, N, seed) cells"
        for m, own in cells_of.items()
        if m != first and own and own != cells_of[first]
    ]
    if not partial:
        return []
    return [
        f"Methods run on part of the grid: {'; '.join(partial)}. Their rows average their own cells, so a row of "
        f"theirs and {first}'s average different tasks or seeds; *Methods against {first}* and the claims compare "
        "them on the cells (task, N, seed, condition) both have.",
        "",
    ]


def _gap_against_n_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    """Each factor's gap at every N with its interval, and its change from the smallest N to the largest."""
    found = {m.name: gap_against_n(rows, m.name, cfg.shifted_factors()) for m in cfg.methods}
    found = {method: g for method, g in found.items() if g is not None}
    if not found:
        return []
    lines = ["## Gap against N (mean gap over tasks and seeds, 95% bootstrap intervals)", ""]
    for method, g in found.items():
        first, last = g.ns[0], g.ns[-1]
        lines += [
            f"{method}: each factor's gap at each N and its change from N={first} to N={last} (the gap at N={last} "
            f"minus the gap at N={first}: negative where more training environments shrink it; section 5.1 says every "
            "gap closes). A larger N may also lower P_T (the success rates below), which caps the gaps.",
            "",
            "| factor | " + " | ".join(f"N={n}" for n in g.ns) + f" | change N={first} -> {last} |",
            "|---|" + "---|" * (len(g.ns) + 1),
        ]
        for label, gaps in g.gaps.items():
            change = g.change[label]
            lines.append(
                f"| {label} | "
                + " | ".join(f"{pm(p, math.nan)} {ci(lo, hi)}" for p, lo, hi in gaps)
                + f" | {pm(change[0], math.nan)} {ci(*change[1:])} |"
            )
        lines.append("")
    return lines


def _methods_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    methods = [m.name for m in cfg.methods]
    labels = {f: (f,) for f in cfg.shifted_factors()}
    labels.update({name: group for name, group in PAPER_FACTOR_GROUPS.items() if set(group) <= set(labels)})
    labels[ALL_FACTORS] = tuple(cfg.shifted_factors())
    found = method_gap_differences(rows, methods, labels)
    if not found:
        return []
    base = methods[0]
    lines = [
        f"## Methods against {base} (mean gap over tasks and N)",
        "",
        f"Each method's mean gap next to {base}'s on the same conditions, and the difference (negative: the method "
        f"shrinks the gap), each with its 95% bootstrap interval. Groups of factors are section 5.2's: "
        + "; ".join(f"{name} = {', '.join(group)}" for name, group in PAPER_FACTOR_GROUPS.items())
        + f". Each method is compared with {base} on the cells (task, N, seed, condition) both have (*cells*: how "
        "many, of both methods' train and shifted conditions). A gap cannot exceed P_T, so a method with a lower P_T "
        "has less gap to lose: read each difference with the P_T table after it.",
        "",
        f"| method | factors | cells | gap of {base} | gap of the method | difference | 95% interval |",
        "|---|---|---|---|---|---|---|",
    ]
    grid = [r for r in rows if r["condition"] in (TRAIN_SUITE, *labels[ALL_FACTORS])]
    for method in methods[1:]:
        shared = shared_cell_count(grid, [base, method])
        for label in labels:
            if (method, label) in found:
                base_gap, gap, diff = found[(method, label)]
                lines.append(
                    f"| {method} | {label} | {shared} | {base_gap[0]:+.3f} | {gap[0]:+.3f} | {diff[0]:+.3f} | "
                    f"{ci(*diff[1:])} |"
                )
    lines.append("")
    return lines + _methods_success_table(base, methods, rows)


def _methods_success_table(base: str, methods: list[str], rows: list[dict]) -> list[str]:
    """Each method's P_T next to the first's on the training cells both have: a gap cannot exceed P_T, so a gap
    difference is read with the P_T difference beside it (a smaller gap with a lower P_T may only be less to lose)."""
    found = method_success_differences(rows, methods)
    if not found:
        return []
    grid = [r for r in main_grid(rows) if r["condition"] == TRAIN_SUITE]
    lines = [
        f"P_T (success on the training environments, mean over tasks and N) of each method next to {base}'s, on the "
        f"train cells (task, N, seed) both have, with the difference (the method minus {base}) and its 95% bootstrap "
        "interval (each cell's episodes resampled on their own, so where both methods played the same episodes a "
        "paired interval would be narrower):",
        "",
        f"| method | train cells | P_T of {base} | P_T of the method | difference | 95% interval |",
        "|---|---|---|---|---|---|",
    ]
    for method, (base_pt, own, diff) in found.items():
        base_text, own_text = (f"{p[0]:.3f} {ci(*p[1:], sign=False)}" for p in (base_pt, own))
        shared = shared_cell_count(grid, [base, method])
        lines.append(f"| {method} | {shared} | {base_text} | {own_text} | {diff[0]:+.3f} | {ci(*diff[1:])} |")
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
        "never succeeds); interaction = gap(A+B) - gap(A) - gap(B). It is given two ways: **per cell** (the "
        "metric of every task x N x seed cell, averaged over tasks and N per seed, then over seeds: the paper's "
        "figure's way, a ratio averaged over cells, heavy-tailed when min(P_A, P_B) is small), and **pooled** "
        "(the metric of success rates pooled over seeds per task x N, averaged over tasks and N). Each with its "
        "95% bootstrap interval.",
        "",
        "A cell (task x N x seed) whose harder factor never succeeded has no pair metric; such cells are "
        "left out of the per-cell mean, and the last two columns count them (per cell, and per task x N cell whose "
        "pooled harder factor never succeeded): a pair with many undefined cells is among the hardest, whatever its "
        "mean says.",
        "",
        "| method | pair | pair metric (per cell) | 95% interval | pooled per task x N [95% interval] | "
        "interaction | cells without a pair metric | pooled cells without one |",
        "|---|---|---|---|---|---|---|---|",
    ]
    cells: dict[tuple, list[bool]] = defaultdict(list)
    for row in pairs:
        cells[(row["method"], row["pair"])].append(math.isnan(row["pair_metric"]))
    tol = PAPER_PAIR_TOLERANCE
    summaries = {method.name: pair_summary(rows, method.name, tol) for method in cfg.methods}
    for method in cfg.methods:
        boot = summaries[method.name]
        for pair in cfg.pair_conditions():
            m = metric.get((method.name, pair))
            i = inter.get((method.name, pair))
            undefined = cells.get((method.name, pair), [])
            if m or i or undefined:
                per_cell = boot.per_cell.get(pair) if boot else None
                pooled = boot.pooled.get(pair) if boot else None
                pooled_undefined = boot.pooled_undefined.get(pair) if boot else None
                lines.append(
                    f"| {method.name} | {pair} | {pm(*m[:2]) if m else 'n/a'} | "
                    f"{ci(*per_cell[1:]) if per_cell else '[n/a]'} | "
                    f"{pm(pooled[0], math.nan) + ' ' + ci(*pooled[1:]) if pooled else 'n/a'} | "
                    f"{pm(*i[:2]) if i else 'n/a'} | {sum(undefined)} of {len(undefined)} | "
                    + (f"{pooled_undefined[0]} of {pooled_undefined[1]}" if pooled_undefined else "n/a")
                    + " |"
                )
    first = cfg.methods[0].name
    boot = summaries[first]
    lines.append("")
    if boot:
        within, low, high = boot.within_per_cell
        p_within, p_low, p_high = boot.within_pooled
        lines += [
            f"{within:.0f} of {boot.pairs_per_cell} pairs lie within ±{tol:.0%} for {first} with the per-cell metric "
            f"(95% bootstrap interval of the count: {low:.0f}-{high:.0f}); {p_within:.0f} of {boot.pairs_pooled} "
            f"with the pooled one ({p_low:.0f}-{p_high:.0f}). Paper: {PAPER_PAIRS_WITHIN}. Resampling adds noise "
            "that moves metrics out of the band, so the count's interval leans below its point.",
            "",
        ]
    bands = pair_bands(rows, first, tol)
    if len(bands) > 1:  # a task where single factors barely matter can hide one where pairs compound
        lines += [
            f"Per task ({first}, per-cell metric averaged over N and seeds): "
            + "; ".join(
                f"{task} {b.within} of {b.within + b.below + b.above} within ±{tol:.0%} (count's 95% interval "
                f"{_count_range(b.within_interval)}; {b.below} below, {b.above} above; mean interaction "
                f"{b.mean_interaction:+.3f} {ci(*b.interaction_interval)})"
                for task, b in bands.items()
            )
            + ".",
            "",
        ]
    return lines


def _renders_at_another_quality(cfg: StudyConfig) -> bool:
    """Whether a scene of the study renders at a quality other than the default: a collection, or a given
    checkpoint with Factor World's observation (LeRobot's renders at Meta-World's own)."""
    renders = cfg.trained_methods() or any(m.obs == FACTORWORLD_OBS for m in cfg.given_methods())
    return bool(renders) and cfg.collect.other_quality is not None


def _count_range(interval: tuple[float, float]) -> str:
    """A count's 95% interval as ``1-9`` (``n/a`` without one)."""
    low, high = interval
    return "n/a" if math.isnan(low) or math.isnan(high) else f"{low:.0f}-{high:.0f}"


def _radius_section(cfg: StudyConfig, rows: list[dict]) -> list[str]:
    if not cfg.radius_factors or not radius_rows(rows, cfg.radius_factors):
        return []
    stats = gap_per_radius(rows, cfg.radius_factors)
    slopes = radius_slopes(rows, cfg.radius_factors)
    radii = sorted({k[2] for k in stats})
    step = f"{RADIUS_STEP_M:g} m"
    lines = [
        "## Gap versus radius (mean ± SE over seeds, averaged over tasks and N)",
        "",
        f"Slope: least-squares slope of the mean gap on the radius, per {step} (one step of the appendix's radii), "
        "with its 95% bootstrap interval.",
        "",
        "| method | factor | " + " | ".join(f"{r:g} m" for r in radii) + f" | slope per {step} [95% interval] |",
        "|---|---|" + "---|" * (len(radii) + 1),
    ]
    for method in cfg.methods:
        for factor in cfg.radius_factors:
            cells = [stats.get((method.name, factor, r)) for r in radii]
            slope = slopes.get((method.name, factor))
            slope_text = (
                f"{pm(slope[0] * RADIUS_STEP_M, math.nan)} {ci(slope[1] * RADIUS_STEP_M, slope[2] * RADIUS_STEP_M)}"
                if slope
                else "n/a"
            )
            lines.append(
                f"| {method.name} | {factor} | "
                + " | ".join(pm(*c[:2]) if c else "n/a" for c in cells)
                + f" | {slope_text} |"
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
    lines += ["", *_partial_methods_note(cfg, rows)]
    return lines


def _per_task_table(cfg: StudyConfig, rows: list[dict], analysis: StudyAnalysis) -> list[str]:
    """Success per task and N of the main grid's train and single-factor conditions, pooled over seeds."""
    conditions = [TRAIN_SUITE, *cfg.factors]
    pooled = analysis.per_task_success
    if not pooled:
        return []
    seeds = len({r["seed"] for r in rows})
    lines = [
        f"## Success per task and N, pooled over the {seeds} seed(s)",
        "",
        "Successes / episodes pooled over training seeds, success rate with a 95% interval that accounts for the "
        "pooling: the seed-level bootstrap's, widened where needed to contain the Wilson interval of the pooled "
        "episodes (with one seed: the Wilson interval).",
        "",
        "| method | task | N | " + " | ".join(conditions) + " |",
        "|---|---|---|" + "---|" * len(conditions),
    ]
    for method in cfg.methods:
        for task in cfg.tasks:
            for n in cfg.n_train_envs:
                cells = [pooled.get((method.name, task, n, c)) for c in conditions]
                if not any(cells):
                    continue
                lines.append(
                    f"| {method.name} | {task} | {n} | "
                    + " | ".join(
                        f"{c[0]}/{c[1]} {c[0] / c[1]:.2f} {ci(c[2], c[3], digits=2, sign=False)}" if c else "n/a"
                        for c in cells
                    )
                    + " |"
                )
    lines.append("")
    return lines


def stages_note(names: Iterable[str] = ()) -> str:
    """The note above the "Where episodes fail" tables; ``names``: the stages they show (the pick family's
    ``reached_other`` is explained only in a report that has it)."""
    other = "reached_other: the gripper went to another object and lifted nothing; " if "reached_other" in names else ""
    return (
        "Every evaluated episode ends at the furthest stage it reached, judged from the task's own Meta-World "
        "quantities (docs/study.md, *Where episodes fail*): object tasks none < reached < grasped < moved < "
        f"succeeded, articulated tasks none < reached < moved < succeeded (the pick family adds {other}wrong_object: "
        "another object lifted first). A stage counts when its own test held at some step, so an episode may skip "
        "one (the pick-place expert slides the puck to its goal without lifting it: reached, then moved). Each row "
        "gives the share of its episodes ending at each stage, pooled over seeds (main grid), the `train` condition "
        "first: a gap shows as episodes ending at earlier stages."
    )


def _stages_section(cfg: StudyConfig, analysis: StudyAnalysis) -> list[str]:
    """Where episodes fail: per method x task x N x condition, the share of episodes by furthest stage, one
    table per list of stages (tasks of one kind share a table); nothing when no row has stage counts."""
    counts = analysis.stage_counts
    if not counts:
        return []
    tables = stage_tables(cfg, counts)
    note = stages_note(name for names in tables for name in names)
    lines = ["## Where episodes fail (share of episodes by the furthest stage reached)", "", note, ""]
    for names, table_keys in tables.items():
        lines += [
            "| method | task | N | condition | episodes | " + " | ".join(names) + " |",
            "|---|---|---|---|---|" + "---|" * len(names),
        ]
        lines += [stage_row(key, counts[key], names) for key in table_keys]
        lines.append("")
    return lines


def stage_tables(cfg: StudyConfig, counts: Mapping[tuple, Mapping[str, int]]) -> dict[tuple[str, ...], list[tuple]]:
    """The rows of the "Where episodes fail" tables: per list of stage names (tasks of one kind share one), the
    keys (method, task, N, condition) of ``aggregate.stage_counts`` in the report's order, ``train`` first."""
    order = [TRAIN_SUITE, *cfg.conditions()]
    conditions = [*order, *(c for c in dict.fromkeys(k[3] for k in counts) if c not in order)]
    keys = [
        (method.name, task, n, condition)
        for method in cfg.methods
        for task in dict.fromkeys([*cfg.tasks, *(k[1] for k in counts)])
        for n in cfg.n_train_envs
        for condition in conditions
        if (method.name, task, n, condition) in counts
    ]
    tables: dict[tuple[str, ...], list[tuple]] = defaultdict(list)  # stage names -> the keys of its rows
    for key in keys:
        tables[tuple(counts[key])].append(key)
    return dict(tables)


def stage_row(key: tuple, counts: dict[str, int], names: Sequence[str]) -> str:
    """A stage table's row: ``key``'s cells, the episodes, and their share at each of ``names``."""
    total = sum(counts.values())
    shares = " | ".join(f"{counts.get(name, 0) / total:.2f}" for name in names)
    return "| " + " | ".join(str(k) for k in key) + f" | {total} | {shares} |"
