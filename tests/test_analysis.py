"""A report computes each shared quantity once (issue 74, "Analyse once, render many"): ``report/write.py``
builds one ``StudyAnalysis`` and report.md, report.html and the plots render it."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from lerobot_factorworld.study.analysis import study as analysis_study
from lerobot_factorworld.study.report.write import regenerate_report
from lerobot_factorworld.study.results import aggregate

F1 = Path(__file__).resolve().parents[1] / "docs" / "results" / "f1_ordering"


def _key(rows, *args) -> tuple:
    """What a call computes on: the rows' studies and tasks, then its arguments."""
    return (tuple(sorted({r["study"] for r in rows})), tuple(sorted({r["task"] for r in rows})), *map(str, args))


@pytest.fixture
def counted(monkeypatch):
    """Counts of each bootstrap, pooling and verdict call by what it computes on, wherever it is called from."""
    calls: Counter = Counter()

    def counting(module, name):
        original = getattr(module, name)

        def wrapped(rows, *args, **kwargs):
            calls[(name, *_key(list(rows), *args))] += 1
            return original(rows, *args, **kwargs)

        monkeypatch.setattr(module, name, wrapped)

    for name in ("factor_gap_bootstrap", "task_orderings", "per_task_success"):
        counting(aggregate, name)  # calls inside aggregate.py (task_orderings' per-task bootstraps)
        counting(analysis_study, name)  # the analysis' own
    decided = []
    original = analysis_study.decide_together
    monkeypatch.setattr(analysis_study, "decide_together", lambda studies: decided.append(1) or original(studies))
    return calls, decided


def test_the_f1_report_computes_each_bootstrap_once(counted, tmp_path):
    calls, decided = counted
    regenerate_report(F1 / "results.csv", F1 / "config.yaml", tmp_path)
    boots = {k: n for k, n in calls.items() if k[0] == "factor_gap_bootstrap"}
    own = [k for k in boots if k[1] == ("f1_ordering",)]
    methods = {k[3] for k in own}
    assert len(own) >= len(methods) + 3  # each method pooled over the tasks, and each of the three tasks alone
    assert {k: n for k, n in boots.items() if n != 1} == {}, "a bootstrap was resampled twice"
    assert [n for k, n in calls.items() if k[0] in ("task_orderings", "per_task_success")] == [1, 1]
    assert decided == [1]  # the claims, decided once for report.md and report.html
    assert (tmp_path / "report.md").read_text() == (F1 / "report.md").read_text()
