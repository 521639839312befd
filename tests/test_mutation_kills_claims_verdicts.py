"""How a claim's comparison is decided (study/results/claims.py), where mutation testing found the suite silent
(docs/testing.md): the two p-values at their edges (exactly half the bootstrap defined, replicates exactly at the
threshold, one or two seeds, no spread between seeds), the episodes and seeds that would resolve an effect at the
edges of their searches, the decision interval at two seeds, a headroom exactly at the smallest resolvable
effect, and, through ``decide``: Holm's order (ties of the p-value broken by the bootstrap's p-value, then by
label), Holm's stop, the claims that share a comparison (one test) and those that do not, the claim's task and the
labels of several factors, and rows whose counts or train rates are unknown (decided without a warning).

The helpers' own tests call them with a bare ``Comparison`` (only the fields the helper reads) and numbers chosen
so that the expected value is exact; each edge they pin is one ``decide`` reaches."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import test_mutation_kills_claims
from scipy import stats
from test_mutation_kills_claims import (
    ALL,
    CAMERA,
    LIGHT,
    NONE,
    PICK_CAMERA,
    PICK_LIGHT,
    PICK_TRAIN,
    TRAIN,
    _first_seed,
    claim,
    rows_of,
)

from lerobot_factorworld.stats import decision
from lerobot_factorworld.study.results import claims
from lerobot_factorworld.study.results.claims import AGREES, CAPPED, NOT_RESOLVED, Comparison, decide

cfg = test_mutation_kills_claims.cfg  # the fixture: a study of two tasks and two methods (bc first)
T_975_DF1 = float(stats.t.ppf(0.975, df=1))  # 12.706: the t quantile of a 95% interval over two seeds


def bare(threshold=0.0, sign=+1, headroom=math.nan, resolvable=None) -> Comparison:
    """A comparison with only what the deciding helpers read (no table, no statistic)."""
    return Comparison("c", None, None, threshold, sign, headroom, resolvable)


# --- the bootstrap's p-value -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("reps", "expected"),
    [
        # threshold 0.5: x = reps - 0.5 = 0, 0.5, 1, 2, 3, 4, 5: one <= 0, seven >= 0: 2 * (1 + 1) / (7 + 1)
        ([0.5, 1.0, 1.5, 2.5, 3.5, 4.5, 5.5], 0.5),
        # x = -5, -4, -3, -2, -1, 0, 0.5: six <= 0, two >= 0 (0 and 0.5): 2 * (2 + 1) / (7 + 1)
        ([-4.5, -3.5, -2.5, -1.5, -0.5, 0.5, 1.0], 0.75),
    ],
    ids=["one replicate at the threshold, below it none", "one at it, one above it"],
)
def test_the_bootstrap_p_value_counts_replicates_at_the_threshold_on_both_sides(reps, expected):
    assert decision.bootstrap_p_value(np.array(reps), 0.5) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("reps", "expected"),
    [
        ([np.nan, np.inf, np.nan, 1.5], 1.0),  # one of four defined (inf is not): undefined too often
        ([np.nan, np.nan, np.nan, 1.5, 2.5], 1.0),  # two of five: fewer than half
        ([np.nan, np.nan, 1.5, 2.5], 2 / 3),  # exactly half is enough: none <= 0.5, both >= 0.5: 2 * 1 / 3
    ],
    ids=["a quarter defined", "two fifths defined", "half defined"],
)
def test_the_bootstrap_p_value_needs_half_the_replicates_defined(reps, expected):
    assert decision.bootstrap_p_value(np.array(reps), 0.5) == pytest.approx(expected, abs=1e-12)


# --- the p-value: the larger of the bootstrap's and the t-test's --------------------------------------------------


def test_the_p_value_is_the_t_tests_from_two_seeds_on():
    """Two seeds 0.1 and 0.3 against 0.1: mean 0.2, sd 0.1 * sqrt(2), standard error 0.1, t = 1 with one degree
    of freedom (a Cauchy: P(T > 1) = 1/4), so p_t = 0.5 > the bootstrap's 0.01. One seed: no t-test, p = 1."""
    c = bare(threshold=0.1)
    assert decision.decision_p_value(0.01, np.array([0.1, 0.3]), c.threshold) == pytest.approx(0.5, abs=1e-12)
    assert decision.decision_p_value(0.01, np.array([0.3]), c.threshold) == 1.0


@pytest.mark.parametrize(
    ("per_seed", "expected"),
    [
        ([0.3, 0.3], 0.01),  # mean 0.3 != 0.1 and no spread: p_t = 0, the bootstrap's p-value decides
        ([1.1, 1.1], 0.01),  # the same at a difference of exactly 1 from the threshold
        ([0.1, 0.1], 1.0),  # exactly at the threshold on every seed: p_t = 1
    ],
    ids=["off the threshold", "1 off the threshold", "at the threshold"],
)
def test_seeds_without_spread_give_a_t_test_p_value_of_0_off_the_threshold_and_1_on_it(per_seed, expected):
    assert decision.decision_p_value(0.01, np.array(per_seed), 0.1) == pytest.approx(expected, abs=1e-12)


# --- the decision interval, the verdict ---------------------------------------------------------------------------


def test_two_seeds_give_a_decision_interval():
    """Two seeds 0.1 and 0.3: the t-interval 0.2 +- t(0.975; 1) * 0.1 (sd 0.1 * sqrt(2) over sqrt(2)) = 0.2 +-
    1.2706, wider than the bootstrap's 0.15 .. 0.25 on both sides."""
    reps = np.array([0.15, 0.2, 0.25])
    hull = decision.decision_interval(0.2, reps, np.array([0.1, 0.3]), 0.95)
    assert (hull.point, hull.level, hull.method) == (0.2, 0.95, decision.HULL)
    assert (hull.low, hull.high) == pytest.approx((0.2 - T_975_DF1 * 0.1, 0.2 + T_975_DF1 * 0.1), abs=1e-12)


def test_a_headroom_exactly_at_the_smallest_resolvable_effect_is_not_capped():
    """Capped means the statistic cannot move the paper's way by as much as the design resolves: a headroom of
    0.1 against a smallest effect of 0.1 can, so an interval across the threshold is not resolved; 0.05 is capped."""
    assert claims._verdict(bare(headroom=0.1), -0.2, 0.3, 0.1, counts_known=True) == NOT_RESOLVED
    assert claims._verdict(bare(headroom=0.05), -0.2, 0.3, 0.1, counts_known=True) == CAPPED


def test_no_resolvable_effect_is_capped_only_when_the_episode_counts_are_known():
    """A NaN smallest effect means "nothing to resolve" (capped) when the counts are known, but "no power
    computed" when they are not: then an interval across the threshold stays not resolved."""
    assert claims._verdict(bare(headroom=0.5), -0.2, 0.3, math.nan, counts_known=True) == CAPPED
    assert claims._verdict(bare(headroom=0.5), -0.2, 0.3, math.nan, counts_known=False) == NOT_RESOLVED


# --- what would resolve the observed effect ---------------------------------------------------------------------


def test_the_episodes_needed_start_at_one_and_stop_where_the_resolution_reaches_the_effect():
    """A design resolving z / e at e episodes per cell (z = 2): an effect of 2 is resolved by one episode; one of
    0.5 by four (2 / 4 = 0.5 exactly: reaching the effect is enough), not three (0.67)."""
    c = bare(resolvable=lambda e, z: z / e)
    assert decision.episodes_needed(c.resolvable, 2.0, 2.0) == 1.0
    assert decision.episodes_needed(c.resolvable, 0.5, 2.0) == 4.0


def test_the_seeds_needed_from_two_seeds_on():
    """Two seeds 1 and 3 (sd sqrt(2)): at two seeds the half-width is t(0.975; 1) * sqrt(2) / sqrt(2) = 12.706 < 13.
    Three seeds without spread: three (the seeds there are)."""
    assert decision.seeds_needed(np.array([1.0, 3.0]), 13.0, 0.95) == 2.0
    assert decision.seeds_needed(np.array([0.25, 0.25, 0.25]), 0.25, 0.95) == 3.0


def test_the_seeds_needed_search_stops_at_1000_seeds_and_wants_the_half_width_below_the_effect():
    """Seeds 1, 2, 3 (sd exactly 1) and an effect exactly the half-width at 1000 seeds, t(0.975; 999) / sqrt(1000) =
    0.06205: no count up to 1000 gives a half-width strictly below it (1000 gives it exactly), so NaN."""
    effect = stats.t.ppf(1 - (1 - 0.95) / 2, df=999) * 1.0 / math.sqrt(1000)  # as decision computes it
    assert math.isnan(decision.seeds_needed(np.array([1.0, 2.0, 3.0]), effect, 0.95))


def test_one_seed_has_no_seeds_needed_and_warns_nothing():
    """One seed has no spread between seeds (its sd of ddof 1 would warn): NaN, without a warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert math.isnan(decision.seeds_needed(np.array([0.3]), 0.1, 0.95))


def test_a_difference_of_exactly_0_needs_neither_episodes_nor_seeds(cfg):
    """camera_pos and light fail every episode: the difference of their gaps (P_T - 0 each, on the same train cells)
    is exactly 0 on every seed and in every replicate, and the success rate of the cells compared is 0, where the
    power code resolves any effect with one episode (z * sqrt(2 * 0 * 1 / n) = 0). An effect of 0 has nothing to
    resolve: the episodes and seeds needed are NaN (not 1 episode, nor the 5 seeds there are); the t-test's p is
    1, and the verdict capped (camera_pos's P_T minus light's gap leaves no headroom)."""
    rows = rows_of({"train": TRAIN, "camera_pos": NONE, "light": NONE})
    ((d,),) = (v.comparisons for v in decide([claim("gap_exceeds", factors=["camera_pos", "light"])], cfg, rows))
    assert (d.point, d.smallest, d.p_value, d.seeds, d.verdict) == (0.0, 0.0, 1.0, 5, CAPPED)
    assert math.isnan(d.episodes_needed) and math.isnan(d.seeds_needed)


# --- Holm through decide: its order and its stop ------------------------------------------------------------------


def test_holms_order_breaks_ties_of_the_p_value_by_the_bootstraps_then_by_label(cfg):
    """One seed, so every p-value is 1 (no t-test) and Holm orders by the bootstrap's p-value: light's gap of 0.7
    (P_T 1, light 0.3 on 100 episodes: every replicate > 0, p = 2 / (B + 1)) comes first, at 1 - 0.05 / 3; then
    camera_pos and table_pos, whose gaps are exactly 0 in every replicate (rates of 1: p = 1, a tie), by label:
    camera_pos at 1 - 0.05 / 2, table_pos at 0.95. The claims are listed in neither order."""
    rows = _first_seed(rows_of({"train": ALL, "camera_pos": ALL, "table_pos": ALL, "light": [0.3] * 5}))
    found = decide([claim("gap_opens", factors=[f]) for f in ("table_pos", "light", "camera_pos")], cfg, rows)
    by_label = {d.label: d for v in found for d in v.comparisons}
    assert {label: d.p_value for label, d in by_label.items()} == {"table_pos": 1.0, "light": 1.0, "camera_pos": 1.0}
    levels = {label: d.level for label, d in by_label.items()}
    assert levels == pytest.approx({"light": 1 - 0.05 / 3, "camera_pos": 1 - 0.05 / 2, "table_pos": 0.95})


HOLM_CAMERA = [0.87, 0.77, 0.67, 0.57, 0.47]  # gaps 0.03 .. 0.43 by 0.1: mean 0.23
HOLM_LIGHT = [0.89, 0.79, 0.69, 0.59, 0.49]  # gaps 0.01 .. 0.41 by 0.1: mean 0.21


def test_holm_resolves_nothing_after_the_first_comparison_it_leaves_unresolved(cfg):
    """Two gaps whose seeds spread alike (sd 0.1 * sqrt(2.5), standard error 0.1 / sqrt(2) = 0.0707; 1000 episodes
    per cell, so the t-test decides): camera_pos's mean 0.23 (t = 3.25, p = 0.031) ranks first, at 1 - 0.05 / 2,
    where its t-interval 0.23 +- t(0.9875; 4) * 0.0707 = 0.23 +- 0.247 reaches below 0: not resolved. light's
    mean 0.21 (t = 2.97, p = 0.041), at 0.95, has the interval 0.21 +- t(0.975; 4) * 0.0707 = 0.0137 .. 0.406,
    above 0, and agrees when decided alone; decided after camera_pos, Holm stops before it: not resolved."""
    rows = rows_of({"train": [0.9] * 5, "camera_pos": HOLM_CAMERA, "light": HOLM_LIGHT}, episodes=1000)
    se = 0.1 / math.sqrt(2)
    light_claim = claim("gap_opens", factors=["light"])
    (light,), (camera,) = (v.comparisons for v in decide([light_claim, claim("gap_opens", factors=["camera_pos"])],
                                                          cfg, rows))  # fmt: skip
    assert (camera.level, camera.verdict) == (pytest.approx(1 - 0.05 / 2), NOT_RESOLVED)
    assert camera.p_value == pytest.approx(2 * stats.t.sf(0.23 / se, df=4), abs=1e-9)
    assert camera.low == pytest.approx(0.23 - stats.t.ppf(0.9875, df=4) * se, abs=1e-9) and camera.low < 0
    assert (light.level, light.verdict) == (pytest.approx(0.95), NOT_RESOLVED)
    assert light.p_value == pytest.approx(2 * stats.t.sf(0.21 / se, df=4), abs=1e-9)
    assert light.low == pytest.approx(0.21 - stats.t.ppf(0.975, df=4) * se, abs=1e-9) and light.low > 0
    ((alone,),) = (v.comparisons for v in decide([light_claim], cfg, rows))
    assert (alone.level, alone.low, alone.verdict) == (pytest.approx(0.95), light.low, AGREES)


# --- which comparisons decide sees: shared ones once, each claim's own task, labels ----------------------------


def test_a_claim_naming_the_default_method_shares_its_comparison_and_another_methods_does_not(cfg):
    """camera_pos's gap for bc named (bc is the study's first method), for bc by default, and for bc_shift: two
    comparisons, not one nor three. bc's gap 0.896 - 0.48 = 0.416 in both of its claims, at one Holm level;
    bc_shift's 0.896 - 0.734 = 0.162; the two levels 1 - 0.05 / 2 and 0.95."""
    shift = [0.7, 0.75, 0.8, 0.7, 0.72]  # mean 0.734
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA}) + rows_of({"train": TRAIN, "camera_pos": shift}, "bc_shift")
    found = decide([claim("gap_opens", factors=["camera_pos"], method=m) for m in ("bc", None, "bc_shift")], cfg, rows)
    (named,), (default,), (other,) = (v.comparisons for v in found)
    assert (named.point, default.point, other.point) == pytest.approx((0.416, 0.416, 0.162), abs=1e-12)
    assert named.level == default.level
    assert sorted((named.level, other.level)) == pytest.approx([0.95, 1 - 0.05 / 2])


SHIFT_CAMERA, SHIFT_LIGHT = [0.7, 0.75, 0.8, 0.7, 0.72], [0.85, 0.8, 0.9, 0.85, 0.85]  # means 0.734 and 0.85
TASK_CASES = {  # claim, label, point on door-open; bc's door-open gaps: camera_pos 0.416, light 0.116
    "gap_opens": (
        claim("gap_opens", factors=["camera_pos", "light"], task="door-open"),
        "camera_pos + light",
        (0.416 + 0.116) / 2,
    ),
    "gap_exceeds": (claim("gap_exceeds", factors=["camera_pos", "light"], task="door-open"), "camera_pos - light", 0.3),
    "ordering": (claim("ordering", tiers=[["camera_pos"], ["light"]], task="door-open"), "camera_pos - light", 0.3),
    # bc_shift's gaps 0.896 - 0.734 = 0.162 and 0.896 - 0.85 = 0.046: (0.162 + 0.046) / 2 - 0.266 = -0.162
    "method_shrinks": (
        claim("method_shrinks", factors=["camera_pos", "light"], method="bc_shift", baseline="bc", task="door-open"),
        "bc_shift - bc on camera_pos + light",
        (0.162 + 0.046) / 2 - 0.266,
    ),
}


@pytest.mark.parametrize("kind", list(TASK_CASES))
def test_a_claim_on_one_task_leaves_out_the_other_tasks_rows_and_names_its_factors(cfg, kind):
    """Both methods on pick-place (placed first; gaps there 0.84 - 0.38 = 0.46 and 0.84 - 0.74 = 0.10, which would
    move every point) and on door-open: a claim on door-open compares door-open's cells alone, and its label joins
    several factors with " + "."""
    pick = {"train": PICK_TRAIN, "camera_pos": PICK_CAMERA, "light": PICK_LIGHT}
    rows = rows_of(pick, task="pick-place") + rows_of(pick, method="bc_shift", task="pick-place")
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT})
    rows += rows_of({"train": TRAIN, "camera_pos": SHIFT_CAMERA, "light": SHIFT_LIGHT}, method="bc_shift")
    c, label, point = TASK_CASES[kind]
    ((d,),) = (v.comparisons for v in decide([c], cfg, rows))
    assert (d.label, d.point) == (label, pytest.approx(point, abs=1e-12))


# --- rows whose counts or train rates are unknown: decided without a warning ---------------------------------------


def _without_counts(rows: list[dict]) -> list[dict]:
    return [{**r, "episodes": 0, "successes": None} for r in rows]


def _without_train_rates(rows: list[dict]) -> list[dict]:
    return [{**r, "success_rate": None, "episodes": None, "successes": None} if r["condition"] == "train" else r
            for r in rows]  # fmt: skip


@pytest.mark.parametrize(
    ("unknown", "headroom_nan"),
    [(_without_counts, False), (_without_train_rates, True)],
    ids=["episode counts", "train success rates"],
)
def test_rows_whose_counts_or_train_rates_are_unknown_are_decided_without_a_warning(cfg, unknown, headroom_nan):
    """Without episode counts no cell has a count to take the median of: no smallest resolvable effect (NaN). With
    train rows that carry no success rate (their gaps still in the shifted rows), the train cells compared have no
    pooled rate: no headroom, nor a smallest effect at that P_T (NaN). Neither takes a mean or median of nothing
    (which warns)."""
    rows = unknown(rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT}))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = decide([claim("gap_opens", factors=["camera_pos"])], cfg, rows)
    ((d,),) = (v.comparisons for v in found)
    assert math.isnan(d.smallest) and math.isnan(d.headroom) == headroom_nan
