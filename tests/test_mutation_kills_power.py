"""The power of a plan (stats/power.py, and study/plan/power.py's lines) where mutation testing found the suite
silent (docs/testing.md): a cell's resolvable gap against an oracle on explicit paired episodes (other sizes,
other z, the edges of both searches), the z of the pair metric, a sweep of one radius, ``--dry-run``'s power
lines word for word, and both searches' boundaries: a lower bound of exactly 0 (z = 0) does not resolve, a half-width equal to the gap does."""

from __future__ import annotations

import math

import pytest

from lerobot_factorworld.stats import power, proportions
from lerobot_factorworld.study.plan import power as plan_power
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.eval_settings import EvalSettings


def _by_episodes(n: int, p_train: float, z: float = proportions.Z95) -> float:
    """The smallest share of train-only successes (no episode succeeds only when shifted) whose Newcombe interval,
    computed from explicit paired episode outcomes, excludes 0."""
    k = round(p_train * n)
    train = [True] * k + [False] * (n - k)
    for b in range(k + 1):
        if proportions.paired_gap(train, [True] * (k - b) + [False] * (n - k + b), z)[1] > 0:
            return b / n
    return math.nan


@pytest.mark.parametrize(("n", "p_train"), [(3, 1.0), (10, 0.5), (20, 0.8), (20, 0.95), (50, 0.3), (64, 0.75)])
def test_a_cells_resolvable_gap_is_the_first_whole_episode_count_that_resolves(n, p_train):
    expected = _by_episodes(n, p_train)
    assert not math.isnan(expected) and power.cell_resolvable_gap(n, p_train) == expected
    if (n, p_train) == (3, 1.0):
        assert expected == 1.0  # all three train successes lost: only the search's last count resolves


def test_a_cells_resolvable_gap_uses_the_z_it_is_given():
    # at z = 1 (a 68% interval) 2 train-only successes of 20 resolve; at 95%, 5 (test_intervals.py)
    assert power.cell_resolvable_gap(20, 0.8, z=1.0) == _by_episodes(20, 0.8, z=1.0) == 0.1
    assert power.cell_resolvable_gap(20, 0.8) == 0.25


@pytest.mark.parametrize(("n", "p_train"), [(6, 0.5), (20, 0.8), (100, 0.5)])
def test_independent_outcomes_resolve_where_the_expected_tables_interval_first_excludes_0(n, p_train):
    d = power.cell_resolvable_gap(n, p_train, paired=False)
    step = p_train / power.GRID

    def lower(gap: float) -> float:  # Newcombe's lower bound on the expected table at P_F = P_T - gap
        p_f = p_train - gap
        q_t, q_f = 1 - p_train, 1 - p_f
        return proportions.newcombe_paired(n * p_train * p_f, n * p_train * q_f, n * q_t * p_f, n * q_t * q_f)[1]

    assert lower(d) > 0 and lower(d - step) <= 0
    if (n, p_train) == (6, 0.5):
        assert d == 0.5  # only P_F = 0 resolves: the search's last point


def test_independent_outcomes_use_the_z_they_are_given():
    d = power.cell_resolvable_gap(20, 0.8, paired=False, z=1.0)
    lower = [
        proportions.newcombe_paired(16 * q, 16 * (1 - q), 4 * q, 4 * (1 - q), 1.0)[1]
        for q in (0.8 - d, 0.8 - d + 0.0004)
    ]
    assert lower[0] > 0 >= lower[1] and d < power.cell_resolvable_gap(20, 0.8, paired=False)


@pytest.mark.parametrize(("pairs", "p_train"), [(48, 0.8), (100, 0.2), (240, 0.95), (48, 1.0), (4, 0.49)])
def test_a_mean_gap_resolves_where_the_normal_interval_first_excludes_it(pairs, p_train):
    d = power.mean_resolvable_gap(pairs, p_train)
    step = p_train / power.GRID

    def half_width(gap: float) -> float:  # independent outcomes at P_F = P_T - gap
        p_f = p_train - gap
        return proportions.Z95 * math.sqrt((p_train * (1 - p_train) + p_f * (1 - p_f)) / pairs)

    assert 0 < d <= p_train and half_width(d) <= d and half_width(d - step) > d - step
    if (pairs, p_train) == (4, 0.49):
        assert d == 0.49  # only P_F = 0 resolves: the search's last point


def test_a_mean_gap_search_spans_its_grid_and_stops_at_p_train():
    assert power.mean_resolvable_gap(10**8, 0.5) == 0.5 / power.GRID  # a huge design: the grid's first step
    assert math.isnan(power.mean_resolvable_gap(6, 0.39))  # even P_F = 0 is not resolved: no gap beyond P_T


def test_the_pair_metric_and_the_slope_use_their_z_and_refuse_one_radius():
    assert power.pair_metric_resolvable(100, 0.5, z=1.0) == pytest.approx(math.sqrt(2 * 0.25 / 100) / 0.5)
    assert power.slope_resolvable(100, [0.025, 0.075], 0.5, z=1.0) == pytest.approx(math.sqrt(0.5 / 100 / 0.00125))
    assert math.isnan(power.slope_resolvable(100, [0.05, 0.05], 0.5))  # one radius: no slope


def test_dry_run_power_lines_word_for_word():
    cfg = StudyConfig(
        tasks=["door-open", "pick-place"],
        factors=["camera_pos", "light"],
        pairs=["camera_pos+light"],
        seeds=[0, 1, 2],
        n_train_envs=[1, 2],
        eval=EvalSettings(n_test_envs=2, episodes=4),
        radius_factors=["camera_pos"],
        radius_widths=["narrow", "wide"],
    )
    # 4 episodes per cell: no count of 1 (P = 0.25) or 2 (P = 0.5) train successes resolves; 2 tasks x 2 N x
    # 3 seeds = 12 cells of 4 episodes: two factors apart at P = 0.5, 1.96 sqrt(2 x 0.25 / 48) = 0.200, the
    # pair metric that / 0.5; the slope over 0.025 and 0.075 m (Sxx = 0.00125) per 0.025 m:
    # 1.96 sqrt(0.5 / 48 / 0.00125) x 0.025 = 0.141
    assert plan_power.power_lines(cfg, planned=(0.25, 0.5, 0.9)) == [
        "  power: smallest effect whose 95% interval excludes 0, at planned P_T (pairs: P_min) below (4 paired "
        "episodes per cell, 3 seed(s); episode noise only, so lower bounds; summaries assume independent outcomes; "
        "methods in study/plan/power.py):",
        "                                                                P=0.25   P=0.5    P=0.9  ",
        "    gap, one cell (Newcombe; no reversals)                         n/a     n/a   0.750",
        "    gap, one cell (Newcombe; independent outcomes)                 n/a     n/a   0.662",
        "    factor's mean gap, 12 cell(s)                                0.149   0.193   0.149",
        "    factor's gap at one N, 6 cell(s)                             0.196   0.263   0.222",
        "    two factors' mean gaps apart (ordering), 12 cell(s)          0.173   0.200   0.120",
        "    pair metric |.|, 12 cell(s), at P_min = P (paper: ±0.06)     0.693   0.400   0.133",
        "    radius slope, gap per 0.025 m over 2 radii                   0.122   0.141   0.085",
    ]
    assert power.cell_resolvable_gap(4, 0.9) == _by_episodes(4, 0.9) == 0.75


def test_a_zero_width_interval_resolves_the_first_gap_above_0_and_not_a_gap_of_0():
    # z = 0: Wilson's interval is the point P itself, so Newcombe's lower bound is the gap itself: a gap of exactly
    # 0 (P_F = P_T) has the lower bound 0, which does not exclude 0 ("> 0", not ">= 0")
    assert proportions.newcombe_paired(16, 0, 0, 4, 0.0) == (0.0, 0.0, 0.0)  # no reversals, 16 of 20 train successes
    assert proportions.newcombe_paired(5, 5, 5, 5, 0.0) == (0.0, 0.0, 0.0)  # independent at P_T = P_F = 0.5, 20 pairs
    # so the first gap above 0 resolves: 1 train-only success of 20 (0.05); the grid's first step 0.5 / 2000
    assert power.cell_resolvable_gap(20, 0.8, z=0.0) == 0.05
    assert power.cell_resolvable_gap(20, 0.5, paired=False, z=0.0) == 0.5 / power.GRID == 0.00025


def test_a_mean_gap_whose_half_width_equals_it_resolves():
    # the rule is z sqrt(Var / pairs) <= d (module docstring): 4 pairs at P_T = 0.5 and z = 2; any P_F > 0 adds
    # P_F (1 - P_F) to Var = 0.25 while d < 0.5, so only P_F = 0 can resolve, where the half-width
    # 2 x sqrt((0.25 + 0) / 4) = 0.5 is the gap 0.5 exactly (every number here is exact in binary)
    assert power.mean_resolvable_gap(4, 0.5, z=2.0) == 0.5


def test_no_mean_gap_resolves_at_a_training_success_of_0():
    """At P_T = 0 every candidate gap is 0 and its interval [0, 0] does not exclude 0: NaN, as for one cell
    (a 0.0 here made the claims table report one episode per cell as enough to resolve any effect)."""
    assert math.isnan(power.mean_resolvable_gap(100, 0.0))
    assert math.isnan(power.cell_resolvable_gap(100, 0.0))


def _decided_by_oracle(rule, k: int, p_train: float) -> tuple[float, int]:
    """The smallest share of train-only successes, spread evenly over the seeds, that ``rule`` decides within its
    budget, one candidate at a time through ``sequential.decide`` (not the vectorised search)."""
    from lerobot_factorworld.study.sequential import decide

    n = rule.max_episodes
    for b in range(round(p_train * n) + 1):
        at = {math.floor(i * n / b) for i in range(b)} if b else set()
        train = [i in at for i in range(n)]
        shifted = {f"c{j}": [False] * n for j in range(k)}  # k conditions to correct for, all alike
        stop = decide(train, shifted, rule)["c0"]
        if stop.reason == "decided":
            return b / n, stop.episodes
    return math.nan, 0


@pytest.mark.parametrize(
    ("budget", "k", "p_train"),
    [(10, 2, 0.8), (10, 2, 0.7), (10, 2, 0.5), (40, 3, 0.5), (60, 7, 0.95)],  # 0.7: 8 of 10 would, 7 do not
)
def test_auto_power_is_the_first_evenly_spread_count_the_rule_decides(budget, k, p_train):
    from lerobot_factorworld.study.sequential import StopRule

    rule = StopRule(block=10, max_episodes=budget, tolerance=0.1, confidence=0.95)
    found, expected = plan_power.auto_decided_within(rule, k, p_train), _decided_by_oracle(rule, k, p_train)
    assert found[1] == expected[1] and (found[0] == expected[0] or math.isnan(found[0]) and math.isnan(expected[0]))


def test_dry_run_power_lines_under_auto_word_for_word():
    cfg = StudyConfig(factors=["camera_pos", "light"], methods=[{"name": "bc", "policy": {"type": "bc"}}])
    cfg.eval = EvalSettings(n_test_envs=10, episodes="auto", block=10, max_episodes=40, confidence=0.9)
    # 2 conditions at 90%: every pair favouring train decides at the first look; 7 train-only successes in 40
    # decide within the budget, at every planned P_T (each has at least 7 train successes to give)
    lines = plan_power.power_lines(cfg, planned=(0.25, 0.5, 0.9))
    assert lines[:2] == [
        "  power under eval.episodes=auto (90% anytime-valid, Bonferroni over 2 condition(s), blocks of 10, budget "
        "40; methods in study/plan/power.py): the earliest decision at 10 episodes, every pair favouring train; the "
        "smallest gap decided within the budget, at planned P_T (no reversals):",
        "                                                                P=0.25   P=0.5    P=0.9  ",
    ]
    gaps = [plan_power.auto_decided_within(cfg.eval.stop_rule(), 2, p)[0] for p in (0.25, 0.5, 0.9)]
    assert lines[2:] == ["    gap, one condition (anytime-valid; no reversals)" + " " * 10 + "   0.175" * 3]
    assert gaps == [0.175] * 3 and "Newcombe" not in "\n".join(lines)
    # 7 conditions at 95% in one block of 10: nothing can be decided, not even every pair favouring train
    cfg.factors = [
        "camera_pos",
        "light",
        "table_pos",
        "table_texture",
        "floor_texture",
        "object_texture",
        "distractors",
    ]
    cfg.eval = EvalSettings(n_test_envs=10, episodes="auto", block=10, max_episodes=10)
    lines = plan_power.power_lines(cfg, planned=(0.5,))
    assert "Bonferroni over 7 condition(s)" in lines[0] and "the earliest decision never, within the budget" in lines[0]
    assert lines[2].endswith("     n/a")
    cfg.factors = ["light"]  # one condition: nothing to correct for
    assert "Bonferroni over 1 condition(s)" in plan_power.power_lines(cfg, planned=(0.5,))[0]
