"""A finished training grows (``train.extends``): 10 epochs continued to 20 give the checkpoint files of 20 epochs
trained in one run, the continued training trains only from the 10-epoch training's last saved pass, its key holds
the training it continues, and a learning curve's earlier points keep the shorter training's evaluation keys."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from toy_study import write_toy_study

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.cost import describe, step_cost
from lerobot_factorworld.study.plan.grid import CURVE_EPOCHS, make_plan
from lerobot_factorworld.study.results.curve import curve_rows
from lerobot_factorworld.study.run.options import RunOptions


def _command(
    folder: Path, epochs: float = 20, extends: tuple = (10,), name: str = "study", curve_every: float = 5
) -> StudyCommand:
    train = {"epochs": epochs, "curve_every": curve_every, "extends": list(extends)}
    path = write_toy_study(folder / f"{name}.yaml", folder / name, train=train)
    return parse_config(StudyCommand, [f"--config_path={path}"], "study")


def test_a_continued_training_is_keyed_by_the_one_it_continues_and_costs_only_its_new_epochs(tmp_path):
    cfg = _command(tmp_path).grid()
    plan = make_plan(cfg)
    short, long = plan.of_kind("train")
    assert (short.inputs["epochs"], long.inputs["epochs"], long.inputs["extends"]) == (10, 20, 10)
    assert "extends" not in short.inputs and long.deps[-1] == short.key  # the first link: a plain 10-epoch training
    plain = make_plan(_command(tmp_path, epochs=10, extends=(), name="plain").grid())
    assert short.key == plain.of_kind("train")[0].key  # the same key as 10 epochs trained by any study
    scratch = make_plan(_command(tmp_path, extends=(), name="scratch").grid()).of_kind("train")[0]
    assert "extends" not in scratch.inputs and scratch.key != long.key
    # the curve's 5- and 10-epoch points are the 10-epoch training's, with the keys a 10-epoch study gives them (10:
    # its last checkpoint, evaluated once that training ends), 15 the continued one's
    by_epochs = {s.meta[CURVE_EPOCHS]: s for s in plan.curve_points()}
    assert {e: s.deps[0] for e, s in by_epochs.items()} == {5: short.key, 10: short.key, 15: long.key}
    assert by_epochs[5].key == plain.curve_points()[0].key
    (plain_last,) = [s for s in plain.evaluations() if s.meta["condition"] == "train"]
    assert by_epochs[10].key == plain_last.key and "checkpoint_epochs" not in by_epochs[10].inputs
    index = {s.key: s for s in plan.steps}
    model = {"train": {"fixed_s": 0.0, "sample_s": {"bc": 1.0}}}
    scratch_index = {s.key: s for s in make_plan(_command(tmp_path, extends=(), name="scratch").grid()).steps}
    assert step_cost(long, index, model)[1] == pytest.approx(step_cost(scratch, scratch_index, model)[1] / 2)
    text = describe(cfg, plan, RunOptions(dry_run=True))
    assert "continues: bc 10 -> 20 epochs (trains only the 10 new epochs" in text and "to run)" in text


def test_a_method_s_own_extends_chains_its_training_as_the_study_s_does(tmp_path):
    """F9's RT-1 arm continues the chain of learning/rt1_curve_pick_160 by setting the chain in its own ``train``:
    the same keys as the chain set in the study's ``train``, and the study's other methods train in one run."""
    settings = {"epochs": 20, "curve_every": 5, "extends": [10]}
    chained = make_plan(_command(tmp_path).grid())
    methods = [
        {"name": "bc", "policy": {"type": "bc"}, "train": settings},
        {"name": "bc_lang", "policy": {"type": "bc", "use_language": True}},
    ]
    path = write_toy_study(tmp_path / "own.yaml", tmp_path / "own", methods=methods, train={"epochs": 20})
    own = make_plan(parse_config(StudyCommand, [f"--config_path={path}"], "study").grid())
    trains = {s.meta["method"]: [] for s in own.of_kind("train")}
    for step in own.of_kind("train"):
        trains[step.meta["method"]].append(step.key)
    assert trains["bc"] == [s.key for s in chained.of_kind("train")] and len(trains["bc_lang"]) == 1
    assert {s.key for s in chained.curve_points()} <= {s.key for s in own.curve_points()}


@pytest.mark.parametrize(
    ("extends", "message"),
    [((10, 5), "increasing epochs below train.epochs"), ((20,), "increasing epochs"), ((0,), "increasing")],
)
def test_bad_budgets_to_continue_are_refused_in_one_line(tmp_path, extends, message):
    with pytest.raises(ValueError, match=message):
        _command(tmp_path, extends=extends).grid()


@pytest.mark.slow
def test_ten_epochs_continued_to_twenty_give_the_checkpoint_files_of_twenty_from_scratch(tmp_path):
    from lerobot_factorworld.study.runner import run_study

    scratch = _command(tmp_path, extends=(), name="scratch")
    outcome = run_study(*scratch.parts(), command="scratch")
    assert not outcome.failed, outcome.failed
    grown = _command(tmp_path, name="grown")
    shutil.copytree(tmp_path / "scratch" / "steps" / "collect", tmp_path / "grown" / "steps" / "collect")
    outcome = run_study(*grown.parts(), command="grown")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 0, "train": 2, "eval": 4}
    short, long = make_plan(grown.grid()).of_kind("train")
    (plain,) = make_plan(scratch.grid()).of_kind("train")
    result = json.loads((long.folder(grown.grid().out_dir) / "result.json").read_text())
    # 51 frames in batches of 8: a pass is 7 steps; 10 epochs are 64 steps, so it continues from 63
    assert (result["steps"], result["resumed_from"], result["extends"]) == (128, 63, short.key)
    assert result["curve"] == {"15": 96}  # its own points; 5 and 10 epochs are the shorter training's
    # its runs: the shorter training's (from 0), then its own from 63, on one machine and one dataset
    assert [run["from_step"] for run in result["trained_on"]] == [0, 63]
    assert len({json.dumps(run["machine"]) + run["dataset"] for run in result["trained_on"]}) == 1
    checkpoints = {
        step: long.folder(grown.grid().out_dir) / "train" / "checkpoints" / f"{step:06d}" for step in (64, 96, 128)
    }
    checkpoints[32] = short.folder(grown.grid().out_dir) / "train" / "checkpoints" / "000032"
    for step, mine in checkpoints.items():
        theirs = plain.folder(scratch.grid().out_dir) / "train" / "checkpoints" / f"{step:06d}"
        files = sorted(p.relative_to(theirs) for p in theirs.rglob("*") if p.is_file())
        assert files == sorted(p.relative_to(mine) for p in mine.rglob("*") if p.is_file()) and len(files) >= 8
        for name in files:
            a, b = (theirs / name).read_bytes(), (mine / name).read_bytes()
            if name.name == "train_config.json" and step != 32:  # names its folder; 32's also its own steps
                a = a.replace(str(theirs.parents[2]).encode(), str(mine.parents[2]).encode())
                a = a.replace(str(tmp_path / "scratch").encode(), str(tmp_path / "grown").encode())
            if name.name != "train_config.json" or step != 32:
                assert a == b, f"{name} of step {step} differs"
    # the curve reads each point's gradient step from the training that saved it (10 epochs: the shorter one's last)
    rows = curve_rows(grown.grid(), make_plan(grown.grid()), grown.grid().out_dir)
    assert [(r["epochs"], r["steps"]) for r in rows] == [(5, 32), (10, 64), (15, 96), (20, 128)]
    assert len({r["trained_on"] for r in rows}) == 1 and re.search(
        r"; \d+ CPUs(;|$)", rows[0]["trained_on"]
    )  # a oneDNN cap follows
    assert [r["trained_since_previous"] for r in rows] == [r["trained_on"] for r in rows]  # one machine throughout


def test_a_chained_curve_s_point_at_a_link_s_end_is_that_link_s_last_step(tmp_path):
    """Where a pass does not divide the budget (51 frames at batch 8, a point every 4 epochs, a link at 8), the
    8-epoch point is the 8-epoch link's last checkpoint, ceil(8 x 51 / 8) = 51 steps, not the 52 a one-run
    curve saves (2 x ceil(4 x 51 / 8)): curve.csv says which step each point is."""
    cfg = _command(tmp_path, epochs=16, extends=(8,), curve_every=4).grid()
    plan = make_plan(cfg)
    short, long = plan.of_kind("train")
    by_epochs = {s.meta[CURVE_EPOCHS]: s for s in plan.curve_points()}
    assert {e: s.deps[0] for e, s in by_epochs.items()} == {4: short.key, 8: short.key, 12: long.key}
    results = {short.key: {"steps": 51, "curve": {"4": 26}}, long.key: {"steps": 102, "curve": {"12": 78}}}
    for step in plan.steps:
        folder = step.folder(cfg.out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        result = results.get(step.key, {"successes": [True]}) if step.kind != "collect" else {}
        (folder / "result.json").write_text(json.dumps(result))
    rows = curve_rows(cfg, plan, cfg.out_dir)
    assert [(r["epochs"], r["steps"]) for r in rows] == [(4, 26), (8, 51), (12, 78), (16, 102)]
