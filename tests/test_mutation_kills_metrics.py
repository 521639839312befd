"""The study's numbers (stats/: proportions, summaries, ranks, bootstrap) where mutation testing found the suite
silent (docs/testing.md), each against
values computed by hand: a gap over one episode pair and over none, gaps of +-1 (their intervals
clamped to [-1, 1] where the formula rounds past), Wilson intervals clamped to [0, 1] likewise, Newcombe's
continuity-corrected phi, the standard error of two seeds, ranks tied at the end, slopes of undefined rows without
a warning, average ranks, Spearman's rho of a constant ranking, pooled rates of unknown episode counts, weighted
means of undefined values, the share of defined replicates an interval needs, and the seed bootstrap's shapes,
its cells of one episode and its rates rounded just past 0 or 1."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from lerobot_factorworld.stats import bootstrap, proportions, ranks, summaries


def test_a_gap_over_one_episode_pair_and_over_none():
    # one pair, train succeeds, shifted fails: P_T = 1 (Wilson 0.2065..1), P_F = 0 (Wilson 0..0.7935), an empty
    # margin so phi = 0: lower = 1 - sqrt(0.7935^2 + 0.7935^2) = -0.1222, upper = 1 + 0
    assert proportions.paired_gap([True], [False]) == pytest.approx((1.0, -0.1222, 1.0), abs=1e-4)
    assert all(math.isnan(v) for v in proportions.paired_gap([], []))


def test_gaps_of_plus_and_minus_one_end_their_interval_at_the_unit_interval():
    # 10 pairs, every episode fails in train and succeeds shifted: the gap is -1 and so is the interval's low end
    # (both Wilson intervals reach their edge); the high end -1 + sqrt(0.2775^2 + 0.2775^2) = -0.6075
    assert proportions.paired_gap([False] * 10, [True] * 10) == pytest.approx((-1.0, -1.0, -0.6075), abs=1e-4)
    assert proportions.paired_gap([True] * 10, [False] * 10) == pytest.approx((1.0, 0.6075, 1.0), abs=1e-4)


def test_newcombes_phi_is_reduced_by_n_over_2_towards_zero_when_positive():
    # (ad - bc) = 1 - 0 = 1, n / 2 = 1: reduced to 0; (9 - 1) = 8 - 4 = 4 over sqrt(4^4) = 16; negative: kept
    assert proportions._phi_corrected(1, 0, 0, 1) == 0.0
    assert proportions._phi_corrected(3, 1, 1, 3) == 0.25
    assert proportions._phi_corrected(1, 3, 3, 1) == -0.5
    assert proportions._phi_corrected(2, 3, 0, 0) == 0.0  # an empty margin
    # so two pairs, one succeeding in both conditions and one in neither: gap 0 with Wilson(1, 2) = 0.5 -+ 0.4055
    # on both sides and phi = 0: 0 -+ sqrt(2) x 0.4055 (phi = 1 would give the interval [0, 0])
    assert proportions.paired_gap([True, False], [True, False]) == pytest.approx((0.0, -0.5735, 0.5735), abs=1e-4)


def test_two_seeds_have_a_standard_error():
    # mean 0.2, sample sd sqrt(0.01 + 0.01) = 0.1414, se 0.1414 / sqrt(2) = 0.1
    assert summaries.mean_se([0.1, 0.3]) == pytest.approx((0.2, 0.1))
    assert summaries.mean_se([0.1, math.nan])[0] == 0.1 and math.isnan(summaries.mean_se([0.1, math.nan])[1])


def test_ties_share_their_average_rank_wherever_they_are():
    assert ranks.rank_hardest_first({"a": 0.3, "b": 0.1, "c": 0.1}) == {"a": 1.0, "b": 2.5, "c": 2.5}
    assert ranks.rank_hardest_first({"a": 0.3, "b": 0.3, "c": 0.1, "d": math.nan}) == {"a": 1.5, "b": 1.5, "c": 3.0}
    assert ranks.rank_hardest_first({"a": 0.2, "b": 0.2, "c": 0.2}) == {"a": 2.0, "b": 2.0, "c": 2.0}


def test_a_slope_of_undefined_points_is_nan_without_a_warning():
    y = np.array([[np.nan, np.nan, np.nan], [0.1, np.nan, np.nan], [0.1, 0.2, 0.4]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's "invalid value" warning would fail here
        slopes = summaries.ols_slope([0.025, 0.05, 0.075], y)
    assert np.isnan(slopes[:2]).all() and slopes[2] == pytest.approx(6.0)


def test_average_ranks_start_at_1_for_the_smallest():
    assert ranks.rerank([0.3, 0.1, 0.2]) == [3.0, 1.0, 2.0]
    assert ranks.rerank([1.0, 3.0, 3.0]) == [1.0, 2.5, 2.5]  # a tie at the end
    assert ranks.rerank([2.0, 2.0, 5.0, 1.0]) == [2.5, 2.5, 4.0, 1.0]  # a tie in the middle


def test_spearman_with_a_constant_ranking_on_either_side_is_nan():
    varied = {"a": 1.0, "b": 2.0, "c": 3.0}
    constant = {"a": 2.0, "b": 2.0, "c": 2.0}
    assert math.isnan(ranks.spearman(constant, varied)) and math.isnan(ranks.spearman(varied, constant))
    assert ranks.spearman(varied, {"a": 3.0, "b": 2.0, "c": 1.0, "d": 4.0}) == -1.0  # shared keys re-ranked


def test_seeds_of_unknown_episode_counts_pool_with_equal_weights():
    # counts unknown (0): (0.5 + 0.2) / 2; one count known (30) and one unknown (weight 1): (0.5 + 0.2 x 30) / 31
    assert summaries.pooled_rates(np.array([[0.5], [0.2]]), np.array([[0], [0]]))[0] == pytest.approx(0.35)
    assert summaries.pooled_rates(np.array([[0.5], [0.2]]), np.array([[0], [30]]))[0] == pytest.approx(6.5 / 31)


def test_a_weighted_mean_leaves_undefined_values_and_their_weights_out():
    x = np.array([[0.5, np.nan, 0.2], [np.nan, np.nan, np.nan]])
    weights = np.array([[10.0, 50.0, 30.0], [1.0, 1.0, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a row with nothing defined is NaN, without numpy's 0 / 0 warning
        mean = summaries.nanmean(x, axis=-1, weights=weights)
    assert mean[0] == pytest.approx((0.5 * 10 + 0.2 * 30) / 40) and np.isnan(mean[1])


def test_an_interval_needs_half_of_its_columns_replicates_defined():
    defined = np.linspace(0.0, 1.0, 9)
    half = np.where(np.arange(9) % 2 == 0, np.nan, defined)  # 4 of 9 defined: no interval
    low, high = bootstrap.percentile_interval(np.stack([defined, half], axis=1))  # 13 of 18 defined overall
    assert (low[0], high[0]) == pytest.approx((0.025, 0.975)) and np.isnan(low[1]) and np.isnan(high[1])
    exactly_half = np.array([0.1, 0.3, 0.2, 0.4, np.nan, np.nan, np.nan, np.nan])
    low, high = bootstrap.percentile_interval(exactly_half)
    assert (low, high) == pytest.approx((0.1075, 0.3925))  # the 2.5th and 97.5th percentiles of 0.1 .. 0.4


def test_the_bootstrap_refuses_other_shapes_and_draws_exactly_n_boot():
    mean = lambda r, n: summaries.nanmean(r, axis=-2)  # noqa: E731
    for rates, episodes in ((np.ones((2, 3)), np.ones((2, 2))), (np.ones(3), np.ones(3))):
        with pytest.raises(ValueError, match=r"rates and episodes must both be \(seeds, cells\), got \("):
            bootstrap.seed_bootstrap(rates, episodes, mean)
    point, reps = bootstrap.seed_bootstrap(np.array([[0.5, 0.3]]), np.array([[1, 10]]), mean, n_boot=250)
    assert reps.shape == (250, 2) and np.allclose(point, [0.5, 0.3])
    # a cell of one episode is resampled too: each replicate's success is 0 or 1, about half of each
    assert set(reps[:, 0]) == {0.0, 1.0} and 0.4 < reps[:, 0].mean() < 0.6


def test_a_wilson_interval_of_more_successes_than_episodes_is_refused_naming_both():
    with pytest.raises(ValueError, match=r"^successes must be in \[0, 10\], got 11$"):
        proportions.wilson_interval(11, 10)


def test_a_wilson_interval_at_0_or_n_successes_ends_exactly_at_0_or_1():
    # 16 of 16: p = 1, so centre + half = (1 + z^2/2n + z^2/2n) / (1 + z^2/n) = 1, which the formula rounds to
    # 1 + 2^-52; the low end is n / (n + z^2) = 16 / (16 + 3.8415) = 0.8064
    low, high = proportions.wilson_interval(16, 16)
    assert high == 1.0 and low == pytest.approx(0.8064, abs=1e-4)
    # 0 of 21: centre - half = 0, rounded to -1.4e-17; the high end is z^2 / (n + z^2) = 3.8415 / 24.8415 = 0.1546
    low, high = proportions.wilson_interval(0, 21)
    assert low == 0.0 and high == pytest.approx(0.1546, abs=1e-4)


def test_a_gap_of_minus_or_plus_one_over_25_pairs_ends_exactly_at_minus_or_plus_one():
    # P_T = 0 (Wilson 0..0.1332: 3.8415 / 28.8415), P_F = 1 (Wilson 0.8668..1), an empty margin so phi = 0: the low
    # end -1 - sqrt((P_T - l_T)^2 + (u_F - P_F)^2) is -1, but Wilson's ends miss by rounding (l_T = 1.4e-17,
    # u_F = 1 - 2^-53), so the formula gives -1 - 2^-52; the high end -1 + sqrt(0.1332^2 + 0.1332^2) = -0.8116
    gap, low, high = proportions.paired_gap([False] * 25, [True] * 25)
    assert (gap, low) == (-1.0, -1.0) and high == pytest.approx(-0.8116, abs=1e-4)
    gap, low, high = proportions.paired_gap([True] * 25, [False] * 25)  # the mirror image
    assert (gap, high) == (1.0, 1.0) and low == pytest.approx(0.8116, abs=1e-4)


def test_rates_rounded_just_past_0_or_1_are_resampled_as_0_and_1():
    # seed 0: counts unknown, its rates 0.4 and 0.7 are kept; seed 1: rates computed as 0.3 - 0.1 - 0.2 = -2.8e-17
    # and 0.1 x 3 / 0.3 = 1 + 2^-52 over 10 and 20 episodes, resampled as Binomial(10, 0) = 0 and Binomial(20, 1) = 20
    # (numpy refuses a probability outside [0, 1]). Per cell the mean over the two seeds drawn: cell 0 is 0.4 (seed 0
    # twice), 0.2 or 0 (seed 1 twice); cell 1 is 0.7, 0.85 or 1. Each extreme is drawn in about 1/4 of the 2000
    # replicates, so the percentile interval is exactly (0, 0.4) and (0.7, 1)
    rates = np.array([[0.4, 0.7], [0.3 - 0.1 - 0.2, 0.1 * 3 / 0.3]])
    episodes = np.array([[0, 0], [10, 20]])
    point, reps = bootstrap.seed_bootstrap(rates, episodes, lambda r, n: r.mean(axis=-2))
    assert point == pytest.approx([0.2, 0.85])
    low, high = bootstrap.percentile_interval(reps)
    assert (low.tolist(), high.tolist()) == ([0.0, 0.7], [0.4, 1.0])
