"""Files other tools and later runs read stay byte-identical across refactors: saved configurations
(``factorworld sample``, evaluation suites), dataset side-cars (``meta/factorworld.json``) and study step
keys (what a cached step is found by). The expected bytes in tests/data/compat were first written by the
code before the package was layered (commit e638860) and are regenerated only by a change meant to alter
them: ``FACTORWORLD_WRITE_COMPAT=1`` makes these tests write the files instead of comparing (see that
folder's README for the command and the record of each regeneration)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig
from lerobot_factorworld.cli import main as factorworld
from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.datasets.collect import CollectConfig, collect
from lerobot_factorworld.factors.values import save_configs
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.grid import make_plan

GOLDEN = Path(__file__).parent / "data" / "compat"
REPO = Path(__file__).resolve().parents[1]
WRITE = os.environ.get("FACTORWORLD_WRITE_COMPAT") == "1"


def _golden(name: str, actual: bytes) -> bytes:
    """The expected bytes of golden file ``name``; with ``FACTORWORLD_WRITE_COMPAT=1``, ``actual`` written there first."""
    if WRITE:
        (GOLDEN / name).write_bytes(actual)
    return (GOLDEN / name).read_bytes()


SAMPLES = {
    "sample_door-open_train.json": ["--task=door-open", "--n=4", "--seed=3"],
    "sample_pick_eval.json": ["--task=pick", "--n=3", "--seed=1", "--split=eval", "--sampling.n_objects=5"],
    "sample_pick-place_train.json": [
        "--task=pick-place",
        "--n=3",
        "--seed=2",
        "--factors=[object_shape,object_size,distractors,arm_pos]",
        "--sampling.n_distractors=3",
    ],
}
SUITES = {
    "pick": ["held_out_phrasings", "held_out_objects", "light", "camera_pos+distractors"],
    "door-open": ["camera_pos", "table_texture+light", "distractors"],
}
SIDECARS = {
    "sidecar_pick.json": ("pick", "[light,table_texture]", "local/compat_pick"),
    "sidecar_door-open.json": ("door-open", "[camera_pos,distractors]", "local/compat_door"),
}


@pytest.mark.parametrize("name", list(SAMPLES))
def test_sampled_configurations_are_byte_identical(name, tmp_path, capsys):
    out = tmp_path / name
    factorworld(["sample", *SAMPLES[name], f"--out={out}"])
    capsys.readouterr()
    assert out.read_bytes() == _golden(name, out.read_bytes())


@pytest.mark.parametrize("task", list(SUITES))
def test_evaluation_suites_are_byte_identical(task, tmp_path):
    cfg = FactorWorldEnvConfig(task=task, n_train_envs=3, n_test_envs=6, shifts=SUITES[task], seed=7)
    suites = cfg.suites(task)
    assert list(suites) == ["train", *SUITES[task]]
    for condition, configs in suites.items():
        path = save_configs(configs, tmp_path / f"suite_{task}_{condition}.json")
        assert path.read_bytes() == _golden(path.name, path.read_bytes()), condition


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SIDECARS))
def test_dataset_sidecars_are_byte_identical(name, tmp_path):
    task, factors, repo_id = SIDECARS[name]
    root = tmp_path / "data"
    cfg = parse_config(
        CollectConfig,
        [
            f"--task={task}",
            "--n_envs=2",
            "--demos=2",
            "--use_videos=false",
            f"--root={root}",
            f"--repo_id={repo_id}",
            f"--factors={factors}",
        ],
        "collect",
    )
    collect(cfg)
    sidecar = (root / "meta" / "factorworld.json").read_bytes()
    assert sidecar == _golden(name, sidecar)


def test_study_step_keys_and_inputs_are_unchanged(monkeypatch):
    monkeypatch.chdir(REPO)
    expected_keys = json.loads((GOLDEN / "study_keys.json").read_text())  # the configs checked, and their form
    expected_inputs = json.loads((GOLDEN / "study_inputs.json").read_text())
    actual_keys, actual_inputs = {}, {}
    for name, expected in expected_keys.items():
        plan = make_plan(parse_config(StudyCommand, [f"--config_path=configs/study/{name}.yaml"], "study"))
        keys = [f"{s.kind} {s.key}" for s in plan.steps]
        if isinstance(expected, dict):  # a large plan: its key list by count and digest
            keys = {"n": len(keys), "sha256": hashlib.sha256("\n".join(keys).encode()).hexdigest()}
        actual_keys[name] = keys
        if name in expected_inputs:
            inputs = [{"kind": s.kind, "key": s.key, "inputs": s.inputs} for s in plan.steps]
            actual_inputs[name] = json.loads(json.dumps(inputs, sort_keys=True, default=str))
    for file, actual in (("study_keys.json", actual_keys), ("study_inputs.json", actual_inputs)):
        expected = json.loads(_golden(file, json.dumps(actual, indent=1, sort_keys=True).encode()))
        for name in expected:
            assert actual[name] == expected[name], (file, name)
