"""``report.html``: the study's answer in one self-contained folder that opens from disk (no server, no network)
and can be pushed to the Hub as it is: each factor's gap with its 95% interval (pooled and per task, the paper's
rank beside it), the paper's claims with their verdicts, where episodes fail, success rates, the learning curve
where the study has one (``curve.csv``), and a viewer that
plays episode ``i`` under ``train`` and under a shift side by side, in sync (``episodes/episodes.json``,
``episode_videos.py``).

Every number comes from the rows of ``results.csv`` through the selectors that report.md's tables use
(``aggregate.py``), and its tables' cells through report.md's own helpers, so the two say the same. The figures
are Plotly's, drawing with ``plotly.min.js`` written once next to the page (:func:`write_plotly_js`); the page
is the small template of ``html_page.py``. The page is deterministic (fixed figure ids, no timestamps): a
report regenerated from committed files is byte for byte the committed one.
"""

from __future__ import annotations

import functools
import html
import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ...core.io import atomic_write_text
from ...protocol.conditions import TRAIN_SUITE
from ...stats.bootstrap import BOOTSTRAP_RESAMPLES
from ...stats.ranks import rank_hardest_first
from ..analysis.study import StudyAnalysis
from ..paper import PAPER_FACTOR_RANKS
from ..plan.config import StudyConfig
from ..results.aggregate import (
    Interval,
    factor_ordering,
)
from ..results.claims import ClaimVerdict
from ..results.curve import CURVE_FILE, pooled_curve
from ..results.rows import RESULTS_FILE
from ..run.recording import VIDEOS_DIR
from .claims_markdown import CLAIM_COLUMNS, COMPARISON_COLUMNS, claim_rows, comparison_rows
from .episode_videos import MANIFEST
from .html_page import PAGE, STYLE, VIEWER_HTML, VIEWER_JS
from .markdown import ORDERING_COLUMNS, ci, ordering_rows, stage_tables, stages_note

HTML_FILE = "report.html"
PLOTLY_JS = "plotly.min.js"  # next to the page; the page loads it by this relative name
INTERVAL_CAPTION = (
    f"95% intervals: the seed-level bootstrap ({BOOTSTRAP_RESAMPLES} resamples of training seeds, then of "
    "episodes within each cell), as report.md's tables print them"
)
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22")
STAGE_COLOURS = {
    "none": "#b03a2e",
    "reached_other": "#c39bd3",
    "wrong_object": "#7d3c98",
    "reached": "#e67e22",
    "grasped": "#f4d03f",
    "moved": "#5dade2",
    "succeeded": "#229954",
}
NO_EPISODES = (
    "No recorded episodes next to this report (<code>{videos}/{manifest}</code>). A study's evaluations keep the "
    "frames of their first <code>eval.record_episodes</code> episodes per condition (default 3; 0 turns it off) "
    "and its report gathers them into <code>{videos}/</code>: run the study (or <code>factorworld profile</code>) "
    "again with <code>--eval.record_episodes=3</code>. An evaluation cached without videos keeps none (frames are "
    "not in a step's key): run it in a fresh <code>out_dir</code>, or remove its step folder, to record them."
)


@dataclass(frozen=True)
class StoppingTable:
    """An ``eval.episodes=auto`` evaluation's stopping table for the page: its note, columns and cells."""

    note: str
    columns: Sequence[str]
    cells: Sequence[Sequence[str]]


def write_html_report(
    cfg: StudyConfig,
    rows: Sequence[dict],
    out_dir: str | Path,
    analysis: StudyAnalysis,
    curve: Sequence[dict] = (),
    stopping: StoppingTable | None = None,
) -> Path:
    """Write ``out_dir/report.html`` (and ``plotly.min.js`` where the folder has no copy of it) from ``results.csv``
    rows, their analysis (``analysis.study.analyze``: the intervals and claims report.md prints too) and the learning curve's points (``curve.csv``'s
    rows; none: no such section); the viewer reads ``out_dir/episodes/``. With ``stopping`` (an
    ``eval.episodes=auto`` evaluation), the page shows how each condition stopped, where episodes fail and the
    paired episodes only: every other section rests on fixed-n intervals, which that stopping invalidates."""
    out_dir = Path(out_dir)
    rows = list(rows)
    if stopping is not None:
        sections = [
            ("stopping", "How each condition stopped",
             _p(stopping.note) + _table(stopping.columns, stopping.cells, numeric=(4, 6, 7, 8, 9))),
            ("stages", "Where episodes fail", _stages_section(cfg, analysis)),
            ("episodes", "Paired episodes", _viewer_section(out_dir)),
        ]  # fmt: skip
    else:
        sections = [
            ("gaps", "Each factor's gap", _gap_section(cfg, rows, analysis)),
            ("claims", "The paper's claims", _claims_section(analysis.verdicts)),
            ("stages", "Where episodes fail", _stages_section(cfg, analysis)),
            ("success", "Success rates", _success_section(cfg, analysis)),
            *([("curve", "Learning curve", _curve_section(curve))] if curve else []),
            ("episodes", "Paired episodes", _viewer_section(out_dir)),
        ]
    entries = _episodes(out_dir)
    page = PAGE.format(
        title=_e(f"Study {cfg.name}"),
        style=STYLE,
        plotly_js=PLOTLY_JS,
        lead=_lead(cfg, rows),
        nav="".join(f'<a href="#{anchor}">{_e(title)}</a>' for anchor, title, _ in sections),
        sections="\n".join(
            f'<section id="{anchor}">\n<h2>{_e(title)}</h2>\n{body}\n</section>' for anchor, title, body in sections
        ),
        viewer_data=(
            '<script type="application/json" id="episodes-data">' + _json(entries) + "</script>" if entries else ""
        ),
        viewer_js=VIEWER_JS if entries else "",
    )
    write_plotly_js(out_dir)
    return atomic_write_text(out_dir / HTML_FILE, page)


def write_plotly_js(folder: Path) -> Path:
    """``plotly.min.js`` of the installed Plotly in ``folder``, written only when the folder has no identical copy
    (a link to one counts: ``factorworld sync-docs`` links the committed reports to one shared copy)."""
    from plotly.offline import get_plotlyjs  # noqa: PLC0415 - a 4.8 MB string, read only to write a report

    path = folder / PLOTLY_JS
    bundle = get_plotlyjs()
    if not (path.is_file() and path.read_text(encoding="utf-8") == bundle):
        atomic_write_text(path, bundle)
    return path


# --- the sections ---------------------------------------------------------------------------------------


def _lead(cfg: StudyConfig, rows: Sequence[dict]) -> str:
    return _e(
        f"Methods {', '.join(m.name for m in cfg.methods)}; tasks {', '.join(cfg.tasks)}; N {cfg.n_train_envs}; "
        f"seeds {cfg.seeds}; {len(rows)} evaluations. Every number comes from {RESULTS_FILE} next to this file, "
        "through the computations of report.md (whose tables give more)."
    )


def _gap_section(cfg: StudyConfig, rows: Sequence[dict], analysis: StudyAnalysis) -> str:
    if not rows or not cfg.factors:
        return _p("No factor was evaluated: this study has no gaps.")
    method = cfg.methods[0].name
    gaps = factor_ordering(rows, method, cfg.factors)
    if not gaps:
        return _p("No gap is defined yet (no shifted condition has its train cell).")
    pooled = analysis.gap_bootstraps[method]
    intervals = pooled.intervals()
    ranks = rank_hardest_first({f: v[0] for f, v in gaps.items()})
    factors = sorted(gaps, key=lambda f: ranks.get(f, 99))
    series = {"all tasks": {f: (gaps[f][0], *intervals[f][1:]) for f in factors if f in intervals}}
    tasks = [t for t in cfg.tasks if any(r["task"] == t for r in rows)]
    if len(tasks) > 1:
        for task, b in analysis.task_orderings.items():
            series[task] = b.intervals()
    labels = [f"{f} · paper {PAPER_FACTOR_RANKS[f]:g}" if f in PAPER_FACTOR_RANKS else f for f in factors]
    figure = _interval_figure(
        "gap-figure",
        factors,
        labels,
        series,
        axis="gap P_T - P_F (mean over N and seeds), 95% interval",
        horizontal=True,
    )
    if len(tasks) > 1:
        whose = (
            "black: all tasks pooled, then each task; pooled: the *Factor ordering* table's, per task: the "
            "*Ordering per task* table's"
        )
    else:
        whose = "the *Factor ordering* table's"
    caption = (
        f"{method}: each factor's mean gap over tasks and N, hardest first, with the paper's rank beside its name "
        f"(1 = hardest). Bars: {INTERVAL_CAPTION} ({whose})."
    )
    parts = [_figure(figure, caption), _table(ORDERING_COLUMNS, ordering_rows(gaps, pooled), numeric=(1, 2, 3, 4))]
    others = {m.name: analysis.gap_bootstraps[m.name].intervals() for m in cfg.methods[1:]}
    others = {name: found for name, found in others.items() if found}
    if others:
        by_method = {method: intervals, **others}
        figure = _interval_figure(
            "methods-figure",
            factors,
            labels,
            by_method,
            axis="gap P_T - P_F (mean over tasks, N and seeds), 95% interval",
            horizontal=True,
        )
        parts.append(
            _figure(figure, f"Each method's mean gap per factor, in {method}'s order. Bars: {INTERVAL_CAPTION}.")
        )
    return "\n".join(parts)


def _claims_section(verdicts: Sequence[ClaimVerdict]) -> str:
    if not verdicts:
        return _p("This study tests none of the paper's claims.")
    claims = [(*row[:4], _verdict(row[4]), row[5]) for row in claim_rows(verdicts)]
    parts = [
        _p(
            "Each claim is decided at 95% with Holm's correction over its finding's comparisons, on the hull of the "
            "seed-level bootstrap and a t-interval over training seeds: <b>agrees</b> / <b>disagrees</b> when the "
            "interval lies on the paper's / the other side, <b>confounded (P_T fell)</b> when a gap shrank only as "
            "success fell, <b>capped</b> when the success rates leave less room either way than the design resolves, "
            "<b>not resolved</b> otherwise (report.md says more).",
            escape=False,
        ),
        _table(CLAIM_COLUMNS, claims, numeric=(2, 3), raw=(4,)),
    ]
    comparisons = [(*row[:4], _verdict(row[4]), row[5]) for row in comparison_rows(verdicts)]
    if comparisons:
        parts.append(
            "<details><summary>Every comparison behind the claims</summary>\n"
            + _table(COMPARISON_COLUMNS, comparisons, numeric=(1, 2, 3), raw=(4,))
            + "</details>"
        )
    return "\n".join(parts)


def _stages_section(cfg: StudyConfig, analysis: StudyAnalysis) -> str:
    counts = analysis.stage_counts
    if not counts:
        return _p("No evaluation of this study recorded its episodes' stages.")
    tables = stage_tables(cfg, counts)
    parts = [_p(stages_note(name for names in tables for name in names))]
    for number, (names, keys) in enumerate(tables.items()):
        labels = [f"{m} · {t} · N={n} · {c}" for m, t, n, c in keys]
        traces = []
        for j, name in enumerate(names):
            shares, hover = [], []
            for key in keys:
                total = sum(counts[key].values())
                shares.append(counts[key].get(name, 0) / total)
                hover.append(f"{name}: {counts[key].get(name, 0)} of {total} episodes")
            traces.append(
                {
                    "type": "bar",
                    "orientation": "h",
                    "name": name,
                    "y": labels,
                    "x": shares,
                    "hovertext": hover,
                    "hoverinfo": "text+y",
                    "marker": {"color": STAGE_COLOURS.get(name, PALETTE[j % len(PALETTE)])},
                }
            )
        layout = {
            "barmode": "stack",
            "xaxis": {"title": {"text": "share of episodes by the furthest stage reached"}, "range": [0, 1]},
            "yaxis": {"autorange": "reversed", "automargin": True},
            "legend": {"orientation": "h", "y": 1.02, "yanchor": "bottom", "traceorder": "normal"},
        }
        parts.append(_figure(_plotly(f"stages-figure-{number}", traces, layout, 26 * len(keys) + 130), ""))
    return "\n".join(parts)


def _success_section(cfg: StudyConfig, analysis: StudyAnalysis) -> str:
    pooled = analysis.per_task_success
    if not pooled:
        return _p("No evaluation has finished yet.")
    conditions = [c for c in (TRAIN_SUITE, *cfg.factors) if any(k[3] == c for k in pooled)]
    series: dict[str, dict[str, Interval]] = {}
    hover: dict[str, dict[str, str]] = {}
    for method, task, n, condition in pooled:
        k, total, low, high = pooled[(method, task, n, condition)]
        name = f"{method} · {task} · N={n}"
        series.setdefault(name, {})[condition] = (k / total, low, high)
        hover.setdefault(name, {})[condition] = f"{k}/{total} = {k / total:.2f} {ci(low, high, digits=2, sign=False)}"
    figure = _interval_figure(
        "success-figure",
        conditions,
        conditions,
        series,
        axis="success rate (pooled over seeds), 95% interval",
        hover=hover,
    )
    caption = (
        "Success rate per condition (<code>train</code>: the training environments) of each method, task and N, "
        "pooled over seeds, with the 95% intervals of report.md's <i>Success per task and N</i> table: the "
        "seed-level bootstrap's, widened to contain the Wilson interval of the pooled episodes (with one seed: "
        "Wilson's)."
    )
    return _figure(figure, caption, escape=False)


def _curve_section(curve: Sequence[dict]) -> str:
    """P_T against epochs on a numeric axis (curves of methods saving at other epochs stay to scale), one line
    per method and task, each point with the *Learning curve* table's Wilson interval as its error bar."""
    lines: dict[tuple[str, str], list[dict]] = {}  # pooled once, then grouped per method and task
    for point in pooled_curve(curve):
        lines.setdefault((point["method"], point["task"]), []).append(point)
    traces = []
    for j, ((method, task), points) in enumerate(lines.items()):
        rates = [p["success_rate"] for p in points]
        colour = PALETTE[j % len(PALETTE)]
        traces.append({
            "type": "scatter",
            "mode": "lines+markers",
            "name": f"{method} · {task}",
            "x": [p["epochs"] for p in points],
            "y": rates,
            "line": {"color": colour, "width": 2},
            "marker": {"color": colour, "size": 8},
            "error_y": {
                "type": "data",
                "symmetric": False,
                "array": [p["ci_high"] - r for p, r in zip(points, rates)],
                "arrayminus": [r - p["ci_low"] for p, r in zip(points, rates)],
                "color": colour,
            },
            "hovertext": [
                f"{p['epochs']:g} epochs: {p['successes']}/{p['episodes']} = {r:.2f} "
                f"{ci(p['ci_low'], p['ci_high'], digits=2, sign=False)}"
                for p, r in zip(points, rates)
            ],
            "hoverinfo": "text+name",
        })  # fmt: skip
    layout = {
        "xaxis": {"title": {"text": "training epochs"}, "rangemode": "tozero"},
        "yaxis": {"title": {"text": "P_T (pooled), 95% interval"}, "range": [-0.05, 1.05]},
        "legend": {"orientation": "h", "y": 1.02, "yanchor": "bottom"},
    }
    caption = (
        "P_T (success on the training environments) of each checkpoint the training saved, per method and task, "
        f"pooled over N and seeds, with the Wilson 95% intervals of report.md's <i>Learning curve</i> table "
        f"(<code>{CURVE_FILE}</code>); report.md gives each checkpoint against the one before and each method "
        "against the first."
    )
    return _figure(_plotly("curve-figure", traces, layout, 420), caption, escape=False)


def _viewer_section(out_dir: Path) -> str:
    if not _episodes(out_dir):
        return _p(NO_EPISODES.format(videos=VIDEOS_DIR, manifest=MANIFEST), escape=False)
    return VIEWER_HTML


# --- pieces -------------------------------------------------------------------------------------------


def _episodes(out_dir: Path) -> list[dict]:
    path = out_dir / VIDEOS_DIR / MANIFEST
    return json.loads(path.read_text()) if path.is_file() else []


def _interval_figure(
    div_id: str,
    keys: Sequence[str],
    labels: Sequence[str],
    series: dict[str, dict[str, Interval]],
    axis: str,
    horizontal: bool = False,
    hover: dict[str, dict[str, str]] | None = None,
) -> str:
    """Per series, a point per key with its interval drawn from its low to its high end (exact where a percentile
    interval is not centred on its point); series side by side at each key."""
    traces = []
    width = 0.7 / max(1, len(series))
    for j, (name, found) in enumerate(series.items()):
        shown = [i for i, key in enumerate(keys) if key in found]
        pos = [i + (j - (len(series) - 1) / 2) * width for i in shown]
        points = [found[keys[i]] for i in shown]
        colour = "#111111" if name == "all tasks" else PALETTE[j % len(PALETTE)]
        text = [
            (hover or {}).get(name, {}).get(keys[i]) or f"{keys[i]}: {p[0]:+.3f} {ci(p[1], p[2])}"
            for i, p in zip(shown, points)
        ]
        segment_a, segment_b = [], []
        for at, (_, low, high) in zip(pos, points):
            segment_a += [low, high, None]
            segment_b += [at, at, None]
        centre = [p[0] for p in points]
        cap = {
            "symbol": "line-ns-open" if horizontal else "line-ew-open",
            "size": 9,
            "line": {"width": 2, "color": colour},
        }
        line = {
            "type": "scatter",
            "mode": "lines+markers",
            "line": {"color": colour, "width": 2},
            "marker": cap,
            "hoverinfo": "skip",
        }
        mark = {"type": "scatter", "mode": "markers", "marker": {"color": colour, "size": 8}, "name": name}
        if horizontal:
            line.update(x=segment_a, y=segment_b)
            mark.update(x=centre, y=pos)
        else:
            line.update(x=segment_b, y=segment_a)
            mark.update(x=pos, y=centre)
        traces += [
            {**line, "legendgroup": name, "showlegend": False},
            {**mark, "legendgroup": name, "hovertext": text, "hoverinfo": "text+name"},
        ]
    ticks = {"tickmode": "array", "tickvals": list(range(len(keys))), "ticktext": list(labels), "automargin": True}
    value = {"title": {"text": axis}, "zeroline": True, "zerolinecolor": "#888888"}
    if horizontal:
        layout = {"xaxis": value, "yaxis": {**ticks, "autorange": "reversed"}}
        height = max(260, 34 * len(keys) * max(1, len(series)) ** 0.5 + 120)
    else:
        layout = {"yaxis": value, "xaxis": {**ticks, "tickangle": -30}}
        height = 420
    layout["legend"] = {"orientation": "h", "y": 1.02, "yanchor": "bottom"}
    return _plotly(div_id, traces, layout, int(height))


def _plotly(div_id: str, traces: list[dict], layout: dict, height: int) -> str:
    """A Plotly figure as an HTML fragment with a fixed id (no plotly.js: the page loads it once). The figure is
    written as the dict ``go.Figure(...).to_dict()`` gives (keys sorted, a trace's ``type`` last, the template
    expanded), without building the figure: Plotly's validation of every property took most of a report's time."""
    import plotly.io as pio  # noqa: PLC0415 - deliberately here: only writing report.html needs Plotly

    layout = {**_sorted_keys({"margin": {"t": 40, "r": 20}, **layout}), "template": _plotly_template()}
    figure = {"data": [_plotly_trace(trace) for trace in traces], "layout": dict(sorted(layout.items()))}
    return pio.to_html(
        figure,
        validate=False,
        full_html=False,
        include_plotlyjs=False,
        div_id=div_id,
        default_height=f"{height}px",
        config={"displaylogo": False, "responsive": True},
    )


def _sorted_keys(value: object) -> object:
    """``value`` with every dict's keys in sorted order, as Plotly's ``to_dict`` writes them."""
    if isinstance(value, dict):
        return {key: _sorted_keys(value[key]) for key in sorted(value)}
    if isinstance(value, (list, tuple)):
        return [_sorted_keys(item) for item in value]
    return value


def _plotly_trace(trace: dict) -> dict:
    out = _sorted_keys({k: v for k, v in trace.items() if k != "type"})
    return {**out, "type": trace["type"]}


@functools.cache
def _plotly_template() -> dict:
    """The ``plotly_white`` template, expanded as a figure's ``to_dict`` holds it."""
    import plotly.graph_objects as go  # noqa: PLC0415 - deliberately here: only writing report.html needs Plotly

    return go.Figure(layout={"template": "plotly_white"}).to_dict()["layout"]["template"]


def _figure(body: str, caption: str, escape: bool = True) -> str:
    text = _inline(caption) if escape else caption
    return f"<figure>{body}" + (f"<figcaption>{text}</figcaption>" if caption else "") + "</figure>"


def _table(
    columns: Sequence[str], rows: Sequence[Sequence[str]], numeric: Sequence[int] = (), raw: Sequence[int] = ()
) -> str:
    head = "".join(f"<th>{_e(c)}</th>" for c in columns)
    body = "".join(
        "<tr>"
        + "".join(
            f"<td{' class=num' if i in numeric else ''}>{cell if i in raw else _e(cell)}</td>"
            for i, cell in enumerate(row)
        )
        + "</tr>\n"
        for row in rows
    )
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}</tbody>\n</table>"


def _verdict(verdict: str) -> str:
    return f'<span class="verdict {_verdict_class(verdict)}">{_e(verdict)}</span>'


def _verdict_class(verdict: str) -> str:
    """``not resolved`` -> ``not-resolved``; ``confounded (P_T fell)`` -> ``confounded`` (its first word)."""
    return verdict.split(" (")[0].replace(" ", "-")


def _p(text: str, escape: bool = True) -> str:
    return f'<p class="note">{_inline(text) if escape else text}</p>'


def _inline(text: str) -> str:
    """Text with report.md's inline marks (``*emphasis*``, ```code```) as HTML, the rest escaped."""
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", _e(text))
    return re.sub(r"\*([^*\s][^*]*)\*", r"<i>\1</i>", text)


def _e(text: str) -> str:
    return html.escape(str(text), quote=True)


def _json(value) -> str:
    """JSON safe inside a <script> element."""
    return json.dumps(value, sort_keys=True, separators=(",", ":")).replace("</", "<\\/")
