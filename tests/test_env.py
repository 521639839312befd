"""The gymnasium contract: registered ids, check_env, observation layout, info, options and errors."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import lerobot_factorworld  # noqa: F401  (registers FactorWorld/<task>-v0)
from lerobot_factorworld import TASKS, FactorValues, SceneConfig
from lerobot_factorworld.factors.sampling import sample_configs


def test_every_task_is_registered_with_gymnasium():
    for task in TASKS.values():
        assert task.gym_id in gym.registry


def test_gymnasium_env_checker_passes():
    env = gym.make("FactorWorld/door-open-v0", image_size=32)
    check_env(env.unwrapped, skip_render_check=False)
    env.close()


def test_observation_layout_matches_lerobot_expectations(make_env):
    env = make_env("pick-place", cameras=("front", "side"), image_size=(48, 64))
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert set(obs["pixels"]) == {"front", "side"}
    assert obs["pixels"]["front"].shape == (48, 64, 3) and obs["pixels"]["front"].dtype == np.uint8
    assert obs["agent_pos"].shape == (8,) and np.allclose(obs["agent_pos"][:4], obs["agent_pos"][4:])
    assert env.task_description == TASKS["pick-place"].instruction
    assert info["is_success"] is False and "factors" in info
    obs2, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0, 0.0, -1.0], np.float32))
    assert np.allclose(obs2["agent_pos"][4:], obs["agent_pos"][:4])  # previous step's gripper state
    assert obs2["agent_pos"][0] > obs["agent_pos"][0]  # moved along +x
    assert env.render().shape == (48, 64, 3)


def test_episode_truncates_at_the_horizon(make_env):
    env = make_env("drawer-open", cameras=(), max_episode_steps=5)
    env.reset(seed=0)
    flags = [env.step(np.zeros(4, np.float32))[3] for _ in range(5)]
    assert flags == [False] * 4 + [True]


def test_configs_are_selected_by_seed_index_or_option(make_env):
    configs = sample_configs("pick-place", 3, seed=0, factors=("light",))
    env = make_env("pick-place", configs, cameras=())
    assert env.reset(seed=4)[1]["env_id"] == configs[1].env_id
    assert env.reset(options={"env_index": 2})[1]["env_id"] == configs[2].env_id
    _, info = env.reset(seed=0, options={"factors": {"light": (0.5, 0.5)}})
    assert info["factors"]["light"] == [0.5, 0.5]


def test_object_position_re_randomises_per_episode_unless_pinned(make_env):
    env = make_env("pick-place", cameras=())
    a = env.reset(seed=1)[1]["factors"]["object_pos"]
    b = env.reset(seed=2)[1]["factors"]["object_pos"]
    assert a != b and env.reset(seed=1)[1]["factors"]["object_pos"] == a
    pinned = SceneConfig("pick-place", FactorValues(object_pos=(0.01, 0.02)))
    assert env.reset(seed=3, options={"config": pinned})[1]["factors"]["object_pos"] == [0.01, 0.02]


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"task": "pick-plac"}, "valid tasks"),
        ({"cameras": ("front", "corner9")}, "valid cameras: front"),
        ({"quality": "ultra"}, "valid: fast, full"),
        ({"image_size": 2}, "at least 8 pixels"),
        ({"configs": [SceneConfig("door-open")]}, "given to a 'pick-place' env"),
    ],
)
def test_bad_constructor_arguments(kwargs, fragment):
    from lerobot_factorworld.envs.factor_env import FactorWorldEnv

    kwargs = {"task": "pick-place", **kwargs}
    with pytest.raises(ValueError, match=fragment):
        FactorWorldEnv(**kwargs)


def test_bad_reset_options(make_env):
    env = make_env("pick-place", cameras=())
    with pytest.raises(ValueError, match="valid options: config, env_index, factors"):
        env.reset(options={"conifg": None})
    with pytest.raises(ValueError, match="out of range"):
        env.reset(options={"env_index": 3})
    env.reset(options={"lerobot_new_rollout": True})  # LeRobot's rollout flag is accepted
