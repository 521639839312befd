"""Where episodes fail (docs/study.md): every episode's furthest stage, judged from Meta-World's own per-step
quantities (``envs/stages.py``), reported by the env in ``info["stage"]``, recorded per evaluated episode,
counted per ``results.csv`` row and shown by the report next to the ``train`` condition.

The stages are checked on real rollouts: the scripted expert passes them in order and succeeds (an episode cut
at any step ends at the stage shown there), zero actions stay at ``none``, random actions rarely get further
than ``reached``, and a pick episode that goes to another object than the named one ends at ``reached_other``, or
at ``wrong_object`` once it lifts it.
"""

import csv
import shutil
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

from lerobot_factorworld.envs import stages as st
from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.experts import expert_action, expert_policy, rollout
from lerobot_factorworld.pick import catalog
from lerobot_factorworld.pick.family import PICK_FAMILY
from lerobot_factorworld.protocol.sampling import sample_configs
from lerobot_factorworld.study.report.markdown import REPORT_FILE
from lerobot_factorworld.study.report.write import regenerate_report
from lerobot_factorworld.study.results.aggregate import stage_counts
from lerobot_factorworld.study.results.rows import (
    RESULT_COLUMNS,
    Evaluation,
    csv_text,
    parse_stage_counts,
    read_results,
    result_rows,
    stage_counts_text,
)
from lerobot_factorworld.study.run.eval_step import of_seeds
from lerobot_factorworld.study.run.recording import EpisodeRecorder
from lerobot_factorworld.study.run.step import Step

DATA = Path(__file__).resolve().parent / "data" / "results"
OBJECT = ("none", "reached", "grasped", "moved", "succeeded")
ARTICULATED = ("none", "reached", "moved", "succeeded")


def stage_path(env, actions) -> list[tuple[str, int]]:
    """(stage, first step it showed) along one episode driven by ``actions(env, t)``; ends when the env does."""
    path = []
    for t in range(1, env.max_episode_steps + 1):
        _, _, terminated, truncated, info = env.step(actions(env, t))
        if not path or path[-1][0] != info["stage"]:
            path.append((info["stage"], t))
        if terminated or truncated:
            return path
    return path


def expert(task):
    policy = expert_policy(task)
    return lambda env, t: expert_action(policy, env.state_observation)


def zeros(env, t):
    return np.zeros(4, np.float32)


# --- the stages of each kind of task ------------------------------------------------------------------------


def test_each_task_kind_has_its_ordered_stages_and_a_family_may_add_its_own():
    assert st.stage_names("door-open") == st.stage_names("drawer-close") == ARTICULATED
    assert st.stage_names("pick-place") == st.stage_names("bin-picking") == OBJECT
    assert st.stage_names("pick") == (
        "none", "reached_other", "reached", "grasped", "moved", "wrong_object", "succeeded"
    )  # fmt: skip
    assert st.tracked_before("pick") == ("none", "reached", "grasped", "moved", "wrong_object", "succeeded")
    assert st.tracked_before("pick-place") == st.stage_names("pick-place")
    # door-open and lever-pull measure progress with their shaped reward (their obj_to_target does not)
    assert set(st.PROGRESS) == {"door-open", "lever-pull"}


def test_a_stage_counts_when_its_own_test_held_and_the_furthest_one_is_kept():
    stages = st.stages_of("pick-place")
    info = {"near_object": 0.0, "grasp_success": 0.0, "obj_to_target": 0.20, "success": 0.0}
    tracker = st.StageTracker(stages)
    assert tracker.name == "none" and tracker.update(info) == "none"
    assert tracker.update({**info, "near_object": 1.0}) == "reached"
    assert tracker.update(info) == "reached"  # the hand left the object: the episode still got that far
    assert tracker.update({**info, "obj_to_target": 0.16}) == "reached"  # 20% of the way: not yet moved
    assert tracker.update({**info, "obj_to_target": 0.14}) == "moved"  # over 25% of the way from the first step's 0.20
    assert tracker.update({**info, "grasp_success": 1.0}) == "moved"  # an earlier stage never lowers it
    assert tracker.update({**info, "success": 1.0}) == "succeeded"
    # a reward rises to 1: door-open's door angle (in_place_reward) from 0.04
    door = st.StageTracker(st.stages_of("door-open"))
    closed = {"near_object": 0.5, "grasp_success": 1.0, "in_place_reward": 0.04, "obj_to_target": 0, "success": 0}
    assert door.update(closed) == "none"  # half of the ready-to-open reward is not at the handle
    assert door.update({**closed, "in_place_reward": 0.27}) == "none"  # 24% of the way to 1
    assert door.update({**closed, "in_place_reward": 0.30}) == "moved"
    assert not st.moved_by("obj_to_target")({"obj_to_target": 0.0}, {"obj_to_target": 0.0})  # started at the goal


# --- real rollouts --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("task", "path"),
    [
        ("door-open", ARTICULATED),
        ("bin-picking", OBJECT),
        # pick-place's goal lies on the table: the expert slides the puck there without lifting it 2 cm,
        # which Meta-World's grasp_success asks for, so it passes from reached to moved
        ("pick-place", ("none", "reached", "moved", "succeeded")),
    ],
)
def test_the_expert_passes_the_stages_in_order_and_succeeds(task, path, make_env):
    env = make_env(task, cameras=())
    for seed in (0, 1):
        _, info = env.reset(seed=seed)
        assert info["stage"] == "none"
        reached = stage_path(env, expert(task))
        # an episode cut at step t ends at the stage shown at t: these are episodes that stop at each stage
        assert tuple(stage for stage, _ in reached) == path, reached
        assert [t for _, t in reached] == sorted(t for _, t in reached)


@pytest.mark.parametrize("task", ["door-open", "pick-place", "bin-picking"])
def test_zero_actions_stay_at_none_and_random_ones_rarely_get_past_reached(task, make_env):
    env = make_env(task, cameras=(), max_episode_steps=150)
    rng = np.random.default_rng(0)
    ends = {"zeros": [], "random": []}
    for seed in range(3):
        env.reset(seed=seed)
        ends["zeros"].append(stage_path(env, zeros)[-1][0])
        env.reset(seed=seed)
        ends["random"].append(stage_path(env, lambda env, t: rng.uniform(-1, 1, 4).astype(np.float32))[-1][0])
    assert ends["zeros"] == ["none"] * 3
    assert ends["random"].count("none") + ends["random"].count("reached") >= 2 and "succeeded" not in ends["random"]


def test_a_pick_episode_stages_and_lifting_another_object_ends_at_wrong_object(make_env):
    task = catalog.PICK_TASK
    base = sample_configs(task, 1, seed=4, factors=())[0]
    first, second = base.content.names[:2]
    named = {name: replace(base, content=replace(base.content, target=name)) for name in (first, second)}
    env = make_env(task, [named[first]], cameras=())
    env.reset(seed=0)
    lift_first = []
    policy = expert_policy(task)

    def act(env, t):
        lift_first.append(expert_action(policy, env.state_observation))
        return lift_first[-1]

    assert tuple(stage for stage, _ in stage_path(env, act)) == ("none", "reached", "grasped", "moved", "succeeded")
    # the same motions in the scene that names the other object reach, then lift, the wrong one
    other = make_env(task, [named[second]], cameras=(), terminate_on_success=False)
    other.reset(seed=0)
    path: dict[str, int] = {}
    for t, action in enumerate(lift_first, 1):
        path.setdefault(other.step(action)[4]["stage"], t)
    assert tuple(path) == ("none", "reached_other", "wrong_object")
    # cut where it reached the other object: it ends there, having lifted nothing
    reached_at = path["reached_other"]
    replay = iter(lift_first)
    recorder = EpisodeRecorder(measure_keys=PICK_FAMILY.episode_measures)
    cut = make_env(task, [named[second]], cameras=(), terminate_on_success=False, max_episode_steps=reached_at)
    cut.unwrapped.episode_observer = recorder  # keeps what an episode ended with: this one is cut at reached_at
    episode = rollout(cut, None, 0, act=lambda *_: next(replay))
    assert episode.info["stage"] == "reached_other" and not episode.success
    # what an evaluation keeps of it: the gripper came within 3 cm of another object, never of the named one
    (measures,) = recorder.measures.values()
    assert measures["closest_other"] <= catalog.REACH_RADIUS < measures["closest_named"]
    assert measures == {k: round(float(episode.info[k]), 6) for k in ("closest_named", "closest_other")}


def test_the_evaluation_records_the_stage_of_every_seeded_episode_of_a_vector_env():
    """As LeRobot's rollout runs them: a batch of envs reset with seeds, stepped until all are done, a finished
    env autoreset (no seed) and stepped on; only the seeded episodes are recorded, by seed, through each env
    instance's observer (the class is left as it is)."""
    task = "door-open"
    policy = expert_policy(task)
    original = FactorWorldEnv.reset, FactorWorldEnv.step
    vec = gym.vector.SyncVectorEnv([lambda: FactorWorldEnv(task, cameras=(), max_episode_steps=110)] * 2)
    ends = EpisodeRecorder()
    other = FactorWorldEnv(task, cameras=(), max_episode_steps=3)  # an env without the observer: not recorded
    try:
        for env in vec.envs:
            env.unwrapped.episode_observer = ends
        vec.reset(seed=[10, 11])
        other.reset(seed=12)
        done = np.zeros(2, bool)
        while not done.all():
            expert_move = expert_action(policy, vec.envs[0].state_observation)
            _, _, terminated, truncated, _ = vec.step(np.stack([expert_move, np.zeros(4, np.float32)]))
            done |= terminated | truncated
        for _ in range(5):  # env 0 was autoreset without a seed: its new episode is not recorded
            vec.step(np.zeros((2, 4), np.float32))
            other.step(np.zeros(4, np.float32))
    finally:
        vec.close()
        other.close()
    assert ends.stages == {10: "succeeded", 11: "none"}
    assert of_seeds(ends.stages, [11, 10]) == ["none", "succeeded"]
    assert ends.lengths[11] == 110 and 0 < ends.lengths[10] < 110  # the idle one ran to the limit
    with pytest.raises(RuntimeError, match=r"seed\(s\) \[12\]"):
        of_seeds(ends.stages, [10, 12])
    assert (FactorWorldEnv.reset, FactorWorldEnv.step) == original


# --- results.csv and the report -----------------------------------------------------------------------------------


def test_results_rows_count_episodes_per_stage_and_older_evaluations_leave_the_column_empty():
    cfg = SimpleNamespace(name="s", methods=[SimpleNamespace(name="bc", policy={"type": "bc"})])
    meta = {"method": "bc", "task": "door-open", "n_train_envs": 2, "seed": 0, "widths": "default"}
    result = {"successes": [True, False, True], "seeds": [0, 1, 2], "n_envs": 2, "envs_visited": 2}
    result |= {"fingerprint": "f" * 16, "stages": ["succeeded", "none", "succeeded"]}
    older = {k: v for k, v in result.items() if k != "stages"}
    evaluations = [
        Evaluation(Step("eval", {"c": c}, ("train-key",), {**meta, "condition": c}), r)
        for c, r in (("train", result), ("light", older))
    ]
    rows = result_rows(cfg, evaluations)
    assert tuple(rows[0]) == RESULT_COLUMNS
    assert [r["stages"] for r in rows] == ["none:1;reached:0;moved:0;succeeded:2", ""]
    assert parse_stage_counts(rows[0]["stages"]) == {"none": 1, "reached": 0, "moved": 0, "succeeded": 2}
    assert parse_stage_counts("") == {}
    assert stage_counts_text("pick-place", ["gone", "none"]) == "none:1;reached:0;grasped:0;moved:0;succeeded:0;gone:1"
    # a stage added later reads 0 only where the evaluation tracked it; one that recorded no names did not
    tracked = st.stage_names("pick")
    assert stage_counts_text("pick", ["none", "succeeded"], tracked).startswith("none:1;reached_other:0;reached:0")
    assert stage_counts_text("pick", ["none", "succeeded"]) == (
        "none:1;reached:0;grasped:0;moved:0;wrong_object:0;succeeded:1"
    )
    # pooled with episodes of an older evaluation, a later stage counts as the stage it refines
    older = st.tracked_before("pick")
    assert st.as_tracked("pick", ["reached_other", "reached"], older) == ["none", "reached"]
    assert stage_counts_text("pick", ["reached_other"], older) == stage_counts_text("pick", ["none"])
    with pytest.raises(ValueError, match="not 'stage:count"):
        parse_stage_counts("none=3")


def test_the_stage_selector_pools_seeds_per_method_task_n_and_condition_on_the_main_grid():
    def row(seed, condition, stages, widths="default"):
        cell = {"method": "bc", "task": "door-open", "n_train_envs": 2, "seed": seed, "condition": condition}
        return {**cell, "widths": widths, "stages": stages}

    rows = [
        row(0, "train", "none:0;reached:1;moved:0;succeeded:4"),
        row(1, "train", "none:1;reached:0;moved:0;succeeded:4"),
        row(0, "camera_pos", "none:3;reached:1;moved:1;succeeded:0"),
        row(1, "camera_pos", ""),  # made before stages were recorded: left out
        row(0, "camera_pos", "none:5;reached:0;moved:0;succeeded:0", widths="camera_pos=large"),  # radius sweep
    ]
    assert stage_counts(rows) == {
        ("bc", "door-open", 2, "train"): {"none": 1, "reached": 1, "moved": 0, "succeeded": 8},
        ("bc", "door-open", 2, "camera_pos"): {"none": 3, "reached": 1, "moved": 1, "succeeded": 0},
    }
    assert list(stage_counts(rows)[("bc", "door-open", 2, "train")]) == list(ARTICULATED)  # the column's order


@pytest.fixture
def quick(tmp_path) -> Path:
    """The committed quick study (door-open, no stages column), copied to a writable folder."""
    shutil.copytree(DATA / "quick", tmp_path / "quick")
    return tmp_path / "quick"


def test_the_report_shows_where_episodes_fail_from_results_csv_alone_train_first(quick, tmp_path):
    old, _ = regenerate_report(quick / "results.csv", out=tmp_path / "old")
    assert "Where episodes fail" not in old.read_text()  # an older results.csv still regenerates, without it
    rows = read_results(quick / "results.csv")
    for r in rows:  # the failures of each row: half at none, the rest at reached
        failed = r["episodes"] - r["successes"]
        r["stages"] = f"none:{failed - failed // 2};reached:{failed // 2};moved:0;succeeded:{r['successes']}"
    (quick / "results.csv").write_text(csv_text(rows, RESULT_COLUMNS))
    header = next(csv.reader(open(quick / "results.csv")))
    assert header == list(RESULT_COLUMNS) and "stages" in header
    report, _ = regenerate_report(quick / "results.csv")
    section = report.read_text().split("## Where episodes fail")[1].split("\n## ")[0]
    table = [line for line in section.splitlines() if line.startswith("| ")]
    assert table[0] == "| method | task | N | condition | episodes | none | reached | moved | succeeded |"
    body = [line.split(" | ") for line in table[1:]]
    assert [(cells[2], cells[3]) for cells in body] == [
        (n, c) for n in ("2", "5") for c in ("train", "camera_pos", "table_texture", "light")
    ]
    camera = next(r for r in rows if r["condition"] == "camera_pos" and r["n_train_envs"] == 2)
    failed = camera["episodes"] - camera["successes"]
    shares = [(failed - failed // 2) / 10, failed // 2 / 10, 0.0, camera["successes"] / 10]
    assert table[2] == "| bc | door-open | 2 | camera_pos | 10 | " + " | ".join(f"{s:.2f}" for s in shares) + " |"
    assert report == quick / REPORT_FILE
