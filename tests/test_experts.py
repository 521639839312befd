"""Meta-World's scripted experts solve every task in the default scene and under each applicable
physical single-factor shift (one seeded episode per sampled environment, at most one failing per cell:
>= 90% of 10 environments for the tasks a packaged study collects, >= 80% of 5 for the others; pick-place,
the paper's main task, >= 95% over 20 episodes, two object starts per environment), and visual factors
leave the physics exactly unchanged."""

import dataclasses

import numpy as np
import pytest
import yaml

from lerobot_factorworld import TASKS, FactorValues, SceneConfig
from lerobot_factorworld.experts import expert_action, expert_policy, rollout
from lerobot_factorworld.factors.registry import FACTORS, supported_factors
from lerobot_factorworld.protocol.sampling import sample_configs
from lerobot_factorworld.study.plan.named import STUDIES_DIR

ENVS, REQUIRED = 10, 0.9  # sampled environments per cell for the tasks a packaged study collects
# The other tasks: 5 environments per cell (every physical factor still sampled), one of which may fail. Halves the
# suite's slowest physics (Meta-World's per-step observation code, not rendering) where no committed result rests on it.
OTHER_ENVS, OTHER_REQUIRED = 5, 0.8
STUDIED = {task for path in STUDIES_DIR.rglob("*.yaml") for task in yaml.safe_load(path.read_text())["tasks"]}
STRICTER = {"pick-place": (2, 0.95)}  # task -> (episodes per environment, required success rate)
NOISE = 0.002
PHYSICAL = [name for name, spec in FACTORS.items() if not spec.visual]
VISUAL = [name for name, spec in FACTORS.items() if spec.visual]


def run_expert(env, policy, seed, record=False, act=expert_action):
    """One episode as ``factorworld collect`` runs it (:func:`rollout`); with ``record``, the qpos after each step."""
    states = []
    after = (lambda e: states.append(e.data.qpos.copy())) if record else None
    episode = rollout(env, policy, seed, NOISE, act=act, after_step=after)
    return episode.success, states


@pytest.mark.slow
# pick's expert is held to more (20 episodes per cell, 95%, every physical factor it supports and its language
# conditions) by tests/test_pick.py::test_expert_succeeds_in_default_scenes_and_under_physical_shifts
@pytest.mark.parametrize("task", [task for task in TASKS if task != "pick"])
def test_expert_solves_default_and_each_physical_shift(task, make_env):
    envs, required = (ENVS, REQUIRED) if task in STUDIED else (OTHER_ENVS, OTHER_REQUIRED)
    per_env, required = STRICTER.get(task, (1, required))
    episodes = envs * per_env  # episode seed % envs picks the environment, the seed the object start
    policy = expert_policy(task)
    cells = {"default": [SceneConfig(task)]}
    for name in PHYSICAL:
        if name in supported_factors(task) and name != "object_pos":
            cells[name] = sample_configs(task, envs, seed=11, factors=(name,))
    # object position: the default cell re-samples it per episode; also pin the default range's draws
    cells["object_pos"] = sample_configs(task, envs, seed=11, factors=("object_pos",))
    failures = {}
    for cell, configs in cells.items():
        env = make_env(task, configs, cameras=(), scene_cache_size=len(configs))
        successes = sum(run_expert(env, policy, seed)[0] for seed in range(episodes))
        env.close()
        if successes < required * episodes:
            failures[cell] = f"{successes}/{episodes}"
    assert not failures, f"{task}: expert below {required:.0%} in cells {failures}"


@pytest.mark.parametrize("task", ["pick-place", "door-open", "bin-picking", "window-close", "pick"])
def test_visual_factors_leave_physics_unchanged(task, make_env):
    policy = expert_policy(task)
    shifted = sample_configs(task, 1, seed=3, split="eval", factors=VISUAL)[0]
    plain = SceneConfig(task, FactorValues(object_pos=(0.01, 0.01)))
    if shifted.content is not None:  # the same objects, poses and named object: only the visual factors differ
        plain = dataclasses.replace(plain, content=shifted.content)
    trajectories = []
    for config in (plain, shifted.with_factors(object_pos=(0.01, 0.01))):
        env = make_env(task, config, cameras=("front",), image_size=32)
        trajectories.append(run_expert(env, policy, seed=0, record=True)[1])
        env.close()
    assert len(trajectories[0]) == len(trajectories[1])
    assert all(np.array_equal(a, b) for a, b in zip(*trajectories, strict=True))


def test_pick_place_expert_leaves_the_puck_on_the_table_goal(make_env):
    """Without early termination the expert keeps the puck where the public Factor World put its goal."""
    env = make_env("pick-place", cameras=(), terminate_on_success=False, max_episode_steps=120)
    policy = expert_policy("pick-place")
    for seed in range(2):
        run_expert(env, policy, seed)
        state = env.state_observation
        puck, goal = state[4:7], state[36:39]
        assert np.linalg.norm(puck - goal) < 0.02 and puck[2] < 0.03, f"seed {seed}: puck at {puck}, goal {goal}"


def test_experts_are_measured_as_the_collector_runs_them(make_env):
    """The rates above are those of ``factorworld collect``: the same actions for the same episode seed."""
    from lerobot_factorworld.datasets.collect import episode_frames, episode_seed

    env = make_env("pick-place", cameras=("front",), image_size=8, max_episode_steps=15)
    policy = expert_policy("pick-place")
    seed = episode_seed(0, 0, 0, 0, 0)
    frames = episode_frames(rollout(env, policy, seed, NOISE), env.task_description)
    actions = []

    def recording(*args):
        actions.append(expert_action(*args))
        return actions[-1]

    run_expert(env, policy, seed, act=recording)
    assert len(actions) == len(frames) == 15
    assert all(np.array_equal(a, f["action"]) for a, f in zip(actions, frames, strict=True))
