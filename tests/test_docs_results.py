"""Every documented study number regenerates from committed data: ``factorworld report`` rebuilds a study's
report.md and plots from its results.csv alone, every committed ``docs/results/<study>/`` report is what its
results.csv regenerates, and every table fenced in docs/*.md equals its regenerated table byte for byte.

The machinery is tested on small committed studies under ``tests/data/results/`` (``quick``: the quick
study's door-open run; ``pick_toy``: a two-seed pick study with its ``pick_breakdowns.csv``)."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.report.html_report import HTML_FILE
from lerobot_factorworld.study.report.markdown import REPORT_FILE, commit_line
from lerobot_factorworld.study.report.published import (
    RESULTS_ROOT,
    check_docs,
    committed_studies,
    doc_files,
    fenced_body,
    find_fences,
    regenerate_studies,
    report_table,
    sync_docs,
)
from lerobot_factorworld.study.report.write import NO_TIMINGS, regenerate_report
from lerobot_factorworld.study.results.rows import read_results

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "results"
FACTORWORLD = Path(sys.executable).with_name("factorworld")


# --- the repository's own docs and committed results ------------------------------------------------


PUBLISHED = {
    "quick": ROOT / "docs" / "study.md",
    "two_tasks": ROOT / "docs" / "study.md",
    "pick": ROOT / "docs" / "pick.md",
    "f1_ordering": ROOT / "docs" / "findings.md",
    "f8_out_of_domain": ROOT / "docs" / "findings.md",
    "f8_out_of_domain_language": ROOT / "docs" / "findings.md",
    "f8_out_of_domain_language_epochs": ROOT / "docs" / "findings.md",
    "f4_radius": ROOT / "docs" / "findings.md",
    "f9_pick": ROOT / "docs" / "findings.md",
    "f3_pairs": ROOT / "docs" / "findings.md",
    "f5_augmentation": ROOT / "docs" / "findings.md",
    "f7_object_texture_images": ROOT / "docs" / "findings.md",
    "f7_object_texture_colours": ROOT / "docs" / "findings.md",
    "f7_object_texture_168px": ROOT / "docs" / "findings.md",
    "learning_curve": ROOT / "docs" / "bc.md",
    "learning_speed": ROOT / "docs" / "bc.md",
    "rt1_curve_pick-place": ROOT / "docs" / "rt1.md",
    "rt1_curve_pick-place_80": ROOT / "docs" / "rt1.md",
    "rt1_speed": ROOT / "docs" / "rt1.md",
    "rt1_curve_pick-place_128": ROOT / "docs" / "rt1.md",
    "learning_curve_bin-picking_500": ROOT / "docs" / "findings.md",
    "learning_curve_n20": ROOT / "docs" / "findings.md",
    "f2_gap_vs_n_pick-place": ROOT / "docs" / "findings.md",
    "f2_gap_vs_n_door-open": ROOT / "docs" / "findings.md",
    "f2_gap_vs_n_400_demos": ROOT / "docs" / "findings.md",
    "f2_gap_vs_n_400_demos_n5_20": ROOT / "docs" / "findings.md",
    "f6_pretrained": ROOT / "docs" / "findings.md",
    "learning_rt1": ROOT / "docs" / "rt1.md",
    "rt1_curve_pick": ROOT / "docs" / "rt1.md",
    "rt1_curve_pick_40": ROOT / "docs" / "rt1.md",
}  # committed studies and a page that must quote them


def test_every_fenced_block_names_a_committed_study():
    studies = committed_studies(ROOT / RESULTS_ROOT)
    assert set(PUBLISHED) <= set(studies), f"committed results missing under {RESULTS_ROOT}/"
    for name, page in PUBLISHED.items():
        assert name in {f.study for f in find_fences(page.read_text(), page)}, f"{page} quotes no {name} table"
    for path in doc_files(ROOT / "docs"):
        for fence in find_fences(path.read_text(), path):
            assert fence.study in studies, f"{fence.label()}: no committed results under {RESULTS_ROOT}/{fence.study}/"


@pytest.mark.slow
def test_every_committed_report_and_fenced_docs_table_is_what_its_results_csv_regenerates(tmp_path):
    studies = committed_studies(ROOT / RESULTS_ROOT)
    reports = regenerate_studies(studies, tmp_path)
    for name, folder in studies.items():
        committed = folder / REPORT_FILE
        assert committed.is_file() and committed.read_text() == reports[name], (
            f"{committed} is stale: run `factorworld sync-docs`"
        )
        for plot in (tmp_path / name).glob("*.png"):
            assert (folder / plot.name).is_file(), f"{folder / plot.name} missing: run factorworld sync-docs"
        html = folder / HTML_FILE  # deterministic: byte for byte, like report.md
        assert html.is_file() and html.read_bytes() == (tmp_path / name / HTML_FILE).read_bytes(), (
            f"{html} is stale: run `factorworld sync-docs`"
        )
    problems = check_docs(doc_files(ROOT / "docs"), reports)
    assert not problems, "stale docs tables (run `factorworld sync-docs`): " + "; ".join(problems)


def test_every_committed_row_is_a_step_today_s_code_plans_from_its_config_and_its_named_study():
    """The keys of every committed study hold: each ``results.csv`` row's and ``curve.csv`` point's step key is planned by today's code from
    the config published beside it, and from the shipped study of the same name (``configs/study/``, which may
    have grown, e.g. F9's RT-1 arm), so a rerun by name finds those steps cached and a changed key fails here."""
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.study.plan.command import StudyCommand
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.plan.named import resolve_study_config, study_names
    from lerobot_factorworld.study.report.write import PUBLISHED_CONFIG, load_config
    from lerobot_factorworld.study.results.curve import CURVE_FILE, read_curve

    shipped = {}
    for name in study_names():
        cfg = parse_config(StudyCommand, [f"--config_path={resolve_study_config(name)}"], "study").grid()
        shipped.setdefault(cfg.name, []).append(cfg)
    named = 0
    for study, folder in committed_studies(ROOT / RESULTS_ROOT).items():
        rows = read_results(folder / "results.csv")
        # a curve still training (rt1_curve_pick_160) has its points committed before any row of the grid
        points = read_curve(folder / CURVE_FILE) if (folder / CURVE_FILE).is_file() else []
        (name,) = {r["study"] for r in [*rows, *points]}
        for cfg in [load_config(folder / PUBLISHED_CONFIG), *shipped.get(name, [])]:
            plan = make_plan(cfg)
            keys = {s.key for s in [*plan.evaluations(), *plan.curve_points()]}
            unplanned = [r["step"] for r in [*rows, *points] if r["step"] not in keys]
            assert not unplanned, f"{study}: {len(unplanned)} committed step(s) not in the plan of {cfg.name}"
        named += bool(shipped.get(name))
    assert named >= 20  # most committed studies have a shipped config of their name


def test_every_findings_row_names_its_configs_and_committed_results():
    """docs/findings.md's summary table has one row per finding F1-F9; each names configs that exist under
    configs/study/findings/ and at least one committed ``docs/results/<study>/results.csv``."""
    rows = {}
    for line in (ROOT / "docs" / "findings.md").read_text().splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 3 and cells[1][:1] == "F" and cells[1][1:].isdigit():
            rows[cells[1]] = cells[3]
    assert sorted(rows) == [f"F{i}" for i in range(1, 10)], sorted(rows)
    for finding, cell in rows.items():
        names = re.findall(r"`([^`]+)`", cell)
        configs = [n for n in names if n.endswith(".yaml")]
        results = [n for n in names if n.startswith(f"{RESULTS_ROOT}/")]
        assert configs and results, f"{finding}: names no config or no committed results: {cell}"
        for config in configs:
            assert (ROOT / "configs" / "study" / "findings" / config).is_file(), f"{finding}: no {config}"
        for folder in results:
            assert (ROOT / folder / "results.csv").is_file(), f"{finding}: no {folder}results.csv"


# --- factorworld report on committed fixture data ---------------------------------------------------


@pytest.fixture
def studies(tmp_path) -> Path:
    """A writable copy of the fixture studies (results.csv, config.yaml, family CSV files only)."""
    shutil.copytree(DATA, tmp_path / "results")
    return tmp_path / "results"


def test_report_command_regenerates_report_and_plots_from_a_results_csv_alone(studies, tmp_path):
    quick = studies / "quick"
    proc = subprocess.run(
        [str(FACTORWORLD), "report", f"--results={quick / 'results.csv'}"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    report = (quick / REPORT_FILE).read_text()
    assert report.startswith("# Study `quick`\n\nProduced by `factorworld report --results=results.csv` (8 of 8 ")
    for section in ("## Factor ordering", "## Gap per factor and N", "## Success rates", "## Every cell", "## Plots"):
        assert section in report
    assert "Numbers made at commit(s): " in report and report.endswith(NO_TIMINGS + "\n")
    assert "## Where the time went" not in report and not (quick / "steps").exists()
    plots = sorted(p.name for p in quick.glob("*.png"))
    assert plots == ["gap_vs_n.png", "methods.png", "success_rates.png"]
    assert all(f"]({name})" in report for name in plots)
    # elsewhere, with the config named: the same report, next to copies of its inputs
    config = tmp_path / "made_it.yaml"
    shutil.copy(quick / "config.yaml", config)
    (quick / "config.yaml").unlink()
    out = tmp_path / "published"
    assert main(["report", f"--results={quick / 'results.csv'}", f"--config_path={config}", f"--out={out}"]) is None
    assert (out / REPORT_FILE).read_text() == report
    assert (out / "results.csv").read_bytes() == (quick / "results.csv").read_bytes()
    assert (out / "config.yaml").read_text() == config.read_text()
    assert sorted(p.name for p in out.glob("*.png")) == plots


def test_a_report_of_the_train_condition_alone_has_no_factor_sections(studies):
    """A profile with ``--factors=[]`` (a policy's success on its training environments, with failure stages)
    reports the success tables and no empty factor ordering, gap table or gap plot."""
    quick = studies / "quick"
    lines = (quick / "results.csv").read_text().splitlines()
    condition = lines[0].split(",").index("condition")
    train_rows = [line for line in lines[1:] if line.split(",")[condition] == "train"]
    assert train_rows
    (quick / "results.csv").write_text("\n".join([lines[0], *train_rows]) + "\n")
    config = (quick / "config.yaml").read_text()
    (quick / "config.yaml").write_text(config.replace("factors: [camera_pos, table_texture, light]", "factors: []"))
    assert main(["report", f"--results={quick / 'results.csv'}"]) is None
    report = (quick / REPORT_FILE).read_text()
    assert "## Success rates" in report and "## Every cell" in report
    assert "## Factor ordering" not in report and "## Gap per factor and N" not in report
    assert not (quick / "gap_vs_n.png").exists()


def test_a_pick_report_reads_its_breakdowns_csv_and_pools_seeds_with_the_bootstrap(studies, tmp_path):
    pick = studies / "pick_toy"
    report, _ = regenerate_report(pick / "results.csv", out=tmp_path / "a")
    text = report.read_text()
    assert "## Pick next to the paper's real-robot table" in text and "seeds pooled: bootstrap" in text
    assert "## Pick: success per named object, shape and phrasing" in text
    assert (tmp_path / "a" / "pick_breakdowns.csv").read_bytes() == (pick / "pick_breakdowns.csv").read_bytes()
    breakdowns = text.split("## Pick: success per named object")[1]
    assert "| bc_language: target |" in breakdowns and "| bc_language: shape |" in breakdowns
    (pick / "pick_breakdowns.csv").unlink()  # without the file, only its section goes (and no stale copy is read)
    again, _ = regenerate_report(pick / "results.csv", out=tmp_path / "a")
    assert not (tmp_path / "a" / "pick_breakdowns.csv").exists()
    without = again.read_text()
    assert "## Pick next to the paper's real-robot table" in without
    rest = text.split("## Factor ordering")[1].split("## Pick: success per named object")[0]
    assert without.split("## Factor ordering")[1] == rest.rstrip("\n") + "\n\n" + NO_TIMINGS + "\n"


def _rewrite(path: Path, old: str, new: str) -> Path:
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    return path


BAD_INPUT = {
    "missing results": (lambda d: d / "nothing.csv", None, "does not exist"),
    "wrong columns": (lambda d: d / "pick_toy" / "pick_breakdowns.csv", None, "lacks the column(s) study"),
    "another study's config": (
        lambda d: _rewrite(d / "quick" / "config.yaml", "name: quick", "name: slow").with_name("results.csv"),
        None,
        "holds study 'quick', but the config is of study 'slow'",
    ),
    "no config": (
        lambda d: (d / "quick" / "config.yaml").unlink() or d / "quick" / "results.csv",
        None,
        "no study config",
    ),
    "a count that is no number": (
        lambda d: _rewrite(d / "quick" / "results.csv", ",10,", ",ten,"),
        None,
        "not a number",
    ),
}


@pytest.mark.parametrize("case", BAD_INPUT)
def test_report_command_refuses_bad_input_in_one_line(case, studies, capsys):
    make, _, expected = BAD_INPUT[case]
    with pytest.raises(SystemExit) as exit_:
        main(["report", f"--results={make(studies)}"])
    err = capsys.readouterr().err
    assert exit_.value.code in (1, 2) and err.startswith("error: ") and len(err.splitlines()) == 1
    assert expected in err


def test_report_and_merge_take_a_packaged_study_s_name_for_its_config(tmp_path, capsys):
    """``--config=quick`` names the packaged study, as ``factorworld study`` reads it; an unknown name is one line
    naming the valid ones, before anything is written."""
    published = ROOT / RESULTS_ROOT / "quick"
    out = tmp_path / "named"
    assert main(["report", f"--results={published / 'results.csv'}", "--config=quick", f"--out={out}"]) is None
    assert (out / REPORT_FILE).read_text() == (published / REPORT_FILE).read_text()
    for command in (
        ["report", f"--results={published / 'results.csv'}", "--config=no_such_study", f"--out={tmp_path / 'x'}"],
        ["merge-results", f"--into={out}", f"--add=[{published}]", "--config=no_such_study"],
    ):
        with pytest.raises(SystemExit):
            main(command)
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and "no packaged study of that name; valid names: " in err and "quick" in err
    assert not (tmp_path / "x").exists()


def test_the_installed_report_command_prints_one_line_and_no_traceback(studies):
    bad = _rewrite(studies / "quick" / "results.csv", "study,method", "studies,method")
    proc = subprocess.run([str(FACTORWORLD), "report", f"--results={bad}"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1 and proc.stderr.startswith("error: ") and len(proc.stderr.splitlines()) == 1
    assert "Traceback" not in proc.stderr


def test_the_report_names_the_commits_behind_its_numbers():
    rows = [{"commit": "826fe54aa"}, {"commit": "826fe54aa"}, {"commit": ""}, {"commit": "0123456789-dirty"}]
    assert commit_line(rows) == (
        "Numbers made at commit(s): 826fe54 (2 rows), commit not recorded (1 row), 0123456-dirty (1 row)"
    )
    assert commit_line([{}]) == "Numbers made at commit(s): commit not recorded (1 row)"  # a CSV from before


def test_results_rows_read_back_with_their_types():
    rows = read_results(DATA / "quick" / "results.csv")
    row = rows[0]
    assert isinstance(row["episodes"], int) and isinstance(row["success_rate"], float)
    assert row["condition"] == "train" and row["n_factors"] == 0 and row["gap"] == 0.0
    assert all(r["commit"] == "" for r in rows)  # made before commits were recorded: empty, not missing


# --- the fenced blocks ----------------------------------------------------------------------------------


def _docs_tree(tmp_path: Path) -> Path:
    """A repository with the fixture studies committed under docs/results/ and one docs page."""
    shutil.copytree(DATA, tmp_path / RESULTS_ROOT)
    docs = tmp_path / "docs" / "page.md"
    docs.write_text(
        "# Page\n\nText above.\n\n"
        '<!-- results: quick "Success rates" -->\n\n| stale |\n|---|\n\n<!-- /results -->\n\n'
        "Between.\n\n"
        '<!-- results: pick_toy "Pick: success per named object" table 2 -->\n<!-- /results -->\n'
        "Text below.\n"
    )
    return docs


def _sync(run_main, tmp_path: Path, *flags: str) -> subprocess.CompletedProcess:
    """``factorworld sync-docs`` run on ``tmp_path``: its ``main()`` in this process (a process would spend ~8 s
    importing what this module has imported already)."""
    return run_main(["factorworld", "sync-docs", f"--root={tmp_path}", *flags], main)


@pytest.mark.slow
def test_the_sync_script_rewrites_fenced_tables_and_check_finds_stale_ones(tmp_path, run_main):
    page = _docs_tree(tmp_path)
    before = page.read_text()
    stale = _sync(run_main, tmp_path, "--check")
    assert stale.returncode == 1 and "page.md:5" in stale.stdout and "page.md:14" in stale.stdout
    assert "quick/report.md is not what its results.csv regenerates" in stale.stdout  # not regenerated yet
    assert page.read_text() == before  # --check changes nothing
    synced = _sync(run_main, tmp_path)
    assert synced.returncode == 0, synced.stderr
    assert "rewrote 1 docs file(s)" in synced.stdout
    text = page.read_text()
    reports = {name: (tmp_path / RESULTS_ROOT / name / REPORT_FILE).read_text() for name in ("quick", "pick_toy")}
    success = report_table(reports["quick"], "Success rates")
    assert success.startswith("| method | condition | N=2 | N=5 |\n|---|---|---|---|\n| bc | train |")
    assert f'<!-- results: quick "Success rates" -->\n{fenced_body(success)}<!-- /results -->' in text
    shape = report_table(reports["pick_toy"], "Pick: success per named object", 2)
    assert shape.startswith("| bc_language: shape |")
    assert (
        text.startswith("# Page\n\nText above.\n\n") and "\n\nBetween.\n\n" in text and text.endswith("Text below.\n")
    )
    assert _sync(run_main, tmp_path, "--check").returncode == 0
    assert _sync(run_main, tmp_path).stdout.count("rewrote 0 docs file(s)") == 1  # idempotent


def test_a_fence_of_a_study_without_committed_results_is_refused(tmp_path, run_main):
    page = _docs_tree(tmp_path)
    page.write_text(page.read_text() + '\n<!-- results: two_tasks "Factor ordering" -->\n<!-- /results -->\n')
    before = page.read_text()
    result = _sync(run_main, tmp_path)
    assert result.returncode == 1 and "names study 'two_tasks', which has no committed results" in result.stderr
    assert page.read_text() == before  # nothing written
    reports = {"quick": (DATA / "quick" / "results.csv").read_text()}
    assert any("two_tasks" in p for p in check_docs([page], reports))


@pytest.mark.parametrize(
    "text, expected",
    [
        ("<!-- results: quick Success rates -->\n<!-- /results -->\n", "malformed marker"),
        ('<!-- results: quick "Success rates" -->\n| a |\n', "not closed"),
        ("| a |\n<!-- /results -->\n", "without an opening marker"),
        ('<!-- results: quick "A" -->\n<!-- results: quick "B" -->\n<!-- /results -->\n', "inside the block"),
    ],
)
def test_malformed_fences_are_refused_in_one_line(text, expected, tmp_path):
    with pytest.raises(ValueError, match=expected):
        find_fences(text, tmp_path / "page.md")


def test_a_fence_names_one_section_and_one_of_its_tables():
    report = (
        "# Study\n\n## Success rates (mean)\n\n| a |\n|---|\n\ntext\n\n| b |\n|---|\n\n## Success per task\n\n| c |\n"
    )
    assert report_table(report, "Success rates") == "| a |\n|---|"
    assert report_table(report, "Success rates", 2) == "| b |\n|---|"
    assert report_table(report, "Success per") == "| c |"
    with pytest.raises(ValueError, match="several section headings start with 'Success'"):
        report_table(report, "Success")
    with pytest.raises(ValueError, match="no section heading starts with 'Pairs'"):
        report_table(report, "Pairs")
    with pytest.raises(ValueError, match="has 2 table"):
        report_table(report, "Success rates", 3)
    docs = Path("page.md")
    fence = find_fences(
        'x\n<!-- results: quick "Success rates" table 2 -->\n\n| b |\n|---|\n\n<!-- /results -->\n', docs
    )
    assert [(f.study, f.section, f.table, f.line) for f in fence] == [("quick", "Success rates", 2, 2)]
    assert fence[0].body == fenced_body("| b |\n|---|")
    assert find_fences('```markdown\n<!-- results: quick "X" -->\n```\n', docs) == []  # an example, not a fence
    assert sync_docs([], {}) == []
