"""The generalization-gap study: metrics against hand-computed numbers, the evaluation protocol
(condition-independent test environments, equal and paired visits, the training condition read from a
dataset), and a toy study end to end (collect, train, evaluate, report), cached, resumed, and on Ray."""

import filecmp
import json
import logging
import math
import os
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from lerobot_factorworld.protocol.conditions import evaluation_suites
from lerobot_factorworld.protocol.coverage import coverage
from lerobot_factorworld.stats import proportions, ranks, summaries
from lerobot_factorworld.study import paper
from lerobot_factorworld.study.plan.command import StudyCommand

ROOT = Path(__file__).resolve().parents[1]

# --- metrics ------------------------------------------------------------------------------------


def test_wilson_interval_matches_hand_computation():
    # 8/10, z = 1.96: centre (0.8 + 0.19207) / 1.38415 = 0.71674, half 1.96 * 0.16 / 1.38415 = 0.22657
    low, high = proportions.wilson_interval(8, 10)
    assert low == pytest.approx(0.49016, abs=1e-5) and high == pytest.approx(0.94332, abs=1e-5)
    assert proportions.wilson_interval(0, 10) == pytest.approx((0.0, 0.27753), abs=1e-5)
    assert proportions.wilson_interval(10, 10) == pytest.approx((0.72247, 1.0), abs=1e-5)
    assert all(math.isnan(v) for v in proportions.wilson_interval(0, 0))
    with pytest.raises(ValueError):
        proportions.wilson_interval(11, 10)


def test_paired_gap_is_newcombes_interval():
    # 4 paired episodes: both succeed 2, only train 1, only shifted 0, neither 1.
    # P_T = 0.75 (Wilson 0.30064..0.95441), P_F = 0.5 (Wilson 0.15004..0.84996); ad - bc = 2 <= n/2 -> phi = 0;
    # lower = 0.25 - sqrt(0.44936^2 + 0.34996^2) = -0.31956; upper = 0.25 + sqrt(0.20441^2 + 0.34996^2) = 0.65529
    train = [True, True, True, False]
    shifted = [True, True, False, False]
    gap, low, high = proportions.paired_gap(train, shifted)
    assert gap == pytest.approx(0.25)
    assert low == pytest.approx(-0.31956, abs=1e-4) and high == pytest.approx(0.65529, abs=1e-4)
    # Newcombe (1998) worked example: 36 both, 12 only first, 2 only second, 0 neither -> 0.0569 .. 0.3404
    gap, low, high = proportions.paired_gap([True] * 48 + [False] * 2, [True] * 36 + [False] * 12 + [True] * 2)
    assert (gap, low, high) == pytest.approx((0.2, 0.0569, 0.3404), abs=1e-4)
    assert proportions.paired_gap([True] * 5, [True] * 5)[0] == 0.0
    with pytest.raises(ValueError, match="equal lengths"):
        proportions.paired_gap([True], [True, False])


def test_results_rows_hold_the_signed_gap_of_each_checkpoints_own_paired_episodes(tmp_path):
    """results.csv's gap is P_T - P_F of the same checkpoint on the same episode seeds, with Newcombe's paired
    interval: one checkpoint loses under its shift, the other gains, so a swapped sign or a gap paired with
    another checkpoint's train episodes shows."""
    from types import SimpleNamespace

    from lerobot_factorworld.study.results.rows import Evaluation, read_results, result_rows, write_results
    from lerobot_factorworld.study.run.step import Step

    cfg = SimpleNamespace(name="s", methods=[SimpleNamespace(name="bc", policy={"type": "bc"})])
    seeds = list(range(1000, 1010))
    t, f = True, False
    outcomes = {  # (checkpoint, condition) -> the 10 paired episodes' successes
        ("a", "train"): [t, t, t, t, t, t, t, t, f, f],  # 8 / 10
        ("a", "light"): [t, t, t, f, f, f, f, f, f, t],  # 4 / 10: 3 both, 5 train only, 1 shifted only, 1 neither
        ("b", "train"): [t, t, t, f, f, f, f, f, f, f],  # 3 / 10
        ("b", "light"): [t, t, f, t, t, t, t, f, f, f],  # 6 / 10: 2 both, 1 train only, 4 shifted only, 3 neither
        ("b", "camera_pos"): [t] * 10,  # other episode seeds than b's train: no paired gap
    }

    def evaluation(checkpoint, condition, successes):
        meta = {"method": "bc", "task": "door-open", "n_train_envs": 2, "seed": 0, "widths": "default"}
        result = {"successes": successes, "seeds": seeds if condition != "camera_pos" else [s + 1 for s in seeds]}
        result |= {"n_envs": 2, "envs_visited": 2, "fingerprint": "f" * 16}
        step = Step("eval", {"condition": condition}, (f"train-{checkpoint}",), {**meta, "condition": condition})
        return Evaluation(step, result)

    rows = result_rows(cfg, [evaluation(c, condition, s) for (c, condition), s in outcomes.items()])
    path = write_results(rows, tmp_path / "results.csv")
    read = {(row["step"], row["condition"]): row for row in read_results(path)}
    by_cell = {cell: read[(row["step"], row["condition"])] for cell, row in zip(outcomes, rows)}
    columns = ("successes", "success_rate", "train_success_rate", "gap", "gap_ci_low", "gap_ci_high")

    def numbers(cell):
        return tuple(by_cell[cell][c] for c in columns)

    assert numbers(("a", "train")) == (8, 0.8, 0.8, 0.0, *[pytest.approx(math.nan, nan_ok=True)] * 2)
    assert numbers(("b", "train")) == (3, 0.3, 0.3, 0.0, *[pytest.approx(math.nan, nan_ok=True)] * 2)
    # a under light: P_T 0.8 (Wilson 0.490162..0.943318), P_F 0.4 (0.168180..0.687326), phi = -2 / sqrt(384);
    # lower 0.4 - sqrt(0.309838^2 + 2 * 0.102062 * 0.309838 * 0.287326 + 0.287326^2) = -0.043540,
    # upper 0.4 + sqrt(0.143318^2 + 2 * 0.102062 * 0.143318 * 0.231820 + 0.231820^2) = 0.684714
    assert numbers(("a", "light")) == pytest.approx((4, 0.4, 0.8, 0.4, -0.04354, 0.684714), abs=1e-6)
    # b under light gains: P_T 0.3 (0.107791..0.603222), P_F 0.6 (0.312674..0.831820), ad - bc = 2 <= n/2: phi 0;
    # lower -0.3 - sqrt(0.192209^2 + 0.231820^2) = -0.601139, upper -0.3 + sqrt(0.303222^2 + 0.287326^2) = 0.117732
    assert numbers(("b", "light")) == pytest.approx((6, 0.6, 0.3, -0.3, -0.601139, 0.117732), abs=1e-6)
    unpaired = numbers(("b", "camera_pos"))
    assert unpaired[:2] == (10, 1.0) and all(math.isnan(v) for v in unpaired[2:])


def test_pair_metric_interaction_mean_se_and_spearman():
    assert summaries.pair_metric(0.4, 0.5, 0.8) == pytest.approx(-0.2)  # (0.4 - 0.5) / 0.5
    assert summaries.pair_metric(0.63, 0.6, 0.9) == pytest.approx(0.05)
    assert math.isnan(summaries.pair_metric(0.1, 0.0, 0.5))  # the harder factor never succeeds
    assert summaries.interaction(0.5, 0.2, 0.25) == pytest.approx(0.05)
    mean, se = summaries.mean_se([0.2, 0.4, 0.6])
    assert mean == pytest.approx(0.4) and se == pytest.approx(0.2 / math.sqrt(3))
    assert math.isnan(summaries.mean_se([0.3])[1])
    assert ranks.rank_hardest_first({"a": 0.3, "b": 0.1, "c": 0.3}) == {"a": 1.5, "c": 1.5, "b": 3.0}
    # 1 - 6 * (0 + 1 + 1) / (3 * 8) = 0.5
    assert ranks.spearman({"a": 1, "b": 2, "c": 3}, {"a": 1, "b": 3, "c": 2}) == pytest.approx(0.5)
    paper_order = sorted(paper.PAPER_FACTOR_RANKS, key=paper.PAPER_FACTOR_RANKS.get)
    reverse = {f: float(len(paper_order) - i) for i, f in enumerate(paper_order)}
    assert ranks.spearman(reverse, paper.PAPER_FACTOR_RANKS) < -0.9
    assert math.isnan(ranks.spearman({"a": 1, "b": 2}, {"a": 1, "b": 2}))


def test_the_pairs_section_counts_cells_whose_pair_metric_is_undefined():
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
    from lerobot_factorworld.study.report.markdown import _pairs_section

    cfg = StudyConfig(tasks=["door-open"], factors=["light", "camera_pos"], pairs=["light+camera_pos"], seeds=[0, 1])

    def row(seed, condition, rate, gap):
        n_factors = condition.count("+") + 1
        return {
            "method": cfg.methods[0].name,
            "task": "door-open",
            "n_train_envs": 5,
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "n_factors": n_factors,
            "success_rate": rate,
            "gap": gap,
        }

    rows = [
        row(0, "light", 0.5, 0.5),
        row(0, "camera_pos", 0.0, 1.0),
        row(0, "light+camera_pos", 0.0, 1.0),
        row(1, "light", 0.5, 0.5),
        row(1, "camera_pos", 0.4, 0.6),
        row(1, "light+camera_pos", 0.2, 0.8),
    ]
    text = "\n".join(_pairs_section(cfg, rows))
    assert "| light+camera_pos | -0.500 | " in text and "| 1 of 2 |" in text  # seed 1: (0.2 - 0.4) / 0.4


def test_a_pick_study_report_sets_success_next_to_the_papers_real_robot_table():
    from lerobot_factorworld.family_reports.pick import real_robot_section as _real_robot_section
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
    from lerobot_factorworld.study.plan.method_config import MethodConfig

    cfg = StudyConfig(
        tasks=["pick"],
        train_factors=["light", "camera_pos", "table_texture"],
        factors=["light", "camera_pos", "table_texture", "held_out_objects"],
        seeds=[0, 1],
    )
    successes = {
        "train": (9, 8),
        "light": (8, 7),
        "camera_pos": (2, 3),
        "table_texture": (5, 4),
        "held_out_objects": (1, 0),
    }
    rows = [
        {
            "method": cfg.methods[0].name,
            "task": "pick",
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": c,
            "successes": k[seed],
            "episodes": 10,
        }
        for c, k in successes.items()
        for seed in (0, 1)
    ]
    text = "\n".join(_real_robot_section(cfg, rows))
    # seeds pooled with the seed-level bootstrap: 17/20 is 9/10 and 8/10; a resample of seed 0 twice whose
    # episodes are redrawn succeeds 20 times in more than 2.5% of resamples, so the upper end is 1.00 (Wilson's
    # 0.95 treated the 20 episodes as one sample); the lower end stays the Wilson interval's 0.64 it must contain
    assert "| original (`train`) | 91.7% | 17/20 | 0.85 [0.64, 1.00] |" in text
    assert "seed-level bootstrap" in text and "seeds pooled" in text
    assert "| held-out objects (`held_out_objects`) | — | 1/20 |" in text
    # light 0.75 > table texture 0.45 > camera 0.25, as in the paper (83.3 > 52.8 > 45.8)
    assert "**+1.00**" in text and "easiest first here: light, table_texture, camera_pos" in text
    door = [dict(r, task="door-open") for r in rows]
    assert _real_robot_section(cfg, door) == []
    # two methods: one table holds both (a second table without its header would render as text), each
    # method's Spearman line under it
    two = replace(cfg, methods=[cfg.methods[0], MethodConfig("other", {"type": "bc", "augmentation": "shift"})])
    lines = _real_robot_section(two, rows + [dict(r, method="other") for r in rows])
    table = [i for i, line in enumerate(lines) if line.startswith("|")]
    assert table == list(range(table[0], table[0] + 2 + 2 * len(successes)))  # header, rule, 5 rows per method
    assert sum(line.startswith("| method |") for line in lines) == 1
    assert [line.split(":")[0] for line in lines[table[-1] + 1 :] if "Spearman" in line] == [
        cfg.methods[0].name,
        "other",
    ]


# --- protocol -----------------------------------------------------------------------------------


def test_pairs_are_counted_against_the_papers_band_per_task():
    """A task where the singles barely matter (pairs at their harder factor) beside one where pairs compound:
    averaged over tasks the band hides the first; per task both show."""
    from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
    from lerobot_factorworld.study.results.aggregate import pair_bands

    def row(task, condition, rate, p_train=1.0):
        return {
            "method": "bc",
            "task": task,
            "n_train_envs": 5,
            "seed": 0,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "n_factors": condition.count("+") + 1,
            "success_rate": rate,
            "gap": p_train - rate,
        }

    rates = {
        "easy": {"a": 0.9, "b": 1.0, "c": 0.95, "a+b": 0.9, "a+c": 0.88, "b+c": 0.95},
        "hard": {"a": 0.5, "b": 0.6, "c": 0.0, "a+b": 0.2, "a+c": 0.0, "b+c": 0.1},
    }
    rows = [row(task, condition, rate) for task, conditions in rates.items() for condition, rate in conditions.items()]
    rows += [{**row(task, "train", 1.0), "n_factors": 0} for task in rates]
    bands = pair_bands(rows, "bc", 0.06)
    assert list(bands) == ["easy", "hard"]
    easy, hard = bands["easy"], bands["hard"]
    assert (easy.within, easy.below, easy.above) == (3, 0, 0)  # a+c: (0.88 - 0.9) / 0.9 = -0.022
    assert (hard.within, hard.below, hard.above) == (0, 1, 0)  # a+b: -0.6; c never succeeds: no metric
    # interactions: a+b (0.8 - 0.5 - 0.4), a+c (1 - 0.5 - 1), b+c (0.9 - 0.4 - 1)
    assert hard.mean_interaction == pytest.approx((-0.1 - 0.5 - 0.5) / 3)
    # no episode counts: nothing to resample, so the interval is the point itself
    assert hard.interaction_interval == pytest.approx((hard.mean_interaction, hard.mean_interaction))
    assert easy.within_interval == (3, 3) and hard.within_interval == (0, 0)
    counted = [{**r, "episodes": 20} for r in rows]  # 20 episodes per cell: an interval around the point
    low, high = pair_bands(counted, "bc", 0.06)["hard"].interaction_interval
    assert low < hard.mean_interaction < high and high - low > 0.1
    low, high = pair_bands(counted, "bc", 0.06)["easy"].within_interval  # resampling moves metrics out of the band
    assert low < 3 and high == 3
    assert pair_bands(rows, "other", 0.06) == {}


def test_methods_are_set_against_the_first_per_factor_and_group():
    """Two methods on two seeds: the report's "Methods against" table gives each mean gap, their difference
    and its bootstrap interval, per factor and per section 5.2 group that the study covers."""
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
    from lerobot_factorworld.study.report.markdown import _methods_section
    from lerobot_factorworld.study.results.aggregate import method_gap_differences

    def row(method, seed, condition, successes):
        return {
            "method": method,
            "task": "door-open",
            "n_train_envs": 5,
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "n_factors": 1,
            "success_rate": successes / 20,
            "episodes": 20,
            "gap": math.nan if condition == "train" else 1.0 - successes / 20,
        }

    successes = {  # (method, condition) -> successes of 20 at seeds 0 and 1; train 20/20 everywhere
        ("none", "camera_pos"): (10, 12),
        ("none", "table_pos"): (14, 14),
        ("shift", "camera_pos"): (18, 18),
        ("shift", "table_pos"): (14, 16),
    }
    rows = [row(m, s, "train", 20) for m in ("none", "shift") for s in (0, 1)]
    rows += [row(m, s, c, k[s]) for (m, c), k in successes.items() for s in (0, 1)]
    labels = {"camera_pos": ("camera_pos",), "spatial": ("camera_pos", "table_pos")}
    found = method_gap_differences(rows, ["none", "shift"], labels)
    (base, gap, diff) = found[("shift", "camera_pos")]
    assert (base[0], gap[0], diff[0]) == pytest.approx((0.45, 0.1, -0.35))
    assert diff[1] <= diff[0] <= diff[2] < 0  # resolved: crop shrinks this gap
    base, gap, diff = found[("shift", "spatial")]
    assert (base[0], gap[0], diff[0]) == pytest.approx((0.375, 0.175, -0.2))
    assert method_gap_differences(rows, ["none"], labels) == {}
    cfg = StudyConfig(
        factors=["camera_pos", "table_pos"],
        methods=[
            {"name": "none", "policy": {"type": "bc", "augmentation": "none"}},
            {"name": "shift", "policy": {"type": "bc", "augmentation": "shift"}},
        ],
    )
    text = "\n".join(_methods_section(cfg, rows))
    assert (
        "## Methods against none" in text and "| shift | spatial | 6 | +0.375 | +0.175 | -0.200 | [" in text
    )  # 6 cells
    assert "| shift | textures |" not in text  # no texture factor in this study


def test_ordering_per_task_sets_each_method_s_spearman_against_the_first():
    """Two methods on two tasks: the per-task table adds the second method's Spearman with the paper and its
    difference to the first's, per task. On door-open the second method reverses the first's ordering (+1 to
    -1: -2); on pick-place both order the factors alike (difference 0). A third method is n/a where it has no
    rows or ties every gap."""
    from lerobot_factorworld.study.analysis.study import StudyAnalysis
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
    from lerobot_factorworld.study.report.markdown import _ordering_per_task_section
    from lerobot_factorworld.study.results.aggregate import task_orderings

    def row(method, task, seed, condition, successes):
        return {
            "method": method,
            "task": task,
            "n_train_envs": 5,
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "n_factors": 1,
            "success_rate": successes / 20,
            "episodes": 20,
            "gap": math.nan if condition == "train" else 1.0 - successes / 20,
        }

    factors = ["camera_pos", "floor_texture", "light"]  # paper ranks 1.5, 5, 6.5: gaps in this order give +1
    hardest_first = (10, 14, 18)  # successes of 20: gaps 0.5, 0.3, 0.1
    ordered = {
        ("bc", "door-open"): hardest_first,
        ("bc_none", "door-open"): hardest_first[::-1],
        ("bc", "pick-place"): hardest_first,
        ("bc_none", "pick-place"): hardest_first,
        ("bc_tied", "door-open"): (14, 14, 14),  # every gap equal: rho undefined; no pick-place rows
    }
    rows = []
    for (method, task), successes in ordered.items():
        for seed in (0, 1):
            rows.append(row(method, task, seed, "train", 20))
            rows += [row(method, task, seed, f, k) for f, k in zip(factors, successes)]
    cfg = StudyConfig(
        tasks=["door-open", "pick-place"],
        factors=factors,
        methods=[
            {"name": "bc", "policy": {"type": "bc", "augmentation": "shift"}},
            {"name": "bc_none", "policy": {"type": "bc", "augmentation": "none"}},
            {"name": "bc_tied", "policy": {"type": "bc", "augmentation": "color"}},
        ],
    )

    def ordering_per_task(cfg, rows):  # these rows carry gaps only: the analysis' per-task orderings alone
        tasks = [t for t in cfg.tasks if any(r["task"] == t for r in rows)]
        orderings = task_orderings(rows, cfg.methods[0].name, cfg.shifted_factors(), tasks)
        return _ordering_per_task_section(cfg, rows, StudyAnalysis(task_orderings=orderings))

    lines = ordering_per_task(cfg, rows)

    def cells(label):  # the row's (point, low, high) per task
        (line,) = [x for x in lines if x.startswith(f"| {label} |")]
        found = re.findall(r"([+-]\d\.\d\d) \[([+-]\d\.\d\d), ([+-]\d\.\d\d)\]", line)
        return [tuple(float(v) for v in f) for f in found]

    assert [c[0] for c in cells("Spearman with the paper")] == [1.0, 1.0]
    assert [c[0] for c in cells("Spearman with the paper, bc_none")] == [-1.0, 1.0]
    (door, pick) = cells("bc_none minus bc")
    assert door[0] == -2.0 and door[1] <= door[0] <= door[2] < 0  # resolved on door-open alone
    assert pick[0] == 0.0 and pick[1] < 0 < pick[2]  # pooled over tasks it would read -1
    # a method without rows on a task, or with every gap tied, is n/a there, and leaves the others' cells alone
    assert "| Spearman with the paper, bc_tied | n/a | n/a | |" in lines
    assert "| bc_tied minus bc | n/a | n/a | |" in lines
    one = replace(cfg, methods=cfg.methods[:1])
    assert not [x for x in ordering_per_task(one, rows) if "bc_none" in x]


def test_test_environments_do_not_depend_on_the_other_conditions():
    alone = evaluation_suites("pick-place", 2, ["light", "table_texture"], ["light"], 4, seed=3)
    crowded = evaluation_suites(
        "pick-place",
        2,
        ["light", "table_texture"],
        ["table_texture", "camera_pos", "light+table_texture", "light"],
        4,
        seed=3,
    )
    assert crowded["light"] == alone["light"]
    assert crowded["train"] == alone["train"]
    # a pair reuses the values its single factors got, on the same training environments
    pair, light, texture = crowded["light+table_texture"], crowded["light"], crowded["table_texture"]
    assert [c.factors.light for c in pair] == [c.factors.light for c in light]
    assert [c.factors.table_texture for c in pair] == [c.factors.table_texture for c in texture]
    # a different seed gives different test environments
    assert evaluation_suites("pick-place", 2, ["light"], ["light"], 4, seed=4)["light"] != alone["light"]


def _run_episodes(env_cfg, batch_size: int, episodes: int, start_seed: int = 1000) -> dict[str, list]:
    """Reset the vector envs the way LeRobot's eval_policy does; (env_index, object start) per episode."""
    envs = env_cfg.create_envs(n_envs=batch_size)
    out = {}
    try:
        for suite, by_task in envs.items():
            vec, seen = by_task[0], []
            for batch in range(math.ceil(episodes / batch_size)):
                seeds = list(range(start_seed + batch * batch_size, start_seed + (batch + 1) * batch_size))
                _, info = vec.reset(seed=seeds)
                starts = info["factors"]["object_pos"]
                seen += [(int(i), tuple(map(float, starts[k]))) for k, i in enumerate(info["env_index"])]
            out[suite] = seen[:episodes]
    finally:
        for by_task in envs.values():
            by_task[0].close()
    return out


def test_episodes_visit_every_environment_equally_and_pair_object_starts(caplog):
    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig

    cfg = FactorWorldEnvConfig(
        task="handle-press", n_train_envs=2, train_factors=["light"], shifts=["light"], n_test_envs=4, image_size=16
    )
    one = _run_episodes(cfg, batch_size=1, episodes=8)
    assert _run_episodes(cfg, batch_size=2, episodes=8) == one  # depends on the episode's index and seed only
    for suite, n_envs in (("train", 2), ("light", 4)):
        visits = [index for index, _ in one[suite]]
        assert sorted(visits) == sorted(list(range(n_envs)) * (8 // n_envs))
    assert [s for _, s in one["train"]] == [s for _, s in one["light"]]  # paired object starts
    assert coverage(range(1000, 1008), 4).equal
    partial = coverage(range(1000, 1003), 4)
    assert not partial.equal and partial.visited == 3 and "3 of its 4 environments" in partial.describe("light")
    with caplog.at_level(logging.WARNING, logger="lerobot_factorworld.protocol.coverage"):
        _run_episodes(replace(cfg, include_train=False), batch_size=1, episodes=3)
    assert "visit 3 of its 4 environments" in caplog.text


def test_coverage_of_batched_resets_does_not_count_lerobot_evals_padding_as_scored():
    from lerobot_factorworld.protocol.coverage import reset_coverage

    # 15 episodes in batches of 10 reset 20 seeds; only the first 15 are scored: never claim "equal"
    unequal, message = reset_coverage(range(1000, 1020), 10, 10, "light")
    assert not unequal and "only if --eval.n_episodes is one of 20" in message
    assert reset_coverage(range(1000, 1020), 10, 1, "light") == (
        False,
        coverage(range(1000, 1020), 10).describe("light"),
    )
    unequal, message = reset_coverage(range(1000, 1006), 4, 3, "light")  # 4, 5 or 6 scored: 4 is equal
    assert not unequal and "one of 4 " in message
    assert reset_coverage(range(1000, 1003), 4, 3, "light")[0]  # 1..3 scored: never equal
    assert reset_coverage(range(1000, 1008), 1, 4, "train") == (False, coverage(range(1000, 1008), 1).describe("train"))


# --- the toy study ------------------------------------------------------------------------------

TOY = """
name: toy
out_dir: {out}
tasks: [handle-press]
n_train_envs: [1, 2]
seeds: [0]
train_factors: [light, table_texture, camera_pos]
factors: [light, table_texture]
pairs: [all]
methods:
  - name: bc
    policy: {{type: bc}}
collect:
  demos: 2
  max_episode_steps: 60
  image_size: 48
train:
  steps: 3
  batch_size: 4
eval:
  n_test_envs: 2
  episodes: 2
  max_episode_steps: 8
executor: {executor}
workers: 2
"""


def _toy_config(
    out: Path, executor: str = "local", n_train_envs: str = "[1, 2]", factors: str = "[light, table_texture]"
):
    """The toy study's settings in ``out``; ``n_train_envs`` and ``factors`` (YAML lists) narrow it to a part of
    its plan."""
    from lerobot_factorworld.core.settings import parse_config

    path = out.parent / f"{out.name}.yaml"
    text = TOY.format(out=out, executor=executor)
    text = text.replace("n_train_envs: [1, 2]\n", f"n_train_envs: {n_train_envs}\n")
    path.write_text(text.replace("\nfactors: [light, table_texture]\n", f"\nfactors: {factors}\n"))
    return parse_config(StudyCommand, [f"--config_path={path}"], "study"), path


# The tests that use (and, resuming, change) the toy study's folder run on one xdist worker, one after the other.
TOY_GROUP = pytest.mark.xdist_group("toy_study")


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    from lerobot_factorworld.study.runner import run_study

    out = tmp_path_factory.mktemp("study") / "toy"
    cfg, path = _toy_config(out)
    outcome = run_study(*cfg.parts(), command=f"factorworld study --config {path}")
    return cfg, outcome


@TOY_GROUP
@pytest.mark.slow
def test_toy_study_end_to_end(toy):
    import csv

    from lerobot_factorworld.study.results.episodes import EPISODES_FILE, read_episodes
    from lerobot_factorworld.study.results.rows import RESULT_COLUMNS

    cfg, outcome = toy
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 2, "train": 2, "eval": 8}
    rows = list(csv.DictReader(open(outcome.results)))
    assert tuple(rows[0]) == RESULT_COLUMNS
    assert {(r["n_train_envs"], r["condition"]) for r in rows} == {
        (n, c) for n in ("1", "2") for c in ("train", "light", "table_texture", "light+table_texture")
    }
    for row in rows:
        assert int(row["episodes"]) == 2 and row["envs_visited"] == row["n_envs"]
        assert float(row["ci_low"]) <= float(row["success_rate"]) <= float(row["ci_high"])
        assert float(row["gap"]) == pytest.approx(float(row["train_success_rate"]) - float(row["success_rate"]))
        assert len(row["fingerprint"]) == 16
    episodes = read_episodes(outcome.results.parent / EPISODES_FILE)  # one row per episode, environments rebuilt
    assert len(episodes) == sum(int(r["episodes"]) for r in rows) and all(e["factors"] for e in episodes)
    report = outcome.report.read_text()
    assert "## Factor ordering" in report and "Spearman" in report
    assert {p.name for p in outcome.plots} >= {"gap_vs_n.png", "pairs.png", "methods.png", "success_rates.png"}
    for plot in outcome.plots:
        assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and plot.stat().st_size > 5000
        assert f"]({plot.name})" in report
    # Every evaluation recorded its episodes (eval.record_episodes 3 >= its 2): paired by index across conditions.
    manifest = json.loads((outcome.results.parent / "episodes" / "episodes.json").read_text())
    assert len(manifest) == len(rows) * 2
    by_cell = {(e["n_train_envs"], e["condition"], e["index"]): e for e in manifest}
    for e in manifest:
        assert (outcome.results.parent / e["video"]).stat().st_size > 500
        twin = by_cell[(e["n_train_envs"], "train", e["index"])]
        assert twin["episode_seed"] == e["episode_seed"] == 1000 + e["index"]
    row_of = {(int(r["n_train_envs"]), r["condition"]): r for r in rows}
    for (n, condition), row in row_of.items():
        assert sum(by_cell[(n, condition, i)]["success"] for i in range(2)) == int(row["successes"])


@TOY_GROUP
@pytest.mark.slow
def test_rerun_does_no_new_work_and_interrupted_study_resumes(toy, run_main):
    import csv
    import fcntl
    import io

    from lerobot_factorworld.cli import main
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.runner import LOCK_FILE, run_study

    cfg, first = toy
    before = first.results.read_text()
    again = run_study(*cfg.parts(), command="rerun")
    assert again.ran == {"collect": 0, "train": 0, "eval": 0}
    assert again.cached == {"collect": 2, "train": 2, "eval": 8}
    assert again.results.read_text() == before
    # interrupt: two evaluations lost their results (one mid-write), results.csv gone
    evals = make_plan(cfg).of_kind("eval")
    for step in evals[:2]:
        (step.folder(cfg.out_dir) / "result.json").unlink()
    (evals[1].folder(cfg.out_dir) / "result.json.tmp123").write_text("{half")
    first.results.unlink()
    # --report-only while a run holds the study's lock: the finished steps' outputs, nothing run
    config = Path(cfg.out_dir).with_suffix(".yaml")  # the toy's config file (_toy_config)
    with open(Path(cfg.out_dir) / LOCK_FILE, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        proc = run_main(["factorworld", "study", f"--config={config}", "--report-only"], main)
    assert proc.returncode == 0, proc.stderr
    assert "finished so far: 2 collect, 2 train, 6 eval" in proc.stdout
    lost = {(str(s.meta["n_train_envs"]), s.meta["condition"]) for s in evals[:2]}
    counts = {(r["n_train_envs"], r["condition"]): r["successes"] for r in csv.DictReader(io.StringIO(before))}
    written = {(r["n_train_envs"], r["condition"]): r["successes"] for r in csv.DictReader(first.results.open())}
    assert len(lost) == 2 and written == {cell: n for cell, n in counts.items() if cell not in lost}
    assert "(6 of 8 evaluations finished)" in first.report.read_text()
    assert all(not (s.folder(cfg.out_dir) / "result.json").exists() for s in evals[:2])
    resumed = run_study(*cfg.parts(), command="resume")
    assert resumed.ran == {"collect": 0, "train": 0, "eval": 2}
    assert resumed.results.read_text() == before  # same rows, none duplicated


@TOY_GROUP
@pytest.mark.slow
def test_the_report_regenerated_from_results_csv_alone_is_the_studys_own(toy, tmp_path):
    from lerobot_factorworld.study.report.write import NO_TIMINGS, regenerate_report

    cfg, outcome = toy
    config = Path(cfg.out_dir).with_suffix(".yaml")  # the toy's config file (_toy_config)
    report, plots = regenerate_report(outcome.results, config, tmp_path)
    live, again = outcome.report.read_text(), report.read_text()
    assert "\nNumbers made at commit(s): " in live and "## Where the time went" in live
    # one renderer: the same text from the commit line on, but for the header's command and the run's timings
    assert (
        live.split("\n## Where the time went")[0].rstrip("\n").split("\n")[3:]
        == again.split(NO_TIMINGS)[0].rstrip("\n").split("\n")[3:]
    )
    assert [p.name for p in plots] == [p.name for p in outcome.plots]
    assert (tmp_path / "results.csv").read_bytes() == outcome.results.read_bytes()
    assert (tmp_path / "config.yaml").read_text() == config.read_text()


def test_changing_one_setting_changes_only_the_steps_that_depend_on_it(tmp_path):
    from lerobot_factorworld.study.plan.grid import make_plan

    cfg, _ = _toy_config(tmp_path / "toy")
    keys = {kind: {s.key for s in make_plan(cfg).of_kind(kind)} for kind in ("collect", "train", "eval")}
    more_episodes = replace(cfg, eval=replace(cfg.eval, episodes=4))
    changed = {kind: {s.key for s in make_plan(more_episodes).of_kind(kind)} for kind in keys}
    assert changed["collect"] == keys["collect"] and changed["train"] == keys["train"]
    assert not changed["eval"] & keys["eval"]
    longer = replace(cfg, train=replace(cfg.train, steps=4))
    changed = {kind: {s.key for s in make_plan(longer).of_kind(kind)} for kind in keys}
    assert changed["collect"] == keys["collect"] and not changed["train"] & keys["train"]


@TOY_GROUP
@pytest.mark.slow
def test_dataset_gives_the_training_condition_and_mismatches_are_refused(toy, tmp_path):
    from lerobot_factorworld.adapters.env_config import LEROBOT_IMAGE_FEATURE, FactorWorldEnvConfig
    from lerobot_factorworld.protocol.sampling import sample_configs
    from lerobot_factorworld.protocol.sidecar import SIDECAR
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.result import read_result

    cfg, _ = toy
    collect = next(s for s in make_plan(cfg).of_kind("collect") if s.inputs["n_envs"] == 2)
    root = read_result(collect, cfg.out_dir)["root"]
    env_cfg = FactorWorldEnvConfig(task="handle-press", dataset_root=root, shifts=["light"], n_test_envs=2)
    assert (env_cfg.n_train_envs, env_cfg.seed) == (2, 0)
    assert env_cfg.train_factors == ["camera_pos", "light", "table_texture"]  # the study sorts them
    train = env_cfg.suites("handle-press")["train"]
    factors = ["light", "table_texture", "camera_pos"]
    assert train == sample_configs("handle-press", 2, 0, "train", factors, env_cfg.sampling)
    assert env_cfg.gym_kwargs["object_pos_width"] == "narrow" and env_cfg.gym_kwargs["quality"] == "fast"
    assert (env_cfg.cameras, env_cfg.image_size) == ("front", 48)  # the toy collects at 48 px, not the default 84
    assert env_cfg.features["pixels/front"].shape == (48, 48, 3)
    FactorWorldEnvConfig(task="handle-press", dataset_root=root, n_train_envs=2, seed=0)  # agreeing: fine
    lod = tmp_path / "lod"  # the same side-car, as if collected at the lod quality: evaluated at lod
    (lod / SIDECAR).parent.mkdir(parents=True)
    sidecar = json.loads(Path(root, SIDECAR).read_text())
    (lod / SIDECAR).write_text(json.dumps({**sidecar, "settings": {**sidecar["settings"], "quality": "lod"}}))
    assert FactorWorldEnvConfig(task="handle-press", dataset_root=str(lod)).gym_kwargs["quality"] == "lod"
    with pytest.raises(ValueError, match="quality='fast' but the dataset has 'lod'"):
        FactorWorldEnvConfig(task="handle-press", dataset_root=str(lod), quality="fast")
    # LeRobot's observation renders its own view (corner2, 480 px, Meta-World's quality) of the dataset's environments
    lerobot = FactorWorldEnvConfig(task="handle-press", dataset_root=str(lod), obs="lerobot_metaworld")
    assert (lerobot.quality, lerobot.n_train_envs) == ("full", 2) and lerobot.features[LEROBOT_IMAGE_FEATURE].shape[
        0
    ] == 480
    wrong_settings = ({"n_train_envs": 5}, {"seed": 1}, {"train_factors": ["light"]}, {"quality": "full"})
    for wrong in (*wrong_settings, {"image_size": 84}, {"cameras": "top"}, {"cameras": "front,top"}):
        with pytest.raises(ValueError, match="disagrees with dataset"):
            FactorWorldEnvConfig(task="handle-press", dataset_root=root, **wrong)
    with pytest.raises(ValueError, match="no environment of task 'door-open'"):
        FactorWorldEnvConfig(task="door-open", dataset_root=root)
    with pytest.raises(FileNotFoundError, match="not a Factor World dataset"):
        FactorWorldEnvConfig(task="handle-press", dataset_root=str(ROOT))


@TOY_GROUP
@pytest.mark.slow
def test_a_plan_on_a_local_ray_instance_gives_the_same_results(toy, tmp_path):
    """The smallest part of the toy's plan (N = 1, the light factor: one collection, one training, two
    evaluations, every key one of the toy's) run again on Ray: the same rows, results and weights."""
    pytest.importorskip("ray")
    import csv

    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.result import read_result
    from lerobot_factorworld.study.runner import run_study

    cfg, local = toy
    ray_cfg, _ = _toy_config(tmp_path / "toy", executor="ray", n_train_envs="[1]", factors="[light]")
    plan = make_plan(ray_cfg)
    assert [s.kind for s in plan.steps] == ["collect", "train", "eval", "eval"]
    assert {s.key for s in plan.steps} <= {s.key for s in make_plan(cfg).steps}
    outcome = run_study(*ray_cfg.parts(), command="ray")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 1, "train": 1, "eval": 2}
    rows, local_rows = list(csv.DictReader(open(outcome.results))), list(csv.DictReader(open(local.results)))
    assert len(rows) == 2 and all(row in local_rows for row in rows)  # the same code: provenance columns too
    for step in plan.steps:
        on_ray, here = read_result(step, ray_cfg.out_dir), read_result(step, cfg.out_dir)
        if step.kind == "eval":
            outcomes = ("successes", "stages", "lengths")
            assert [on_ray[k] for k in outcomes] == [here[k] for k in outcomes]
        if step.kind == "train":  # the same weights, not only the same (toy) outcomes
            weights = Path(here["checkpoint"]) / "model.safetensors"
            assert filecmp.cmp(weights, Path(on_ray["checkpoint"]) / "model.safetensors", shallow=False)


@TOY_GROUP
@pytest.mark.slow
def test_a_study_reuses_another_studys_finished_steps_by_key(toy, tmp_path):
    """N = 1 of the toy with camera position instead of table texture, reusing the toy's folder: its collection,
    training and the two evaluations it shares are linked (the same rows), only the two new ones run, and
    nothing in the toy's folder changes; its published config leaves the reused folders out, and a report
    regenerates where they do not exist."""
    import csv

    from lerobot_factorworld.study.plan.cost import describe
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.report.write import regenerate_report
    from lerobot_factorworld.study.runner import run_study

    cfg, first = toy
    toy_steps = sorted(p.relative_to(cfg.out_dir) for p in Path(cfg.out_dir, "steps").rglob("*"))
    narrow, _ = _toy_config(tmp_path / "reuser", n_train_envs="[1]", factors="[light, camera_pos]")
    reuser = replace(narrow, reuse_from=[cfg.out_dir])
    assert "eval          4 steps,      2 cached (2 in reuse_from),      2 to run" in describe(
        reuser.grid(), make_plan(reuser), reuser.options()
    )
    outcome = run_study(*reuser.parts(), command="reuse")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 0, "train": 0, "eval": 2}
    assert outcome.cached == {"collect": 1, "train": 1, "eval": 2}
    rows, toy_rows = list(csv.DictReader(open(outcome.results))), list(csv.DictReader(open(first.results)))
    shared = [r for r in rows if r["condition"] in ("train", "light")]
    assert len(shared) == 2 and all(row in toy_rows for row in shared)
    linked = [
        s.folder(reuser.out_dir)
        for s in make_plan(reuser).steps
        if s.kind != "eval" or s.meta["condition"] in ("train", "light")
    ]
    assert len(linked) == 4 and all(p.is_symlink() for p in linked)
    assert sorted(p.relative_to(cfg.out_dir) for p in Path(cfg.out_dir, "steps").rglob("*")) == toy_steps
    published, _ = regenerate_report(outcome.results, out=tmp_path / "published")
    config = published.parent / "config.yaml"  # reuse_from names this machine's folders: left out
    assert json.loads(config.read_text())["reuse_from"] == []
    config.write_text(config.read_text().replace('"reuse_from": []', f'"reuse_from": ["{tmp_path}/gone"]'))
    report = published.read_text()
    published.unlink()
    assert regenerate_report(published.parent / "results.csv")[0].read_text() == report
    with pytest.raises(ValueError, match="is this study's own folder"):
        replace(reuser, reuse_from=[reuser.out_dir])
    with pytest.raises(ValueError, match=f"reuse_from: {tmp_path} is not a study folder"):
        replace(reuser, reuse_from=[str(tmp_path)])


@TOY_GROUP
@pytest.mark.slow
def test_a_batched_evaluation_is_its_own_step_and_runs_vectorised(toy, tmp_path):
    """``eval.batch_size: 2`` on N = 1 of the toy, reusing its folder: the collection and training are linked, but
    both evaluations run anew (a batch changes the actions' last bits, so it is in their key) in one batch of 2."""
    import csv

    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.runner import run_study

    cfg, _ = toy
    narrow, _ = _toy_config(tmp_path / "batched", n_train_envs="[1]", factors="[light]")
    batched = replace(narrow, reuse_from=[cfg.out_dir], eval=replace(narrow.eval, batch_size=2))
    outcome = run_study(*batched.parts(), command="batched")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 0, "train": 0, "eval": 2} and outcome.cached == {
        "collect": 1,
        "train": 1,
        "eval": 0,
    }
    for step in make_plan(batched).of_kind("eval"):
        recorded = json.loads((step.folder(batched.out_dir) / "step.json").read_text())
        assert recorded["inputs"]["batch_size"] == 2
        log = (step.folder(batched.out_dir) / "log.txt").read_text()  # LeRobot's progress: one batch of 2 episodes
        assert re.search(r"Stepping through eval batches: +0%\|[^|]*\| 0/1 ", log), log[:300]
    rows = list(csv.DictReader(open(outcome.results)))
    assert sorted(r["condition"] for r in rows) == ["light", "train"] and all(r["episodes"] == "2" for r in rows)


@TOY_GROUP
@pytest.mark.slow
def test_a_study_collects_and_evaluates_at_the_quality_it_names(toy, tmp_path, monkeypatch):
    """``collect.quality: lod`` on N = 1 of the toy: new keys for every step (other pixels), the dataset records
    lod, every evaluation renders its scenes at lod, and the report says so; the toy's default keys hold none."""
    from lerobot_factorworld.envs import runtime
    from lerobot_factorworld.study import runner
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.executors import InlineExecutor
    from lerobot_factorworld.study.run.result import read_result

    cfg, _ = toy
    assert all("quality" not in s.inputs for s in make_plan(cfg).of_kind("collect"))
    narrow, _ = _toy_config(tmp_path / "lod", n_train_envs="[1]", factors="[light]")
    lod = replace(narrow, reuse_from=[cfg.out_dir], collect=replace(narrow.collect, quality="lod"))
    qualities = []  # every scene built, in this process: the steps run inline
    build = runtime.build_spec

    def recording_build(task, factors, cameras, quality, image_size):
        qualities.append(quality)
        return build(task, factors, cameras, quality, image_size)

    monkeypatch.setattr(runtime, "build_spec", recording_build)
    monkeypatch.setattr(runner, "make_executor", lambda kind, study_dir, *a: InlineExecutor(study_dir, a[-1]))
    outcome = runner.run_study(*lod.parts(), command="lod")
    assert not outcome.failed, outcome.failed
    assert outcome.ran == {"collect": 1, "train": 1, "eval": 2}  # nothing of the toy's (fast) is reused
    collect = make_plan(lod).of_kind("collect")[0]
    assert collect.inputs["quality"] == "lod"
    sidecar = json.loads((Path(read_result(collect, lod.out_dir)["root"]) / "meta" / "factorworld.json").read_text())
    assert sidecar["settings"]["quality"] == "lod"
    assert qualities and set(qualities) == {"lod"}, qualities  # collection and both evaluations
    assert "rendered at quality lod" in outcome.report.read_text()


# --- command line -------------------------------------------------------------------------------


def test_cli_dry_run_and_one_line_errors(tmp_path, run_main):
    """``factorworld study`` run in this process (the installed command's one-line errors: test_cli.py)."""
    from lerobot_factorworld.cli import main

    def _factorworld(*args: str) -> subprocess.CompletedProcess:
        return run_main(["factorworld", *args], main)

    _, path = _toy_config(tmp_path / "toy")
    result = _factorworld("study", "--config", str(path), "--dry-run")
    assert result.returncode == 0, result.stderr
    assert "collect       2 steps,      0 cached" in result.stdout and "eval          8 steps" in result.stdout
    assert "one CPU machine" in result.stdout and "Ray cluster" in result.stdout
    assert not (tmp_path / "toy").exists()  # a dry run does nothing
    bad = path.read_text().replace("episodes: 2", "episodes: 3")
    (tmp_path / "bad.yaml").write_text(bad)
    result = _factorworld("study", f"--config={tmp_path / 'bad.yaml'}")
    assert result.returncode == 2 and result.stderr.startswith("error: ") and len(result.stderr.splitlines()) == 1
    assert "multiple" in result.stderr
    result = _factorworld("study", f"--config={path}", "--factors=[lights]")
    assert result.returncode == 2 and "valid factors" in result.stderr


def test_a_method_may_be_any_registered_lerobot_policy_type():
    """LeRobot's own policy types (act, diffusion, ...) train in a study like bc and rt1; a typo names them all."""
    from lerobot_factorworld.study.plan.method_config import MethodConfig
    from lerobot_factorworld.study.plan.policy_checks import check_policy

    check_policy(MethodConfig(name="act", policy={"type": "act", "chunk_size": 10, "n_action_steps": 10}))
    with pytest.raises(ValueError, match="unknown policy type 'actt'; valid types: act, bc, diffusion"):
        check_policy(MethodConfig(name="typo", policy={"type": "actt"}))


def test_a_bad_policy_stops_a_study_and_its_dry_run_but_not_a_report_s_reading(tmp_path, run_main):
    """LeRobot checks the policies where a study runs or is planned, in one line before any work: the command's
    parsing and the library's entry points; a report reads the config without it (loading no torch:
    tests/test_runtime_layers.py)."""
    from lerobot_factorworld.cli import main
    from lerobot_factorworld.study.report.write import load_config
    from lerobot_factorworld.study.run.options import RunOptions
    from lerobot_factorworld.study.runner import inspect_study, report_study, run_study

    _, path = _toy_config(tmp_path / "toy")
    for policy, message in (("{type: actt}", "unknown policy type 'actt'"), ("{type: bc, bogus: 1}", "bogus")):
        bad = tmp_path / "bad.yaml"
        bad.write_text(path.read_text().replace("{type: bc}", policy))
        for args in (["--dry-run"], [], ["--report-only"]):
            result = run_main(["factorworld", "study", f"--config={bad}", *args], main)
            assert result.returncode == 2 and result.stderr.startswith("error: method 'bc': "), result.stderr
            assert message in result.stderr and len(result.stderr.splitlines()) == 1
        grid = load_config(bad)  # as factorworld report reads it: no LeRobot
        for start, options in (
            (inspect_study, RunOptions(dry_run=True)),
            (run_study, RunOptions()),
            (report_study, RunOptions(report_only=True)),
        ):
            with pytest.raises(ValueError, match=message):
                start(grid, options, *(["factorworld study"] if start is report_study else []))
    assert not (tmp_path / "toy").exists()  # refused before any work


STUDY_CONFIGS = sorted(
    str(p.relative_to(ROOT / "configs" / "study")) for p in (ROOT / "configs" / "study").rglob("*.yaml")
)
FINDINGS = [name for name in STUDY_CONFIGS if name.startswith("findings/")]


def _config(name: str):
    from lerobot_factorworld.core.settings import parse_config

    return parse_config(StudyCommand, [f"--config_path={ROOT / 'configs' / 'study' / name}"], "study")


@pytest.mark.parametrize("name", STUDY_CONFIGS)
def test_study_configs_parse_and_plan(name):
    from lerobot_factorworld.study.plan.grid import make_plan

    assert make_plan(_config(name)).counts()["eval"] > 0


# Findings that change the amount of data on purpose (the paper's scale), and how many demos they collect.
DATA_SCALE = {"findings/f2_gap_vs_n_400_demos.yaml": 400}


def test_findings_configs_share_one_recipe_and_their_own_folders():
    """Every finding (docs/findings.md) trains with the documented recipe, so findings compare; each writes
    to its own folder named after it, and the pick protocol (F9) differs only where pick.yaml does. Only the
    findings listed in ``DATA_SCALE`` collect another number of demos."""
    assert len(FINDINGS) >= 9
    configs = {name: _config(name) for name in FINDINGS}
    recipe = configs["findings/f1_ordering.yaml"]
    assert set(DATA_SCALE) <= set(configs)
    for name, cfg in configs.items():
        assert cfg.train == recipe.train, name
        assert cfg.out_dir == f"outputs/study/findings/{cfg.name}" and name == f"findings/{cfg.name}.yaml", name
        if cfg.tasks != ["pick"]:
            assert cfg.collect.demos == DATA_SCALE.get(name, recipe.collect.demos), name
            assert cfg.collect.action_noise == recipe.collect.action_noise, name


def test_run_findings_runs_every_findings_config_and_refuses_an_unknown_one():
    """scripts/run_findings.sh lists every config under configs/study/findings/ once (a new finding is not
    left out of "run them all"); a misspelt name is one error line naming the valid ones, before anything runs."""
    script = ROOT / "scripts" / "run_findings.sh"
    listed = re.search(r"FINDINGS=\(\n(.*?)\n\)", script.read_text(), re.S).group(1).split()
    assert sorted(listed) == sorted(Path(name).stem for name in FINDINGS) and len(set(listed)) == len(listed)
    proc = subprocess.run(["bash", str(script)], env={**os.environ, "ONLY": "f3_pair"}, capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.startswith("error: unknown finding 'f3_pair'; valid: f3_pairs ")
    assert proc.stderr.count("\n") == 1 and not proc.stdout


def test_run_findings_reuses_finished_folders_and_goes_on_past_a_failed_study(tmp_path):
    """With a stand-in ``factorworld`` (BIN): each study names every folder finished before it in ``reuse_from``,
    a failed study does not stop the next one, and the script ends with exit 1 naming the studies that failed."""
    bin_dir, out = tmp_path / "bin", tmp_path / "findings"
    bin_dir.mkdir()
    stub = bin_dir / "factorworld"
    stub.write_text(
        "#!/usr/bin/env bash\n"
        'echo "args: $*"\n'
        'for a in "$@"; do case "$a" in --out_dir=*) mkdir -p "${a#--out_dir=}/steps";; esac; done\n'
        'case "$*" in *f1_ordering.yaml*) exit 1;; esac\n'
    )
    stub.chmod(0o755)
    env = {**os.environ, "BIN": str(bin_dir), "OUT": str(out), "ONLY": "f3_pairs f1_ordering f5_augmentation"}
    proc = subprocess.run(["bash", str(ROOT / "scripts" / "run_findings.sh")], env=env, capture_output=True, text=True)
    assert proc.returncode == 1 and proc.stderr.strip().startswith("error: these findings did not finish: f1_ordering ")
    runs = [line for line in proc.stdout.splitlines() if line.startswith("args: ")]
    assert len(runs) == 3 and "--reuse_from" not in runs[0]
    assert f"--reuse_from=[{out}/f3_pairs]" in runs[1]
    assert f"--reuse_from=[{out}/f3_pairs,{out}/f1_ordering]" in runs[2]  # a failed study's finished steps count


def test_study_datasets_store_lossless_frames_by_default():
    """Training frames are PNG (lossless) unless a study asks for video: AV1's 4:2:0 chroma would smear a
    13-pixel object's colour in training while evaluation sees raw renders."""
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.collect_step import collect_config

    for cfg in (StudyConfig(), *(_config(name) for name in STUDY_CONFIGS)):
        for step in make_plan(cfg).of_kind("collect"):
            assert collect_config(step.inputs, Path("unused"), step.key).use_videos is False, cfg.name


def test_paper_config_is_the_papers_grid():
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.factors.registry import PAPER_STUDY_FACTORS
    from lerobot_factorworld.study.plan.grid import make_plan, radius_of

    cfg = parse_config(StudyCommand, [f"--config_path={ROOT / 'configs' / 'study' / 'paper.yaml'}"], "study")
    assert cfg.tasks == ["pick-place", "bin-picking", "door-open"] and cfg.n_train_envs == [5, 20, 50, 100]
    assert len(cfg.seeds) == 5 and cfg.train.epochs == 100 and cfg.eval.n_test_envs == 100
    assert cfg.collect.demos_for("pick-place") == 2000 and cfg.collect.demos_for("door-open") == 1000
    assert set(cfg.factors) == set(PAPER_STUDY_FACTORS) and len(cfg.pair_conditions()) == 21
    assert cfg.radius_factors == ["camera_pos", "table_pos"]
    widths = {s.meta["widths"] for s in make_plan(cfg).of_kind("collect")}
    assert widths == {"default", "camera_pos=medium", "camera_pos=wide", "table_pos=medium", "table_pos=wide"}
    assert radius_of("camera_pos=wide", "camera_pos") == 0.075 and radius_of("default", "table_pos") == 0.025


def test_findings_cost_counts_each_shared_step_once_in_run_findings_order():
    """scripts/findings_cost.py (docs/findings.md's cost of the whole set) reads run_findings.sh's list, picks one
    config per finding, and charges a config only for the steps no config before it has: F1 after F3 reuses
    F3's seed-0 datasets, trainings and single-factor evaluations, so it costs less than alone."""
    import importlib.util  # a script, loaded by path

    spec = importlib.util.spec_from_file_location("findings_cost", ROOT / "scripts" / "findings_cost.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    names = script.findings_order()
    assert sorted(names) == sorted(Path(name).stem for name in FINDINGS)
    firsts = script.first_of_each_finding(names)
    assert [name.split("_")[0] for name in sorted(firsts)] == [f"f{i}" for i in range(1, 10)]
    assert "f8_out_of_domain" in firsts and "f8_out_of_domain_language" not in firsts
    (_, f3_alone, f3_new, f3_total, f3_hours), (_, f1_alone, f1_new, f1_total, f1_hours) = script.costs(
        ["f3_pairs", "f1_ordering"]
    )
    assert f3_new == f3_total and f3_hours == pytest.approx(f3_alone)
    assert 0 < f1_new < f1_total and 0 < f1_hours < f1_alone
