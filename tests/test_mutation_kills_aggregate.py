"""The report's aggregations (study/results/aggregate.py) where mutation testing found the suite silent
(docs/testing.md): each selector's rows and groups, means over tasks then seeds, the pair metric and interaction
per cell and per task, stage counts, the (seed x cell) arrays, and every seed-bootstrap interval. Rows are built
by hand; their episode counts are unknown (0) or their rates 0 and 1, so the bootstrap only resamples the two
training seeds: its 95% interval is then exactly the smallest and largest value of the statistic over the seeds
drawn (each of "both seeds 0" and "both seeds 1" is about a quarter of the 2000 replicates), computed by hand
below."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from lerobot_factorworld.stats.proportions import Z95, wilson_interval
from lerobot_factorworld.study.results import aggregate

WIDE = "camera_pos=wide"


def row(condition: str, rate, *, method="bc", task="t1", n=5, seed=0, widths="default", gap=None, **extra) -> dict:
    """A ``results.csv`` row; ``gap`` defaults to NaN (train, or unpaired); episodes unknown unless given."""
    n_factors = 0 if condition == "train" else len(condition.split("+"))
    return {
        "method": method,
        "task": task,
        "n_train_envs": n,
        "seed": seed,
        "widths": widths,
        "condition": condition,
        "n_factors": n_factors,
        "success_rate": rate,
        "gap": math.nan if gap is None else gap,
        "radius_m": extra.pop("radius_m", None),
        **extra,
    }


def runs(rates: list[tuple[int, dict, dict[str, float]]]) -> list[dict]:
    """Rows of ``[(seed, other row keywords, {condition: rate})]``, each shifted gap = train rate - its rate."""
    out = []
    for seed, kw, by_condition in rates:
        train = by_condition.get("train")
        for condition, rate in by_condition.items():
            gap = None if condition == "train" or train is None else train - rate
            out.append(row(condition, rate, seed=seed, gap=gap, **kw))
    return out


def plain(value):
    """NaN -> None and numpy scalars -> floats, recursively (NaN != NaN would fail equality)."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(plain(v) for v in value)
    if isinstance(value, (float, np.floating)):
        return None if math.isnan(value) else pytest.approx(float(value), abs=1e-12)
    return value


# --- the means over tasks, then seeds ---------------------------------------------------------------------


SUMMARY_ROWS = [
    row("light", 0.5, task="t2", seed=1, gap=math.nan),  # undefined: left out, and not the end of the rows
    row("camera_pos", 0.5, task="t1", seed=0, gap=None),
    row("light", 0.5, task="t1", seed=0, gap=0.5),
    row("light", 0.75, task="t2", seed=0, gap=0.25),
    row("light", 0.875, task="t1", seed=1, gap=0.125),
    row("camera_pos", 0.25, task="t2", seed=0, gap=0.75),
    row("train", 1.0, task="t1", seed=0),
    row("train", 0.75, task="t1", seed=1),
    row("light", 0.5, task="t1", seed=0, n=50, gap=0.5),
    row("light", 0.0, task="t1", seed=0, widths=WIDE, gap=1.0),  # the radius sweep: not the main grid
    row("train", 0.25, task="t1", seed=0, widths=WIDE),
]


def test_per_seed_averages_over_tasks_leaving_undefined_values_out():
    assert aggregate.per_seed(SUMMARY_ROWS, "gap", ["condition", "widths"]) == {
        ("light", "default"): {1: 0.125, 0: (0.5 + 0.25 + 0.5) / 3},
        ("camera_pos", "default"): {0: 0.75},
        ("light", WIDE): {0: 1.0},
    }
    assert aggregate.per_seed([row("train", 0.5, seed=3), row("train", 0.25, seed=3)], "success_rate", []) == {
        (): {3: 0.375}
    }


def test_the_selectors_take_their_rows_and_groups():
    # light, N = 5: seed 0 averages t1 0.5 and t2 0.25 (0.375), seed 1 has 0.125: mean 0.25, SE |0.375 - 0.125| / 2
    assert plain(aggregate.gap_per_factor_and_n(SUMMARY_ROWS)) == plain(
        {
            ("bc", "light", 5): (0.25, 0.125, 2),
            ("bc", "camera_pos", 5): (0.75, math.nan, 1),
            ("bc", "light", 50): (0.5, math.nan, 1),
        }
    )
    assert plain(aggregate.success_per_condition_and_n(SUMMARY_ROWS)) == plain(
        {
            ("bc", "light", 5): ((0.625 + 0.6875) / 2, 0.03125, 2),  # seed 1: t1 0.875, t2 0.5 (its gap is undefined)
            ("bc", "camera_pos", 5): (0.375, math.nan, 1),
            ("bc", "train", 5): (0.875, 0.125, 2),
            ("bc", "light", 50): (0.5, math.nan, 1),
        }
    )
    # over N: light's seed 0 is (0.5 + 0.25 + 0.5) / 3 = 5/12, seed 1 0.125
    light = ((5 / 12 + 0.125) / 2, (5 / 12 - 0.125) / 2, 2)
    assert plain(aggregate.gap_per_factor(SUMMARY_ROWS, ["light"])) == plain({("bc", "light"): light})
    assert plain(aggregate.factor_ordering(SUMMARY_ROWS, "bc", ["table_texture", "light", "camera_pos"])) == plain(
        {"light": light[:2], "camera_pos": (0.75, math.nan)}
    )
    assert aggregate.factor_ordering(SUMMARY_ROWS, "other", ["light"]) == {}
    assert [r["seed"] for r in aggregate.main_grid(SUMMARY_ROWS)] == [1, 0, 0, 0, 1, 0, 0, 1, 0]


def test_the_radius_rows_and_gaps_per_radius():
    rows = [
        row("camera_pos", 0.75, seed=0, gap=0.25, radius_m=0.025),
        row("camera_pos", 0.5, seed=1, gap=0.5, radius_m=0.025),
        row("camera_pos", 0.25, seed=0, widths=WIDE, gap=0.75, radius_m=0.075),
        row("camera_pos", 0.5, seed=1, widths=WIDE, n=50, gap=0.5, radius_m=0.075),
        row("table_pos", 0.5, seed=1, gap=0.5, radius_m=0.025),  # not a factor asked for
        row("light", 0.5, seed=1, gap=0.5),  # no radius
        row("train", 1.0, seed=0),
    ]
    assert aggregate.radius_rows(rows, ["camera_pos"]) == rows[:4]
    assert plain(aggregate.gap_per_radius(rows, ["camera_pos"])) == plain(
        {("bc", "camera_pos", 0.025): (0.375, 0.125, 2), ("bc", "camera_pos", 0.075): (0.625, 0.125, 2)}
    )
    assert plain(aggregate.gap_per_radius(rows, ["camera_pos", "table_pos"], per_n=True)) == plain(
        {
            ("bc", "camera_pos", 5, 0.025): (0.375, 0.125, 2),
            ("bc", "camera_pos", 5, 0.075): (0.75, math.nan, 1),
            ("bc", "camera_pos", 50, 0.075): (0.5, math.nan, 1),
            ("bc", "table_pos", 5, 0.025): (0.5, math.nan, 1),
        }
    )


def test_stage_counts_are_pooled_over_seeds_in_the_columns_order():
    rows = [
        {**row("light", 0.5, seed=0), "stages": "none:3;reached:1"},
        {**row("light", 0.5, seed=0, task="t2"), "stages": ""},  # no counts: left out
        row("train", 0.5, seed=0),  # no stages column at all
        {**row("light", 0.5, seed=1), "stages": "none:1;grasped:2;reached:4"},
        {**row("light", 0.5, seed=0, widths=WIDE), "stages": "none:100"},
        {**row("train", 0.5, seed=1, n=50), "stages": "grasped:8"},
    ]
    assert aggregate.stage_counts(rows) == {
        ("bc", "t1", 5, "light"): {"none": 4, "reached": 5, "grasped": 2},
        ("bc", "t1", 50, "train"): {"grasped": 8},
    }
    assert list(aggregate.stage_counts(rows)[("bc", "t1", 5, "light")]) == ["none", "reached", "grasped"]


# --- pairs ---------------------------------------------------------------------------------------------------

LC, LT, CT = "light+camera_pos", "light+table_texture", "camera_pos+table_texture"
PAIR_RATES = [
    # t1 seed 0: light+camera_pos 0 (within), light+table_texture +0.5 (above), camera_pos+table_texture 0
    (0, {}, {"train": 1.0, "light": 0.5, "camera_pos": 0.75, "table_texture": 0.5, LC: 0.5, LT: 0.75, CT: 0.5}),
    # t1 seed 1: no table_texture, so its pairs have no factor cell: light+camera_pos -0.5 (below)
    (1, {}, {"train": 1.0, "light": 0.25, "camera_pos": 0.5, LC: 0.125, LT: 0.5}),
    # t2 seed 0: light+camera_pos 0; light+table_texture undefined (table_texture never succeeds)
    (0, {"task": "t2"}, {"train": 0.5, "light": 0.25, "camera_pos": 0.25, "table_texture": 0.0, LC: 0.25, LT: 0.0}),
    # another method and the radius sweep: never part of bc's pairs
    (0, {"method": "aug"}, {"train": 1.0, "light": 1.0, "camera_pos": 0.5, LC: 0.0}),
    (0, {"widths": WIDE}, {"train": 1.0, "light": 0.125, "camera_pos": 1.0, LC: 1.0}),
]
PAIRS = [row("distractors", 0.5, seed=1), *runs(PAIR_RATES)]  # first a single factor's row: not the pairs' end


def test_pair_rows_hold_the_pair_metric_and_interaction_of_each_cell_with_both_factors():
    def pair(task, seed, name, metric, inter, method="bc"):
        return {
            "method": method,
            "task": task,
            "n_train_envs": 5,
            "seed": seed,
            "pair": name,
            "pair_metric": metric,
            "interaction": inter,
        }

    assert plain(aggregate.pair_rows(PAIRS)) == plain(
        [
            # (P_AB - min) / min; gap(A+B) - gap(A) - gap(B)
            pair("t1", 0, LC, 0.0, 0.5 - 0.5 - 0.25),
            pair("t1", 0, LT, 0.5, 0.25 - 0.5 - 0.5),
            pair("t1", 0, CT, 0.0, 0.5 - 0.25 - 0.5),
            pair("t1", 1, LC, -0.5, 0.875 - 0.75 - 0.5),  # seed 1's light+table_texture: no table_texture row
            pair("t2", 0, LC, 0.0, 0.25 - 0.25 - 0.25),
            pair("t2", 0, LT, math.nan, 0.5 - 0.25 - 0.5),
            pair("t1", 0, LC, -1.0, 1.0 - 0.0 - 0.5, method="aug"),
        ]
    )


def _counts(band: aggregate.PairBand) -> tuple[int, int, int]:
    return band.within, band.below, band.above


def test_pair_bands_count_each_tasks_pairs_against_the_band_with_intervals():
    bands = aggregate.pair_bands(PAIRS, "bc", 0.1)
    assert list(bands) == ["t1", "t2"]
    # t1: light+camera_pos averages 0 and -0.5 (below), light+table_texture 0.5 (above), camera_pos+table_texture 0
    # mean interaction over its 4 pair rows; its interval from the rates: seed 0's three pairs average
    # -1.25 / 3 (light+camera_pos -0.25, light+table_texture -0.75, camera_pos+table_texture -0.25), seed 1 -0.375
    # within the band per cell: 2 pairs drawing seed 0 only, 0 drawing seed 1 only
    assert plain(bands["t1"]) == plain(
        aggregate.PairBand(1, 1, 1, (-0.25 - 0.75 - 0.25 - 0.375) / 4, (-1.25 / 3, -0.375), (0.0, 2.0))
    )
    assert plain(bands["t2"]) == plain(aggregate.PairBand(1, 0, 0, -0.25, (-0.25, -0.25), (1.0, 1.0)))
    assert aggregate.pair_bands(PAIRS, "other", 0.1) == {}
    # a wider band takes in t1's light+camera_pos (-0.25) and light+table_texture (0.5)
    assert _counts(aggregate.pair_bands(PAIRS, "bc", 0.5)["t1"]) == (3, 0, 0)
    assert _counts(aggregate.pair_bands(PAIRS, "bc", 0.25)["t1"]) == (2, 0, 1)


def test_pair_summary_per_cell_and_pooled_with_intervals():
    t1 = aggregate.pair_summary([r for r in PAIRS if r["task"] == "t1"], "bc", 0.1)
    # per cell, per seed: light+camera_pos 0 / -0.5; light+table_texture 0.5 / undefined; camera_pos+table_texture
    # 0 / undefined
    assert plain(t1.per_cell) == plain({LC: (-0.25, -0.5, 0.0), LT: (0.5, 0.5, 0.5), CT: (0.0, 0.0, 0.0)})
    # pooled over seeds (equal weights): light 0.375, camera_pos 0.625, table_texture 0.5, the pairs 0.3125, 0.625,
    # 0.5; seed 0 alone gives 0, 0.5, 0; seed 1 alone -0.5 and two undefined
    assert plain(t1.pooled) == plain({LC: (-1 / 6, -0.5, 0.0), LT: (2 / 3, 0.5, 2 / 3), CT: (0.0, 0.0, 0.0)})
    assert t1.pooled_undefined == {LC: (0, 1), LT: (0, 1), CT: (0, 1)}
    assert plain((t1.within_per_cell, t1.within_pooled)) == plain(((1.0, 0.0, 2.0), (1.0, 0.0, 2.0)))
    assert (t1.pairs_per_cell, t1.pairs_pooled) == (3, 3)

    both = aggregate.pair_summary(PAIRS, "bc", 0.1)
    assert both.pooled_undefined == {LC: (0, 2), LT: (1, 2), CT: (0, 1)}  # t2's light+table_texture
    assert plain(both.pooled[LC][0]) == plain((-1 / 6 + 0.0) / 2)
    assert plain(both.per_cell) == plain(t1.per_cell)  # t2's cells are 0 and undefined: seed 0 is unchanged
    assert aggregate.pair_summary([r for r in PAIRS if r["n_factors"] < 2], "bc", 0.1) is None
    # a pair whose factor has no cell at all is not counted
    no_b = [r for r in PAIRS if r["condition"] != "camera_pos" and r["task"] == "t1"]
    assert list(aggregate.pair_summary(no_b, "bc", 0.1).per_cell) == [LT]


def test_task_interactions_from_the_rates():
    assert plain(aggregate.task_interactions(PAIRS, "bc")) == plain({"t1": (-1.25 / 3, -0.375), "t2": (-0.25, -0.25)})
    assert plain(aggregate.task_interactions(PAIRS, "aug")) == plain({"t1": (0.5, 0.5)})  # 1 + 0.5 - 0 - 1
    no_train = [r for r in PAIRS if r["condition"] != "train"]
    assert aggregate.task_interactions(no_train, "bc") == {}


# --- the (seed x cell) arrays --------------------------------------------------------------------------------


def test_cells_put_rows_into_seed_by_cell_arrays():
    rows = [
        row("train", 0.5, seed=2, episodes=4, successes=2),
        row("light", None, seed=2, gap=-0.25, episodes=8, successes=6),  # a rate from its counts
        row("light", 0.25, seed=0, gap=math.nan, episodes=4),  # unpaired: left out of the gaps
        row("train", None, seed=0),  # no rate and no counts
        row("camera_pos", 0.125, seed=0, gap=0.375, n=50),
    ]
    table = aggregate.cells(rows)
    assert table.seeds == (0, 2)
    assert table.keys == (
        ("bc", "t1", 5, "default", "train"),
        ("bc", "t1", 5, "default", "light"),
        ("bc", "t1", 50, "default", "camera_pos"),
    )
    np.testing.assert_array_equal(table.rates, [[np.nan, 0.25, 0.125], [0.5, 0.75, np.nan]])
    np.testing.assert_array_equal(table.episodes, [[0, 4, 0], [4, 8, 0]])
    assert table.column == {k: i for i, k in enumerate(table.keys)}
    np.testing.assert_array_equal(table.train_columns(), [-1, 0, -1])  # N = 50 has no train cell

    gaps = aggregate.cells(rows, gaps=True)
    np.testing.assert_array_equal(gaps.rates, [[np.nan, np.nan, 0.125], [0.5, 0.75, np.nan]])
    assert gaps.keys == table.keys
    # cell_gaps: P_T - P_F per cell, NaN for train cells and cells without one
    rates = np.array([[1.0, 0.25, 0.5], [0.5, 0.75, 0.0]])
    np.testing.assert_array_equal(
        aggregate.cell_gaps(rates, np.array([-1, 0, -1])), [[np.nan, 0.75, np.nan], [np.nan, -0.25, np.nan]]
    )
    # a table of one column, and of none: integer indices either way
    np.testing.assert_array_equal(aggregate.cell_gaps(np.array([[0.5]]), np.array([-1])), [[np.nan]])
    assert aggregate.cell_gaps(np.zeros((2, 0)), aggregate.cells([]).train_columns()).shape == (2, 0)
    np.testing.assert_array_equal(
        aggregate.cell_gaps(rates, np.array([2, -1, 1])), [[-0.5, np.nan, -0.25], [-0.5, np.nan, 0.75]]
    )


# --- the factor ordering's bootstrap ------------------------------------------------------------------------

ORDER_RATES = [
    # gaps light, camera_pos, table_texture: seed 0 0.75, 0.5, 0.125; seed 1 0.5, 0, 0.25
    (0, {}, {"train": 1.0, "light": 0.25, "camera_pos": 0.5, "table_texture": 0.875}),
    (1, {}, {"train": 0.75, "light": 0.25, "camera_pos": 0.75, "table_texture": 0.5}),
    # t2 ranks camera_pos first: 0.5, 0.75, 0.125
    (0, {"task": "t2"}, {"train": 1.0, "light": 0.5, "camera_pos": 0.25, "table_texture": 0.875}),
    # t3 shares light and table_texture only, in t1's order: 0.5 and 0.25
    (0, {"task": "t3"}, {"train": 1.0, "light": 0.5, "table_texture": 0.75}),
]
ORDER = [
    *runs(ORDER_RATES),
    row("light", 1.0, seed=0, widths=WIDE, gap=0.0),  # not the main grid
    row("train", 1.0, seed=0, method="aug"),  # another method
    row("light", 0.0, seed=0, method="aug", gap=1.0),
    row("table_texture", 0.0, seed=1, gap=math.nan),  # an unpaired duplicate: left out
]
T1 = [r for r in ORDER if r["task"] == "t1"]
FACTORS = ["table_texture", "distractors", "light", "camera_pos"]  # distractors has no rows
REFERENCE = {"light": 1.0, "camera_pos": 2.0, "table_texture": 3.0}


def test_the_factor_ordering_bootstrap_per_factor_per_pair_and_its_rho():
    boot = aggregate.factor_gap_bootstrap(T1, "bc", FACTORS)
    assert boot.names == ["table_texture", "light", "camera_pos"]
    np.testing.assert_array_equal(boot.point, [0.1875, 0.625, 0.25])
    expected = {"table_texture": (0.1875, 0.125, 0.25), "light": (0.625, 0.5, 0.75), "camera_pos": (0.25, 0.0, 0.5)}
    assert plain(boot.intervals()) == plain(expected)
    assert plain(aggregate.factor_gap_intervals(T1, "bc", FACTORS)) == plain(expected)
    # differences per seed: tt - light -0.625 / -0.25, tt - camera_pos -0.375 / 0.25, light - camera_pos 0.25 / 0.5
    differences = {
        ("table_texture", "light"): (-0.4375, -0.625, -0.25),
        ("table_texture", "camera_pos"): (-0.0625, -0.375, 0.25),
        ("light", "camera_pos"): (0.375, 0.25, 0.5),
    }
    assert plain(boot.differences()) == plain(differences)
    assert plain(aggregate.factor_gap_differences(T1, "bc", FACTORS)) == plain(differences)
    # seed 0 alone and the mean rank light, camera_pos, table_texture (rho 1), seed 1 alone light, tt, cam (0.5)
    assert boot.rho_interval(REFERENCE) == (0.5, 1.0)
    assert aggregate.ordering_rho_interval(T1, "bc", FACTORS, REFERENCE) == (0.5, 1.0)
    assert aggregate.ordering_rho_interval(T1, "bc", FACTORS, {"light": 1.0, "camera_pos": 2.0}) == (
        pytest.approx(math.nan, nan_ok=True),
        pytest.approx(math.nan, nan_ok=True),
    )

    empty = aggregate.factor_gap_bootstrap(T1, "bc", ["distractors"])
    assert (empty.names, empty.point.shape, empty.reps.shape) == ([], (0,), (0, 0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert empty.intervals() == {} and empty.differences() == {}
    assert all(math.isnan(v) for v in empty.rho_interval(REFERENCE))


def test_task_orderings_and_whether_tasks_disagree():
    orderings = aggregate.task_orderings(ORDER, "bc", FACTORS, ["t2", "t1", "t9"])
    assert list(orderings) == ["t2", "t1"]
    assert orderings["t2"].names == ["table_texture", "light", "camera_pos"]
    np.testing.assert_array_equal(orderings["t2"].point, [0.125, 0.5, 0.75])
    np.testing.assert_array_equal(orderings["t1"].point, [0.1875, 0.625, 0.25])
    assert aggregate.tasks_disagree(orderings)
    agree = aggregate.task_orderings(ORDER, "bc", FACTORS, ["t1", "t3"])
    np.testing.assert_array_equal(agree["t3"].point, [0.25, 0.5])
    assert not aggregate.tasks_disagree(agree)  # t3's two factors are in t1's order
    assert not aggregate.tasks_disagree({"t1": orderings["t1"]})
    assert aggregate.tasks_disagree({"t3": agree["t3"], "t2": orderings["t2"], "t1": orderings["t1"]})


# --- gaps against N and between methods ----------------------------------------------------------------------

N_RATES = [
    # gaps light, camera_pos: N = 5 seed 0 0.5, 0.25, seed 1 0.75, 0.5; N = 50 seed 0 0.25, 0, seed 1 0.25, 0.25
    (0, {}, {"train": 1.0, "light": 0.5, "camera_pos": 0.75}),
    (1, {}, {"train": 1.0, "light": 0.25, "camera_pos": 0.5}),
    (0, {"n": 50}, {"train": 1.0, "light": 0.75, "camera_pos": 1.0}),
    (1, {"n": 50}, {"train": 1.0, "light": 0.75, "camera_pos": 0.75}),
    (0, {"n": 500}, {"train": 1.0}),  # no shifted cell: not an N of the gaps
    (0, {"method": "aug"}, {"train": 1.0, "light": 0.75, "camera_pos": 0.75}),
    (1, {"method": "aug"}, {"train": 0.75, "light": 0.75, "camera_pos": 0.5}),
]
BY_N = [
    *runs(N_RATES),
    row("light", 0.0, seed=0, widths=WIDE, gap=1.0),  # not the main grid
    row("light", 0.0, seed=1, gap=math.nan),  # an unpaired duplicate of N = 5's light: left out
]


def test_gap_against_n_per_factor_and_over_all_with_the_change():
    found = aggregate.gap_against_n(BY_N, "bc", ["light", "table_texture", "camera_pos"])
    assert found.ns == [5, 50]
    assert list(found.gaps) == ["light", "camera_pos", aggregate.ALL_FACTORS]
    assert plain(found.gaps) == plain(
        {
            "light": [(0.625, 0.5, 0.75), (0.25, 0.25, 0.25)],
            "camera_pos": [(0.375, 0.25, 0.5), (0.125, 0.0, 0.25)],
            aggregate.ALL_FACTORS: [(0.5, 0.375, 0.625), (0.1875, 0.125, 0.25)],
        }
    )
    # the change N = 50 minus N = 5, per seed: light -0.25 / -0.5, camera_pos -0.25 / -0.25, all -0.25 / -0.375
    assert plain(found.change) == plain(
        {
            "light": (-0.375, -0.5, -0.25),
            "camera_pos": (-0.25, -0.25, -0.25),
            aggregate.ALL_FACTORS: (-0.3125, -0.375, -0.25),
        }
    )
    assert aggregate.gap_against_n([r for r in BY_N if r["n_train_envs"] != 50], "bc", ["light"]) is None
    assert aggregate.gap_against_n(BY_N, "bc", ["table_texture"]) is None


def test_method_gap_differences_set_each_method_against_the_first():
    labels = {"light": ["light"], "none": ["distractors"], "both": ["light", "camera_pos"]}
    five = [r for r in BY_N if r["n_train_envs"] == 5]
    found = aggregate.method_gap_differences(five, ["bc", "aug"], labels)
    assert list(found) == [("aug", "light"), ("aug", "both")]
    # aug's gaps: light 0.25 / 0, camera_pos 0.25 / 0.25; aug - bc per seed: light -0.25 / -0.75, both -0.125 / -0.5
    assert plain(found[("aug", "light")]) == plain(((0.625, 0.5, 0.75), (0.125, 0.0, 0.25), (-0.5, -0.75, -0.25)))
    assert plain(found[("aug", "both")]) == plain(((0.5, 0.375, 0.625), (0.1875, 0.125, 0.25), (-0.3125, -0.5, -0.125)))
    assert aggregate.method_gap_differences(five, ["bc"], labels) == {}
    assert aggregate.method_gap_differences(five, ["bc", "aug"], {"none": ["distractors"]}) == {}
    only_aug_light = [r for r in five if not (r["method"] == "bc" and r["condition"] == "light")]
    assert list(aggregate.method_gap_differences(only_aug_light, ["bc", "aug"], labels)) == [("aug", "both")]
    # three methods: each against the first
    third = [{**r, "method": "rt1"} for r in five if r["method"] == "bc"]
    assert list(aggregate.method_gap_differences([*five, *third], ["bc", "aug", "rt1"], {"light": ["light"]})) == [
        ("aug", "light"),
        ("rt1", "light"),
    ]


def test_a_method_run_on_part_of_the_grid_is_compared_on_the_cells_both_have():
    """A method with seed 0 only (a study made in parts) against bc's seed 0, not bc's mean over both seeds;
    a method on the whole grid beside it keeps the comparison it has alone."""
    labels = {"light": ["light"]}
    five = [r for r in BY_N if r["n_train_envs"] == 5]
    seed0 = [r for r in five if not (r["method"] == "aug" and r["seed"] == 1)]
    base, gap, diff = aggregate.method_gap_differences(seed0, ["bc", "aug"], labels)[("aug", "light")]
    assert (base[0], gap[0], diff[0]) == (0.5, 0.25, -0.25)  # bc's seed-0 light gap, not its mean 0.625
    part = [{**r, "method": "rt1"} for r in seed0 if r["method"] == "aug"]
    both = aggregate.method_gap_differences([*five, *part], ["bc", "aug", "rt1"], labels)
    assert both[("aug", "light")] == aggregate.method_gap_differences(five, ["bc", "aug"], labels)[("aug", "light")]
    assert both[("rt1", "light")][0][0] == 0.5 and both[("rt1", "light")][2][0] == -0.25
    # a cell only the partial method has (seed 5, light gap 1) is not compared: bc has nothing there
    alone = [{**r, "seed": 5, "success_rate": 0.0 if r["condition"] == "light" else 1.0} for r in part]
    found = aggregate.method_gap_differences([*five, *part, *alone], ["bc", "rt1"], labels)[("rt1", "light")]
    assert (found[0][0], found[1][0], found[2][0]) == (0.5, 0.25, -0.25)
    # a method not asked for adds nothing to the bootstrap, not its seeds nor its cells' episode draws
    counted = [{**r, "episodes": 4, "successes": round(4 * r["success_rate"])} for r in five]
    other = [{**r, "method": "other", "seed": 7} for r in counted if r["method"] == "aug"]
    asked = aggregate.method_gap_differences(counted, ["bc", "aug"], labels)
    assert aggregate.method_gap_differences([*counted, *other], ["bc", "aug"], labels) == asked


def test_method_rho_differences_resample_both_methods_together():
    aug = [
        # aug's gaps light, camera_pos, table_texture: seed 0 0.125, 0.5, 0.75 (rho -1), seed 1 0.875, 0.25, 0.125
        # (rho 1); their means 0.5, 0.375, 0.4375 rank light, table_texture, camera_pos (rho 0.5)
        (0, {"method": "aug"}, {"train": 1.0, "light": 0.875, "camera_pos": 0.5, "table_texture": 0.25}),
        (1, {"method": "aug"}, {"train": 1.0, "light": 0.125, "camera_pos": 0.75, "table_texture": 0.875}),
    ]
    rows = [*T1, *runs(aug)]
    factors = ["light", "camera_pos", "distractors", "table_texture"]
    found = aggregate.method_rho_differences(rows, ["bc", "aug"], factors, REFERENCE)
    # bc: rho 1 (seed 0 alone 1, seed 1 alone 0.5); aug - bc: -0.5, seed 0 alone -2, seed 1 alone 0.5
    assert plain(found) == plain({"aug": ((0.5, -1.0, 1.0), (-0.5, -2.0, 0.5))})
    assert aggregate.method_rho_differences(rows, ["bc"], factors, REFERENCE) == {}
    two = [r for r in rows if r["condition"] != "camera_pos" or r["method"] == "bc"]  # aug lacks camera_pos
    assert aggregate.method_rho_differences(two, ["bc", "aug"], factors, REFERENCE) == {}


def test_radius_slopes_per_metre_with_their_interval():
    rows = [
        row("train", 1.0, seed=0),
        row("train", 1.0, seed=1),
        row("camera_pos", 0.75, seed=0, gap=0.25, radius_m=0.025),
        row("camera_pos", 0.5, seed=1, gap=0.5, radius_m=0.025),
        row("train", 1.0, seed=0, widths=WIDE),
        row("train", 0.75, seed=1, widths=WIDE),
        row("camera_pos", 0.25, seed=0, widths=WIDE, gap=0.75, radius_m=0.075),
        row("camera_pos", 0.25, seed=1, widths=WIDE, gap=0.5, radius_m=0.075),
        row("light", 0.0, seed=0, gap=1.0),
        row("train", 0.0, seed=0, n=50),  # a run without swept rows
        row("camera_pos", 0.0, seed=0, n=500, gap=1.0, radius_m=0.025),  # no train cell: no gap
        row("camera_pos", 0.0, seed=1, gap=math.nan, radius_m=0.025),  # an unpaired duplicate: left out
    ]
    # mean gap 0.375 at 0.025 m and 0.625 at 0.075 m: 0.25 / 0.05 = 5 per metre; seed 0 alone 10, seed 1 alone 0
    assert plain(aggregate.radius_slopes(rows, ["camera_pos", "table_pos"])) == plain(
        {("bc", "camera_pos"): (5.0, 0.0, 10.0)}
    )
    assert aggregate.radius_slopes(rows, ["table_pos"]) == {}


# --- success pooled over seeds -------------------------------------------------------------------------------


def test_pooled_success_widens_the_bootstrap_to_the_wilson_interval():
    rows = [
        row("train", 1.0, seed=0, episodes=4, successes=4),
        row("train", 1.0, seed=1, episodes=4, successes=4),
        row("light", 1.0, seed=0, episodes=4, successes=4),
        row("light", 0.0, seed=1, episodes=4, successes=0),
        row("light", 0.0, seed=1, task="t2", episodes=0, successes=0),  # no episodes: left out
        row("camera_pos", 0.5, seed=1, episodes=None),
    ]
    pooled = aggregate.pooled_success(rows, ["method", "condition"])
    # train: every episode succeeds, the bootstrap is the point 1: Wilson's 1 / (1 + z^2 / 8) to 1
    # light: 4 of 8, the bootstrap spans 0 (seed 1 alone) to 1 (seed 0 alone), wider than Wilson's
    assert plain(pooled) == plain(
        {("bc", "train"): (8, 8, 1 / (1 + Z95**2 / 8), 1.0), ("bc", "light"): (4, 8, 0.0, 1.0)}
    )
    one_seed = aggregate.pooled_success([r for r in rows if r["seed"] == 1], ["condition"])
    # one seed: Wilson's interval, even where the bootstrap is a point
    assert plain(one_seed) == plain(
        {("train",): (4, 4, 1 / (1 + Z95**2 / 4), 1.0), ("light",): (0, 4, 0.0, 1 - 1 / (1 + Z95**2 / 4))}
    )
    # a group run at one seed beside groups at two (a method of a study made in parts): Wilson's interval, not its
    # union with the bootstrap over the study's seeds (1 success in 4 bootstraps down to 0, below Wilson's low end)
    part = [*rows, row("train", 0.25, method="rt1", seed=0, episodes=4, successes=1)]
    assert aggregate.pooled_success(part, ["method", "condition"])[("rt1", "train")] == (1, 4, *wilson_interval(1, 4))
    assert aggregate.pooled_success(rows[-2:], ["condition"]) == {}
    with pytest.raises(ValueError, match=r"pooled_success groups by columns of .*, got \['seed'\]"):
        aggregate.pooled_success(rows, ["seed"])


def test_pooled_success_groups_any_cell_columns_and_per_task_success_takes_train_and_single_factors():
    rows = [
        row("train", 1.0, seed=0, episodes=2, successes=2),
        row("train", 1.0, seed=0, task="t2", episodes=6, successes=6),
        row("light", 0.0, seed=0, episodes=2, successes=0),
        row("light", 0.0, seed=0, task="t2", episodes=2, successes=0),
        row(LC, 0.0, seed=0, episodes=2, successes=0),
        row("light", 1.0, seed=0, widths=WIDE, episodes=2, successes=2),
    ]
    by_condition = aggregate.pooled_success(rows, ["condition"])
    assert list(by_condition) == [("train",), ("light",), (LC,)]
    assert by_condition[("light",)][:2] == (2, 6)  # both tasks and both widths pooled
    shown = aggregate.per_task_success(rows, ["light"])
    assert list(shown) == [
        ("bc", "t1", 5, "train"),
        ("bc", "t2", 5, "train"),
        ("bc", "t1", 5, "light"),
        ("bc", "t2", 5, "light"),
    ]
    assert [v[:2] for v in shown.values()] == [(2, 2), (6, 6), (0, 2), (0, 2)]
    # the pooled rate of groups whose columns are not adjacent: train then light per task
    _, point, _ = aggregate._pooled_bootstrap(rows[:4], ["task"])
    np.testing.assert_array_equal(point, [2 / 4, 6 / 8])


def test_pooled_rho_interval_reranks_each_replicates_pooled_rates():
    reference = {"light": 3.0, "camera_pos": 2.0, "table_texture": 1.0}
    rows = [
        row("light", 1.0, seed=0, episodes=4, successes=4),
        row("camera_pos", 1.0, seed=0, episodes=4, successes=4),
        row("table_texture", 0.0, seed=0, episodes=4, successes=0),
        row("light", 1.0, seed=1, episodes=4, successes=4),
        row("camera_pos", 0.0, seed=1, episodes=4, successes=0),
        row("table_texture", 0.0, seed=1, episodes=4, successes=0),
        row("distractors", 0.5, seed=1, episodes=4, successes=2),  # not in the reference
        row("table_texture", 1.0, seed=1, task="t2", episodes=0),  # no episodes
    ]
    # seed 0 alone: 1, 1, 0 (rho 1.5 / sqrt(3)); seed 1 alone 1, 0, 0 (the same); both: 1, 0.5, 0 (rho 1)
    low, high = aggregate.pooled_rho_interval(rows, "condition", reference)
    assert (low, high) == (pytest.approx(1.5 / math.sqrt(3)), 1.0)
    two = [r for r in rows if r["condition"] != "camera_pos"]
    assert all(math.isnan(v) for v in aggregate.pooled_rho_interval(two, "condition", reference))


def test_the_change_over_three_n_is_the_largest_minus_the_smallest():
    rates = [(0, {"n": n}, {"train": 1.0, "light": 1.0 - gap}) for n, gap in ((5, 0.5), (50, 0.25), (500, 0.125))]
    found = aggregate.gap_against_n(runs(rates), "bc", ["light"])
    assert found.ns == [5, 50, 500]
    assert plain(found.gaps["light"]) == plain([(0.5, 0.5, 0.5), (0.25, 0.25, 0.25), (0.125, 0.125, 0.125)])
    assert plain(found.change) == plain({"light": (-0.375,) * 3, aggregate.ALL_FACTORS: (-0.375,) * 3})


def test_pair_bands_of_a_task_without_train_and_gaps_after_another_methods_pairs():
    rows = [
        *runs([(0, {"method": "aug"}, {"train": 1.0, "light": 0.5, "camera_pos": 0.5, LC: 0.25})]),
        row("light", 0.5),
        row("camera_pos", 0.5),
        row(LC, 0.5),  # no train row: no gaps, no interaction
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bands = aggregate.pair_bands(rows, "bc", 0.1)
    assert plain(bands) == plain({"t1": aggregate.PairBand(1, 0, 0, math.nan, (math.nan, math.nan), (1.0, 1.0))})


def test_a_cell_without_a_seeds_row_pools_nothing_and_warns_nothing():
    rows = [
        row("light", 1.0, seed=0, episodes=4, successes=4),
        row("light", 0.0, seed=1, episodes=4, successes=0),
        row("camera_pos", 1.0, seed=0, episodes=4, successes=4),  # no seed 1 row: light has no seed 2 row
        row("camera_pos", 1.0, seed=2, episodes=4, successes=4),
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pooled = aggregate.pooled_success(rows, ["condition"])
    # light: 1 when the seeds drawn with a row are seeds 0 only, 0 when 1 only (each about a quarter of the
    # replicates; a replicate of seed 2 alone has no light); camera_pos: every drawn row succeeds, so Wilson's
    assert plain(pooled) == plain({("light",): (4, 8, 0.0, 1.0), ("camera_pos",): (8, 8, 1 / (1 + Z95**2 / 8), 1.0)})


def test_a_condition_without_episodes_is_not_a_third_value_of_rho():
    reference = {"light": 3.0, "camera_pos": 2.0, "table_texture": 1.0}
    rows = [
        row("light", 1.0, seed=0, episodes=4, successes=4),
        row("table_texture", 0.0, seed=0, episodes=4, successes=0),
        row("camera_pos", 0.5, seed=0, episodes=0),
        row("distractors", 0.5, seed=0, episodes=4, successes=2),
    ]
    assert all(math.isnan(v) for v in aggregate.pooled_rho_interval(rows, "condition", reference))


def test_three_methods_share_only_the_factors_each_has():
    rt1 = [(s, {"method": "rt1"}, {"train": 1.0, "light": 0.5, "camera_pos": 0.75}) for s in (0, 1)]
    aug = [
        (s, {"method": "aug"}, {"train": 1.0, "light": 0.5, "camera_pos": 0.75, "table_texture": 0.5}) for s in (0, 1)
    ]
    rows = [*T1, *runs(aug), *runs(rt1)]
    found = aggregate.method_rho_differences(rows, ["bc", "aug", "rt1"], list(REFERENCE), REFERENCE)
    # each method against bc on the cells the two share: aug has three of bc's factors, rt1 two (no rho)
    assert set(found) == {"aug"}
    assert found["aug"] == aggregate.method_rho_differences(rows, ["bc", "aug"], list(REFERENCE), REFERENCE)["aug"]


# four seeds with unequal gaps: the percentile interval lies inside the seeds' range, so it moves if a seed is added
SEEDS4 = [
    (s, kw, {"train": 1.0, "light": lt, "camera_pos": cp, "table_texture": tt})
    for kw in ({}, {"method": "aug"})
    for s, (lt, cp, tt) in enumerate(
        [(0.125, 0.5, 0.75), (0.5, 0.25, 0.875), (0.25, 0.625, 0.5), (0.375, 0.875, 1.0)]
        if not kw
        else [(0.5, 0.25, 0.375), (0.75, 0.125, 0.5), (0.25, 0.5, 0.625), (0.875, 0.375, 0.25)]
    )
]
RADIUS4 = [
    row(c, rate, seed=s, widths=w, gap=None if c == "train" else 1.0 - rate, radius_m=radius)
    for s, (near, far) in enumerate([(0.875, 0.25), (0.5, 0.5), (0.75, 0.125), (0.625, 0.375)])
    for c, rate, w, radius in (
        ("train", 1.0, "default", None),
        ("camera_pos", near, "default", 0.025),
        ("train", 1.0, WIDE, None),
        ("camera_pos", far, WIDE, 0.075),
    )
]


def test_rows_of_other_methods_conditions_and_runs_do_not_move_an_interval():
    rows = runs(SEEDS4)
    other = [
        *runs(
            [
                (s, {"method": "rt1"}, {"train": 1.0, "light": 0.0, "camera_pos": 0.0, "table_texture": 0.0})
                for s in range(9, 15)
            ]
        ),
        row("distractors", 0.5, seed=8, gap=0.5),  # a condition of bc's not asked for
    ]
    labels = {"light": ["light"]}
    moved = aggregate.method_gap_differences([*rows, *other], ["bc", "aug"], labels)
    assert moved == aggregate.method_gap_differences(rows, ["bc", "aug"], labels)
    args = (["bc", "aug"], list(REFERENCE), REFERENCE)
    assert aggregate.method_rho_differences([*rows, *other], *args) == aggregate.method_rho_differences(rows, *args)
    slopes = aggregate.radius_slopes(RADIUS4, ["camera_pos"])
    unswept = row("train", 1.0, seed=7, n=50)  # the train row of a run without swept rows
    assert aggregate.radius_slopes([*RADIUS4, *other, unswept], ["camera_pos"]) == slopes
    # the slope: mean gaps 0.3125 at 0.025 m and 0.6875 at 0.075 m: 0.375 / 0.05 = 7.5 per metre
    assert slopes[("bc", "camera_pos")][0] == pytest.approx(7.5)


def test_method_rho_differences_resample_only_the_seeds_of_the_methods_compared():
    """Two seeds of bc and aug, and (placed first) rows of another method on a third seed: the bootstrap draws
    from bc's and aug's two seeds alone. Gaps light, camera_pos, table_texture: bc seed 0 0.75, 0.5, 0.125, seed
    1 0.25, 0.625, 0.125; aug seed 0 0.625, 0.5, 0.125, seed 1 0.25, 0.75, 0.125. With a share w of the seeds
    drawn being seed 0, light's gap exceeds camera_pos's (rho 1, else 0.5) where w > 0.6 for bc (0.25 w - 0.375
    (1 - w) > 0) and w > 0.8 for aug (0.125 w - 0.5 (1 - w) > 0). Two seeds give w = 0, 1/2 or 1: the two rhos
    are equal on every resample. A third seed drawn too would give w = 2/3 (seeds 0, 0, 1: bc 1, aug 0.5) in
    about 3 / 27 of the replicates, a difference of -0.5 inside the interval."""
    other = runs([(2, {"method": "rt1"}, {"train": 1.0, "light": 0.5})])
    bc = [
        (0, {}, {"train": 1.0, "light": 0.25, "camera_pos": 0.5, "table_texture": 0.875}),
        (1, {}, {"train": 1.0, "light": 0.75, "camera_pos": 0.375, "table_texture": 0.875}),
    ]
    aug = [
        (0, {"method": "aug"}, {"train": 1.0, "light": 0.375, "camera_pos": 0.5, "table_texture": 0.875}),
        (1, {"method": "aug"}, {"train": 1.0, "light": 0.75, "camera_pos": 0.25, "table_texture": 0.875}),
    ]
    found = aggregate.method_rho_differences([*other, *runs(bc), *runs(aug)], ["bc", "aug"], list(REFERENCE), REFERENCE)
    # the point (w = 1/2): both rank camera_pos, light, table_texture (rho 0.5); each rho is 0.5 at w = 0, 1 at w = 1
    assert plain(found) == plain({"aug": ((0.5, 0.5, 1.0), (0.0, 0.0, 0.0))})


def test_method_success_differences_set_each_method_s_p_t_against_the_first_on_the_train_cells_both_have():
    """P_T per method (mean over tasks and N per seed, then seeds) next to the first's, on the train cells both
    have: a cell only one method has, a shifted condition and a method not asked for change nothing."""
    train = [
        row("train", 0.8, seed=0),
        row("train", 0.6, seed=1),
        row("train", 0.4, method="rt1", seed=0),
        row("train", 0.2, method="rt1", seed=1),
        row("train", 0.9, method="rt1", seed=2),  # bc has no seed 2: left out
        row("light", 0.0, method="rt1", seed=0, gap=0.4),  # not a train cell
        row("train", 0.1, method="other", seed=0),
    ]
    found = aggregate.method_success_differences(train, ["bc", "rt1"])
    assert list(found) == ["rt1"]
    base, own, diff = found["rt1"]
    assert (base[0], own[0], diff[0]) == pytest.approx((0.7, 0.3, -0.4))
    assert base[1] <= 0.7 <= base[2] and own[1] <= 0.3 <= own[2] and diff[1] <= -0.4 <= diff[2]
    assert diff[1] < diff[2]  # two seeds: the seed bootstrap moves it
    assert aggregate.method_success_differences(train, ["bc"]) == {}
    assert aggregate.method_success_differences(train, ["bc", "absent"]) == {}
    # each method against the first: the third's P_T is compared with bc's, not with rt1's
    third = [{**r, "method": "aug", "success_rate": 1.0} for r in train if r["method"] == "bc"]
    both = aggregate.method_success_differences([*train, *third], ["bc", "rt1", "aug"])
    assert list(both) == ["rt1", "aug"] and both["rt1"] == found["rt1"]
    assert (both["aug"][0][0], both["aug"][2][0]) == pytest.approx((0.7, 0.3))
