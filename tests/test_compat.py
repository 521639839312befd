"""Files other tools and later runs read stay byte-identical across refactors: saved configurations
(``factorworld sample``, evaluation suites), dataset side-cars (``meta/factorworld.json``) and study step
keys (what a cached step is found by). The expected bytes in tests/data/compat were written by the code
before the package was layered (commit e638860); see that folder's README before regenerating them."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig
from lerobot_factorworld.cli import main as factorworld
from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.datasets.collect import CollectConfig, collect
from lerobot_factorworld.factors.values import save_configs
from lerobot_factorworld.study.config import StudyConfig
from lerobot_factorworld.study.plan import make_plan

GOLDEN = Path(__file__).parent / "data" / "compat"
REPO = Path(__file__).resolve().parents[1]

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
    assert out.read_bytes() == (GOLDEN / name).read_bytes()


@pytest.mark.parametrize("task", list(SUITES))
def test_evaluation_suites_are_byte_identical(task, tmp_path):
    cfg = FactorWorldEnvConfig(task=task, n_train_envs=3, n_test_envs=6, shifts=SUITES[task], seed=7)
    suites = cfg.suites(task)
    assert list(suites) == ["train", *SUITES[task]]
    for condition, configs in suites.items():
        path = save_configs(configs, tmp_path / f"suite_{task}_{condition}.json")
        assert path.read_bytes() == (GOLDEN / path.name).read_bytes(), condition


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
    assert (root / "meta" / "factorworld.json").read_bytes() == (GOLDEN / name).read_bytes()


def test_study_step_keys_and_inputs_are_unchanged(monkeypatch):
    monkeypatch.chdir(REPO)
    expected_keys = json.loads((GOLDEN / "study_keys.json").read_text())
    expected_inputs = json.loads((GOLDEN / "study_inputs.json").read_text())
    for name, expected in expected_keys.items():
        plan = make_plan(parse_config(StudyConfig, [f"--config_path=configs/study/{name}.yaml"], "study"))
        keys = [f"{s.kind} {s.key}" for s in plan.steps]
        if isinstance(expected, dict):  # a large plan: its key list by count and digest
            keys = {"n": len(keys), "sha256": hashlib.sha256("\n".join(keys).encode()).hexdigest()}
        assert keys == expected, name
        if name in expected_inputs:
            inputs = [{"kind": s.kind, "key": s.key, "inputs": s.inputs} for s in plan.steps]
            assert json.loads(json.dumps(inputs, sort_keys=True, default=str)) == expected_inputs[name], name
