"""A rerun against the results it repeats (``study/results/rerun.py``, ``factorworld compare-reruns``): cells matched by step
key, the rerun's rate and gap checked against the first run's stated intervals, episodes compared one by one."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from lerobot_factorworld.stats.proportions import paired_gap, wilson_interval
from lerobot_factorworld.study.results.rerun import compare_reruns

ROOT = Path(__file__).resolve().parents[1]
FACTORWORLD = str(Path(sys.executable).with_name("factorworld"))


def row(step, condition, successes, train=None, episodes=20):
    """A results.csv row as the study writes it: Wilson interval, and for a shifted cell the paired gap against
    ``train`` (a list of outcomes) with Newcombe's interval."""
    low, high = wilson_interval(successes, episodes)
    outcomes = [i < successes for i in range(episodes)]
    gap, gap_low, gap_high = (0.0, math.nan, math.nan) if train is None else paired_gap(train, outcomes)
    return {
        "step": step,
        "method": "bc",
        "task": "door-open",
        "n_train_envs": 5,
        "seed": 0,
        "widths": "default",
        "condition": "train" if train is None else condition,
        "episodes": episodes,
        "successes": successes,
        "success_rate": successes / episodes,
        "ci_low": low,
        "ci_high": high,
        "gap": gap,
        "gap_ci_low": gap_low,
        "gap_ci_high": gap_high,
    }


def test_cells_are_matched_by_step_and_checked_against_the_first_runs_intervals():
    train = [True] * 18 + [False] * 2
    first = [
        row("t", "train", 18),
        row("a", "light", 16, train),
        row("b", "camera_pos", 10, train),
        row("x", "d", 5, train),
    ]
    rerun = [
        row("t", "train", 17),
        row("a", "light", 16, train),
        row("b", "camera_pos", 2, train),
        row("y", "d", 5, train),
    ]
    found = compare_reruns(first, rerun)
    cells = {c.step: c for c in found.cells}
    assert set(cells) == {"t", "a", "b"} and (found.only_first, found.only_rerun) == (1, 1)
    assert cells["t"].rate_within and cells["t"].gap_within is None  # train: no gap
    assert cells["a"].rate_within and cells["a"].gap_within and cells["a"].successes == (16, 16)
    assert not cells["b"].rate_within and not cells["b"].gap_within  # 2/20 is outside [0.30, 0.70]
    assert found.within == 2 and found.identical == 1
    assert cells["a"].same_outcome is None  # no episode rows given

    episodes_first = [{"step": "a", "episode_ix": i, "success": i < 16, "n_steps": 50 + i} for i in range(20)]
    episodes_rerun = [
        {"step": "a", "episode_ix": i, "success": i != 0 and i < 17, "n_steps": 50 + i if i % 2 == 0 else 0}
        for i in range(20)
    ]
    cell = next(c for c in compare_reruns(first, rerun, episodes_first, episodes_rerun).cells if c.step == "a")
    assert (cell.same_outcome, cell.same_length) == (18, 8)  # episodes 0 and 16 differ; of the rest the even ones match


def test_runs_without_a_shared_step_or_with_other_episode_counts_are_refused():
    with pytest.raises(ValueError, match="share no evaluation step"):
        compare_reruns([row("t", "train", 18)], [row("u", "train", 18)])
    with pytest.raises(ValueError, match="20 episodes in one run and 40"):
        compare_reruns([row("t", "train", 18)], [row("t", "train", 36, episodes=40)])


def test_the_committed_rerun_of_f5s_bc_on_a_fresh_machine_lands_within_every_interval():
    """docs/findings.md (F6) quotes this: F6's `bc` is F5's `bc` on pick-place (same step keys), run again on
    another machine. Every cell lies within F5's intervals; 154 of 160 episodes end alike."""
    proc = subprocess.run(
        [FACTORWORLD, "compare-reruns", "--first=docs/results/f5_augmentation", "--rerun=docs/results/f6_pretrained"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("8 evaluation steps in both")
    assert "episodes ending alike: 154/160; identically (same length too): 92/160" in lines
    assert "identical cells (same successes and gap): 4/8" in lines
    assert lines[-1] == "within: 8/8"


def test_the_command_says_what_is_missing_in_one_line(tmp_path):
    proc = subprocess.run(
        [FACTORWORLD, "compare-reruns", f"--first={tmp_path}", "--rerun=docs/results/f6_pretrained"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 2 and proc.stderr.strip() == f"error: first {tmp_path}/results.csv does not exist"


@pytest.mark.slow
def test_the_cpu_fingerprint_hashes_each_layer_and_a_oneDNN_cap_leaves_pixels_and_physics_alone():
    """oneDNN's instruction set cannot reach MuJoCo or Mesa: under its cap the pixels and physics hash the same
    (and so does every rerun of a process: the hashes are of fresh processes)."""
    proc = subprocess.run(
        [sys.executable, "scripts/check_cpu_determinism.py", "--quick"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("CPU: ")
    assert any(line.startswith("| default | ") for line in lines) and any(
        line.startswith("| oneDNN SSE4.1 | ") for line in lines
    )
    assert "pixels: the same under every cap" in lines and "physics: the same under every cap" in lines
    assert any(line.startswith("weights: ") for line in lines)
