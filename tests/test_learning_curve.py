"""A learning curve as a study feature (``train.curve_every``): the training saves a checkpoint every k epochs,
each is evaluated on ``train`` as its own cached step, and ``curve.csv`` / the report's "Learning curve" give
P_T against epochs with intervals; a study without it keeps every key it had."""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import pytest
from toy_study import write_toy_study

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.envs.stages import stage_names
from lerobot_factorworld.stats.proportions import newcombe_independent, paired_gap
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.grid import CURVE_EPOCHS, make_plan
from lerobot_factorworld.study.plan.train_settings import TrainSettings
from lerobot_factorworld.study.report.curve_report import curve_section
from lerobot_factorworld.study.results.curve import (
    CURVE_COLUMNS,
    CURVE_FILE,
    OPTIONAL_CURVE_COLUMNS,
    machines_between,
    machines_text,
    pooled_curve,
    read_curve,
    write_curve,
)
from lerobot_factorworld.study.results.merge import merge_curve_rows
from lerobot_factorworld.study.results.rows import parse_stage_counts
from lerobot_factorworld.study.run.inputs import EvalInputs, TrainInputs
from lerobot_factorworld.study.run.train_schedule import curve_saves


def _command(tmp_path: Path, every: float = 1) -> StudyCommand:
    train, evaluation = {"epochs": 3, "curve_every": every}, {"episodes": 2}
    path = write_toy_study(tmp_path / f"curve_{every}.yaml", tmp_path / "out", train=train, eval=evaluation, workers=2)
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


def test_newcombe_s_interval_for_two_independent_rates_is_his_published_example():
    """Newcombe (1998), Table II, example (a): 56/70 against 48/80, difference 0.2000, method 10 gives
    [0.0524, 0.3339]; no episodes on either side: no interval."""
    diff, low, high = newcombe_independent(56, 70, 48, 80)
    assert (diff, low, high) == pytest.approx((0.2, 0.0524, 0.3339), abs=5e-5)
    assert all(math.isnan(v) for v in newcombe_independent(3, 10, 0, 0))


def test_the_curve_section_gives_each_step_along_a_curve_and_each_method_against_the_first():
    """Two methods on one task saving at other epochs (``b`` at 4, 8, 12; ``a`` at 6, 12), ``b`` first in the
    config: each curve's steps are from its own checkpoint before, and ``a`` is set against ``b`` where both have
    a checkpoint, each with Newcombe's interval; one method with one checkpoint has no difference to show."""
    points = [("a", 6, 7), ("a", 12, 1), ("b", 4, 1), ("b", 8, 7), ("b", 12, 8)]
    rows = [{"method": m, "task": "t", "epochs": e, "successes": k, "episodes": 30} for m, e, k in points]
    text = "\n".join(curve_section(rows, plotted=False, methods=["b", "a"]))
    cell = lambda d: f"{d[0]:+.2f} [{d[1]:+.2f}, {d[2]:+.2f}]"  # noqa: E731
    a_step, b_steps = (
        newcombe_independent(1, 30, 7, 30),
        [newcombe_independent(7, 30, 1, 30), newcombe_independent(8, 30, 7, 30)],
    )
    assert "| method | against | task | 4 epochs | 6 epochs | 8 epochs | 12 epochs |" in text
    assert f"| a | its checkpoint before | t |  |  |  | {cell(a_step)} |" in text
    assert f"| b | its checkpoint before | t |  |  | {cell(b_steps[0])} | {cell(b_steps[1])} |" in text
    against = newcombe_independent(1, 30, 8, 30)
    assert f"| a | b | t |  |  |  | {cell(against)} |" in text and against[2] < 0  # a's 12 epochs resolved below b's
    assert "| b | a |" not in text
    assert "### Differences" not in "\n".join(curve_section(rows[:1], plotted=False, methods=["a"]))
    # the grid uses each method's full budget: the last column while no curve is short of it, else who is short
    assert "The last column is the checkpoint" in "\n".join(curve_section(rows, False, ["b", "a"], {"a": 12, "b": 12}))
    short = "\n".join(curve_section(rows, False, ["b", "a"], {"a": 12, "b": 16}))
    assert "Still training: b has reached 12 of its 16 epochs" in short and "The last column" not in short


def test_points_holding_their_episodes_outcomes_are_compared_episode_by_episode():
    """Points with ``outcomes`` (the same episode seeds at every checkpoint and for every method) get Newcombe's
    paired interval over their cells' episodes in one order; points are compared on the cells both have, marked
    where one has more; a cell without outcomes gets the independent interval, marked where a table has both."""
    early = "110000000000" + "0" * 18  # 2 of 30
    later = "111111000000" + "0" * 18  # 6 of 30: the two early successes again, and four more
    rows = [
        {"method": "b", "task": "t", "n_train_envs": 10, "seed": 0, "epochs": e, "episodes": 30,
         "successes": o.count("1"), "outcomes": o} for e, o in ((8, early), (16, later))
    ]  # fmt: skip
    text = "\n".join(curve_section(rows, plotted=False, methods=["b"]))
    diff, low, high = paired_gap([o == "1" for o in later], [o == "1" for o in early])
    independent = newcombe_independent(6, 30, 2, 30)
    assert diff == pytest.approx(independent[0]) == pytest.approx(4 / 30) and low > independent[1]  # narrower
    assert f"| b | its checkpoint before | t |  | {diff:+.2f} [{low:+.2f}, {high:+.2f}] |" in text
    assert "95% interval for paired samples (episode by episode) (each on its own" in text
    assert "indep." not in text and "†" not in text
    # a second cell (another seed) pairs its own episodes: 12 more, the later point losing one of its own
    second = [
        {**r, "seed": 1, "episodes": 12, "outcomes": o, "successes": o.count("1")}
        for r, o in zip(rows, ("1" * 12, "1" * 11 + "0"))
    ]
    (point_8, point_16) = pooled_curve(second + rows)  # cells in another order: paired by cell all the same
    assert point_8["by_cell"] == {("10", "0", ""): (2, 30, early), ("10", "1", ""): (12, 12, "1" * 12)}
    both = "\n".join(curve_section(second + rows, plotted=False, methods=["b"]))
    pooled = paired_gap([o == "1" for o in later + "1" * 11 + "0"], [o == "1" for o in early + "1" * 12])
    assert f"| {pooled[0]:+.2f} [{pooled[1]:+.2f}, {pooled[2]:+.2f}] |" in both
    # seed 1 still training at 16 epochs: the step is over seed 0 alone, marked, not pooled 8 against seed 0's 16
    training = "\n".join(curve_section(rows + second[:1], plotted=False, methods=["b"]))
    assert f"| {diff:+.2f} [{low:+.2f}, {high:+.2f}] † |" in training and "A difference marked † is over" in training
    # a method against the first on the cells both have: paired at 8 epochs; at 16 a cell without outcomes, marked
    other = [{**r, "method": "a", "outcomes": "0" * 30, "successes": 0} for r in rows]
    other[1] = {**other[1], "outcomes": ""}
    mixed = "\n".join(curve_section(rows + other, plotted=False, methods=["b", "a"]))
    against_8 = paired_gap([False] * 30, [o == "1" for o in early])
    against_16 = newcombe_independent(0, 30, 6, 30)
    assert f"| a | b | t | {against_8[0]:+.2f} [{against_8[1]:+.2f}, {against_8[2]:+.2f}] | " in mixed
    assert f" | {against_16[0]:+.2f} [{against_16[1]:+.2f}, {against_16[2]:+.2f}] (indep.) |" in mixed
    assert "or for two independent samples where a point lacks its episodes' outcomes" in mixed
    # a method on another seed only: no cell in common, no difference
    apart = [{**r, "method": "a", "seed": 3} for r in rows]
    assert "| a | b | t |  |  |" in "\n".join(curve_section(rows + apart, plotted=False, methods=["b", "a"]))
    # without outcomes (an older curve.csv): the independent interval and the text it always had
    old = "\n".join(curve_section([{**r, "outcomes": ""} for r in rows], plotted=False, methods=["b"]))
    assert f"| {independent[0]:+.2f} [{independent[1]:+.2f}, {independent[2]:+.2f}] |" in old
    assert "Newcombe's 95% interval for two independent samples (each on its own" in old and "paired samples" not in old


def test_the_curve_says_which_machines_trained_each_checkpoint(tmp_path):
    """A checkpoint's machines are its training's runs before the step it was saved at (``trained_on``), each once in
    the order they trained; the report says so in one sentence for one machine, per checkpoint otherwise."""
    amd = {"cpu": "AMD EPYC", "isa": ["avx2"], "isa_cap": None, "cpus": 2}
    intel = {"cpu": "Intel Xeon", "isa": ["amx_bf16", "avx2"], "isa_cap": None, "cpus": 2}
    runs = [{"from_step": 0, "machine": amd}, {"from_step": 100, "machine": intel}, {"from_step": 200, "machine": amd}]
    assert machines_text(runs, 100) == "AMD EPYC; avx2; 2 CPUs"
    assert machines_text(runs, 300) == "AMD EPYC; avx2; 2 CPUs | Intel Xeon; amx_bf16, avx2; 2 CPUs"
    assert machines_text([], 300) == ""
    # since the previous point: the runs whose steps fall after it (a run ends where the next one starts)
    assert machines_between(runs, 100, 300) == "Intel Xeon; amx_bf16, avx2; 2 CPUs | AMD EPYC; avx2; 2 CPUs"
    assert machines_between(runs, 120, 180) == "Intel Xeon; amx_bf16, avx2; 2 CPUs"
    assert machines_between(runs, 200, 300) == machines_between(runs, 0, 100) == "AMD EPYC; avx2; 2 CPUs"
    killed = [{"from_step": 0, "machine": amd}, {"from_step": 50, "machine": intel}, {"from_step": 50, "machine": amd}]
    assert machines_between(killed, 0, 100) == "AMD EPYC; avx2; 2 CPUs"  # Intel saved nothing before AMD resumed
    rows = [{"method": "a", "task": "t", "n_train_envs": 1, "seed": 0, "epochs": e, "successes": 1, "episodes": 4,
             "stages": "", "trained_on": machines_text(runs, at)} for e, at in ((10, 100), (20, 300))]  # fmt: skip
    text = "\n".join(curve_section(rows, plotted=False, methods=["a"]))
    assert "### Which machines trained the curve" in text
    assert "| a | t | 1 | 0 | 10 | AMD EPYC; avx2; 2 CPUs |" in text
    assert "| a | t | 1 | 0 | 20 | AMD EPYC; avx2; 2 CPUs; then Intel Xeon; amx_bf16, avx2; 2 CPUs |" in text
    # two cells each trained on one machine, another each (a study run in parts): a row per cell, none of two machines
    parts = [
        {**rows[0], "seed": seed, "trained_on": machines_text(runs[i : i + 1], 300)} for seed, i in ((0, 0), (1, 1))
    ]
    text = "\n".join(curve_section(parts, plotted=False, methods=["a"]))
    assert "| a | t | 1 | 1 | 10 | Intel Xeon; amx_bf16, avx2; 2 CPUs |" in text and "; then" not in text
    linked = [{**row, "trained_since_previous": machines_between(runs, after, at)}
              for row, (after, at) in zip(rows, ((0, 100), (100, 300)))]  # fmt: skip
    text = "\n".join(curve_section(linked, plotted=False, methods=["a"]))
    assert "| epochs | trained on | since the previous point |" in text
    assert (
        "| 20 | AMD EPYC; avx2; 2 CPUs; then Intel Xeon; amx_bf16, avx2; 2 CPUs | Intel Xeon; amx_bf16, avx2; 2 CPUs; then AMD EPYC; avx2; 2 CPUs |"
        in text
    )
    one = "\n".join(curve_section(rows[:1], plotted=False, methods=["a"]))
    assert "One machine trained every checkpoint: AMD EPYC; avx2; 2 CPUs." in one
    assert "### Which machines" not in "\n".join(curve_section([{**rows[0], "trained_on": ""}], False, ["a"]))
    path = write_curve([{c: rows[1].get(c, 0) for c in CURVE_COLUMNS}], tmp_path / CURVE_FILE)
    assert read_curve(path)[0]["trained_on"] == rows[1]["trained_on"]  # the separator survives the CSV


def test_the_curve_shows_where_each_checkpoint_s_episodes_end_and_reads_older_files_without_it(tmp_path):
    """Each checkpoint's episodes by furthest stage, pooled over cells: a point one of whose cells has no stage
    counts gets no row; a curve.csv written before the column existed is read (stages empty) and merged with a
    newer one holding the same point, which keeps its counts."""
    staged = [
        ("a", 10, "none:2;reached:1;succeeded:1"),
        ("a", 10, "none:2;reached:1;succeeded:1"),
        ("a", 20, "none:0;reached:1;succeeded:3"),
        ("b", 10, "none:4;reached:0;succeeded:0"),
        ("b", 10, ""),
    ]
    rows = [{"method": m, "task": "handle-press", "epochs": e, "successes": int(st[-1] if st else 0), "episodes": 4, "stages": st}
            for m, e, st in staged]  # fmt: skip
    text = "\n".join(curve_section(rows, plotted=False, methods=["a", "b"]))
    assert "### Where the curve's episodes end" in text
    assert "| method | task | epochs | episodes | none | reached | succeeded |" in text
    assert (
        "| a | handle-press | 10 | 8 | 0.50 | 0.25 | 0.25 |" in text
        and "| a | handle-press | 20 | 4 | 0.00 | 0.25 | 0.75 |" in text
    )
    assert "| b | handle-press |" not in text.split("### Where the curve's episodes end")[1]
    assert "### Where" not in "\n".join(curve_section([{**r, "stages": ""} for r in rows], False, ["a", "b"]))

    cmd = _command(tmp_path)
    plan = make_plan(cmd.grid())
    point = plan.curve_points()[0]
    new = {"study": "s", "method": "bc", "policy": "bc", "task": "handle-press", "n_train_envs": 1, "seed": 0,
           "widths": "default", "epochs": 1, "steps": 7, "episodes": 2, "successes": 1, "success_rate": 0.5,
           "ci_low": 0.1, "ci_high": 0.9, "step": point.key, "stages": "none:1;reached:0;succeeded:1"}  # fmt: skip
    old_file = tmp_path / "old.csv"
    old_columns = [c for c in CURVE_COLUMNS if c not in OPTIONAL_CURVE_COLUMNS]
    old_file.write_text(",".join(old_columns) + "\n" + ",".join(str(new[c]) for c in old_columns) + "\n")
    (old,) = read_curve(old_file)
    assert old["stages"] == "" and "### Where" not in "\n".join(curve_section([old], False, ["bc"]))
    for parts, names in (([[old], [new]], ["old", "new"]), ([[new], [old]], ["new", "old"])):  # either order
        assert [r["stages"] for r in merge_curve_rows(parts, plan, names)] == [new["stages"]]
    with pytest.raises(ValueError, match="differs between old and new in successes"):
        merge_curve_rows([[old], [{**new, "successes": 2}]], plan, ["old", "new"])
    with pytest.raises(
        ValueError, match="differs between new and again in outcomes"
    ):  # the same counts, other episodes
        merge_curve_rows([[{**new, "outcomes": "10"}], [{**new, "outcomes": "01"}]], plan, ["new", "again"])
    other = {**new, "stages": "none:0;reached:1;succeeded:1"}  # two parts that both hold stages must agree
    with pytest.raises(ValueError, match="differs between new and other in stages"):
        merge_curve_rows([[old], [new], [other]], plan, ["old", "new", "other"])  # named by the part that held it
    # written: the column where any row holds it (the others empty), left out where none does
    write_curve([old, {**new, "step": "b" * 16}], tmp_path / "mixed.csv")
    assert [r["stages"] for r in read_curve(tmp_path / "mixed.csv")] == ["", new["stages"]]
    write_curve([old], tmp_path / "once.csv")
    write_curve(read_curve(tmp_path / "once.csv"), tmp_path / "twice.csv")
    text = (tmp_path / "once.csv").read_text()
    assert "stages" not in text.splitlines()[0] and (tmp_path / "twice.csv").read_text() == text


def test_the_curve_s_stage_table_orders_the_task_s_stages_and_skips_points_without_episodes():
    """Cells of one checkpoint whose counts list the stages in another order (or lack one) give one row in the
    task's order; a checkpoint with no episodes has no shares to give."""
    rows = [
        {"method": "a", "task": "handle-press", "epochs": 5, "successes": 1, "episodes": 2,
         "stages": "succeeded:1;none:1"},
        {"method": "a", "task": "handle-press", "epochs": 5, "successes": 1, "episodes": 2,
         "stages": "none:0;reached:0;moved:1;succeeded:1"},
        {"method": "a", "task": "handle-press", "epochs": 10, "successes": 0, "episodes": 0,
         "stages": "none:0;reached:0;moved:0;succeeded:0"},
    ]  # fmt: skip
    (first, second) = pooled_curve(rows)
    assert list(first["stages"]) == ["none", "reached", "moved", "succeeded"]
    text = "\n".join(curve_section(rows, plotted=False, methods=["a"]))
    assert "| a | handle-press | 5 | 4 | 0.25 | 0.00 | 0.25 | 0.50 |" in text
    assert "| a | handle-press | 10 |" not in text.split("### Where the curve's episodes end")[1]


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
    for row in rows:  # each checkpoint's episodes by furthest stage, the task's stages in order
        counts = parse_stage_counts(row["stages"])
        assert list(counts) == list(stage_names("handle-press")) and sum(counts.values()) == 2
        assert counts["succeeded"] == row["successes"]
        assert len(row["outcomes"]) == 2 and row["outcomes"].count("1") == row["successes"]  # episode by episode
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

    def stage_rows(text: str) -> list[str]:  # the stage table's rows: one per checkpoint
        lines = text[text.index("### Where the curve's episodes end") :].splitlines()
        header = lines.index("| method | task | epochs | episodes | none | reached | moved | succeeded |")
        return lines[header + 2 : lines.index("", header)]

    assert [row.split(" | ")[2] for row in stage_rows(report)] == ["1", "2", "3"]
    assert stage_rows(again) == stage_rows(report)


TWO_METHODS = """
name: two
out_dir: {out}
tasks: [handle-press]
n_train_envs: [1]
seeds: [0]
train_factors: [light]
factors: [light]
methods:
  - name: cnn
    policy: {{type: bc}}
  - name: transformer
    policy: {{type: rt1, preset: small}}
    train: {{epochs: 2, batch_size: 4, curve_every: 1}}
collect:
  demos: 2
train:
  epochs: 3
  batch_size: 8
eval:
  n_test_envs: 1
  episodes: 2
"""


def _two_methods(tmp_path: Path, **edits: str) -> StudyCommand:
    text = TWO_METHODS.format(out=tmp_path / "out")
    for old, new in edits.items():
        text = text.replace(old, new)
    path = tmp_path / "two.yaml"
    path.write_text(text)
    return parse_config(StudyCommand, [f"--config_path={path}"], "study")


def test_a_method_s_own_training_settings_key_its_training_alone(tmp_path):
    """A method's ``train`` overrides the study's for its training only: the other method keeps the key it has
    in a study of its own, and the overriding method's training is the one a study with those settings as its
    ``train`` makes (one key: each study reuses the other's step)."""
    cfg = _two_methods(tmp_path).grid()
    plan = make_plan(cfg)
    by_method = {s.meta["method"]: s for s in plan.of_kind("train")}
    assert (by_method["cnn"].inputs["epochs"], by_method["cnn"].inputs["batch_size"]) == (3, 8)
    assert "curve_every" not in by_method["cnn"].inputs
    t = by_method["transformer"].inputs
    assert (t["epochs"], t["batch_size"], t["curve_every"]) == (2, 4, 1)
    assert [(s.meta["method"], s.meta[CURVE_EPOCHS]) for s in plan.curve_points()] == [("transformer", 1)]
    alone = replace(cfg, methods=cfg.methods[:1])
    assert make_plan(alone).of_kind("train")[0].key == by_method["cnn"].key
    as_study = _two_methods(  # the same settings as the study's own train (parsed from YAML as floats)
        tmp_path,
        **{
            "  - name: cnn\n    policy: {type: bc}\n": "",
            "    train: {epochs: 2, batch_size: 4, curve_every: 1}\n": "",
            "epochs: 3\n  batch_size: 8": "epochs: 2\n  batch_size: 4\n  curve_every: 1",
        },
    ).grid()
    assert [m.name for m in as_study.methods] == ["transformer"] and not as_study.methods[0].train
    assert make_plan(as_study).of_kind("train")[0].key == by_method["transformer"].key
    steps_only = replace(cfg.methods[1], train={"steps": 5})
    assert cfg.train_for(steps_only) == replace(cfg.train, steps=5, epochs=None)  # steps clear epochs
    curved = replace(cfg, train=replace(cfg.train, curve_every=1))
    assert curved.train_for(steps_only) == replace(cfg.train, steps=5, epochs=None)  # and the study's curve


@pytest.mark.parametrize(
    "edits, message",
    [
        (
            {"train: {epochs: 2,": "train: {lr: 1, epochs: 2,"},
            "method 'transformer': unknown train setting.s. lr; valid: steps, epochs, batch_size, curve_every, extends, extra_args",
        ),
        ({"{epochs: 2,": "{steps: 5,"}, "method 'transformer': train.curve_every is a number of epochs below"),
        ({"batch_size: 4,": "batch_size: 0,"}, "method 'transformer': train.batch_size must be at least 1, got 0"),
        ({"epochs: 2,": "epochs: -2,"}, "method 'transformer': train.epochs must be a positive number, got -2"),
        (
            {"batch_size: 4,": "batch_size: 4.5,"},
            "method 'transformer': train.batch_size must be a whole number, got 4.5",
        ),
        ({"epochs: 2,": "epochs: two,"}, "method 'transformer': train.epochs must be a number, got 'two'"),
        ({"curve_every: 1}": "extra_args: --x}"}, "method 'transformer': train.extra_args must be a list of flags"),
        ({"epochs: 2,": "epochs: 2, steps: 5,"}, "method 'transformer': train sets steps or epochs, not both"),
        ({"curve_every: 1}": "curve_every: 2}"}, "method 'transformer': train.curve_every is a number of epochs below"),
        ({"epochs: 2,": "epochs: .nan,"}, "method 'transformer': train.epochs must be a positive number, got nan"),
        ({"curve_every: 1}": "curve_every: .inf}"}, "method 'transformer': train.curve_every is a number of epochs"),
        ({"curve_every: 1}": "extends: 1}"}, "method 'transformer': train.extends must be a list of numbers"),
        ({"curve_every: 1}": "extends: [one]}"}, "method 'transformer': train.extends must be a list of numbers"),
        ({"curve_every: 1}": "extends: [1, 1]}"}, "method 'transformer': train.extends is a list of increasing"),
    ],
)
def test_a_method_s_bad_training_settings_are_refused_naming_the_method(tmp_path, edits, message):
    with pytest.raises(ValueError, match=message):
        _two_methods(tmp_path, **edits)


def test_a_given_checkpoint_takes_no_training_settings(tmp_path):
    from lerobot_factorworld.study.plan.method_config import MethodConfig

    with pytest.raises(ValueError, match="train settings apply to a trained method, not a given checkpoint"):
        MethodConfig("given", checkpoint=str(tmp_path), train={"epochs": 2})


def test_two_methods_alike_but_for_their_training_settings_are_two_methods(tmp_path):
    """The same policy at two budgets trains twice (two keys), so it is allowed; the report names each budget."""
    from lerobot_factorworld.study.report.markdown import _training_text

    cfg = _two_methods(tmp_path, **{"type: bc}": "type: rt1, preset: small}"}).grid()
    keys = {s.meta["method"]: s.key for s in make_plan(cfg).of_kind("train")}
    assert len(set(keys.values())) == 2
    assert _training_text(cfg) == "cnn 3 epochs at batch 8, transformer 2 epochs at batch 4"
    assert _training_text(replace(cfg, methods=cfg.methods[:1])) == "3 epochs at batch 8"
    with pytest.raises(ValueError, match="training settings and training data"):
        replace(cfg, methods=[cfg.methods[0], replace(cfg.methods[1], name="again", train={})])
    # settings that differ but train the same: a curve every 0 epochs is none; steps are unused under epochs
    cnn, same = cfg.methods[0], {"curve_every": 0}
    with pytest.raises(ValueError, match="training settings and training data"):
        replace(cfg, methods=[cnn, replace(cnn, name="again", train=same)])
    with pytest.raises(ValueError, match="training settings and training data"):
        replace(cfg, train=replace(cfg.train, steps=99), methods=[cnn, replace(cnn, name="again", train={"epochs": 3})])


def test_the_curve_s_last_point_is_its_own_training_s_epochs(tmp_path):
    """curve.csv holds the points of the methods with a curve only, the last at that method's own epochs (2),
    not the study's (3), with the step its training ended at."""
    import json

    from lerobot_factorworld.study.results.curve import curve_rows

    cfg = _two_methods(tmp_path).grid()
    plan = make_plan(cfg)
    study = tmp_path / "out"
    for step in plan.of_kind("train"):
        folder = step.folder(study)
        folder.mkdir(parents=True)
        (folder / "result.json").write_text(json.dumps({"steps": 6, "curve": {"1": 3}}))
    for step in plan.of_kind("eval"):
        folder = step.folder(study)
        folder.mkdir(parents=True)
        (folder / "result.json").write_text(json.dumps({"successes": [True, False]}))
    rows = curve_rows(cfg, plan, study)
    assert [(r["method"], r["epochs"], r["steps"], r["successes"]) for r in rows] == [
        ("transformer", 1, 3, 1),
        ("transformer", 2, 6, 1),
    ]


def test_a_report_of_a_curve_still_training_says_its_points_come_below(tmp_path):
    """No grid evaluation yet (the grid's use the last checkpoint): the report says the curve below has its points so
    far, and without a curve it says only that nothing has finished."""
    from lerobot_factorworld.study.report.markdown import FAMILY_DETAILS, render

    cfg = _command(tmp_path).grid()
    rows = [{"method": "bc", "task": "handle-press", "epochs": 1, "successes": 1, "episodes": 2}]
    curve = curve_section(rows, plotted=False, methods=["bc"], budgets={"bc": 3})

    def sections(part: str) -> list[str]:
        return curve if part == FAMILY_DETAILS else []

    text = render(cfg, [], [], "factorworld study --report-only", planned=1, family_sections=sections)
    assert "(0 of 1 evaluations finished)" in text and "Still training: bc has reached 1 of its 3 epochs" in text
    assert "No evaluation of the grid has finished yet; the learning curve below has its points so far." in text
    bare = render(cfg, [], [], "factorworld study", planned=1)
    assert "No evaluation of the grid has finished yet." in bare and "learning curve" not in bare
