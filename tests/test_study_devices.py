"""Where a study's steps run: ``train.device`` and ``eval.device`` are refused where this machine lacks them,
before any step runs and again in the step (LeRobot's configs would quietly train on the CPU instead), and the
study's own process never asks CUDA while it validates (a process that has asked cannot fork workers that use
CUDA: on a GPU machine every grouped training then failed with "Cannot re-initialize CUDA in forked subprocess")."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.run.device import device_problem, require_device

NO_CUDA = pytest.mark.skipif(torch.cuda.is_available(), reason="checks the refusal on a machine without CUDA")
METHODS = [
    {"name": "bc", "policy": {"type": "bc"}},
    {"name": "bc_lang", "policy": {"type": "bc", "use_language": True, "speed": "fast"}},
    {"name": "rt1", "policy": {"type": "rt1", "preset": "small"}},
]


def test_validating_a_study_never_asks_cuda(monkeypatch):
    def asked(*args, **kwargs):
        raise AssertionError("the study's process asked CUDA: the workers it forks could not use it")

    monkeypatch.setattr(torch.cuda, "is_available", asked)
    monkeypatch.setattr(torch.cuda, "device_count", asked)
    StudyConfig(tasks=["door-open"], n_train_envs=[2], factors=["light"], methods=METHODS)


def test_device_problem_names_the_setting_and_what_the_machine_has():
    assert device_problem("train.device", "cuda", 1, False) is None
    assert device_problem("eval.device", "cuda:1", 2, False) is None
    assert device_problem("eval.device", "cpu", 0, False) is None
    assert device_problem("train.device", "cuda:1", 1, False) == (
        "train.device=cuda:1 but this machine has 1 CUDA device(s); use --train.device=cpu"
    )
    assert device_problem("eval.device", "mps", 0, False) == (
        "eval.device=mps but this machine has no MPS device; use --eval.device=cpu"
    )
    assert device_problem("eval.device", "mps", 0, True) is None


@NO_CUDA
def test_a_step_refuses_a_device_this_machine_lacks():
    assert require_device("train.device", "cpu") == "cpu"
    with pytest.raises(RuntimeError, match=r"^train.device=cuda but this machine has 0 CUDA device\(s\)"):
        require_device("train.device", "cuda")


@NO_CUDA
def test_a_study_on_cuda_is_refused_in_one_line_before_any_step_runs(tmp_path: Path, capsys):
    config = tmp_path / "on_gpu.yaml"
    settings = {
        "name": "on_gpu",
        "out_dir": str(tmp_path / "study"),
        "tasks": ["door-open"],
        "n_train_envs": [2],
        "factors": ["light"],
        "methods": METHODS[:1],
        "collect": {"demos": 2},
        "train": {"steps": 2, "device": "cuda"},
        "eval": {"n_test_envs": 2, "episodes": 2, "device": "cuda:0"},
    }
    config.write_text(json.dumps(settings))
    # in process (the command line's one-line contract for a bad setting: tests/test_cli.py, as a new process)
    with pytest.raises(SystemExit) as exit_info:
        main(["study", f"--config_path={config}"])
    assert exit_info.value.code == 1
    stderr = capsys.readouterr().err
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert errors == [
        "error: eval.device=cuda:0 but this machine has 0 CUDA device(s); use --eval.device=cpu; "
        "train.device=cuda but this machine has 0 CUDA device(s); use --train.device=cpu"
    ]
    assert "Traceback" not in stderr
    assert not (tmp_path / "study" / "steps").exists()
