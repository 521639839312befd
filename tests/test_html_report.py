"""report.html (study/report/html_report.py): written from synthetic results.csv rows and a synthetic episodes.json with
tiny real WebM files, its figures draw the intervals report.md's tables print, its claims are the decided ones,
it is deterministic and self-contained (plotly.min.js next to it, written once), and, in a real headless Chromium
(the system's, driven by Playwright), it loads without console errors, every video loads, and the paired viewer
plays episode i of train and of a shift in sync. And the PNG figures (study/report/plots.py) draw the intervals of the
tables they stand beside, a figure against N only with two or more N, the per-task ordering when tasks disagree."""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from lerobot_factorworld.stats.proportions import wilson_interval
from lerobot_factorworld.study.analysis.study import analyze
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.report.claims_markdown import claim_rows
from lerobot_factorworld.study.report.episode_videos import MANIFEST
from lerobot_factorworld.study.report.html_report import HTML_FILE, PLOTLY_JS, write_html_report, write_plotly_js
from lerobot_factorworld.study.report.markdown import render
from lerobot_factorworld.study.report.published import report_table
from lerobot_factorworld.study.results.aggregate import factor_gap_bootstrap, per_task_success, task_orderings
from lerobot_factorworld.study.results.curve import pooled_curve
from lerobot_factorworld.study.run.recording import VIDEOS_DIR

ROOT = Path(__file__).resolve().parents[1]
FACTORS = ["camera_pos", "table_texture", "light"]
TASKS = ["door-open", "drawer-open"]
EPISODES = 10
# successes of 10 per task and condition at seed 0, N=2; each later seed and the larger N lose one. The two tasks
# rank the factors differently (door-open: camera_pos hardest; drawer-open: table_texture).
SUCCESSES = {
    "door-open": {"train": 9, "camera_pos": 4, "table_texture": 6, "light": 8},
    "drawer-open": {"train": 8, "camera_pos": 7, "table_texture": 2, "light": 7},
}
FPS = 10
FRAMES = {"train": 10, "camera_pos": 16, "light": 13}  # the recorded episodes' lengths, in frames


def _row(task: str, n: int, seed: int, condition: str, k: int, k_train: int) -> dict:
    reached = min(2, EPISODES - k)
    return {
        "study": "synthetic",
        "method": "bc",
        "policy": "bc",
        "task": task,
        "n_train_envs": n,
        "seed": seed,
        "widths": "default",
        "condition": condition,
        "n_factors": 0 if condition == "train" else 1,
        "radius_m": None,
        "n_envs": n if condition == "train" else 10,
        "episodes": EPISODES,
        "successes": k,
        "success_rate": k / EPISODES,
        "ci_low": 0.0,
        "ci_high": 1.0,
        "train_success_rate": k_train / EPISODES,
        "gap": (k_train - k) / EPISODES,
        "gap_ci_low": -1.0,
        "gap_ci_high": 1.0,
        "envs_visited": n if condition == "train" else 10,
        "fingerprint": "f",
        "stages": f"none:{EPISODES - k - reached};reached:{reached};moved:0;succeeded:{k}",
        "step": f"{task}-{n}-{seed}-{condition}",
        "commit": "",
        "source_hash": "",
    }


def synthetic_study() -> tuple[StudyConfig, list[dict]]:
    cfg = StudyConfig(
        name="synthetic",
        tasks=TASKS,
        seeds=[0, 1],
        n_train_envs=[2, 5],
        factors=FACTORS,
        methods=[MethodConfig("bc", {"type": "bc"})],
    )
    rows = []
    for task in TASKS:
        for n in cfg.n_train_envs:
            for seed in cfg.seeds:
                lost = seed + (n == 5)
                k_train = SUCCESSES[task]["train"] - lost
                for condition, k in SUCCESSES[task].items():
                    rows.append(_row(task, n, seed, condition, k - lost, k_train))
    return cfg, rows


def write_webm(path: Path, frames: int, shade: int) -> None:
    """A tiny real VP9 WebM of 84x84 frames: a white square moving down over a ``shade`` of red."""
    import av

    path.parent.mkdir(parents=True, exist_ok=True)
    with av.open(str(path), "w", format="webm") as container:
        stream = container.add_stream("libvpx-vp9", rate=FPS)
        stream.width, stream.height, stream.pix_fmt = 84, 84, "yuv420p"
        for f in range(frames):
            image = np.zeros((84, 84, 3), np.uint8)
            image[..., 0] = shade
            image[10 + 3 * f : 30 + 3 * f, 20:40] = 255
            for packet in stream.encode(av.VideoFrame.from_ndarray(image, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


def write_episodes(out: Path, indices: int = 2) -> list[dict]:
    """``out/episodes/episodes.json`` as ``episode_videos.collect_videos`` writes it, for two checkpoints (N=2 and
    N=5 of door-open, seed 0): ``train`` and two shifts, episodes 0..indices-1 each, with their WebM files."""
    entries = []
    for n in (2, 5):
        for condition, frames in FRAMES.items():
            for i in range(indices):
                video = f"{VIDEOS_DIR}/n{n}_{condition}_{i:03d}.webm"
                write_webm(out / video, frames, shade=40 * i + 20 * n)
                success = condition == "train"
                entries.append(
                    {
                        "method": "bc",
                        "task": "door-open",
                        "n_train_envs": n,
                        "seed": 0,
                        "widths": "default",
                        "condition": condition,
                        "index": i,
                        "episode_seed": 1000 + i,
                        "success": success,
                        "stage": "succeeded" if success else "reached",
                        "length": frames - 1,
                        "video": video,
                    }
                )
    (out / VIDEOS_DIR / MANIFEST).write_text(json.dumps(entries, indent=1) + "\n")
    return entries


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The synthetic study's report.html with its episodes: (cfg, rows, analysis, folder)."""
    cfg, rows = synthetic_study()
    out = tmp_path_factory.mktemp("html") / "synthetic"
    out.mkdir()
    write_episodes(out)
    analysis = analyze(cfg, rows)
    write_html_report(cfg, rows, out, analysis)
    return cfg, rows, analysis, out


def figure(page: str, div_id: str, layout: bool = False):
    """The traces of the Plotly figure ``div_id`` in ``page`` (with ``layout``: and its layout)."""
    call = re.search(rf'Plotly\.newPlot\(\s*"{div_id}",\s*', page)
    decoder = json.JSONDecoder()
    traces, end = decoder.raw_decode(page, call.end())
    if not layout:
        return traces
    return traces, decoder.raw_decode(page, re.compile(r",\s*").match(page, end).end())[0]


def intervals_drawn(traces: list[dict], horizontal: bool) -> dict[str, list[tuple[float, float]]]:
    """Per series (legend name), the (low, high) ends of its interval segments, in order."""
    out = {}
    for line, mark in zip(traces[::2], traces[1::2]):
        ends = line["x"] if horizontal else line["y"]
        out[mark["name"]] = [(ends[i], ends[i + 1]) for i in range(0, len(ends), 3)]
    return out


def table_cells(page: str, after: str) -> list[list[str]]:
    """The body cells of the first <table> after ``after`` in ``page`` (tags stripped, entities unescaped)."""
    import html

    table = page[page.index(after) :]
    table = table[table.index("<tbody>") : table.index("</tbody>")]
    rows = re.findall(r"<tr>(.*?)</tr>", table, re.S)
    return [
        [html.unescape(re.sub(r"<[^>]+>", "", c)) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)] for r in rows
    ]


# --- the page's content ------------------------------------------------------------------------------------


def test_the_gap_figure_and_table_give_the_factor_ordering_tables_intervals_pooled_and_per_task(study):
    cfg, rows, analysis, out = study
    page = (out / HTML_FILE).read_text()
    traces, layout = figure(page, "gap-figure", layout=True)
    drawn = intervals_drawn(traces, horizontal=True)
    pooled = factor_gap_bootstrap(rows, "bc", FACTORS).intervals()
    order = ["table_texture", "camera_pos", "light"]  # hardest first: pooled gaps 0.45, 0.3, 0.1
    assert drawn["all tasks"] == [pooled[f][1:] for f in order]
    for task, b in task_orderings(rows, "bc", FACTORS, TASKS).items():
        assert drawn[task] == [b.intervals()[f][1:] for f in order]
    assert set(drawn) == {"all tasks", *TASKS}
    # the table beside it is report.md's Factor ordering table, cell for cell (the paper's rank included)
    report = render(cfg, rows, [], "test", len(rows), analysis=analysis)
    markdown = [
        [c.strip() for c in line.strip("|").split("|")]
        for line in report_table(report, "Factor ordering").splitlines()[2:]
    ]
    assert table_cells(page, 'id="gaps"') == markdown
    assert [(r[0], r[3], r[4]) for r in markdown] == [
        ("table_texture", "1.0", "3.5"),
        ("camera_pos", "2.0", "1.5"),
        ("light", "3.0", "6.5"),
    ]
    ticks = ["table_texture · paper 3.5", "camera_pos · paper 1.5", "light · paper 6.5"]
    assert layout["yaxis"]["ticktext"] == ticks
    assert "seed-level bootstrap" in page


def test_the_claims_are_the_decided_ones_and_report_md_prints_the_same(study):
    cfg, rows, analysis, out = study
    page = (out / HTML_FILE).read_text()
    verdicts = list(analysis.verdicts)
    assert verdicts, "the synthetic study tests the paper's ordering"
    cells = table_cells(page, 'id="claims"')
    assert cells == [list(row) for row in claim_rows(verdicts)]
    report = render(cfg, rows, [], "test", len(rows), analysis=analysis)
    for row in claim_rows(verdicts):
        assert f"| **{row[4]}** |" in report


def test_stages_and_success_rates_are_the_report_tables(study):
    cfg, rows, _, out = study
    page = (out / HTML_FILE).read_text()
    stages = figure(page, "stages-figure-0")
    assert [t["name"] for t in stages] == ["none", "reached", "moved", "succeeded"]
    assert np.allclose(np.sum([t["x"] for t in stages], axis=0), 1.0)
    assert len(stages[0]["y"]) == len(rows) // len(cfg.seeds)  # one bar per method x task x N x condition
    assert stages[0]["y"][0] == "bc · door-open · N=2 · train"
    success = intervals_drawn(figure(page, "success-figure"), horizontal=False)
    pooled = per_task_success(rows, FACTORS)
    for task in TASKS:
        for n in cfg.n_train_envs:
            expected = [pooled[("bc", task, n, c)][2:] for c in ("train", *FACTORS)]
            assert success[f"bc · {task} · N={n}"] == expected
    assert sum(len(v) for v in success.values()) == len(pooled)


def test_the_viewer_inlines_episodes_json_and_every_video_is_next_to_the_page(study):
    _, _, _, out = study
    page = (out / HTML_FILE).read_text()
    data = page.split('<script type="application/json" id="episodes-data">')[1].split("</script>")[0]
    entries = json.loads(data)
    assert entries == json.loads((out / VIDEOS_DIR / MANIFEST).read_text())
    assert all((out / e["video"]).stat().st_size > 100 for e in entries)
    assert page.count("<video ") == 2 and "image-rendering: pixelated" in page


def test_without_episodes_the_viewer_says_how_to_record_them(study, tmp_path):
    cfg, rows, analysis, _ = study
    page = write_html_report(cfg, rows, tmp_path, analysis).read_text()
    viewer = page.split('<section id="episodes">')[1]
    assert "<video" not in page and "episodes-data" not in page
    assert "eval.record_episodes" in viewer and "episodes/episodes.json" in viewer


def test_a_learning_curve_is_drawn_with_the_report_tables_intervals_and_only_where_there_is_one(study, tmp_path):
    """Two seeds' points of one checkpoint pool into one (as report.md's *Learning curve* table pools them), each
    point with that table's Wilson interval; a study without a curve has no such section."""
    cfg, rows, analysis, _ = study
    curve = [
        {"method": "bc", "task": "door-open", "epochs": e, "successes": k, "episodes": 10}
        for e, k in [(5, 2), (5, 4), (10, 9)]
    ]
    page = write_html_report(cfg, rows, tmp_path, analysis, curve).read_text()
    assert '<a href="#curve">Learning curve</a>' in page
    (line,) = figure(page, "curve-figure")
    ends = [
        (y - minus, y + plus)
        for y, minus, plus in zip(line["y"], *(line["error_y"][k] for k in ("arrayminus", "array")))
    ]
    assert line["name"] == "bc · door-open" and line["x"] == [5, 10]  # epochs to scale, not categories
    assert np.allclose(ends, [(p["ci_low"], p["ci_high"]) for p in pooled_curve(curve)])
    assert ends[0] == pytest.approx(wilson_interval(6, 20))
    assert 'id="curve"' not in write_html_report(cfg, rows, tmp_path / "none", analysis).read_text()


def test_the_page_is_deterministic_loads_nothing_from_the_network_and_writes_plotly_js_once(study, tmp_path):
    cfg, rows, analysis, _ = study
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first = write_html_report(cfg, rows, tmp_path / "a", analysis)
    second = write_html_report(cfg, rows, tmp_path / "b", analysis)
    assert first.read_bytes() == second.read_bytes()
    page = first.read_text()
    assert not re.search(r"""(src|href)=["']?(https?:)?//""", page), "the page loads something from the network"
    assert f'<script src="{PLOTLY_JS}"></script>' in page
    from plotly.offline import get_plotlyjs

    js = tmp_path / "a" / PLOTLY_JS
    assert js.read_text() == get_plotlyjs()
    # a folder whose plotly.min.js is a link to an identical copy keeps the link; a stale copy is replaced
    shared = tmp_path / "shared.js"
    shutil.copyfile(js, shared)
    js.unlink()
    js.symlink_to(os.path.relpath(shared, js.parent))
    write_plotly_js(tmp_path / "a")
    assert js.is_symlink()
    js.unlink()
    js.write_text("old plotly")
    write_plotly_js(tmp_path / "a")
    assert not js.is_symlink() and js.read_text() == get_plotlyjs()


def test_render_report_writes_report_html_and_decides_the_claims_once(monkeypatch, tmp_path):
    from lerobot_factorworld.study.analysis import study as analysis
    from lerobot_factorworld.study.report.write import render_report

    calls = []
    decide = analysis.decide_together
    monkeypatch.setattr(analysis, "decide_together", lambda *a: calls.append(1) or decide(*a))
    monkeypatch.setattr("lerobot_factorworld.study.report.write.write_plots", lambda rows, cfg, out, analysis: [])
    cfg, rows = synthetic_study()
    report, _ = render_report(cfg, rows, tmp_path, "test", len(rows))
    assert len(calls) == 1
    assert (tmp_path / HTML_FILE).is_file() and (tmp_path / PLOTLY_JS).is_file()
    assert "## The paper's claims" in report.read_text()


@pytest.mark.slow
def test_the_committed_quick_report_html_is_what_its_results_csv_regenerates(tmp_path):
    from plotly.offline import get_plotlyjs

    from lerobot_factorworld.study.report.write import regenerate_report

    folder = ROOT / "docs" / "results" / "quick"
    regenerate_report(folder / "results.csv", out=tmp_path)
    assert (folder / HTML_FILE).read_bytes() == (tmp_path / HTML_FILE).read_bytes()
    js = folder / PLOTLY_JS  # a link to the one shared copy (published.share_plotly_js)
    assert js.is_symlink() and js.resolve() == (ROOT / "docs" / "results" / PLOTLY_JS).resolve()
    assert js.read_text() == get_plotlyjs()


# --- the PNG figures say what the tables say ------------------------------------------------------------------


@pytest.fixture
def drawn_intervals(monkeypatch):
    """Every interval the PNG plots draw, per plot: [(xs, intervals)] of each ``plots.draw_intervals`` call."""
    from lerobot_factorworld.study.report import plots

    calls: dict[str, list] = {}
    draw = plots.draw_intervals

    def record(ax, xs, found, horizontal=False, **style):
        calls.setdefault(record.plot, []).append((list(xs), [tuple(f) for f in found]))
        return draw(ax, xs, found, horizontal, **style)

    monkeypatch.setattr(plots, "draw_intervals", record)
    for name, plotter in list(plots.PLOTTERS.items()):

        def traced(rows, cfg, path, analysis, plotter=plotter, name=name):
            record.plot = name
            return plotter(rows, cfg, path, analysis)

        monkeypatch.setitem(plots.PLOTTERS, name, traced)
    return calls


def test_the_figures_error_bars_are_the_tables_intervals(drawn_intervals, tmp_path):
    from lerobot_factorworld.study.report.plots import CAPTIONS, write_plots
    from lerobot_factorworld.study.results.aggregate import gap_against_n

    cfg, rows = synthetic_study()
    drawn = {p.name for p in write_plots(rows, cfg, tmp_path)}
    assert drawn == {"gap_vs_n.png", "methods.png", "ordering_per_task.png", "success_rates.png"}
    # gap_vs_n.png: the Gap against N table's intervals, per factor and over all factors
    g = gap_against_n(rows, "bc", FACTORS)
    assert [found for _, found in drawn_intervals["gap_vs_n.png"]] == list(g.gaps.values())
    # methods.png: the Factor ordering table's intervals, hardest first
    pooled = factor_gap_bootstrap(rows, "bc", FACTORS).intervals()
    assert drawn_intervals["methods.png"] == [
        ([0, 1, 2], [pooled[f] for f in ("table_texture", "camera_pos", "light")])
    ]
    # ordering_per_task.png: each task's Ordering per task intervals
    per_task = task_orderings(rows, "bc", FACTORS, TASKS)
    assert [found for _, found in drawn_intervals["ordering_per_task.png"]] == [
        [per_task[t].intervals()[f] for f in ("table_texture", "camera_pos", "light")] for t in TASKS
    ]
    # success_rates.png: the Success per task and N table's pooled rates and intervals
    success = per_task_success(rows, FACTORS)
    expected = [
        [(k / n, low, high) for k, n, low, high in (success[("bc", t, nn, c)] for c in ("train", *FACTORS))]
        for t in TASKS
        for nn in cfg.n_train_envs
    ]
    assert [found for _, found in drawn_intervals["success_rates.png"]] == expected
    for name in drawn:
        assert "95%" in CAPTIONS[name] and "table" in CAPTIONS[name]


def test_a_figure_against_n_needs_two_n_and_the_per_task_ordering_a_disagreement(tmp_path):
    from dataclasses import replace

    from lerobot_factorworld.study.report.plots import write_plots

    cfg, rows = synthetic_study()
    one_n = replace(cfg, n_train_envs=[2])
    drawn = {p.name for p in write_plots([r for r in rows if r["n_train_envs"] == 2], one_n, tmp_path)}
    assert "gap_vs_n.png" not in drawn and "methods.png" in drawn
    report = render(one_n, [r for r in rows if r["n_train_envs"] == 2], [], "test", 16)
    assert "gap_vs_n.png (drawn only with two or more N)" in report
    agreeing = [r for r in rows if r["task"] == "door-open"]
    agreeing += [{**r, "task": "drawer-open"} for r in agreeing]  # the same gaps: the same ordering
    drawn = {p.name for p in write_plots(agreeing, cfg, tmp_path)}
    assert "gap_vs_n.png" in drawn and "ordering_per_task.png" not in drawn


# --- in a real browser ---------------------------------------------------------------------------------------

CHROMIUM = shutil.which("chromium")
SYNCED = 0.1  # seconds: how far apart the two videos may be


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="no chromium on the PATH (scripts/setup.sh installs Debian's)")
def test_report_html_in_headless_chromium(study, tmp_path):
    from playwright.sync_api import sync_playwright

    _, _, _, out = study
    errors = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--autoplay-policy=no-user-gesture-required"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto((out / HTML_FILE).as_uri())
            figures = "[...document.querySelectorAll('.plotly-graph-div')]"
            page.wait_for_function(f"{figures}.length === 3 && {figures}.every(d => d.querySelector('.main-svg'))")
            videos = "[...document.querySelectorAll('video')]"
            loaded = f"{videos}.every(v => v.readyState >= 1 && !v.error)"

            # every recorded episode loads its metadata: each checkpoint, shift and index in turn
            cells = page.eval_on_selector_all("#v-cell option", "os => os.map(o => o.value)")
            assert len(cells) == 2 and page.is_visible("#v-cell")
            for cell in cells:
                page.select_option("#v-cell", cell)
                for condition in page.eval_on_selector_all("#v-condition option", "os => os.map(o => o.value)"):
                    page.select_option("#v-condition", condition)
                    for step in range(2):
                        page.wait_for_function(loaded)
                        sources = page.evaluate(f"{videos}.map(v => v.getAttribute('src'))")
                        assert sources == [
                            f"{VIDEOS_DIR}/n{cell.split(' | ')[2]}_{c}_{step:03d}.webm" for c in ("train", condition)
                        ]
                        if step == 0:
                            page.click("#v-next")
                    assert page.is_disabled("#v-next")
            labels = [page.inner_text("#v-left-label"), page.inner_text("#v-right-label")]
            assert "success" in labels[0] and "succeeded" in labels[0]
            assert "failure" in labels[1] and "reached" in labels[1]

            # choosing a shift shows episode i under train and under it, playing in sync
            page.select_option("#v-cell", cells[0])
            page.select_option("#v-condition", "camera_pos")
            page.wait_for_function(loaded)
            assert page.is_visible("#v-left") and page.is_visible("#v-right")
            times = f"{videos}.map(v => v.currentTime)"
            page.click("#v-play")
            page.wait_for_function(f"{videos}.every(v => v.currentTime > 0.3)")
            a, b = page.evaluate(times)
            assert abs(a - b) < SYNCED and not any(page.evaluate(f"{videos}.map(v => v.paused)"))
            page.click("#v-play")  # pause
            page.evaluate(
                "s => { s.value = 300; s.dispatchEvent(new Event('input')); }", page.query_selector("#v-seek")
            )
            page.wait_for_function(f"{videos}.every(v => !v.seeking)")
            a, b = page.evaluate(times)
            assert abs(a - b) < SYNCED and abs(a - 0.3 * FRAMES["camera_pos"] / FPS) < SYNCED
            # the shorter (train) video holds its last frame while the longer plays on; both start again together
            page.click("#v-play")
            page.wait_for_function(f"{videos}[0].ended")
            a, b = page.evaluate(times)
            assert a == pytest.approx(FRAMES["train"] / FPS, abs=0.05) and b > a - SYNCED
            page.wait_for_function(f"{videos}.every(v => v.currentTime > 0.15 && v.currentTime < 0.6 && !v.paused)")
            a, b = page.evaluate(times)
            assert abs(a - b) < SYNCED

            shot = tmp_path / "report.png"
            page.screenshot(path=str(shot), full_page=True)
        finally:
            browser.close()
    assert not errors, errors
    from PIL import Image

    pixels = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert pixels.shape[0] > 1500 and pixels.std() > 20, "the screenshot is blank"
