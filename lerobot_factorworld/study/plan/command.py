"""What ``factorworld study`` and a study's YAML file hold: the grid (:class:`.config.StudyConfig`) and how to run
it (:class:`..run.options.RunOptions`) side by side, flat, as users write them (``workers: 2`` beside ``tasks:``).
The library's entry points take the two apart (:meth:`StudyCommand.grid`, :meth:`StudyCommand.options`).

A study to run is checked whole, LeRobot's verdict on its policies included (:class:`StudyCommand`); a study's
file read for its report is checked without LeRobot (:class:`ReportedStudy`), which would load torch (seconds)
to check settings that were checked when the study ran.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar

from ..run.options import RunOptions
from ..run.reuse import check_reuse_from
from .config import StudyConfig


@dataclass
class StudyCommand(StudyConfig, RunOptions):
    """A study's grid and its run options in one flat config (see the two classes for each setting)."""

    # whether reading the file asks LeRobot about the policies (StudyConfig.check_policies): a study to run does
    checks_policies: ClassVar[bool] = True

    def __post_init__(self) -> None:
        StudyConfig.__post_init__(self)
        if self.checks_policies:  # the grid's checks, then LeRobot's on its policies, then the run options'
            self.check_policies()
        RunOptions.__post_init__(self)
        check_reuse_from(self.reuse_from, self.out_dir)
        if self.only_methods:  # the names checked before any work
            self.grid()

    def grid(self) -> StudyConfig:
        """The grid to run: the whole study's, or the part ``only_methods`` names."""
        whole = StudyConfig(**{f.name: getattr(self, f.name) for f in fields(StudyConfig)})
        return whole.only(self.only_methods) if self.only_methods else whole

    def options(self) -> RunOptions:
        return RunOptions(**{f.name: getattr(self, f.name) for f in fields(RunOptions)})

    def parts(self) -> tuple[StudyConfig, RunOptions]:
        """``(grid, options)``, as :func:`..runner.run_study` and :func:`..runner.inspect_study` take them."""
        return self.grid(), self.options()


@dataclass
class ReportedStudy(StudyCommand):
    """A study's file as a report reads it (``factorworld report``, ``sync-docs``, the comparisons): every check of
    :class:`StudyCommand` but LeRobot's, so that writing a report loads no torch or LeRobot. A report runs nothing;
    running or planning the study asks LeRobot again (:func:`..runner.run_study`, :func:`..runner.inspect_study`)."""

    checks_policies: ClassVar[bool] = False
