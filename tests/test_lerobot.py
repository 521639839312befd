"""LeRobot integration: the ``factorworld`` env type is found with no extra flag, and ``lerobot-eval``
reports success per evaluation condition (train, each shifted factor, each pair)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

LEROBOT_EVAL = Path(sys.executable).with_name("lerobot-eval")


def test_env_config_builds_one_suite_per_condition():
    from lerobot_factorworld.envs.configs import FactorWorldEnvConfig

    cfg = FactorWorldEnvConfig(
        task="pick-place", shifts=["light", "table_texture+distractors"], n_train_envs=2, n_test_envs=3
    )
    assert cfg.features_map["pixels/front"] == "observation.images.front"
    assert cfg.features["agent_pos"].shape == (8,)
    envs = cfg.create_envs(n_envs=1)
    try:
        assert set(envs) == {"train", "light", "table_texture+distractors"}
        assert envs["light"][0].call("_max_episode_steps")[0] == 500
        assert envs["train"][0].call("task_description")[0] == "pick up the puck and place it at the blue goal"
    finally:
        for suite in envs.values():
            for vec in suite.values():
                vec.close()


@pytest.mark.slow
def test_lerobot_eval_runs_a_lerobot_policy_on_factorworld(tmp_path):
    out = tmp_path / "eval"
    cmd = [
        str(LEROBOT_EVAL),
        "--env.type=factorworld",
        "--env.task=door-open",
        "--env.shifts=[camera_pos]",
        "--env.n_train_envs=2",
        "--env.n_test_envs=2",
        "--env.episode_length=10",
        "--policy.type=act",
        "--policy.pretrained_backbone_weights=null",
        "--policy.device=cpu",
        "--eval.n_episodes=2",
        "--eval.batch_size=1",
        f"--output_dir={out}",
    ]
    env = {**os.environ, "MUJOCO_GL": "egl"}
    result = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    info = json.loads((out / "eval_info.json").read_text())
    assert set(info["per_group"]) == {"train", "camera_pos"}
    assert info["overall"]["n_episodes"] == 4
    shutil.rmtree(out / "videos", ignore_errors=True)
