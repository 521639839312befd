"""Stale-step detection (study/plan/stale.py) where mutation testing found the suite silent (docs/testing.md): the
stale line's label count at exactly STALE_LABELS, the strict refusal's text, when the dirty-tree part joins the
warning, the warning flushed at once, the order and names of the folders set aside (a stale step's commit from the
list, its result not read again). Fast: result files written by hand, no step runs."""

from __future__ import annotations

import io
import json
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from lerobot_factorworld.core import provenance
from lerobot_factorworld.core.provenance import Provenance
from lerobot_factorworld.study.plan import stale
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.eval_settings import EvalSettings
from lerobot_factorworld.study.plan.grid import Plan, make_plan
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.run.options import RunOptions
from lerobot_factorworld.study.run.result import PROVENANCE, RESULT_FILE, is_done, read_result
from lerobot_factorworld.study.run.step import Step

OTHER = "826fe542cafcf25ef4dd4d5f7e92595c9abe6388"
NOW = Provenance("a" * 40, True, "1" * 64)
OLD = Provenance(OTHER, True, "0" * 64)


@pytest.fixture
def study(tmp_path, monkeypatch) -> tuple[StudyConfig, Plan, Path]:
    """A plan of 1 collection, 1 training and 3 evaluations, every step finished by ``NOW``."""
    monkeypatch.setattr(provenance, "current", lambda: NOW)
    cfg = StudyConfig(
        tasks=["door-open"],
        n_train_envs=[1],
        train_factors=["light", "table_texture"],
        factors=["light", "table_texture"],
        methods=[MethodConfig("bc", {"type": "bc"})],
        eval=EvalSettings(n_test_envs=2, episodes=2),
        out_dir=str(tmp_path / "study"),
    )
    plan = make_plan(cfg)
    assert plan.counts() == {"collect": 1, "train": 1, "eval": 3}
    for step in plan.steps:
        _made_by(step, tmp_path / "study", NOW)
    return cfg, plan, tmp_path / "study"


def _made_by(step: Step, study_dir: Path, made: Provenance | None) -> None:
    folder = step.folder(study_dir)
    folder.mkdir(parents=True, exist_ok=True)
    result = {PROVENANCE: made.to_dict()} if made else {}
    (folder / RESULT_FILE).write_text(json.dumps(result))


def test_exactly_stale_labels_steps_are_all_named_with_no_more(study):
    _, plan, _ = study
    evals = plan.of_kind("eval")
    three = [stale.Stale(s, OLD) for s in evals]
    assert len(three) == stale.STALE_LABELS
    text = stale.stale_summary(three, NOW)
    labels = "; ".join(s.label for s in evals)
    assert text == (
        f"3 cached steps were made by other code than the current, aaaaaaa: eval x3 at 826fe54 (e.g. {labels})"
    )
    one = stale.stale_summary(three[:1], NOW)
    assert one == f"1 cached step was made by other code than the current, aaaaaaa: eval x1 at 826fe54 (e.g. {evals[0].label})"  # fmt: skip


def test_strict_refuses_in_these_words(study):
    cfg, plan, _ = study
    found = [stale.Stale(plan.of_kind("collect")[0], OLD)]
    stale.check_not_stale(RunOptions(), found)  # not strict: nothing to refuse
    with pytest.raises(ValueError) as err:
        stale.check_not_stale(RunOptions(strict=True), found)
    assert str(err.value) == (
        f"{stale.stale_summary(found, NOW)}; --strict=true refuses to mix them with steps of the current code: "
        "--rerun_stale=true redoes them, or choose another out_dir"
    )


def test_the_dirty_tree_joins_the_warning_only_when_steps_run(study, monkeypatch):
    cfg, plan, study_dir = study
    dirty = replace(NOW, clean=False)
    monkeypatch.setattr(provenance, "current", lambda: dirty)
    collect = plan.of_kind("collect")[0]
    _made_by(collect, study_dir, OLD)
    found = stale.stale_steps(plan, study_dir)
    assert found == [stale.Stale(collect, OLD)]
    summary = stale.stale_summary(found, dirty)
    # every step cached and stale ones kept: nothing runs, so the dirty tree is not named
    assert stale.provenance_warning(RunOptions(), plan, study_dir, found) == (
        f"warning: {summary}; --rerun_stale=true redoes them, --strict=true refuses"
    )
    # redone: the stale step and its 4 dependents run with the dirty tree, and both parts are named, "; " apart
    assert stale.provenance_warning(RunOptions(rerun_stale=True), plan, study_dir, found) == (
        f"warning: {summary}; --rerun_stale=true: they and the 4 cached step(s) depending on them are redone "
        "(old folders kept as steps/<kind>/<key>.stale-<commit>); the current code, aaaaaaa-dirty (source "
        "111111111111), has uncommitted changes: steps run now are not reproducible from a commit"
    )
    assert stale.provenance_warning(RunOptions(), plan, study_dir, []) is None  # clean of stale steps, nothing to run


def test_rerun_stale_sets_dependents_aside_first_under_the_commit_that_made_each(study):
    _, plan, study_dir = study
    collect, (train,), evals = plan.of_kind("collect")[0], plan.of_kind("train"), plan.of_kind("eval")
    _made_by(collect, study_dir, OLD)
    _made_by(evals[1], study_dir, None)  # made before provenance was recorded
    found = stale.stale_steps(plan, study_dir)
    assert [s.step for s in found] == [collect, evals[1]]
    moved = stale.rerun_stale(plan, study_dir, found)
    # dependents first, in reverse plan order: an interruption leaves no cached step whose inputs are gone
    assert [p.name for p in moved] == [
        f"{evals[2].key}.stale-aaaaaaa",
        f"{evals[1].key}.stale-unknown",
        f"{evals[0].key}.stale-aaaaaaa",
        f"{train.key}.stale-aaaaaaa",
        f"{collect.key}.stale-826fe54",
    ]
    assert all(p.is_dir() and not is_done(s, study_dir) for p, s in zip(moved, plan.steps[::-1]))


def test_the_warning_reaches_a_block_buffered_stderr_at_once(study, monkeypatch):
    _, plan, study_dir = study
    _made_by(plan.of_kind("collect")[0], study_dir, OLD)
    found = stale.stale_steps(plan, study_dir)
    raw = io.BytesIO()
    # no line buffering: what is printed stays in the wrapper until a flush (stderr piped through such a stream)
    monkeypatch.setattr(sys, "stderr", io.TextIOWrapper(raw, encoding="utf-8"))
    stale.warn_stale(RunOptions(), plan, study_dir, [])  # nothing stale, clean tree, nothing to run: no line
    assert raw.getvalue() == b""
    stale.warn_stale(RunOptions(), plan, study_dir, found)  # before hours of steps: flushed, not held
    summary = stale.stale_summary(found, NOW)
    assert raw.getvalue().decode() == f"warning: {summary}; --rerun_stale=true redoes them, --strict=true refuses\n"


def test_rerun_stale_takes_a_stale_steps_commit_from_the_list_without_reading_its_result_again(study, monkeypatch):
    _, plan, study_dir = study
    collect, (train,), evals = plan.of_kind("collect")[0], plan.of_kind("train"), plan.of_kind("eval")
    _made_by(collect, study_dir, OLD)
    found = stale.stale_steps(plan, study_dir)
    assert found == [stale.Stale(collect, OLD)]
    read = []

    def spy(step: Step, folder: Path) -> dict:
        read.append(step.key)
        return read_result(step, folder)

    monkeypatch.setattr(stale, "read_result", spy)
    moved = stale.rerun_stale(plan, study_dir, found)
    # only the 4 dependents' results are read (reverse plan order); the collection's commit is the list's
    assert read == [evals[2].key, evals[1].key, evals[0].key, train.key]
    assert [p.name for p in moved] == [
        *(f"{s.key}.stale-aaaaaaa" for s in (evals[2], evals[1], evals[0], train)),
        f"{collect.key}.stale-826fe54",
    ]
