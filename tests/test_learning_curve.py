"""A learning curve as a study feature (``train.curve_every``): the training saves a checkpoint every k epochs,
each is evaluated on ``train`` as its own cached step, and ``curve.csv`` / the report's "Learning curve" give
P_T against epochs with intervals; a study without it keeps every key it had."""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import pytest

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.config import TrainSettings
from lerobot_factorworld.study.plan.grid import CURVE_EPOCHS, make_plan
from lerobot_factorworld.study.results.curve import CURVE_FILE, pooled_curve, read_curve
from lerobot_factorworld.study.run.inputs import EvalInputs, TrainInputs
from lerobot_factorworld.study.run.steps import curve_saves

CURVE = """
name: curve
out_dir: {out}
tasks: [handle-press]
n_train_envs: [1]
seeds: [0]
train_factors: [light]
factors: []
methods:
  - name: bc
    policy: {{type: bc}}
collect:
  demos: 2
  max_episode_steps: 60
  image_size: 48
train:
  epochs: 3
  batch_size: 8
  curve_every: {every}
eval:
  n_test_envs: 1
  episodes: 2
  max_episode_steps: 8
  record_episodes: 0
workers: 2
"""


def _command(tmp_path: Path, every: float = 1) -> StudyCommand:
    path = tmp_path / f"curve_{every}.yaml"
    path.write_text(CURVE.format(out=tmp_path / "out", every=every))
    return parse_config(StudyCommand, [f"--config_path={path}"], "study")


def test_the_curve_epochs_are_every_k_before_the_last():
    assert TrainSettings(epochs=60, curve_every=20).curve_epochs() == [20, 40]
    assert TrainSettings(epochs=50, curve_every=20).curve_epochs() == [20, 40]
    assert TrainSettings(epochs=3, curve_every=1.5).curve_epochs() == [1.5]
    assert TrainSettings(epochs=60).curve_epochs() == [] and TrainSettings(curve_every=5).curve_epochs() == []


def test_the_saves_are_multiples_of_the_first_checkpoints_step_before_the_last():
    inputs = TrainInputs({"type": "bc"}, 0, None, 60, 32, 1, "cpu", (), {}, curve_every=20)
    # 20 epochs of 1000 frames at batch 32: ceil(625) steps; the last (1875) is the grid's own checkpoint
    assert curve_saves(inputs, 1000, math.ceil(60 * 1000 / 32)) == {"20": 625, "40": 1250}
    assert curve_saves(replace(inputs, curve_every=None), 1000, 1875) == {}
    assert curve_saves(replace(inputs, curve_every=25), 1000, 1875) == {"25": 782, "50": 1564}


def test_a_curve_adds_evaluations_of_earlier_checkpoints_and_only_its_training_key_changes(tmp_path):
    with_curve, without = (
        _command(tmp_path).grid(),
        replace(_command(tmp_path).grid(), train=TrainSettings(epochs=3, batch_size=8)),
    )
    plan, plain = make_plan(with_curve), make_plan(without)
    assert [s.meta[CURVE_EPOCHS] for s in plan.curve_points()] == [1, 2]
    assert [s.key for s in plan.evaluations()] != [s.key for s in plain.evaluations()]  # another training
    (train,), (plain_train,) = plan.of_kind("train"), plain.of_kind("train")
    assert train.inputs["curve_every"] == 1 and "curve_every" not in plain_train.inputs  # old keys hold
    assert {k: v for k, v in train.inputs.items() if k != "curve_every"} == plain_train.inputs
    for step in plan.curve_points():
        inputs = EvalInputs.from_dict(step.inputs)
        assert inputs.condition == "train" and step.deps == (train.key, plan.of_kind("collect")[0].key)
    assert all("checkpoint_epochs" not in s.inputs for s in plan.evaluations())
    assert len({s.key for s in plan.of_kind("eval")}) == 3


@pytest.mark.parametrize(
    "train, message",
    [
        ({"epochs": None, "steps": 10, "curve_every": 2}, "train.curve_every is a number of epochs"),
        ({"epochs": 3, "curve_every": -1}, "train.curve_every is a number of epochs"),
    ],
)
def test_a_curve_without_epochs_is_refused(tmp_path, train, message):
    cfg = _command(tmp_path).grid()
    with pytest.raises(ValueError, match=message):
        replace(cfg, train=TrainSettings(**train))


def test_the_pooled_curve_sums_episodes_per_checkpoint_with_wilson_intervals():
    rows = [
        {"method": "bc", "task": "t", "epochs": 10.0, "successes": 3, "episodes": 10},
        {"method": "bc", "task": "t", "epochs": 10.0, "successes": 5, "episodes": 10},
        {"method": "bc", "task": "t", "epochs": 20.0, "successes": 9, "episodes": 10},
    ]
    first, second = pooled_curve(rows)
    assert (first["epochs"], first["successes"], first["episodes"], first["cells"]) == (10.0, 8, 20, 2)
    assert first["success_rate"] == 0.4 and second["success_rate"] == 0.9
    assert first["ci_low"] == pytest.approx(0.2188, abs=1e-4) and first["ci_high"] == pytest.approx(0.6134, abs=1e-4)


@pytest.mark.slow
def test_a_study_with_a_curve_evaluates_each_checkpoint_and_reports_it(tmp_path):
    from lerobot_factorworld.study.report.write import regenerate_report
    from lerobot_factorworld.study.runner import run_study

    cmd = _command(tmp_path)
    outcome = run_study(*cmd.parts(), command="curve")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 1, "train": 1, "eval": 3}
    rows = read_curve(tmp_path / "out" / CURVE_FILE)
    assert [r["epochs"] for r in rows] == [1, 2, 3] and all(r["episodes"] == 2 for r in rows)
    steps = [r["steps"] for r in rows]
    assert steps[1] == 2 * steps[0] and steps[2] > steps[1]
    checkpoints = sorted(p.name for p in (tmp_path / "out" / "steps" / "train").glob("*/train/checkpoints/*"))
    assert [int(name) for name in checkpoints if name.isdigit()] == steps
    plan = make_plan(cmd.grid())
    for step, saved in zip(plan.curve_points(), steps):  # each point evaluated its own checkpoint
        result = (step.folder(tmp_path / "out") / "result.json").read_text()
        assert f"checkpoints/{int(saved):06d}/pretrained_model" in result
    with open(tmp_path / "out" / "results.csv") as f:
        assert [r["condition"] for r in csv.DictReader(f)] == ["train"]  # the grid's rows only
    report = (tmp_path / "out" / "report.md").read_text()
    assert "## Learning curve" in report and "| bc | handle-press | " in report
    assert (tmp_path / "out" / "learning_curve.png").stat().st_size > 1000
    # regenerated from the committed files alone, into another folder: the same section
    regenerate_report(tmp_path / "out" / "results.csv", out=tmp_path / "published")
    assert (tmp_path / "published" / CURVE_FILE).is_file()
    again = (tmp_path / "published" / "report.md").read_text()

    def section(text: str) -> str:
        start = text.index("## Learning curve")
        return text[start : text.index(f"(`{CURVE_FILE}`).*", start)]

    assert section(again) == section(report)
