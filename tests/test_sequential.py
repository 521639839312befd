"""The anytime-valid confidence sequence (stats/confseq.py) and the stopping rule of ``eval.episodes=auto``
(stats/stopping.py, with its settings in study/sequential.py): closed-form limits of the construction, then simulated profiles with known truth, run
through the rule exactly as a profile runs it, whose stopped intervals must cover the truth, and whose
declarations must be false or of the wrong sign, at most at the stated level. A naive rule that peeks at fixed-n
intervals fails the same checks, so they can fail."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lerobot_factorworld.stats.confseq import BET_CAP, BettingCS, candidate_grid, gap_cs, mean_cs
from lerobot_factorworld.stats.stopping import BUDGET, DECIDED, RUNNING, WITHIN_TOLERANCE
from lerobot_factorworld.study.sequential import StopRule, decide, running

SIM_GRID = candidate_grid(201)  # simulations: bounds at 0.01 of a gap (outwards), the production code otherwise


def _reference_capital(xs: list[float], m: float, alpha: float) -> float:
    """The hedged capital max(K+, K-)/2 at ``m`` after ``xs``, written out term by term from the paper."""
    k_plus = k_minus = 1.0
    total = sq = 0.0
    for t, x in enumerate(xs, start=1):
        var = (0.25 + sq) / t
        lam = math.sqrt(2 * math.log(2 / alpha) / (var * t * math.log(1 + t)))
        k_plus *= 1 + min(lam, BET_CAP / m if m > 0 else math.inf) * (x - m)
        k_minus *= 1 - min(lam, BET_CAP / (1 - m) if m < 1 else math.inf) * (x - m)
        total += x
        sq += (x - (0.5 + total) / (t + 1)) ** 2
    return max(k_plus, k_minus) / 2


def test_one_observation_excludes_nothing():
    # closed form: after one observation the capital is at most (1 + c) / 2 < 1 / alpha at every candidate
    for x in (0.0, 0.5, 1.0):
        assert mean_cs([x], 0.05) == (0.0, 1.0)


def test_bounds_match_the_capital_written_out():
    # a candidate is out exactly when the term-by-term capital reaches 1/alpha at some look (running intersection)
    rng = np.random.default_rng(0)
    xs = list(rng.integers(0, 2, 30) * 1.0)
    grid = candidate_grid(101)
    cs = BettingCS(0.05, grid=grid)
    cs.extend(np.array(xs))
    excluded = [any(_reference_capital(xs[:t], m, 0.05) >= 20 for t in range(1, 31)) for m in grid]
    kept = [m for m, out in zip(grid, excluded, strict=True) if not out]
    low, high = cs.bounds()
    assert low == pytest.approx(max(0.0, kept[0] - 0.01)) and high == pytest.approx(min(1.0, kept[-1] + 0.01))


def test_all_successes_close_in_on_one_and_never_leave_it():
    # limits: a run of successes excludes 0.5 after a fixed number of them, the upper bound stays 1, and the
    # lower bound climbs towards 1; failures mirror it
    first_out = next(t for t in range(1, 60) if _reference_capital([1.0] * t, 0.5, 0.05) >= 20)
    cs = BettingCS(0.05)
    lows = []
    for _ in range(400):
        cs.update(1.0)
        lows.append(float(cs.bounds()[0]))
    assert float(cs.bounds()[1]) == 1.0
    assert lows[first_out - 2] <= 0.5 < lows[first_out - 1]  # grid rounding outwards: never sooner
    assert lows == sorted(lows) and lows[-1] > 0.97
    assert mean_cs([0.0] * 400, 0.05) == pytest.approx((0.0, 1 - lows[-1]))  # the mirror image


def test_gap_interval_is_the_mean_interval_of_the_shifted_differences():
    train, shifted = [1, 1, 0, 1] * 10, [0, 1, 0, 1] * 10
    low, high = mean_cs([(t - s + 1) / 2 for t, s in zip(train, shifted, strict=True)], 0.05)
    assert gap_cs(np.array(train), np.array(shifted), 0.05) == pytest.approx((2 * low - 1, 2 * high - 1))


def test_wider_at_a_smaller_alpha():
    xs = np.r_[np.ones(30), np.zeros(10)]
    wide, narrow = mean_cs(xs, 0.005), mean_cs(xs, 0.05)
    assert wide[0] <= narrow[0] and wide[1] >= narrow[1] and wide != narrow


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="in \\[0, 1\\]"):
        mean_cs([1.5], 0.05)
    with pytest.raises(ValueError, match="multiple of eval.block"):
        StopRule(block=10, max_episodes=25, tolerance=0.1)
    with pytest.raises(ValueError, match="tolerance"):
        StopRule(block=10, max_episodes=20, tolerance=1.5)


# --- simulated profiles with known truth ------------------------------------------------------------

P_TRAIN = (0.5, 0.8, 0.95)  # true train success rates of the grid
GAPS = (0.0, 0.0, 0.1, 0.3, -0.05)  # true gaps of the k = 5 shifted conditions (two without a gap)
PROFILES = 700  # per train rate: 2,100 profiles, 10,500 stopped conditions
RULE = StopRule(block=10, max_episodes=100, tolerance=0.1, confidence=0.9)


def _profiles(p_train: float, n: int, rng: np.random.Generator, copula: float = 0.6) -> tuple[np.ndarray, ...]:
    """``n`` profiles of paired, correlated outcomes: each episode seed has one latent difficulty that, with
    probability ``copula``, decides every condition's outcome (as an object start does), else each draws its own."""
    gaps = np.clip(np.array(GAPS), p_train - 1, p_train)
    rates = p_train - gaps
    shared = rng.random((n, 1, RULE.max_episodes))
    own = rng.random((n, len(GAPS) + 1, RULE.max_episodes))
    use = rng.random((n, len(GAPS) + 1, RULE.max_episodes)) < copula
    u = np.where(use, shared, own)
    train = (u[:, 0] < p_train).astype(float)
    shifted = (u[:, 1:] < rates[None, :, None]).astype(float)
    return train, shifted, gaps


def _simulate(stop_fn) -> dict[str, float]:
    rng = np.random.default_rng(58)
    missed = families_missed = false = declared_nonzero = wrong_sign = nulls = decided = 0
    total = 0
    for p_train in P_TRAIN:
        train, shifted, gaps = _profiles(p_train, PROFILES, rng)
        stops = stop_fn(train, shifted)
        assert not (stops.reason == RUNNING).any()  # the budget ends every condition
        out = (stops.low > gaps) | (stops.high < gaps)
        missed += out.sum()
        families_missed += out.any(axis=1).sum()
        is_null = gaps == 0
        declared = stops.reason == DECIDED
        false += declared[:, is_null].sum()
        nulls += is_null.sum() * PROFILES
        sign = np.sign(stops.low + stops.high)
        wrong_sign += (declared[:, ~is_null] & (sign[:, ~is_null] != np.sign(gaps[~is_null]))).sum()
        declared_nonzero += declared[:, ~is_null].sum()
        decided += declared.sum()
        total += stops.reason.size
    return {
        "miss": missed / total,
        "family_miss": families_missed / (PROFILES * len(P_TRAIN)),
        "false": false / nulls,
        "wrong_sign": wrong_sign / max(1, declared_nonzero),
        "decided": decided / total,
    }


def test_simulated_profiles_hold_the_level_under_the_stopping():
    rates = _simulate(lambda train, shifted: RULE.apply(train, shifted, grid=SIM_GRID))
    alpha = RULE.alpha
    assert rates["family_miss"] <= alpha  # every condition of a profile covered at once, at the stop
    assert rates["miss"] <= alpha / len(GAPS)  # each condition at its corrected level
    assert rates["false"] <= alpha and rates["wrong_sign"] <= alpha
    assert rates["decided"] > 0.2  # it does decide (the 0.3 gap nearly always): not vacuous


def _naive_rule(train: np.ndarray, shifted: np.ndarray):
    """The same stopping on Wald intervals (Bonferroni over conditions) recomputed after every block: peeking."""
    d = train[:, None, :] - shifted
    z = 2.326  # two-sided 0.9 / 5 conditions
    shape = d.shape[:2]
    reason, low, high = np.full(shape, RUNNING), np.zeros(shape), np.zeros(shape)
    for end in range(RULE.block, RULE.max_episodes + 1, RULE.block):
        mean, se = d[..., :end].mean(-1), d[..., :end].std(-1) / math.sqrt(end) + 1e-9
        lo, hi = mean - z * se, mean + z * se
        now = np.where((lo > 0) | (hi < 0), DECIDED, np.where((lo >= -0.1) & (hi <= 0.1), WITHIN_TOLERANCE, RUNNING))
        if end == RULE.max_episodes:
            now = np.where(now == RUNNING, BUDGET, now)
        stop = (reason == RUNNING) & (now != RUNNING)
        low, high = np.where(reason == RUNNING, lo, low), np.where(reason == RUNNING, hi, high)
        reason = np.where(stop, now, reason)
    return type("Stops", (), {"reason": reason, "low": low, "high": high})


def test_peeking_at_fixed_n_intervals_fails_the_same_checks():
    rates = _simulate(_naive_rule)
    assert rates["family_miss"] > RULE.alpha or rates["false"] > RULE.alpha


# --- the rule on one profile ------------------------------------------------------------------------


def test_a_clear_gap_stops_early_a_null_one_runs_to_the_budget_and_train_runs_longest():
    rule = StopRule(block=10, max_episodes=60, tolerance=0.05)
    train = [True] * 60
    stops = decide(train, {"table_pos": [False] * 60, "light": [True] * 59 + [False]}, rule)
    assert stops["table_pos"].reason == "decided" and stops["table_pos"].episodes < 30
    assert stops["table_pos"].gap_low > 0 and stops["table_pos"].gap == 1.0
    assert stops["light"].reason in ("within tolerance", "budget") and stops["light"].episodes > 30
    assert stops["train"].episodes == max(stops["table_pos"].episodes, stops["light"].episodes)
    assert stops["train"].reason == "paired" and stops["train"].gap is None
    assert stops["train"].success_low <= 1.0 == stops["train"].success_high


def test_the_rule_is_a_function_of_the_outcomes_and_of_nothing_else():
    rng = np.random.default_rng(1)
    train = list(rng.random(100) < 0.9)
    shifted = {f"c{i}": list(rng.random(100) < r) for i, r in enumerate((0.9, 0.5, 0.85))}
    rule = StopRule(block=10, max_episodes=100, tolerance=0.1)
    first = decide(train, shifted, rule)
    assert first == decide(train, shifted, rule)
    # the outcomes after a condition's stop never change it: a run does not have them
    cut = {name: outcomes[: first[name].episodes] for name, outcomes in shifted.items()}
    assert decide(train[: first["train"].episodes], cut, rule) == first


def test_a_run_cut_short_leaves_conditions_running():
    rule = StopRule(block=10, max_episodes=100, tolerance=0.05)
    stops = decide([True, False] * 10, {"light": [True, False] * 10}, rule)
    assert running(stops) == ["light"] and stops["light"].episodes == 20
