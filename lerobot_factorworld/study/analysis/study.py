"""One analysis of a study (:class:`StudyAnalysis`), built once per report by :func:`analyze` and rendered by
report.md, report.html and the plots alike: a number they share is then computed once, so they agree by
construction rather than by calling the same functions with the same arguments."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

from ..plan.config import StudyConfig
from ..results.aggregate import (
    FactorGapBootstrap,
    factor_gap_bootstrap,
    per_task_success,
    stage_counts,
    task_orderings,
)
from ..results.claims import ClaimVerdict, decide_together, study_claims

Pooled = tuple[int, int, float, float]  # successes, episodes, 95% interval low, high (aggregate.pooled_success)


@dataclass(frozen=True)
class StudyAnalysis:
    """What the reports share, each computed once.

    Args:
        gap_bootstraps: per method (config order), its seed-level bootstrap of the mean gap per factor of
            ``cfg.factors`` (empty without rows or factors): the factor ordering table and figures.
        shifted_bootstrap: the first method's over ``cfg.shifted_factors()`` (the same object as its
            ``gap_bootstraps`` entry when no family condition is among the factors): the per-task plot's order.
        task_orderings: per task with rows (two or more), the first method's bootstrap over the shifted
            factors on that task's rows alone.
        per_task_success: success per (method, task, N, condition), pooled over seeds, with its interval.
        verdicts: the study's claims decided on the rows, corrected with its finding's other studies.
        stage_counts: episodes per furthest stage per (method, task, N, condition), pooled over seeds.
    """

    gap_bootstraps: Mapping[str, FactorGapBootstrap] = field(default_factory=lambda: MappingProxyType({}))
    shifted_bootstrap: FactorGapBootstrap | None = None
    task_orderings: Mapping[str, FactorGapBootstrap] = field(default_factory=lambda: MappingProxyType({}))
    per_task_success: Mapping[tuple, Pooled] = field(default_factory=lambda: MappingProxyType({}))
    verdicts: tuple[ClaimVerdict, ...] = ()
    stage_counts: Mapping[tuple, Mapping[str, int]] = field(default_factory=lambda: MappingProxyType({}))


def analyze(
    cfg: StudyConfig, rows: Sequence[dict], companions: Sequence[tuple[StudyConfig, Sequence[dict]]] = ()
) -> StudyAnalysis:
    """The :class:`StudyAnalysis` of ``rows`` (``results.csv``'s, typed by ``read_results``) under ``cfg``;
    ``companions``: the other studies of its finding, whose claims are corrected with its own. An
    ``eval.episodes=auto`` study gets its stage counts alone: every other quantity rests on fixed-n intervals,
    which its stopping invalidates."""
    rows = list(rows)
    stages = MappingProxyType(stage_counts(rows))
    if not rows or cfg.eval.auto:
        return StudyAnalysis(stage_counts=stages)
    boots: dict[str, FactorGapBootstrap] = {}
    shifted = None
    orderings: dict[str, FactorGapBootstrap] = {}
    if cfg.factors:
        boots = {m.name: factor_gap_bootstrap(rows, m.name, cfg.factors) for m in cfg.methods}
        method = cfg.methods[0].name
        factors = cfg.shifted_factors()
        same = list(factors) == list(cfg.factors)
        shifted = boots[method] if same else factor_gap_bootstrap(rows, method, factors)
        tasks = [t for t in cfg.tasks if any(r["task"] == t for r in rows)]
        if len(tasks) > 1:
            orderings = task_orderings(rows, method, factors, tasks)
    return StudyAnalysis(
        gap_bootstraps=MappingProxyType(boots),
        shifted_bootstrap=shifted,
        task_orderings=MappingProxyType(orderings),
        per_task_success=MappingProxyType(per_task_success(rows, cfg.factors)),
        verdicts=tuple(decide_claims(cfg, rows, companions)),
        stage_counts=stages,
    )


def decide_claims(
    cfg: StudyConfig, rows: Sequence[dict], companions: Sequence[tuple[StudyConfig, Sequence[dict]]] = ()
) -> list[ClaimVerdict]:
    """The study's claims decided on ``rows`` (none without rows), corrected together with those of
    ``companions``, the other studies of its finding: what report.md and report.html both print."""
    if not rows:
        return []
    studies = [(study_claims(cfg), cfg, rows), *((study_claims(c), c, r) for c, r in companions if r)]
    return decide_together(studies)[0]
