"""LeRobot integration: the ``factorworld`` env type is found with no extra flag, and ``lerobot-eval``
reports success per evaluation condition (train, each shifted factor, each pair)."""

import json
import shutil

import pytest


def test_env_config_builds_one_suite_per_condition():
    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig

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
def test_lerobot_eval_runs_a_lerobot_policy_on_factorworld(tmp_path, run_lerobot):
    out = tmp_path / "eval"
    run_lerobot(
        "lerobot-eval",
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
    )
    info = json.loads((out / "eval_info.json").read_text())
    assert set(info["per_group"]) == {"train", "camera_pos"}
    assert info["overall"]["n_episodes"] == 4
    shutil.rmtree(out / "videos", ignore_errors=True)


@pytest.mark.parametrize(
    ("settings", "expected"),
    [
        ({"task": "pick-plac"}, "unknown task 'pick-plac'; valid tasks: pick-place"),
        ({"task": "pick-place,nope"}, "unknown task 'nope'"),
        ({"cameras": "front,wrist"}, "valid cameras: front, side, top, far"),
        ({"image_size": 3}, "image_size must be at least 8 pixels"),
        ({"quality": "ultra"}, "unknown quality 'ultra'; valid: fast, full"),
        ({"fps": 30}, "fps is fixed by the simulator"),
        ({"episode_length": 0}, "episode_length must be at least 1"),
        ({"n_train_envs": 0}, "n_train_envs must be at least 1"),
        ({"n_test_envs": 0}, "n_test_envs must be at least 1"),
        ({"seed": -1}, "seed must be at least 0"),
        ({"train_factors": ["lighting"]}, "unknown factor(s) 'lighting'; valid factors"),
        ({"shifts": ["camera"]}, "unknown factor(s) 'camera'; valid factors"),
        ({"shifts": ["light+light"]}, "pair of distinct factors"),
        ({"shifts": ["light", "light"]}, "more than once"),
        ({"task": "door-open", "shifts": ["object_shape"]}, "factor 'object_shape' does not apply to task 'door-open'"),
        ({"task": "door-open", "shifts": ["light+object_size"]}, "factor 'object_size' does not apply"),
        ({"include_train": False}, "nothing to evaluate"),
        ({"configs_path": "/nonexistent/envs.json"}, "configs_path /nonexistent/envs.json does not exist"),
        ({"dataset_root": "/data", "configs_path": "/envs.json"}, "give dataset_root or configs_path, not both"),
    ],
)
def test_env_config_refuses_bad_settings_when_parsed(settings, expected):
    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig

    with pytest.raises((ValueError, FileNotFoundError)) as err:
        FactorWorldEnvConfig(**settings)
    assert expected in str(err.value) and "\n" not in str(err.value)


def test_env_config_checks_the_configs_file_and_asset_folders(tmp_path):
    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig
    from lerobot_factorworld.factors.values import save_configs
    from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs

    path = save_configs(sample_configs("door-open", 2, factors=["light"]), tmp_path / "envs.json")
    assert FactorWorldEnvConfig(task="door-open", configs_path=str(path)).configs_path == str(path)
    with pytest.raises(ValueError, match="holds no configuration for task"):
        FactorWorldEnvConfig(task="door-open,pick-place", configs_path=str(path))
    (tmp_path / "broken.json").write_text("{not json")
    with pytest.raises(ValueError, match="holds no valid configurations"):
        FactorWorldEnvConfig(configs_path=str(tmp_path / "broken.json"))
    with pytest.raises(ValueError, match="no texture files found"):
        FactorWorldEnvConfig(sampling=SamplingOptions(texture_folder=str(tmp_path)))


def test_lerobot_eval_fails_on_a_bad_env_setting_before_building_a_policy(tmp_path, run_lerobot):
    result = run_lerobot(
        "lerobot-eval",
        "--env.type=factorworld",
        "--env.task=door-open",
        "--env.shifts=[object_shape]",
        "--policy.type=act",
        "--policy.device=cpu",
        f"--output_dir={tmp_path / 'eval'}",
        check=False,
    )
    assert result.returncode != 0
    output = result.stdout + result.stderr
    assert "factor 'object_shape' does not apply to task 'door-open'" in output, output[-3000:]
    assert "Making policy" not in output and "Making environment" not in output
    assert not (tmp_path / "eval").exists()


def test_env_config_warns_when_test_environments_cannot_pair_with_training_environments(caplog):
    import logging

    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig

    with caplog.at_level(logging.WARNING, logger="lerobot_factorworld.adapters.env_config"):
        FactorWorldEnvConfig(task="door-open", n_train_envs=2, shifts=["light"], n_test_envs=4).suites("door-open")
        assert "not a multiple" not in caplog.text
        FactorWorldEnvConfig(task="door-open", n_train_envs=2, shifts=["light"], n_test_envs=3).suites("door-open")
    assert "n_test_envs=3 is not a multiple of 2" in caplog.text
