"""``results.csv`` rows (study/results/rows.py) where mutation testing found the suite silent (docs/testing.md): the
study and policy columns, a given checkpoint's policy, undefined gaps as NaN, the radius of single-factor rows
only, an evaluation without episodes, a commit outside git, the file's line ends and its radius column read
back. Evaluation steps are built by hand (no study runs); the outcomes differ between train and the shifts."""

from __future__ import annotations

import math

import pytest

from lerobot_factorworld.core.provenance import Provenance
from lerobot_factorworld.stats import proportions
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.results.rows import (
    RESULT_COLUMNS,
    Evaluation,
    csv_text,
    parse_stage_counts,
    read_results,
    result_rows,
    stage_counts_text,
    write_results,
)
from lerobot_factorworld.study.run.step import Step

TRAIN = [True, True, True, False, True, True, False, True]  # 6 of 8
SHIFTED = [True, False, False, False, True, False, True, False]  # 3 of 8: 4 train-only, 1 shifted-only
SEEDS = list(range(1000, 1008))


def _eval(method: str, checkpoint: str, condition: str, successes: list[bool], widths: str = "default", **result):
    meta = {"method": method, "task": "door-open", "n_train_envs": 2, "seed": 0, "widths": widths}
    step = Step(
        "eval", {"condition": condition, "checkpoint": checkpoint}, (checkpoint,), {**meta, "condition": condition}
    )
    outcome = {"successes": successes, "seeds": SEEDS[: len(successes)], "n_envs": 4, "envs_visited": 4}
    return Evaluation(step, {**outcome, "fingerprint": "f" * 16, **result})


@pytest.fixture(scope="module")
def cfg() -> StudyConfig:
    return StudyConfig(name="paired", tasks=["door-open"], methods=[MethodConfig("bc", {"type": "bc"})])


def test_rows_name_the_study_and_policy_and_hold_the_signed_paired_gap(cfg):
    rows = result_rows(
        cfg,
        [
            _eval("bc", "t1", "train", TRAIN),
            _eval("bc", "t1", "camera_pos", SHIFTED),
            _eval("bc", "t1", "light", TRAIN[::-1]),
            _eval("bc", "t1", "camera_pos+light", SHIFTED[::-1]),
            _eval("bc", "t2", "train", SHIFTED, widths="camera_pos=wide"),
            _eval("bc", "t2", "camera_pos", TRAIN, widths="camera_pos=wide"),
        ],
    )
    assert {(r["study"], r["policy"]) for r in rows} == {("paired", "bc")}
    by = {(r["condition"], r["widths"]): r for r in rows}
    shifted = by[("camera_pos", "default")]
    assert shifted["train_success_rate"] == 0.75 and shifted["success_rate"] == 0.375
    gap, low, high = proportions.paired_gap(TRAIN, SHIFTED)
    assert gap == 0.375 and (shifted["gap"], shifted["gap_ci_low"], shifted["gap_ci_high"]) == (gap, low, high)
    assert by[("camera_pos", "camera_pos=wide")]["gap"] == -0.375  # the shift succeeds more: a negative gap
    # the radius of single-factor rows of camera_pos / table_pos only: the default (narrow) and the wide sweep
    radius = {key: r["radius_m"] for key, r in by.items()}
    assert radius == {
        ("train", "default"): None,
        ("camera_pos", "default"): 0.025,
        ("light", "default"): None,
        ("camera_pos+light", "default"): None,
        ("train", "camera_pos=wide"): None,
        ("camera_pos", "camera_pos=wide"): 0.075,
    }


def test_an_undefined_gap_is_nan_and_an_evaluation_without_episodes_has_no_rate(cfg):
    other_seeds = _eval("bc", "t1", "train", TRAIN)
    other_seeds.result["seeds"] = [s + 1 for s in SEEDS]  # train on other episode seeds: not paired
    (unpaired, _, empty) = result_rows(
        cfg, [_eval("bc", "t1", "light", SHIFTED), other_seeds, _eval("bc", "t9", "light", [])]
    )
    for key in ("gap", "gap_ci_low", "gap_ci_high", "train_success_rate"):
        assert isinstance(unpaired[key], float) and math.isnan(unpaired[key]), key
    assert (
        csv_text([unpaired], ["gap", "train_success_rate", "success_rate"])
        == "gap,train_success_rate,success_rate\n,,0.375000\n"
    )
    assert empty["episodes"] == 0 and math.isnan(empty["success_rate"]) and math.isnan(empty["ci_low"])


def test_a_given_checkpoints_policy_comes_from_its_result(cfg):
    rows = result_rows(
        cfg,
        [
            _eval("published", "c1", "train", TRAIN, policy_type="rt1"),
            _eval("older", "c2", "train", TRAIN),  # evaluated before the policy type was recorded
        ],
    )
    assert [r["policy"] for r in rows] == ["rt1", ""]


def test_a_commit_outside_git_is_empty_and_the_file_reads_back_typed(cfg, tmp_path):
    outside = Provenance(None, None, "ab" * 32)
    dirty = Provenance("c" * 40, False, "cd" * 32)
    rows = result_rows(
        cfg,
        [
            _eval("bc", "t1", "train", TRAIN, provenance=outside.to_dict()),
            _eval("bc", "t1", "camera_pos", SHIFTED, provenance=dirty.to_dict(), stages=["none", "moved"]),
        ],
    )
    assert [(r["commit"], r["source_hash"]) for r in rows] == [
        ("", "abababababab"),
        ("c" * 40 + "-dirty", "cdcdcdcdcdcd"),
    ]
    text = csv_text(rows, RESULT_COLUMNS)
    assert "\r" not in text and text.count("\n") == 3  # "\n" line ends, as the docstring says
    back = read_results(write_results(rows, tmp_path / "results.csv"))
    assert [r["radius_m"] for r in back] == [None, 0.025]  # an empty radius is None, a radius a float
    assert back[1]["stages"] == "none:1;reached:0;moved:1;succeeded:0" and back[1]["gap"] == 0.375


def test_stage_counts_round_trip_a_stage_name_holding_a_colon():
    text = stage_counts_text("door-open", ["succeeded", "legacy:grasp", "none", "legacy:grasp"])
    assert text == "none:1;reached:0;moved:0;succeeded:1;legacy:grasp:2"  # a stage the task no longer has: last
    assert parse_stage_counts(text) == {"none": 1, "reached": 0, "moved": 0, "succeeded": 1, "legacy:grasp": 2}
