"""The gymnasium contract: registered ids, check_env, observation layout, info, options and errors."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import lerobot_factorworld  # noqa: F401  (registers FactorWorld/<task>-v0)
from lerobot_factorworld import TASKS, FactorValues, SceneConfig
from lerobot_factorworld.experts import expert_action, expert_policy
from lerobot_factorworld.protocol.sampling import sample_configs


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


def test_agent_pos_is_in_the_robot_frame_under_a_table_shift(make_env):
    """The table factor moves the robot side by -delta; the robot's readings must see the table move by +delta."""
    delta = np.array([0.02, -0.03, -0.04])
    pinned = FactorValues(object_pos=(0.02, -0.01))
    policy = expert_policy("pick-place")
    runs = []
    for values in (pinned, pinned.set(table_pos=tuple(delta))):
        env = make_env("pick-place", SceneConfig("pick-place", values), image_size=32)
        obs, _ = env.reset(seed=0)
        # the hand relative to the robot base, whatever the base's world position
        hand = env.data.body("hand").xpos - env.data.body("base").xpos
        assert np.allclose(obs["agent_pos"][[0, 1, 2, 4, 5, 6]], np.tile(hand, 2), atol=1e-6)
        run = {"agent_pos": [obs["agent_pos"]], "pixels": obs["pixels"]["front"], "state": env.state_observation}
        for _ in range(150):
            previous = obs["agent_pos"]
            obs, _, terminated, _, info = env.step(expert_action(policy, env.state_observation))
            assert np.array_equal(obs["agent_pos"][4:], previous[:4])  # the previous-step half, same frame
            run["agent_pos"].append(obs["agent_pos"])
            if terminated:
                break
        run["success"] = info["is_success"]
        runs.append(run)
    default, shifted = runs
    expected = np.concatenate([delta, [0.0], delta, [0.0]])
    assert np.allclose(shifted["agent_pos"][0] - default["agent_pos"][0], expected, atol=1e-3)
    n = min(len(default["agent_pos"]), len(shifted["agent_pos"]))
    assert np.allclose(np.array(shifted["agent_pos"][:n]) - np.array(default["agent_pos"][:n]), expected, atol=0.01)
    # the task itself is unchanged on the table (Meta-World's state is in the table frame) and still solved ...
    assert np.allclose(shifted["state"][4:7], default["state"][4:7]) and shifted["success"] and default["success"]
    # ... while the cameras, which move with the robot, see the table shift
    assert np.abs(shifted["pixels"].astype(int) - default["pixels"].astype(int)).max() > 10


def test_pick_place_is_the_public_factor_world_definition(make_env):
    """Goal fixed on the table at (-0.005, 0.40, 0.02), success within 3 cm (Meta-World: in the air, 7 cm)."""
    goal = np.array([-0.005, 0.40, 0.02])
    env = make_env("pick-place", cameras=())
    for seed in range(3):
        env.reset(seed=seed)
        assert np.allclose(env.state_observation[36:39], goal)  # the goal scripted experts read
        assert np.allclose(env.model.site("goal").pos, goal) and np.allclose(env.data.site("goal").xpos, goal)
    for offset, solved in ((0.025, True), (0.035, False)):
        env.reset(seed=0)
        puck = env.data.joint("objjoint")  # put the puck on the table beside the goal
        puck.qpos[:3], puck.qvel[:] = goal + np.array([offset, 0.0, 0.0]), 0.0
        obs, reward, terminated, _, info = env.step(np.zeros(4, np.float32))
        assert info["is_success"] is solved and terminated is solved and reward == float(solved)
        assert np.allclose(env.state_observation[36:39], goal)  # not clipped to Meta-World's goal space
    assert 0.03 < np.linalg.norm(env.state_observation[4:7] - goal) < 0.07  # Meta-World's radius would count it
