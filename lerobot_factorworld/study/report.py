"""Study outputs: ``results.csv`` (``results.py``), PNG plots mirroring the paper's figures (``plots.py``),
the task families' own files and sections (their ``write_report_files`` and ``report_sections`` hooks, e.g. a
CSV of breakdowns per episode record), and ``report.md`` (``markdown.py``).

One renderer, two ways in, so a documented number can always be recomputed from committed files:

- a study that ran (:func:`write_report`) writes ``results.csv`` and the families' CSV files from its
  finished steps, then renders the report from what it wrote, read back (:func:`render_report`);
- ``factorworld report`` (:func:`regenerate_report`) renders the same report from a ``results.csv``, the
  study's config and the families' CSV files alone, with no step folder: only the "Where the time went"
  section (per-step timings) is left out, and a line says so.
"""

from __future__ import annotations

import csv
import math
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..core.io import atomic_write_text
from ..core.settings import parse_config
from ..families import TaskFamily, family_of
from .config import StudyConfig
from .markdown import REPORT_FILE, render
from .plan import Plan, make_plan
from .plots import write_plots
from .profile import profile_markdown
from .results import RESULT_COLUMNS, RESULTS_FILE, finished_evaluations, result_rows, write_results

CONFIG_FILE = "config.yaml"  # the study's config, committed next to its results.csv
REPORT_COMMAND = "report"  # factorworld report
OPTIONAL_COLUMNS = ("commit", "source_hash")  # provenance, added later: older results.csv files lack them
INTEGER_COLUMNS = ("n_train_envs", "seed", "n_factors", "n_envs", "episodes", "successes", "envs_visited")
FLOAT_COLUMNS = (  # empty: NaN (undefined)
    "success_rate",
    "ci_low",
    "ci_high",
    "train_success_rate",
    "gap",
    "gap_ci_low",
    "gap_ci_high",
)
OPTIONAL_FLOAT_COLUMNS = ("radius_m",)  # empty: None (not a radius-sweep row)
NO_TIMINGS = (
    "*Where the time went* is left out: it comes from the per-step timings in the study's step folders, "
    f"which a report regenerated from `{RESULTS_FILE}` does not read."
)


def write_report(cfg: StudyConfig, plan: Plan, study_dir: str | Path, command: str) -> tuple[Path, Path, list[Path]]:
    """A study that ran: ``results.csv`` and the families' files from the finished evaluations, then the plots
    and ``report.md`` rendered from them, with where the time went at the end; returns the CSV's, the report's
    and the plots' paths."""
    study_dir = Path(study_dir)
    evaluations = finished_evaluations(plan, study_dir)
    csv_path = write_results(result_rows(cfg, evaluations), study_dir / RESULTS_FILE)
    for family in families_of(cfg):
        family.write_report_files(cfg=cfg, evaluations=evaluations, study_dir=study_dir)
    timing = profile_markdown(plan, study_dir)  # last: it is about the run, not the results
    report, plots = render_report(cfg, read_results(csv_path), study_dir, command, len(plan.of_kind("eval")), timing)
    return csv_path, report, plots


def rebuild_report(cfg: StudyConfig, command: str) -> tuple[Path, Path, list[Path]]:
    """Rewrite the outputs of the finished study in ``cfg.out_dir`` from its step results (nothing is run)."""
    return write_report(cfg, make_plan(cfg), cfg.out_dir, command)


def render_report(
    cfg: StudyConfig, rows: list[dict], out_dir: Path, command: str, planned: int, tail: Sequence[str] = ()
) -> tuple[Path, list[Path]]:
    """The one renderer: plots and ``report.md`` in ``out_dir`` from ``results.csv`` rows and the families'
    files in ``out_dir`` (``tail``: lines after the report); the report's and the plots' paths."""
    plots = write_plots(rows, cfg, out_dir)
    families = families_of(cfg)

    def family_sections(part: str) -> list[str]:
        return [
            line
            for family in families
            for line in family.report_sections(cfg=cfg, rows=rows, study_dir=out_dir, part=part)
        ]

    text = render(cfg, rows, plots, command, planned, family_sections)
    if tail:
        text = text.rstrip("\n") + "\n\n" + "\n".join(tail)
    return atomic_write_text(out_dir / REPORT_FILE, text), plots


def families_of(cfg: StudyConfig) -> list[TaskFamily]:
    """The task families of the study's tasks, each once, in task order."""
    return list(dict.fromkeys(family_of(task) for task in cfg.tasks))


# --- factorworld report: from committed files alone -----------------------------------------------


def regenerate_report(
    results: str | Path, config: str | Path | None = None, out: str | Path | None = None
) -> tuple[Path, list[Path]]:
    """``report.md`` and the plots from a ``results.csv``, the study's config (default: ``config.yaml`` next
    to it) and the families' files next to it; nothing is run. ``out`` (default: the CSV's folder) receives
    copies of every input, so that the report's "next to this file" holds wherever it is written. Returns
    the report's and the plots' paths; bad input raises one-line errors (``ValueError``, ``OSError``)."""
    results = Path(results)
    config = Path(config) if config else results.parent / CONFIG_FILE
    if not config.is_file():
        raise FileNotFoundError(
            f"no study config at {config}: pass --config_path=<the study's config.yaml> or put it next to {results}"
        )
    rows = read_results(results)
    cfg = load_config(config)
    check_study_name(rows, cfg.name, results)
    out = Path(out) if out else results.parent
    out.mkdir(parents=True, exist_ok=True)
    _copy(results, out / RESULTS_FILE)
    _copy(config, out / CONFIG_FILE)
    for family in families_of(cfg):
        for name in family.report_files:
            if (results.parent / name).is_file():
                _copy(results.parent / name, out / name)
            elif out.resolve() != results.parent.resolve():
                (out / name).unlink(missing_ok=True)  # a stale copy would be read as this study's
    command = f"factorworld {REPORT_COMMAND} --results={RESULTS_FILE}"
    return render_report(cfg, rows, out, command, len(make_plan(cfg).of_kind("eval")), [NO_TIMINGS, ""])


def load_config(path: str | Path) -> StudyConfig:
    """The study config a ``results.csv`` was made with (a YAML file as ``factorworld study`` reads it)."""
    return parse_config(StudyConfig, [f"--config_path={path}"], "study")


def check_study_name(rows: Sequence[dict], name: str, results: Path) -> None:
    """Refuse a config of another study than the rows'."""
    studies = sorted({r["study"] for r in rows})
    if studies and studies != [name]:
        raise ValueError(f"{results} holds study {', '.join(map(repr, studies))}, but the config is of study {name!r}")


def _copy(source: Path, target: Path) -> None:
    if not (target.exists() and source.resolve() == target.resolve()):
        shutil.copyfile(source, target)


# --- reading the CSV files back ---------------------------------------------------------------------


def read_results(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a ``results.csv`` with their types (as ``result_rows`` made them, floats as written); one
    that is not a results file is refused in one line. Older files without the provenance columns are read
    (those columns empty)."""
    required = [c for c in RESULT_COLUMNS if c not in OPTIONAL_COLUMNS]
    rows = read_table(path, required, INTEGER_COLUMNS, FLOAT_COLUMNS, OPTIONAL_FLOAT_COLUMNS)
    return [{**{c: "" for c in OPTIONAL_COLUMNS}, **row} for row in rows]


def read_table(
    path: str | Path,
    columns: Sequence[str],
    integers: Sequence[str] = (),
    floats: Sequence[str] = (),
    optional_floats: Sequence[str] = (),
) -> list[dict[str, Any]]:
    """The rows of a CSV file that must have ``columns`` (more are kept as text); ``integers`` and ``floats``
    converted (an empty float: NaN, an empty optional float: ``None``). Errors name the file and line."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []
            missing = [c for c in columns if c not in header]
            if missing:
                shown = ",".join(header) or "none"
                raise ValueError(
                    f"{path} is not the expected CSV file: it lacks the column(s) {', '.join(missing)} "
                    f"(its header: {shown[:120] + '...' if len(shown) > 120 else shown})"
                )
            return [_typed(row, integers, floats, optional_floats, f"{path} line {reader.line_num}") for row in reader]
    except (csv.Error, UnicodeDecodeError) as err:
        raise ValueError(f"{path} is not a readable CSV file: {err}") from None


def _typed(
    row: dict[str, Any], integers: Sequence[str], floats: Sequence[str], optional_floats: Sequence[str], where: str
) -> dict[str, Any]:
    if None in row or any(v is None for v in row.values()):
        raise ValueError(f"{where}: the row has another number of fields than the header")
    out = dict(row)
    try:
        for c in integers:
            out[c] = int(row[c])
        for c in floats:
            out[c] = float(row[c]) if row[c] != "" else math.nan
        for c in optional_floats:
            out[c] = float(row[c]) if row[c] != "" else None
    except ValueError:
        raise ValueError(f"{where}: column {c} holds {row[c]!r}, not a number") from None
    return out
