"""Intervals for every summary (issue 18, item 6) and the power of a plan (item 7): the seed-level bootstrap
(deterministic, covering its point estimates, hand-checkable small cases), the summaries it is run on (the
same numbers as the report's tables), the report's lines, and power numbers for textbook cases."""

import math
import random

import numpy as np
import pytest

from lerobot_factorworld.stats import bootstrap, power, proportions, ranks, summaries
from lerobot_factorworld.study.analysis.study import analyze
from lerobot_factorworld.study.paper import PAPER_FACTOR_RANKS
from lerobot_factorworld.study.plan import power as plan_power
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.eval_settings import EvalSettings
from lerobot_factorworld.study.plan.grid import DEFAULT_WIDTHS
from lerobot_factorworld.study.report.markdown import (
    _gap_against_n_section,
    _ordering_section,
    _pairs_section,
    _per_task_table,
    _radius_section,
)
from lerobot_factorworld.study.results import aggregate

FACTORS = list(PAPER_FACTOR_RANKS)
HARDNESS = dict(zip(FACTORS, (0.3, 0.25, 0.15, 0.12, 0.05, 0.0, 0.0)))
RADIUS_WIDTHS = {DEFAULT_WIDTHS: 0.025, "camera_pos=medium": 0.05, "camera_pos=wide": 0.075}


def study_rows(method="bc", seeds=(0, 1, 2), tasks=("door-open", "pick-place"), ns=(5, 20), episodes=20, seed=0):
    """results.csv-like rows of a synthetic study: paired episodes, gaps growing with each factor's hardness
    and with the camera radius; every pair of the seven factors; the camera radius sweep."""
    rnd = random.Random(seed)
    pairs = [f"{a}+{b}" for i, a in enumerate(FACTORS) for b in FACTORS[i + 1 :]]
    rows = []
    for task in tasks:
        for n in ns:
            for s in seeds:
                for widths, radius in RADIUS_WIDTHS.items():
                    train = [rnd.random() < 0.8 for _ in range(episodes)]
                    conditions = ["train", *FACTORS, *pairs] if widths == DEFAULT_WIDTHS else ["train", "camera_pos"]
                    for c in conditions:
                        factors = [] if c == "train" else c.split("+")
                        drop = sum(HARDNESS[f] for f in factors) * radius / 0.025
                        outcomes = [t and rnd.random() >= drop for t in train]
                        k = sum(outcomes)
                        gap = 0.0 if c == "train" else proportions.paired_gap(train, outcomes)[0]
                        rows.append(
                            {
                                "method": method,
                                "task": task,
                                "n_train_envs": n,
                                "seed": s,
                                "widths": widths,
                                "condition": c,
                                "n_factors": len(factors),
                                "radius_m": radius if c in ("camera_pos", "table_pos") else None,
                                "episodes": episodes,
                                "successes": k,
                                "success_rate": k / episodes,
                                "gap": gap,
                            }
                        )
    return rows


def config(**kw):
    settings = {
        "tasks": ["door-open", "pick-place"],
        "factors": FACTORS,
        "pairs": ["all"],
        "seeds": [0, 1, 2],
        "n_train_envs": [5, 20],
        "eval": EvalSettings(n_test_envs=20, episodes=20),
        "radius_factors": ["camera_pos"],
    }
    return StudyConfig(**{**settings, **kw})


# --- the bootstrap itself -------------------------------------------------------------------------


def test_bootstrap_is_deterministic_and_seeded():
    rates = np.array([[0.5, 0.2, np.nan], [0.7, 0.1, 0.3]])
    episodes = np.array([[20, 20, 0], [20, 20, 20]])

    def statistic(r, n):
        return summaries.nanmean(r, axis=-2)  # mean over seeds per cell

    point, a = bootstrap.seed_bootstrap(rates, episodes, statistic)
    _, b = bootstrap.seed_bootstrap(rates, episodes, statistic)
    assert a.shape == (bootstrap.BOOTSTRAP_RESAMPLES, 3) and np.array_equal(a, b, equal_nan=True)
    assert np.allclose(point, [0.6, 0.15, 0.3])
    _, other = bootstrap.seed_bootstrap(rates, episodes, statistic, seed=1)
    assert not np.array_equal(a, other, equal_nan=True)
    assert bootstrap.BOOTSTRAP_RESAMPLES == 2000 and bootstrap.BOOTSTRAP_SEED == 0


def test_known_small_cases():
    mean = lambda r, n: summaries.nanmean(r, axis=-2)  # noqa: E731
    # one seed, unknown episode counts: nothing to resample, the interval is the point
    point, reps = bootstrap.seed_bootstrap(np.array([[0.4]]), np.array([[0]]), mean)
    assert np.all(reps == 0.4) and bootstrap.percentile_interval(reps) == (0.4, 0.4)
    # two seeds, counts unknown: replicates are 0.2 (1/4), 0.5 (1/2), 0.8 (1/4): interval [0.2, 0.8]
    _, reps = bootstrap.seed_bootstrap(np.array([[0.2], [0.8]]), np.array([[0], [0]]), mean)
    assert set(np.round(reps.ravel(), 9)) == {0.2, 0.5, 0.8}
    assert abs((reps == 0.2).mean() - 0.25) < 0.03
    assert np.allclose(bootstrap.percentile_interval(reps), ([0.2], [0.8]))
    # one seed, one cell of 400 episodes at 0.5: the episode resample is binomial, sd sqrt(0.25 / 400); the
    # interval is the replicates' 2.5th and 97.5th percentiles (about 0.5 -+ 1.96 * 0.025; 90% would be -+ 0.041)
    _, reps = bootstrap.seed_bootstrap(np.array([[0.5]]), np.array([[400]]), mean)
    assert reps.std() == pytest.approx(0.025, rel=0.1)
    low, high = bootstrap.percentile_interval(reps)
    assert (low[0], high[0]) == (np.quantile(reps, 0.025), np.quantile(reps, 0.975))
    assert low[0] == pytest.approx(0.451, abs=0.005) and high[0] == pytest.approx(0.549, abs=0.005)
    # a statistic undefined in most replicates has no interval
    assert all(math.isnan(v) for v in bootstrap.percentile_interval(np.array([np.nan, np.nan, 1.0])))


def test_the_percentile_interval_is_the_95_percent_one():
    """0 .. 1 in 1001 even steps: the 2.5th and 97.5th percentiles are 0.025 and 0.975 exactly (a 90% interval
    would be 0.05 .. 0.95); NaN replicates are left out, not counted as values."""
    replicates = np.arange(1001) / 1000
    assert bootstrap.percentile_interval(replicates) == pytest.approx((0.025, 0.975), abs=1e-12)
    assert bootstrap.percentile_interval(replicates, level=0.9) == pytest.approx((0.05, 0.95), abs=1e-12)
    with_nan = np.concatenate([replicates, [np.nan] * 10])
    assert bootstrap.percentile_interval(with_nan) == pytest.approx((0.025, 0.975), abs=1e-12)
    columns = np.stack([replicates, 2 * replicates], axis=1)  # per column
    low, high = bootstrap.percentile_interval(columns)
    assert low == pytest.approx([0.025, 0.05], abs=1e-12) and high == pytest.approx([0.975, 1.95], abs=1e-12)


def test_a_factors_gap_interval_is_the_95_percent_interval_of_the_seed_bootstrap():
    """The report's interval of a factor's mean gap, recomputed from the same resamples (numpy's PCG64 from
    BOOTSTRAP_SEED and the seeds' values for the seeds, from BOOTSTRAP_SEED and each cell's identity for its
    episodes, as ``seed_bootstrap`` draws them by identity) and numpy's percentiles:
    equal to the last digit, and at least one step (1/60) from the 90% interval at either end."""
    successes = {0: (16, 9), 1: (13, 10), 2: (18, 6)}  # seed -> (train, light) successes of 20 paired episodes
    rows = [
        {
            "method": "bc",
            "task": "door-open",
            "n_train_envs": 5,
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "episodes": 20,
            "successes": k,
            "success_rate": k / 20,
            "gap": 0.0 if condition == "train" else (train - light) / 20,
        }
        for seed, (train, light) in successes.items()
        for condition, k in (("train", train), ("light", light))
    ]
    ((point, low, high),) = aggregate.factor_gap_intervals(rows, "bc", ["light"]).values()

    rates = np.array([[train / 20, light / 20] for train, light in successes.values()])  # (seeds, [train, light])
    b = bootstrap.BOOTSTRAP_RESAMPLES
    seeds = np.random.default_rng([bootstrap.BOOTSTRAP_SEED, bootstrap.identity_seed((0, 1, 2))]).integers(0, 3, (b, 3))
    drawn = rates[seeds]  # (resamples, seeds drawn, cells)
    resampled = np.stack(
        [
            np.random.default_rng(
                [bootstrap.BOOTSTRAP_SEED, bootstrap.identity_seed(("bc", "door-open", 5, DEFAULT_WIDTHS, c))]
            ).binomial(np.full(drawn.shape[:2], 20), drawn[..., i])
            / 20
            for i, c in enumerate(("train", "light"))
        ],
        axis=-1,
    )  # each cell's episodes from a generator of its own identity
    gaps = (resampled[..., 0] - resampled[..., 1]).mean(axis=1)  # mean over the drawn seeds
    assert point == pytest.approx((7 + 3 + 12) / 3 / 20)
    assert (low, high) == pytest.approx((np.percentile(gaps, 2.5), np.percentile(gaps, 97.5)), abs=1e-12)
    narrower = np.percentile(gaps, 5), np.percentile(gaps, 95)
    assert narrower[0] - low > 0.01 and high - narrower[1] > 0.01  # at least one step of 1/60 (3 seeds x 20)


def test_vectorised_pieces_match_the_scalar_ones():
    assert summaries.ols_slope([0.025, 0.05, 0.075], np.array([0.1, 0.2, 0.3])) == pytest.approx(4.0)
    assert summaries.ols_slope([0.025, 0.05, 0.075], np.array([0.1, np.nan, 0.3])) == pytest.approx(4.0)
    assert math.isnan(summaries.ols_slope([0.025, 0.05], np.array([0.1, np.nan])))
    assert summaries.pair_metric_array(np.array(0.4), np.array(0.5), np.array(0.8)) == pytest.approx(-0.2)
    assert math.isnan(summaries.pair_metric_array(np.array(0.1), np.array(0.0), np.array(0.5)))
    assert summaries.count_within(np.array([0.05, -0.06, 0.07, np.nan]), 0.06) == 2
    # per seed over columns, then over seeds, each over defined values: (0.2 + 0.4) / 2 and 0.6 -> 0.45
    values = np.array([[0.2, 0.4], [0.6, np.nan]])
    assert summaries.group_mean(values, [[0, 1]])[0] == pytest.approx(0.45)
    # pooled over seeds, weighted by episodes: (0.5 * 10 + 0.2 * 30) / 40
    assert summaries.pooled_rates(np.array([[0.5], [0.2]]), np.array([[10], [30]]))[0] == pytest.approx(0.275)


# --- the summaries: the report's numbers, with intervals -------------------------------------------


def test_intervals_cover_the_point_estimates_which_match_the_tables():
    rows = study_rows()
    ordering = aggregate.factor_ordering(rows, "bc", FACTORS)
    intervals = aggregate.factor_gap_intervals(rows, "bc", FACTORS)
    assert set(intervals) == set(ordering)
    for factor, (point, low, high) in intervals.items():
        assert point == pytest.approx(ordering[factor][0]) and low <= point <= high and high - low > 0.02
    low, high = aggregate.ordering_rho_interval(rows, "bc", FACTORS, PAPER_FACTOR_RANKS)
    assert -1 <= low < high <= 1 and high > 0.5

    differences = aggregate.factor_gap_differences(rows, "bc", FACTORS)
    assert len(differences) == 21 and set(differences) <= {
        (a, b) for i, a in enumerate(FACTORS) for b in FACTORS[i + 1 :]
    }
    for (a, b), (point, low, high) in differences.items():
        assert point == pytest.approx(ordering[a][0] - ordering[b][0]) and low <= point <= high
    # the hardest synthetic factor (drop 0.3) is resolved from the two with none; those two are not resolved
    assert differences[(FACTORS[0], FACTORS[-1])][1] > 0 and differences[(FACTORS[-2], FACTORS[-1])][1] <= 0
    pairs = aggregate.pair_summary(rows, "bc", 0.06)
    table = aggregate.summary(aggregate.pair_rows(rows), "pair_metric", ["method", "pair"])
    assert len(pairs.per_cell) == 21 and pairs.pairs_per_cell == 21
    for pair, (point, low, high) in pairs.per_cell.items():
        assert point == pytest.approx(table[("bc", pair)][0]) and low <= point <= high
    for point, low, high in pairs.pooled.values():
        assert low <= point <= high
    assert 0 <= pairs.within_per_cell[1] <= pairs.within_per_cell[2] <= 21

    slopes = aggregate.radius_slopes(rows, ["camera_pos"])
    radius = aggregate.gap_per_radius(rows, ["camera_pos"])
    means = [radius[("bc", "camera_pos", r)][0] for r in (0.025, 0.05, 0.075)]
    point, low, high = slopes[("bc", "camera_pos")]
    assert point == pytest.approx(summaries.ols_slope([0.025, 0.05, 0.075], np.array(means)))
    assert low <= point <= high and low > 0  # camera gaps grow with the radius here

    pooled = aggregate.pooled_success(aggregate.main_grid(rows), ["method", "task", "n_train_envs", "condition"])
    for (_, task, n, condition), (k, total, low, high) in pooled.items():
        cell = [
            r
            for r in rows
            if (r["task"], r["n_train_envs"], r["condition"], r["widths"]) == (task, n, condition, DEFAULT_WIDTHS)
        ]
        assert (k, total) == (sum(r["successes"] for r in cell), sum(r["episodes"] for r in cell))
        wilson = proportions.wilson_interval(k, total)
        assert low <= wilson[0] and high >= wilson[1] and low <= k / total <= high


def test_the_pair_metric_per_cell_and_pooled_by_hand():
    def row(seed, condition, k):
        return {
            "method": "bc",
            "task": "door-open",
            "n_train_envs": 5,
            "seed": seed,
            "widths": DEFAULT_WIDTHS,
            "condition": condition,
            "n_factors": condition.count("+") + 1,
            "episodes": 10,
            "successes": k,
            "success_rate": k / 10,
            "gap": math.nan,
        }

    rows = [row(0, "light", 5), row(0, "camera_pos", 0), row(0, "light+camera_pos", 0)]
    rows += [row(1, "light", 5), row(1, "camera_pos", 4), row(1, "light+camera_pos", 2)]
    summary = aggregate.pair_summary(rows, "bc", 0.06)
    assert summary.per_cell["light+camera_pos"][0] == pytest.approx(-0.5)  # seed 0 undefined, seed 1 (0.2-0.4)/0.4
    assert summary.pooled["light+camera_pos"][0] == pytest.approx(-0.5)  # pooled 0.1 vs min(0.5, 0.2)
    assert summary.pooled_undefined["light+camera_pos"] == (0, 1)
    assert summary.within_per_cell[0] == 0 and summary.within_pooled[0] == 0


def test_pooled_rho_interval_covers_the_pooled_rates_rho():
    """The pick report's rho of pooled success per condition against a reference gets a seed-bootstrap interval;
    against the synthetic truth (success falls with hardness) the point and the interval are high (a percentile
    interval of a rank correlation need not contain its point: resampling breaks the point's ties)."""
    rows = [r for r in study_rows() if r["widths"] == DEFAULT_WIDTHS and r["condition"] in FACTORS]
    truth = {f: 1.0 - HARDNESS[f] for f in FACTORS}  # a success-rate-like reference: easier = higher
    pooled = aggregate.pooled_success(rows, ["condition"])
    point = ranks.spearman({c: k / n for (c,), (k, n, _, _) in pooled.items()}, truth)
    low, high = aggregate.pooled_rho_interval(rows, "condition", truth)
    assert point > 0.9 and 0.5 < low <= high <= 1.0
    assert all(math.isnan(v) for v in aggregate.pooled_rho_interval(rows, "condition", {"light": 1.0, "x": 0.5}))


def test_one_seed_pooled_success_is_the_wilson_interval():
    rows = [r for r in study_rows(seeds=(0,)) if r["widths"] == DEFAULT_WIDTHS and r["condition"] == "train"]
    pooled = aggregate.pooled_success(rows, ["method", "task", "n_train_envs", "condition"])
    for k, n, low, high in pooled.values():
        assert (low, high) == pytest.approx(proportions.wilson_interval(k, n))


def test_gap_against_n_matches_the_gap_table_and_resolves_a_gap_that_closes():
    """F2's numbers: each factor's gap per N is the gap table's, 'all factors' their mean, the change the last N's
    gap minus the first's; where every gap closes at the larger N (synthetic), the change's interval is below 0."""
    rows = [r for r in study_rows(ns=(5,), episodes=60) if r["widths"] == DEFAULT_WIDTHS]
    wide = [dict(r, n_train_envs=50) for r in study_rows(ns=(5,), episodes=60, seed=1) if r["widths"] == DEFAULT_WIDTHS]
    train = {(r["task"], r["seed"]): r for r in wide if r["condition"] == "train"}
    for r in wide:  # at N = 50 every shifted condition keeps the train condition's successes: no gap
        t = train[(r["task"], r["seed"])]
        r.update(successes=t["successes"], success_rate=t["success_rate"], gap=0.0)
    rows += wide
    found = aggregate.gap_against_n(rows, "bc", FACTORS)
    table = aggregate.gap_per_factor_and_n(rows)
    assert found.ns == [5, 50] and list(found.gaps) == [*FACTORS, aggregate.ALL_FACTORS]
    for factor in FACTORS:
        for n, (point, low, high) in zip(found.ns, found.gaps[factor]):
            assert point == pytest.approx(table[("bc", factor, n)][0]) and low <= point <= high
        change = found.change[factor]
        assert change[0] == pytest.approx(found.gaps[factor][1][0] - found.gaps[factor][0][0])
        assert change[1] <= change[0] <= change[2]
    everything = found.gaps[aggregate.ALL_FACTORS]
    assert everything[0][0] == pytest.approx(np.mean([found.gaps[f][0][0] for f in FACTORS]))
    assert found.change[FACTORS[0]][2] < 0 and found.change[aggregate.ALL_FACTORS][2] < 0  # the hardest closes
    assert found.gaps[FACTORS[0]][1][0] == 0.0  # no gap at N = 50
    assert aggregate.gap_against_n([r for r in rows if r["n_train_envs"] == 5], "bc", FACTORS) is None  # one N
    assert aggregate.gap_against_n(rows, "other", FACTORS) is None

    bc = [{"name": "bc", "policy": {"type": "bc"}}]
    wide_config = config(methods=bc, n_train_envs=[5, 50], eval=EvalSettings(n_test_envs=50, episodes=50))
    section = "\n".join(_gap_against_n_section(wide_config, rows))
    assert "## Gap against N" in section and "| factor | N=5 | N=50 | change N=5 -> 50 |" in section
    line = next(x for x in section.splitlines() if x.startswith(f"| {FACTORS[0]} | "))
    assert line.count("[") == 3 and line.endswith("] |")
    assert (
        _gap_against_n_section(config(methods=bc, n_train_envs=[5]), [r for r in rows if r["n_train_envs"] == 5]) == []
    )


def test_the_report_prints_intervals_for_rho_pairs_slopes_and_pooled_tables():
    cfg = config(methods=[{"name": "bc", "policy": {"type": "bc"}}])
    rows = study_rows()
    analysis = analyze(cfg, rows)  # the claims decided as decide(study_claims(cfg), cfg, rows) does
    ordering = "\n".join(_ordering_section(cfg, rows, analysis))
    assert "95% interval (bootstrap)" in ordering
    assert "Spearman correlation with the paper's ordering over 7 factors: **" in ordering
    assert "95% interval [+" in ordering or "95% interval [-" in ordering
    assert "### Which factors are resolved from each other (bc)" in ordering
    hardest = f"| {FACTORS[0]} | "
    resolved = ordering.split("### Which factors are resolved")[1]
    row = next(line for line in resolved.splitlines() if line.startswith(hardest))
    assert f"{FACTORS[-1]} +0." in row  # resolved from the factors with no gap, with its difference
    pairs = "\n".join(_pairs_section(cfg, rows))
    assert "95% bootstrap interval of the count" in pairs and "with the pooled one" in pairs
    assert "| bc | camera_pos+object_texture | " in pairs
    assert "slope per 0.025 m [95% interval]" in "\n".join(_radius_section(cfg, rows))
    table = "\n".join(_per_task_table(cfg, rows, analysis))
    assert "pooled over the 3 seed(s)" in table and "| bc | door-open | 5 | " in table
    assert _ordering_section(cfg, rows, analysis) == _ordering_section(cfg, rows, analyze(cfg, rows))  # deterministic
    assert "Against the paper's ordering (decided in *The paper's claims* below)" in ordering
    assert _pairs_section(cfg, rows) == _pairs_section(cfg, rows)


# --- power ----------------------------------------------------------------------------------------


def test_power_numbers_for_textbook_cases():
    z = proportions.Z95
    # two proportions of 100 each at 0.5: 1.96 * sqrt(2 * 0.25 / 100) = 0.139 (the two-sample z-test)
    assert power.difference_resolvable(100, 0.5) == pytest.approx(z * math.sqrt(0.005))
    assert power.difference_resolvable(100, 0.5) == pytest.approx(0.1386, abs=1e-4)
    # a paired mean gap at P_T = 0.5, independent outcomes: d = z sqrt((0.5 - d^2) / N) -> sqrt(z^2 / 2 / (N + z^2))
    assert power.mean_resolvable_gap(100, 0.5) == pytest.approx(math.sqrt(z * z / 2 / (100 + z * z)), abs=5e-4)
    # the slope over radii 0.025 / 0.05 / 0.075 m (Sxx = 0.00125), 100 episodes per radius at 0.5: 3.92 per m
    assert power.slope_resolvable(100, [0.025, 0.05, 0.075], 0.5) == pytest.approx(2 * z)
    assert power.pair_metric_resolvable(100, 0.5) == pytest.approx(2 * power.difference_resolvable(100, 0.5))


def test_a_cells_resolvable_gap_is_where_newcombes_interval_starts_to_exclude_0():
    # 20 paired episodes at P_T = 0.8, no reversals: 5 train-only successes (gap 0.25) are resolved, 4 are not
    assert power.cell_resolvable_gap(20, 0.8) == 0.25
    train = [True] * 16 + [False] * 4
    assert proportions.paired_gap(train, [True] * 11 + [False] * 9)[1] > 0
    assert proportions.paired_gap(train, [True] * 12 + [False] * 8)[1] <= 0
    independent = power.cell_resolvable_gap(20, 0.8, paired=False)
    assert 0.25 < independent < 0.35  # independent outcomes need more
    assert power.cell_resolvable_gap(100, 0.8) < power.cell_resolvable_gap(20, 0.8)
    assert math.isnan(power.cell_resolvable_gap(4, 0.25))  # one train success can never be resolved


def test_dry_run_power_lines():
    lines = plan_power.power_lines(config())
    text = "\n".join(lines)
    assert "20 paired episodes per cell, 3 seed(s)" in text and "P=0.5" in text and "P=0.95" in text
    cell = next(line for line in lines if "one cell (Newcombe; no reversals)" in line)
    assert cell.split()[-3:] == ["0.250", "0.250", "0.250"]
    assert "factor's mean gap, 12 cell(s)" in text and "pair metric" in text and "radius slope" in text
    no_pairs = "\n".join(plan_power.power_lines(config(pairs=[], radius_factors=[])))
    assert "pair metric" not in no_pairs and "radius slope" not in no_pairs
