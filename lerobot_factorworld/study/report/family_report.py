"""A task family's part of a study report, loaded by the entry point its family names
(``TaskFamily.report_entry_point``): the family's report parts sit above the study, in
``lerobot_factorworld/family_reports/``, so the study reaches them by name, never by a static import."""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any

from ...families import TaskFamily


class FamilyReport:
    """What a family adds to a report; every default adds nothing (the plain Meta-World tasks).

    Attributes:
        report_files: Files the family's sections read, next to ``results.csv`` (e.g. a CSV of per-episode
            breakdowns); committed and copied with it.
    """

    report_files: tuple[str, ...] = ()

    def write_report_files(self, cfg: Any, evaluations: Sequence[Any], study_dir: str | Path) -> list[Path]:
        """Write the :attr:`report_files` from a finished study's ``evaluations`` (step and result, whose family
        entry holds the episode records); the paths written. Only a study that ran calls it: a report
        regenerated from committed CSV files reads what this wrote, so every number of the family's sections
        is in a CSV."""
        return []

    def report_sections(self, cfg: Any, rows: Sequence[dict], study_dir: str | Path, part: str) -> list[str]:
        """The family's extra report.md lines: from ``rows`` (``results.csv``) and the :attr:`report_files` in
        ``study_dir`` only, so a live study and a regenerated report give the same lines; ``part`` is where they
        go (``markdown.FAMILY_RESULTS``: after the factor ordering; ``markdown.FAMILY_DETAILS``: at the end)."""
        return []


NO_REPORT = FamilyReport()


def report_of(family: TaskFamily) -> FamilyReport:
    """The family's report part (:data:`NO_REPORT` when it names none)."""
    return _load(family.report_entry_point) if family.report_entry_point else NO_REPORT


@cache
def _load(entry_point: str) -> FamilyReport:
    # The study's one dynamic import: a family's report part sits above the study (it imports the study's
    # aggregation and Markdown), so the study reaches it by the name the family gives, as families.py does.
    module, _, attr = entry_point.partition(":")
    report = getattr(importlib.import_module(module), attr)
    if not isinstance(report, FamilyReport):
        raise TypeError(f"report entry point {entry_point!r} is a {type(report).__name__}, not a FamilyReport")
    return report
