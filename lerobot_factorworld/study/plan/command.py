"""What ``factorworld study`` and a study's YAML file hold: the grid (:class:`.config.StudyConfig`) and how to run
it (:class:`..run.options.RunOptions`) side by side, flat, as users write them (``workers: 2`` beside ``tasks:``).
The library's entry points take the two apart (:meth:`StudyCommand.grid`, :meth:`StudyCommand.options`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..run.options import RunOptions
from ..run.reuse import check_reuse_from
from .config import StudyConfig


@dataclass
class StudyCommand(StudyConfig, RunOptions):
    """A study's grid and its run options in one flat config (see the two classes for each setting)."""

    def __post_init__(self) -> None:
        StudyConfig.__post_init__(self)
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
