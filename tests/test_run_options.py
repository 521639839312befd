"""The grid and how it runs are two configs (``StudyConfig``, ``RunOptions``); a study's YAML holds both, flat
(``StudyCommand``), and the entry points take them apart."""

from __future__ import annotations

import re
from dataclasses import fields
from pathlib import Path

import pytest

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study import runner
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.run.options import EXECUTORS, RunOptions

ROOT = Path(__file__).resolve().parents[1]
YAML = """name: split
out_dir: {out}
tasks: [door-open]
n_train_envs: [1]
factors: [light]
train_factors: [light]
methods: [{{name: bc, policy: {{type: bc}}}}]
collect: {{demos: 2}}
eval: {{n_test_envs: 2, episodes: 2}}
workers: 2
execution: per_step
"""


def _command(tmp_path: Path, *flags: str) -> StudyCommand:
    path = tmp_path / "split.yaml"
    path.write_text(YAML.format(out=tmp_path / "out"))
    return parse_config(StudyCommand, [f"--config_path={path}", *flags], "study")


def test_the_grid_and_the_options_share_no_setting():
    grid, options = {f.name for f in fields(StudyConfig)}, {f.name for f in fields(RunOptions)}
    assert not grid & options
    assert {f.name for f in fields(StudyCommand)} == grid | options


def test_a_yaml_file_splits_into_its_grid_and_its_options_and_the_options_change_no_key(tmp_path):
    cmd = _command(tmp_path, "--dry_run=true")
    grid, options = cmd.parts()
    assert type(grid) is StudyConfig and type(options) is RunOptions
    assert (options.workers, options.execution, options.dry_run) == (2, "per_step", True)
    assert (grid.name, grid.tasks, grid.factors) == ("split", ["door-open"], ["light"])
    other = _command(tmp_path, "--workers=1", "--execution=grouped").grid()
    assert [s.key for s in make_plan(grid).steps] == [s.key for s in make_plan(other).steps]
    assert len(make_plan(grid).steps) == 4  # collect, train, eval train, eval light


def test_the_entry_points_refuse_a_command_passed_as_the_grid(tmp_path):
    cmd = _command(tmp_path)
    with pytest.raises(TypeError, match=r"run_study\(\*command.parts\(\)\)"):
        runner.run_study(cmd)
    with pytest.raises(TypeError, match="pass the grid and the run options apart"):
        runner.inspect_study(cmd, RunOptions(dry_run=True))
    assert not (tmp_path / "out").exists()


def test_inspect_study_describes_the_plan_with_the_options_execution(tmp_path):
    grid, options = _command(tmp_path, "--dry_run=true").parts()
    text = runner.inspect_study(grid, options)
    assert "execution per_step" in text and "collect       1 steps,      0 cached,      1 to run" in text
    with pytest.raises(ValueError, match="inspect_study needs dry_run, profile or fit_cost"):
        runner.inspect_study(grid, RunOptions())
    with pytest.raises(ValueError, match="use inspect_study"):
        runner.run_study(grid, options)
    with pytest.raises(ValueError, match="report_only runs nothing: use report_study"):
        runner.run_study(grid, RunOptions(report_only=True))
    with pytest.raises(ValueError, match="report_study writes the report of a study's finished steps"):
        runner.report_study(grid, options, "factorworld study")
    # nothing finished yet: refused in one line, and nothing written
    with pytest.raises(
        ValueError,
        match=r"nothing to report: none of this study's 2 evaluations \(learning-curve points included\) has finished in .*out; run",
    ):
        runner.report_study(grid, RunOptions(report_only=True), "factorworld study")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "options, message",
    [
        ({"executor": "slurm"}, f"unknown executor 'slurm'; valid executors: {', '.join(EXECUTORS)}"),
        ({"execution": "fast"}, "unknown execution 'fast'; valid: grouped, per_step"),
        ({"workers": 0}, "workers must be at least 1, got 0"),
        ({"strict": True, "rerun_stale": True}, "strict=true refuses steps made by other code"),
        ({"dry_run": True, "profile": True}, "dry_run, profile and fit_cost each inspect the study"),
        ({"push_to_hub": True}, "push_to_hub=true needs --hub_repo_id=<user>/<name>"),
        ({"report_only": True, "dry_run": True, "rerun_stale": True}, "runs nothing; dry_run, rerun_stale would run"),
        ({"report_only": True, "reuse_from": ["elsewhere"]}, "reuse_from links other studies' steps into it only"),
    ],
)
def test_a_bad_option_is_refused_naming_the_valid_choices(options, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        RunOptions(**options)


def test_a_bad_option_at_the_command_line_is_one_line(tmp_path, capsys):
    from lerobot_factorworld.cli import main

    path = tmp_path / "split.yaml"
    path.write_text(YAML.format(out=tmp_path / "out"))
    with pytest.raises(SystemExit) as exit_info:
        main(["study", f"--config={path}", "--executor=slurm"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: unknown executor 'slurm'; valid executors: {', '.join(EXECUTORS)}"]
    assert not (tmp_path / "out").exists()


def test_the_study_guides_python_block_runs(tmp_path, monkeypatch, capsys):
    (block,) = re.findall(r"^```python\n(.*?)^```", (ROOT / "docs" / "study.md").read_text(), flags=re.S | re.M)
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "docs/study.md", "exec"), {})
    out = capsys.readouterr().out
    assert "study 'mine' in outputs/mine" in out and "collect       1 steps" in out
    assert not (tmp_path / "outputs").exists()  # a dry run writes nothing
