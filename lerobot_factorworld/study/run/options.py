"""How a study runs, never what it computes: the executor and its workers, whether it only inspects the plan
(``dry_run``, ``profile``, ``fit_cost``) or only reports the steps finished so far (``report_only``), what happens to cached steps made by other code (``strict``,
``rerun_stale``), finished steps linked from other studies (``reuse_from``), and the push of its results to the
Hub. None of these enters a step's key: the same grid gives the same keys, results and checkpoints whichever way
it runs. The grid itself is :class:`..plan.config.StudyConfig`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from ...datasets.hub import check_hub_repo_id
from .context import EXECUTIONS

EXECUTORS = ("local", "ray")
# what report_only cannot go with: other ways of not running (each inspects), redoing steps, pushing a finished study
REPORT_ONLY_CLASHES = ("dry_run", "profile", "fit_cost", "rerun_stale", "push_to_hub")


@dataclass
class RunOptions:
    """How ``factorworld study`` runs a grid.

    Attributes:
        executor: ``local`` (a process pool on this machine) or ``ray``.
        workers: Steps run at once (local pool size, or concurrent Ray tasks).
        ray_address: Ray cluster address (``None``: start a local Ray instance).
        execution: How steps run, never what they compute (same keys, results, checkpoints, datasets):
            ``grouped`` (default) trains inside the worker process and evaluates all conditions of a
            checkpoint in one task as soon as it exists (policy loaded once); ``per_step`` runs
            ``lerobot-train`` as a subprocess and every evaluation as its own task.
        dry_run: Print the plan (steps per kind, cached, cost estimate, power) and stop.
        profile: Run nothing; print where the finished steps' time went (per kind and component).
        report_only: Run nothing; write ``results.csv``, ``episodes.parquet``, ``curve.csv``, the plots and
            ``report.md`` from the steps finished so far, also while another process runs the study (a long
            learning curve's points as they come): that run rewrites them when it ends.
        fit_cost: Run nothing; refit the ``--dry-run`` cost model's constants from the finished steps'
            timings and write them to ``study/plan/cost_model.json``.
        strict: Refuse to run (one ``error:`` line, before any work) when cached steps of the plan were
            made by other code than the current (another source hash; see ``core/provenance.py``).
        rerun_stale: Redo the cached steps made by other code, and every cached step that depends on one
            (its inputs are remade); their old folders are kept as ``steps/<kind>/<key>.stale-<commit>``.
        push_to_hub: After the report, push ``episodes.parquet`` and ``results.csv`` with a dataset card to the
            Hugging Face dataset repo ``hub_repo_id`` (a token is checked before any work; an unreachable Hub
            is one warning line, and the local results stay complete). Not done while steps have failed.
        hub_repo_id: ``user/name`` of that dataset repo (required by ``push_to_hub`` unless ``model_repo_id``).
        model_repo_id: ``user/name`` of a model repo (the profiled checkpoint's): with ``push_to_hub``, a pull
            request adds ``.eval_results/factorworld.yaml`` and the per-episode Parquet to it (a profile only).
        reuse_from: Other studies' folders whose finished steps this study uses where the keys (the inputs)
            are the same, linked into ``steps/`` instead of run again (``study/run/reuse.py``): e.g. F3 and F5
            reuse F1's seed-0 collections, trainings and single-factor evaluations.
        only_methods: Run (and report) only these of the study's methods, a part of the study: another machine
            runs the others, and ``factorworld merge-results`` puts the parts together. Their steps keep their
            keys (:meth:`..plan.config.StudyConfig.only`). Empty: every method.
    """

    executor: str = "local"
    workers: int = 1
    ray_address: str | None = None
    execution: str = "grouped"
    dry_run: bool = False
    profile: bool = False
    fit_cost: bool = False
    report_only: bool = False
    strict: bool = False
    rerun_stale: bool = False
    push_to_hub: bool = False
    hub_repo_id: str | None = None
    model_repo_id: str | None = None
    reuse_from: list[str] = field(default_factory=list)
    only_methods: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        # steps run elsewhere (a worker's folder, a Ray node): the folders as seen from where the command runs
        self.reuse_from = [os.path.abspath(os.path.expanduser(folder)) for folder in self.reuse_from]
        self.check_options()

    @property
    def inspects(self) -> bool:
        """Whether this run only inspects the study (``dry_run``, ``profile``, ``fit_cost``): nothing runs."""
        return self.dry_run or self.profile or self.fit_cost

    def check_options(self) -> None:
        """Refuse a bad option in one line naming the valid choices (``reuse_from``'s folders are checked
        against the study's own folder by :func:`.reuse.check_reuse_from`, which needs the grid's ``out_dir``)."""
        if self.executor not in EXECUTORS:
            raise ValueError(f"unknown executor {self.executor!r}; valid executors: {', '.join(EXECUTORS)}")
        if self.execution not in EXECUTIONS:
            raise ValueError(f"unknown execution {self.execution!r}; valid: {', '.join(EXECUTIONS)}")
        if self.workers < 1:
            raise ValueError(f"workers must be at least 1, got {self.workers}")
        if self.strict and self.rerun_stale:
            raise ValueError("strict=true refuses steps made by other code, rerun_stale=true redoes them: set one")
        if sum((self.dry_run, self.profile, self.fit_cost)) > 1:
            raise ValueError("dry_run, profile and fit_cost each inspect the study in their own way: set one")
        if self.report_only:
            clashing = [name for name in REPORT_ONLY_CLASHES if getattr(self, name)]
            if clashing:
                raise ValueError(
                    f"report_only writes the report of the finished steps and runs nothing; {', '.join(clashing)} "
                    "would run or inspect: set one"
                )
            if self.reuse_from:
                raise ValueError(
                    "report_only reports the steps in the study's own folder; reuse_from links other studies' "
                    "steps into it only when the study runs: drop it, or run the study"
                )
        if self.push_to_hub:
            if not self.hub_repo_id and not self.model_repo_id:
                raise ValueError(
                    "push_to_hub=true needs --hub_repo_id=<user>/<name>, the Hugging Face dataset repo to push to"
                    " (or --model_repo_id=<user>/<name>, the model repo to open a pull request on)"
                )
            for name in ("hub_repo_id", "model_repo_id"):
                if getattr(self, name):
                    check_hub_repo_id(getattr(self, name), name)
