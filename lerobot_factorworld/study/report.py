"""Study outputs, written from the finished eval steps: ``results.csv`` (``results.py``), PNG plots
mirroring the paper's figures (``plots.py``), the task families' own files and sections (their
``report_sections`` hook, e.g. a CSV of breakdowns per episode record), and ``report.md``
(``markdown.py``). A rerun or a resumed study rewrites the same files; :func:`rebuild_report` rewrites
them for a finished study folder without running anything."""

from __future__ import annotations

from pathlib import Path

from ..core.io import atomic_write_text
from ..families import family_of
from .config import StudyConfig
from .markdown import REPORT_FILE, render
from .plan import Plan, make_plan
from .plots import write_plots
from .profile import profile_markdown
from .results import RESULTS_FILE, finished_evaluations, result_rows, write_results


def write_report(cfg: StudyConfig, plan: Plan, study_dir: str | Path, command: str) -> tuple[Path, Path, list[Path]]:
    """Write ``results.csv``, the plots, the families' files and ``report.md``; returns the first three's paths."""
    study_dir = Path(study_dir)
    evaluations = finished_evaluations(plan, study_dir)
    rows = result_rows(cfg, evaluations)
    csv_path = write_results(rows, study_dir / RESULTS_FILE)
    plots = write_plots(rows, cfg, study_dir)
    families = list(dict.fromkeys(family_of(task) for task in cfg.tasks))

    def family_sections(part: str) -> list[str]:
        return [
            line
            for family in families
            for line in family.report_sections(
                cfg=cfg, rows=rows, evaluations=evaluations, study_dir=study_dir, part=part
            )
        ]

    text = render(cfg, plan, rows, plots, command, family_sections)
    timing = profile_markdown(plan, study_dir)  # where the time went: last, it is about the run, not the results
    report = atomic_write_text(
        study_dir / REPORT_FILE, text.rstrip("\n") + "\n\n" + "\n".join(timing) if timing else text
    )
    return csv_path, report, plots


def rebuild_report(cfg: StudyConfig, command: str) -> tuple[Path, Path, list[Path]]:
    """Rewrite the outputs of the finished study in ``cfg.out_dir`` from its step results (nothing is run)."""
    return write_report(cfg, make_plan(cfg), cfg.out_dir, command)
