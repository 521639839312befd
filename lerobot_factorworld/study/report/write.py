"""Study outputs: ``results.csv`` (``results/rows.py``), ``episodes.parquet`` (one row per episode: ``episodes.py``),
PNG plots mirroring the paper's figures (``plots.py``), the task families' own files and sections (their
report parts' ``write_report_files`` and ``report_sections``, ``family_report.py``, e.g. a CSV of breakdowns per episode record), and
``report.md`` (``markdown.py``).

One renderer, two ways in, so a documented number can always be recomputed from committed files:

- a study that ran (:func:`write_report`) writes ``results.csv`` and the families' CSV files from its
  finished steps, then renders the report from what it wrote, read back (:func:`render_report`);
- ``factorworld report`` (:func:`regenerate_report`) renders the same report from a ``results.csv``, the
  study's config and the families' CSV files alone, with no step folder: only the "Where the time went"
  section (per-step timings) is left out, and a line says so.
"""

from __future__ import annotations

import copy
import functools
import json
import shutil
from collections.abc import Sequence
from pathlib import Path

import yaml

from ...core.io import atomic_write_text
from ...core.settings import parse_config
from ...families import family_of
from ..analysis.study import analyze
from ..plan.command import ReportedStudy
from ..plan.config import StudyConfig, write_run_config
from ..plan.grid import Plan, make_plan
from ..plan.profile import profile_markdown
from ..results.curve import CURVE_FILE, curve_rows, read_curve, write_curve
from ..results.episodes import EPISODES_FILE, episode_rows, write_episodes
from ..results.eval_results import write_eval_results
from ..results.rows import RESULTS_FILE, finished_evaluations, read_results, result_rows, write_results
from ..run.recording import VIDEOS_DIR
from ..run.step import RUN_CONFIG_FILE, STEPS_DIR
from ..sequential import INTERVAL_LABEL
from .curve_report import CURVE_PLOT, curve_section, plot_curve
from .episode_videos import MANIFEST, collect_videos
from .family_report import FamilyReport, report_of
from .html_report import StoppingTable, write_html_report
from .markdown import FAMILY_DETAILS, REPORT_FILE, _stages_section, render
from .plots import write_plots
from .stopping_report import STOP_COLUMNS, STOPPED_NOTE, render_auto, rule_text, stop_cells

PUBLISHED_CONFIG = "config.yaml"  # the study's config, committed next to its results.csv (docs/results/<study>/)
REPORT_COMMAND = "report"  # factorworld report
REUSE_SETTING = "reuse_from"  # StudyConfig's other studies' folders: how a study ran, left out of a published config
NO_TIMINGS = (
    "*Where the time went* is left out: it comes from the per-step timings in the study's step folders, "
    f"which a report regenerated from `{RESULTS_FILE}` does not read."
)


def write_report(cfg: StudyConfig, plan: Plan, study_dir: str | Path, command: str) -> tuple[Path, Path, list[Path]]:
    """A study that ran: ``results.csv``, ``episodes.parquet`` and the families' files from the finished
    evaluations, then the plots and ``report.md`` rendered from them, with where the time went at the end;
    returns the CSV's, the report's and the plots' paths (the episodes are ``study_dir / EPISODES_FILE``)."""
    study_dir = Path(study_dir)
    evaluations = finished_evaluations(plan, study_dir)
    csv_path = write_results(result_rows(cfg, evaluations), study_dir / RESULTS_FILE)
    write_episodes(episode_rows(cfg, evaluations, study_dir), study_dir / EPISODES_FILE)
    for family in families_of(cfg):
        family.write_report_files(cfg=cfg, evaluations=evaluations, study_dir=study_dir)
    if plan.curve_points():
        write_curve(curve_rows(cfg, plan, study_dir), study_dir / CURVE_FILE)
    collect_videos(evaluations, study_dir)  # the recorded episodes, for report.html's paired viewer
    timing = profile_markdown(plan, study_dir)  # last: it is about the run, not the results
    report, plots = render_report(
        cfg, read_results(csv_path), study_dir, command, len(plan.evaluations()), timing,
        finding_companions(cfg, study_dir),
    )  # fmt: skip
    return csv_path, report, plots


def rebuild_report(cfg: StudyConfig, command: str) -> tuple[Path, Path, list[Path]]:
    """Rewrite the outputs of the finished study in ``cfg.out_dir`` from its step results (nothing is run)."""
    return write_report(cfg, make_plan(cfg), cfg.out_dir, command)


def render_report(
    cfg: StudyConfig,
    rows: list[dict],
    out_dir: Path,
    command: str,
    planned: int,
    tail: Sequence[str] = (),
    companions: Sequence[tuple[StudyConfig, list[dict]]] = (),
) -> tuple[Path, list[Path]]:
    """The one renderer: plots, ``report.md`` and ``report.html`` (with its paired-episode viewer of
    ``out_dir/episodes/``) in ``out_dir`` from ``results.csv`` rows and the families' files in ``out_dir``
    (``tail``: lines after report.md; ``companions``: the other studies of its finding, whose claims are
    corrected with its own: :func:`finding_companions`); report.md's and the plots' paths."""
    if not cfg.trained_methods():  # a profile of given checkpoints: its results for their model pages
        write_eval_results(cfg, rows, out_dir)
    analysis = analyze(cfg, rows, companions)  # once, for the plots, report.md and report.html
    if cfg.eval.auto:  # intervals valid under the stopping only: none of the fixed-n sections, plots or page
        text = render_auto(cfg, rows, command, planned, _stages_section(cfg, analysis))
        if tail:
            text = text.rstrip("\n") + "\n\n" + "\n".join(tail)
        note = f"Every interval is {INTERVAL_LABEL}: {rule_text(cfg)}. " + STOPPED_NOTE.format(
            tolerance=cfg.eval.tolerance, budget=cfg.eval.max_episodes
        )
        write_html_report(
            cfg, rows, out_dir, analysis, stopping=StoppingTable(note, STOP_COLUMNS, stop_cells(cfg, rows))
        )
        return atomic_write_text(out_dir / REPORT_FILE, text), []
    plots = write_plots(rows, cfg, out_dir, analysis)
    families = families_of(cfg)
    (out_dir / CURVE_PLOT).unlink(missing_ok=True)
    curve = read_curve(out_dir / CURVE_FILE) if cfg.curve_methods() and (out_dir / CURVE_FILE).is_file() else []
    plotted = bool(curve) and plot_curve(curve, out_dir / CURVE_PLOT)
    budgets = {m.name: cfg.train_for(m).epochs for m in cfg.curve_methods()}
    curve_lines = curve_section(curve, plotted, [m.name for m in cfg.methods], budgets) if curve else []

    def family_sections(part: str) -> list[str]:
        own = curve_lines if part == FAMILY_DETAILS else []  # the learning curve, a breakdown of P_T
        return own + [
            line
            for family in families
            for line in family.report_sections(cfg=cfg, rows=rows, study_dir=out_dir, part=part)
        ]

    others = [c.name for c, _ in companions]
    text = render(cfg, rows, plots, command, planned, family_sections, analysis, others)
    if tail:
        text = text.rstrip("\n") + "\n\n" + "\n".join(tail)
    write_html_report(cfg, rows, out_dir, analysis, curve)
    return atomic_write_text(out_dir / REPORT_FILE, text), plots


def families_of(cfg: StudyConfig) -> list[FamilyReport]:
    """The report parts of the study's task families, each once, in task order."""
    return list(dict.fromkeys(report_of(family_of(task)) for task in cfg.tasks))


# --- factorworld report: from committed files alone -----------------------------------------------


def regenerate_report(
    results: str | Path, config: str | Path | None = None, out: str | Path | None = None
) -> tuple[Path, list[Path]]:
    """``report.md`` and the plots from a ``results.csv``, the study's config and the families' files next to
    it; nothing is run. The config defaults to the one next to the CSV: a study folder's ``config.json`` (the
    settings it ran with, command-line overrides included), else a published folder's ``config.yaml``.
    ``out`` (default: the CSV's folder) receives copies of every input, so that the report's "next to this
    file" holds wherever it is written; in a study folder that still has its steps the report keeps "Where
    the time went". Returns the report's and the plots' paths; bad input raises one-line errors."""
    results = Path(results)
    config = Path(config) if config else config_next_to(results)
    rows = read_results(results)
    cfg = load_config(config)
    check_study_name(rows, cfg.name, results)
    plan = make_plan(cfg)
    check_rows_planned(rows, plan, results, config)
    out = Path(out) if out else results.parent
    out.mkdir(parents=True, exist_ok=True)
    _copy(results, out / RESULTS_FILE)
    if (results.parent / EPISODES_FILE).is_file():  # not read by the report, but part of the results
        _copy(results.parent / EPISODES_FILE, out / EPISODES_FILE)
    videos = results.parent / VIDEOS_DIR
    if (videos / MANIFEST).is_file() and videos.resolve() != (out / VIDEOS_DIR).resolve():  # report.html's viewer
        shutil.copytree(videos, out / VIDEOS_DIR, dirs_exist_ok=True)
    if not (out / RUN_CONFIG_FILE).is_file() or config.resolve() != (out / RUN_CONFIG_FILE).resolve():
        _publish_config(config, out / PUBLISHED_CONFIG)
    for name in [CURVE_FILE] if cfg.curve_methods() else []:
        if (results.parent / name).is_file():
            _copy(results.parent / name, out / name)
    for family in families_of(cfg):
        for name in family.report_files:
            if (results.parent / name).is_file():
                _copy(results.parent / name, out / name)
            elif out.resolve() != results.parent.resolve():
                (out / name).unlink(missing_ok=True)  # a stale copy would be read as this study's
    command = f"factorworld {REPORT_COMMAND} --results={RESULTS_FILE}"
    timing = profile_markdown(plan, out) if (out / STEPS_DIR).is_dir() else []
    companions = finding_companions(cfg, results.parent)
    return render_report(cfg, rows, out, command, len(plan.evaluations()), timing or [NO_TIMINGS, ""], companions)


def finding_companions(cfg: StudyConfig, study_dir: Path) -> list[tuple[StudyConfig, list[dict]]]:
    """The other studies of ``cfg.finding`` beside ``study_dir``: each sibling folder holding a ``results.csv``
    and a config (``config.json`` or ``config.yaml``) that names the same finding, with its rows, in folder
    order. None for a study of no finding. ``docs/results/`` holds a finding's committed studies side by side,
    and a study's own output folder its siblings of the same ``findings/`` run."""
    if not cfg.finding or not study_dir.parent.is_dir():
        return []
    out = []
    for folder in sorted(p for p in study_dir.parent.iterdir() if p.is_dir()):
        if folder.resolve() == study_dir.resolve() or not (folder / RESULTS_FILE).is_file():
            continue
        config = next((folder / n for n in (RUN_CONFIG_FILE, PUBLISHED_CONFIG) if (folder / n).is_file()), None)
        if config is None or _finding_of(config) != cfg.finding:
            continue
        other = load_config(config)
        if other.name != cfg.name:
            out.append((other, read_results(folder / RESULTS_FILE)))
    return out


def _finding_of(config: Path) -> str:
    """The ``finding`` a study config names, read without parsing the whole study (most siblings name none), by
    libyaml where PyYAML has it (every report of a finding reads each sibling's config)."""
    settings = yaml.load(config.read_text(encoding="utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    return str(settings.get("finding") or "") if isinstance(settings, dict) else ""


def config_next_to(results: Path) -> Path:
    """The study config beside a ``results.csv``: its study folder's ``config.json``, or a published ``config.yaml``."""
    for name in (RUN_CONFIG_FILE, PUBLISHED_CONFIG):
        if (results.parent / name).is_file():
            return results.parent / name
    raise FileNotFoundError(
        f"no study config next to {results} ({RUN_CONFIG_FILE} or {PUBLISHED_CONFIG}): pass --config_path=<the study's "
        "config YAML>"
    )


def load_config(path: str | Path) -> StudyConfig:
    """The study grid a ``results.csv`` was made with (a YAML file as ``factorworld study`` reads it; its run
    options, ``workers`` and the like, are read and dropped).

    Its ``reuse_from`` is left out: where finished steps were linked from is how a study ran on one machine,
    not what it computed (a step's key is its inputs), and those folders need not exist where a report is
    regenerated. A file read before and unchanged since is not parsed again (a finding's every report reads
    its siblings' configs: ``factorworld sync-docs`` would parse each of them once per sibling)."""
    file = Path(path).expanduser().resolve()
    if not file.is_file():
        return _parsed_config(str(path))  # the parser's own one-line refusal
    stat = file.stat()
    return copy.deepcopy(_parsed_config(str(file), stat.st_mtime_ns, stat.st_size))


@functools.lru_cache(maxsize=128)
def _parsed_config(path: str, mtime_ns: int = 0, size: int = 0) -> StudyConfig:
    """``path`` parsed (``mtime_ns`` and ``size`` only key the cache: a changed file is parsed again)."""
    return parse_config(ReportedStudy, [f"--config_path={path}", f"--{REUSE_SETTING}=[]"], "study").grid()


def check_study_name(rows: Sequence[dict], name: str, results: Path) -> None:
    """Refuse a config of another study than the rows'."""
    studies = sorted({r["study"] for r in rows})
    if studies and studies != [name]:
        raise ValueError(f"{results} holds study {', '.join(map(repr, studies))}, but the config is of study {name!r}")


def check_rows_planned(rows: Sequence[dict], plan: Plan, results: Path, config: Path) -> None:
    """Refuse rows the config would not have made (another grid under the same study name): every row's cell
    and condition must be one of the plan's evaluations, or the report would describe a grid that never ran."""
    planned = {_cell(step.meta) for step in plan.evaluations()}
    unplanned = [_cell(row) for row in rows if _cell(row) not in planned]
    if unplanned:
        method, task, n, seed, widths, condition = unplanned[0]
        raise ValueError(
            f"{len(unplanned)} row(s) of {results} are not in the plan of {config}, e.g. method={method} task={task} "
            f"N={n} seed={seed} widths={widths} condition={condition}: pass the config that made them"
        )


def _cell(labels: dict) -> tuple:
    keys = ("method", "task", "n_train_envs", "seed", "widths", "condition")
    return tuple(str(labels[k]) for k in keys)


def _publish_config(source: Path, target: Path) -> None:
    """Copy the study's config next to its results. A run's ``config.json`` (:data:`RUN_CONFIG_FILE`, as the
    runner wrote it) is written without the machine-local ``reuse_from`` folders (:func:`load_config`), in the
    runner's own format; any other config file is copied verbatim, comments included (a ``reuse_from`` in it is
    ignored when it is read)."""
    if source.name == RUN_CONFIG_FILE:
        settings = json.loads(source.read_text())
        if settings.get(REUSE_SETTING):
            write_run_config(target, {**settings, REUSE_SETTING: []})
            return
    _copy(source, target)


def _copy(source: Path, target: Path) -> None:
    if not (target.exists() and source.resolve() == target.resolve()):
        shutil.copyfile(source, target)
