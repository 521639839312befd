"""Verdicts on the paper's claims (study/results/claims.py) where mutation testing found the suite silent (docs/testing.md).

tests/test_claims.py checks each kind's four verdicts; the numbers a claims table prints were not checked. Here
every comparison of every kind (both trend directions, over N and over the radius, both pair relations) is
decided on synthetic rows whose per-seed statistic is computed by hand, and each field of its ``Decided`` is
checked against the module docstring's recipe: the point, the hull of the bootstrap's percentile interval and the
t-interval over seeds at Holm's level, the larger of the two p-values, the headroom the success rates leave, the
smallest effect the power code resolves, and the episodes and seeds that would resolve the observed effect.
Then the rows each comparison leaves out (other tasks and methods, factors without rows, rows without a gap), the
cells its smallest effect counts and the Holm level it is taken at, rows without their train rows (NaN, and no
warning), and which claims a study tests (its own, else the paper's ordering)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import stats

from lerobot_factorworld.stats import bootstrap, decision, power
from lerobot_factorworld.study.plan.claim_config import ClaimConfig
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.results import claims
from lerobot_factorworld.study.results.claims import AGREES, CAPPED, DISAGREES, NOT_RESOLVED, Decided, decide

SEEDS = (0, 1, 2, 3, 4)
EPISODES = 100
WIDTHS = {"default": 0.025, "camera_pos=medium": 0.05, "camera_pos=wide": 0.075}


@pytest.fixture(scope="module")
def cfg() -> StudyConfig:
    return StudyConfig(
        name="synthetic",
        tasks=["door-open", "pick-place"],
        seeds=list(SEEDS),
        factors=["camera_pos", "table_pos", "light"],
        pairs=["camera_pos+light"],
        methods=[MethodConfig("bc", {"type": "bc"}), MethodConfig("bc_shift", {"type": "bc", "augmentation": "shift"})],
    )


def rows_of(rates: dict, method="bc", task="door-open", n=5, widths="default", radius=None, episodes=EPISODES):
    """results.csv rows of one method x task x N x widths: ``rates[condition]`` has one success rate per seed
    (``train`` included); ``radius`` is the row's radius_m for single-factor rows of camera_pos."""
    out = []
    for s, seed in enumerate(SEEDS):
        p_train = rates["train"][s]
        for condition, per_seed in rates.items():
            rate = per_seed[s]
            out.append(
                {
                    "method": method,
                    "task": task,
                    "n_train_envs": n,
                    "seed": seed,
                    "widths": widths,
                    "condition": condition,
                    "n_factors": 0 if condition == "train" else condition.count("+") + 1,
                    "radius_m": radius if condition == "camera_pos" else None,
                    "episodes": episodes,
                    "successes": round(rate * episodes),
                    "success_rate": rate,
                    "gap": p_train - rate,
                }
            )
    return out


def claim(kind: str, **settings) -> ClaimConfig:
    return ClaimConfig(kind=kind, text=f"a {kind} claim", source="test", **settings)


def z_at(level: float) -> float:
    return float(stats.norm.ppf(1 - (1 - level) / 2))


def episodes_needed(resolvable, effect: float, z: float) -> float:
    e = 1
    while e <= decision.MAX_EPISODES:
        if resolvable(e, z) <= effect:
            return float(e)
        e = max(e + 1, math.ceil(e * 1.1))
    return math.nan


def check(
    d: Decided,
    comparison,
    *,
    label,
    threshold,
    sign,
    point,
    per_seed,
    headroom,
    resolvable,
    verdict,
    level,
    episodes=EPISODES,
):
    """``d`` against the recipe, from ``per_seed`` (the statistic on each seed alone, by hand) and the bootstrap's
    replicates of ``comparison``'s statistic (its point is checked against the hand-computed one first)."""
    per_seed = np.asarray(per_seed, dtype=float)
    s, mean, sd = len(per_seed), float(per_seed.mean()), float(per_seed.std(ddof=1))
    own_point, reps = comparison.table.bootstrap(comparison.statistic)
    assert (d.label, d.threshold, d.sign, d.seeds, d.level) == (label, threshold, sign, s, pytest.approx(level))
    assert d.point == pytest.approx(point, abs=1e-12) and float(own_point) == pytest.approx(point, abs=1e-12)
    assert d.headroom == pytest.approx(headroom, abs=1e-12)
    low, high = (float(v) for v in bootstrap.percentile_interval(reps, level=level))
    half = stats.t.ppf(1 - (1 - level) / 2, df=s - 1) * sd / math.sqrt(s)
    assert d.bootstrap == pytest.approx((low, high), abs=1e-12)
    assert (d.low, d.high) == pytest.approx((min(low, mean - half), max(high, mean + half)), abs=1e-12)
    x = reps[np.isfinite(reps)] - threshold
    p_boot = min(1.0, 2 * (min(np.sum(x <= 0), np.sum(x >= 0)) + 1) / (x.size + 1))
    p_t = 2 * stats.t.sf(abs(mean - threshold) / (sd / math.sqrt(s)), df=s - 1) if sd else float(mean != threshold)
    assert d.p_value == pytest.approx(max(p_boot, p_t), abs=1e-12)
    z = z_at(level)
    assert d.smallest == pytest.approx(resolvable(episodes, z), abs=1e-12, nan_ok=True)
    effect = abs(d.point - threshold)
    assert d.episodes_needed == pytest.approx(episodes_needed(resolvable, effect, z), nan_ok=True)
    seeds = next(
        (n for n in range(2, 1001) if stats.t.ppf(1 - (1 - level) / 2, n - 1) * sd / math.sqrt(n) < effect), None
    )
    assert d.seeds_needed == (float(seeds) if seeds else pytest.approx(math.nan, nan_ok=True))
    assert d.verdict == verdict


def decide_one(c: ClaimConfig, cfg: StudyConfig, rows: list[dict]):
    (found,) = decide([c], cfg, rows)
    return found, claims.comparisons(c, cfg, rows)


TRAIN = [0.9, 0.85, 0.95, 0.9, 0.88]
CAMERA = [0.4, 0.5, 0.45, 0.55, 0.5]
LIGHT = [0.8, 0.7, 0.85, 0.75, 0.8]


def test_a_gap_that_opens(cfg):
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT})
    found, (c,) = decide_one(claim("gap_opens", factors=["camera_pos"]), cfg, rows)
    gaps = np.subtract(TRAIN, CAMERA)
    p_train = np.mean(TRAIN)  # pooled over seeds of equal episode counts
    check(found.comparisons[0], c, label="camera_pos", threshold=0.0, sign=1, point=gaps.mean(), per_seed=gaps,
          headroom=p_train, resolvable=lambda e, z: power.mean_resolvable_gap(max(1, round(5 * e)), p_train, z),
          verdict=AGREES, level=0.95)  # fmt: skip
    assert found.verdict == AGREES and found.summary == found.comparisons[0]


def test_a_gap_that_exceeds_another_and_the_ordering_that_says_so(cfg):
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT})
    diff = np.subtract(TRAIN, CAMERA) - np.subtract(TRAIN, LIGHT)  # = LIGHT - CAMERA per seed
    p = np.mean(CAMERA + LIGHT)
    expected = dict(
        label="camera_pos - light", threshold=0.0, sign=1, point=diff.mean(), per_seed=diff,
        headroom=np.mean(TRAIN) - np.mean(np.subtract(TRAIN, LIGHT)),  # camera_pos's P_T minus light's gap
        resolvable=lambda e, z: power.difference_resolvable(max(1, round(5 * e)), p, z), verdict=AGREES, level=0.95,
    )  # fmt: skip
    for c in (
        claim("gap_exceeds", factors=["camera_pos", "light"]),
        claim("ordering", tiers=[["camera_pos"], ["light"]]),
    ):
        found, (comparison,) = decide_one(c, cfg, rows)
        check(found.comparisons[0], comparison, **expected)


def test_a_method_that_shrinks_the_gap(cfg):
    shift = [0.7, 0.75, 0.8, 0.7, 0.72]
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA}) + rows_of({"train": TRAIN, "camera_pos": shift}, "bc_shift")
    c = claim("method_shrinks", factors=["camera_pos"], method="bc_shift", baseline="bc")
    found, (comparison,) = decide_one(c, cfg, rows)
    diff = np.subtract(TRAIN, shift) - np.subtract(TRAIN, CAMERA)
    p = np.mean(shift + CAMERA)
    check(found.comparisons[0], comparison, label="bc_shift - bc on camera_pos", threshold=0.0, sign=-1,
          point=diff.mean(), per_seed=diff, headroom=np.mean(np.subtract(TRAIN, CAMERA)),  # bc's gap: the most to shrink
          resolvable=lambda e, z: power.difference_resolvable(max(1, round(5 * e)), p, z), verdict=AGREES, level=0.95)  # fmt: skip


@pytest.mark.parametrize(("direction", "verdict"), [("shrinks", AGREES), ("grows", DISAGREES)])
def test_a_trend_over_n(cfg, direction, verdict):
    small, large = [0.5, 0.4, 0.55, 0.45, 0.5], [0.8, 0.75, 0.9, 0.8, 0.85]  # table_pos at N = 5 and N = 20
    rows = rows_of({"train": TRAIN, "table_pos": small}, n=5) + rows_of({"train": TRAIN, "table_pos": large}, n=20)
    found, (c,) = decide_one(claim("trend", factors=["table_pos"], over="n", direction=direction), cfg, rows)
    change = np.subtract(TRAIN, large) - np.subtract(TRAIN, small)  # the gap at the largest N minus the smallest's
    start = np.mean(np.subtract(TRAIN, small))
    p = np.mean(small + large)
    check(found.comparisons[0], c, label="table_pos over N", threshold=0.0, sign=-1 if direction == "shrinks" else 1,
          point=change.mean(), per_seed=change, headroom=start if direction == "shrinks" else np.mean(TRAIN) - start,
          resolvable=lambda e, z: power.difference_resolvable(max(1, round(5 * e)), p, z), verdict=verdict, level=0.95)  # fmt: skip


@pytest.mark.parametrize(("direction", "verdict"), [("grows", AGREES), ("shrinks", DISAGREES)])
def test_a_trend_over_the_radius(cfg, direction, verdict):
    per_radius = {
        0.025: [0.8, 0.75, 0.85, 0.8, 0.78],
        0.05: [0.6, 0.55, 0.7, 0.6, 0.6],
        0.075: [0.4, 0.4, 0.5, 0.35, 0.45],
    }
    rows = [
        r
        for (w, rad) in WIDTHS.items()
        for r in rows_of({"train": TRAIN, "camera_pos": per_radius[rad]}, widths=w, radius=rad)
    ]
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA}, method="bc_shift")  # another method's rows: left out
    c = claim("trend", factors=["camera_pos"], over="radius", direction=direction)
    found, (comparison,) = decide_one(c, cfg, rows)
    radii = np.array(list(per_radius))
    gaps = np.array([np.subtract(TRAIN, per_radius[r]) for r in radii])  # (radius, seed)
    dx = radii - radii.mean()
    slopes = (dx @ (gaps - gaps.mean(axis=0))) / (dx @ dx) * 0.025  # least squares per seed, per radius step
    start = gaps[0].mean()
    p = np.mean(per_radius[0.075])
    headroom = (start if direction == "shrinks" else np.mean(TRAIN) - start) / 2  # over the two steps
    check(found.comparisons[0], comparison, label="camera_pos over the radius (per radius step)", threshold=0.0,
          sign=-1 if direction == "shrinks" else 1, point=slopes.mean(), per_seed=slopes, headroom=headroom,
          resolvable=lambda e, z: power.slope_resolvable(max(1, round(5 * e)), list(radii), p, z) * 0.025,
          verdict=verdict, level=0.95)  # fmt: skip


PAIR_EPISODES = 2000


def _pair_rows(pair: list[float]) -> list[dict]:
    rates = {"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT, "camera_pos+light": pair}
    other = {"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT, "camera_pos+light": [0.1] * 5}
    # another task, left out by the claim's task
    return rows_of(rates, episodes=PAIR_EPISODES) + rows_of(other, task="pick-place", episodes=PAIR_EPISODES)


def _pair_metric(pair, a, b):
    harder = np.minimum(a, b)
    return (np.asarray(pair) - harder) / harder


def test_a_pair_within_the_band_and_a_synergistic_pair(cfg):
    pair = [0.41, 0.5, 0.46, 0.54, 0.5]
    rows = _pair_rows(pair)
    per_seed = _pair_metric(pair, CAMERA, LIGHT)
    point = float(_pair_metric(np.mean(pair), np.mean(CAMERA), np.mean(LIGHT)))  # the metric of the pooled rates
    p_min = np.mean(CAMERA)

    def resolvable(e, z):
        return power.pair_metric_resolvable(max(1, round(5 * e)), p_min, z)

    within = claim("pair", pair="camera_pos+light", relation="within", task="door-open", tolerance=0.1)
    found, (upper, lower) = decide_one(within, cfg, rows)
    by_label = {d.label: d for d in found.comparisons}
    # Holm over the two: the smaller p-value is decided at 1 - 0.05 / 2, the other at 0.95
    first, second = sorted(found.comparisons, key=lambda d: d.p_value)
    assert (first.level, second.level) == (pytest.approx(0.975), pytest.approx(0.95))
    check(by_label["camera_pos+light metric < +0.1"], upper, label="camera_pos+light metric < +0.1", threshold=0.1,
          sign=-1, point=point, per_seed=per_seed, headroom=1.1, resolvable=resolvable, episodes=PAIR_EPISODES,
          verdict=AGREES, level=by_label["camera_pos+light metric < +0.1"].level)  # fmt: skip
    check(by_label["camera_pos+light metric > -0.1"], lower, label="camera_pos+light metric > -0.1", threshold=-0.1,
          sign=1, point=point, per_seed=per_seed, headroom=math.inf, resolvable=resolvable, episodes=PAIR_EPISODES,
          verdict=AGREES, level=by_label["camera_pos+light metric > -0.1"].level)  # fmt: skip
    assert found.verdict == AGREES

    synergistic = claim("pair", pair="camera_pos+light", relation="synergistic", task="door-open", tolerance=0.1)
    worse = [0.2, 0.25, 0.15, 0.2, 0.22]
    found, (c,) = decide_one(synergistic, cfg, _pair_rows(worse))
    check(found.comparisons[0], c, label="camera_pos+light metric < -0.1", threshold=-0.1, sign=-1,
          point=float(_pair_metric(np.mean(worse), np.mean(CAMERA), np.mean(LIGHT))),
          per_seed=_pair_metric(worse, CAMERA, LIGHT), headroom=0.9, resolvable=resolvable, verdict=AGREES, level=0.95,
          episodes=PAIR_EPISODES)  # fmt: skip


def test_a_pair_without_its_rows_has_no_comparison(cfg):
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT})
    (found,) = decide([claim("pair", pair="camera_pos+light")], cfg, rows)
    assert found.comparisons == [] and found.verdict == NOT_RESOLVED and found.summary is None


def test_the_papers_ordering_claims_name_their_source():
    stated, fig3a = claims.ordering_claims(["camera_pos", "table_pos", "light", "floor_texture"])
    assert (stated.text, stated.source, stated.tiers) == (
        "the factor ordering, the text's tiers",
        "section 5.1 (text)",
        [["camera_pos", "table_pos"], ["floor_texture"], ["light"]],
    )
    assert (fig3a.text, fig3a.source, fig3a.tiers) == (
        "the factor ordering, Fig. 3a's tiers (our reading)",
        "section 5.1, Fig. 3a",
        [["camera_pos"], ["table_pos"], ["floor_texture"], ["light"]],
    )
    assert claims.ordering_claims(["light", "distractors"]) == []  # one tier: nothing to order
    assert CAPPED in claims.VERDICTS


# --- the rows each comparison leaves out, the cells it counts, and the level its smallest effect is taken at -------


def test_a_trend_over_n_compares_the_factors_smallest_and_largest_n_of_its_task(cfg):
    """Two factors at N = 5, 10 and 20 of the claim's task: their mean gap at N = 20 minus that at N = 5. Left out
    (and placed first): another task's rows, and an N (50) where only the train suite and another factor ran."""
    light = {5: [0.6, 0.55, 0.7, 0.6, 0.6], 10: [0.7, 0.7, 0.75, 0.7, 0.65], 20: [0.85, 0.8, 0.9, 0.85, 0.8]}
    table_pos = {5: [0.5, 0.4, 0.55, 0.45, 0.5], 10: [0.6, 0.6, 0.7, 0.65, 0.6], 20: [0.8, 0.75, 0.9, 0.8, 0.85]}
    rows = [
        r
        for n in (5, 20)
        for r in rows_of({"train": TRAIN, "table_pos": CAMERA, "light": CAMERA}, task="pick-place", n=n)
    ]
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA}, n=50)
    rows += [
        r for n in (5, 10, 20) for r in rows_of({"train": TRAIN, "table_pos": table_pos[n], "light": light[n]}, n=n)
    ]
    c = claim("trend", factors=["table_pos", "light"], over="n", direction="shrinks", task="door-open")
    found, (comparison,) = decide_one(c, cfg, rows)
    gap = {n: (np.subtract(TRAIN, table_pos[n]) + np.subtract(TRAIN, light[n])) / 2 for n in (5, 20)}  # per seed
    change = gap[20] - gap[5]  # = (table_pos + light at 5 - the same at 20) / 2: -0.275, -0.3, -0.275, -0.3, -0.275
    p = np.mean(table_pos[5] + light[5] + table_pos[20] + light[20])  # the four cells, pooled over equal episodes
    check(found.comparisons[0], comparison, label="table_pos + light over N", threshold=0.0, sign=-1,
          point=change.mean(), per_seed=change, headroom=gap[5].mean(),  # the gap at N = 5: the most it can shrink
          resolvable=lambda e, z: power.difference_resolvable(max(1, round(10 * e)), p, z),  # 2 factors x 5 seeds
          verdict=AGREES, level=0.95)  # fmt: skip


PICK_TRAIN = [0.8, 0.85, 0.9, 0.8, 0.85]


@pytest.mark.parametrize("wider", [20, 5])
def test_a_trend_over_n_compares_only_the_cells_both_ends_have(cfg, wider):
    """table_pos at N = 5 and 20 on door-open, and on pick-place at N = ``wider`` only: pick-place has no cell at
    the other end, so the change is door-open's alone (a task at one N would compare tasks, not N), with door-open's
    5 cells per side and its P_T."""
    small, large = [0.5, 0.4, 0.55, 0.45, 0.5], [0.8, 0.75, 0.9, 0.8, 0.85]
    pick = [0.7, 0.65, 0.8, 0.75, 0.7]
    rows = rows_of({"train": TRAIN, "table_pos": small}, n=5) + rows_of({"train": TRAIN, "table_pos": large}, n=20)
    rows += rows_of({"train": PICK_TRAIN, "table_pos": pick}, task="pick-place", n=wider)
    found, (c,) = decide_one(claim("trend", factors=["table_pos"], over="n", direction="shrinks"), cfg, rows)
    change = np.subtract(TRAIN, large) - np.subtract(TRAIN, small)  # per seed: 0.5 - 0.8 = -0.3 on seed 0
    p = np.mean(small + large)  # two cells of five seeds each, equal episodes
    check(found.comparisons[0], c, label="table_pos over N", threshold=0.0, sign=-1, point=change.mean(),
          per_seed=change, headroom=np.subtract(TRAIN, small).mean(),
          resolvable=lambda e, z: power.difference_resolvable(max(1, round(5 * e)), p, z), verdict=AGREES,
          level=0.95)  # fmt: skip
    assert found.comparisons[0].cells == 4 * 5  # train and table_pos at both N, five seeds


PER_RADIUS = {0.025: [0.8, 0.75, 0.85, 0.8, 0.78], 0.05: [0.6, 0.55, 0.7, 0.6, 0.6], 0.075: [0.4, 0.4, 0.5, 0.35, 0.45]}


def _radius_expected(direction: str, per_radius: dict) -> dict:
    """``check``'s expectations for a camera_pos trend over the radius of one task at N = 5 (TRAIN at every width)."""
    radii = np.array(list(per_radius))
    gaps = np.array([np.subtract(TRAIN, per_radius[r]) for r in radii])  # (radius, seed)
    dx = radii - radii.mean()
    slopes = (dx @ (gaps - gaps.mean(axis=0))) / (dx @ dx) * 0.025  # least squares per seed, per radius step
    start, span, p = gaps[0].mean(), len(radii) - 1, np.mean(per_radius[radii[-1]])
    return dict(
        label="camera_pos over the radius (per radius step)", threshold=0.0, sign=-1 if direction == "shrinks" else 1,
        point=slopes.mean(), per_seed=slopes, headroom=(start if direction == "shrinks" else np.mean(TRAIN) - start) / span,
        resolvable=lambda e, z: power.slope_resolvable(max(1, round(5 * e)), list(radii), p, z) * 0.025, level=0.95,
    )  # fmt: skip


def test_a_trend_over_the_radius_leaves_out_other_tasks_other_methods_and_rows_without_a_gap(cfg):
    """The sweep of the claim's task and method, as in ``test_a_trend_over_the_radius``; placed first and left
    out: the same sweep of another task and of another method (evaluated on 2000 episodes, enough to move the
    median episode count of the table if they were in it), and a run at N = 20 whose shifted rows have no gap (its
    train suite ran on other episode seeds)."""
    rows = [
        r
        for (w, rad) in WIDTHS.items()
        for r in rows_of({"train": PICK_TRAIN, "camera_pos": [0.7, 0.8, 0.75, 0.7, 0.8]}, task="pick-place",
                         widths=w, radius=rad, episodes=2000)
        + rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT}, method="bc_shift", widths=w, radius=rad,
                  episodes=2000)
    ]  # fmt: skip
    no_gap = rows_of({"train": TRAIN, "camera_pos": [0.1] * 5}, n=20, widths="camera_pos=wide", radius=0.075)
    rows += [{**r, "gap": None} if r["condition"] == "camera_pos" else r for r in no_gap]
    rows += [
        r
        for (w, rad) in WIDTHS.items()
        for r in rows_of({"train": TRAIN, "camera_pos": PER_RADIUS[rad]}, widths=w, radius=rad)
    ]
    c = claim("trend", factors=["camera_pos"], over="radius", direction="grows", task="door-open")
    found, (comparison,) = decide_one(c, cfg, rows)
    # what's left is the other test's sweep alone: 100 episodes per cell (the N = 20 train cells' count too)
    check(found.comparisons[0], comparison, verdict=AGREES, **_radius_expected("grows", PER_RADIUS))


def test_a_trend_over_two_radii_is_the_change_over_one_step(cfg):
    """Two radii are enough for a slope: the gap at the wider one minus that at the narrower, over one step."""
    two = {r: PER_RADIUS[r] for r in (0.025, 0.05)}
    widths = {"default": 0.025, "camera_pos=medium": 0.05}
    rows = [
        r
        for (w, rad) in widths.items()
        for r in rows_of({"train": TRAIN, "camera_pos": two[rad]}, widths=w, radius=rad)
    ]
    c = claim("trend", factors=["camera_pos"], over="radius", direction="grows")
    found, (comparison,) = decide_one(c, cfg, rows)
    expected = _radius_expected("grows", two)
    # the slope per step of two points is their difference: (0.8 - 0.6, 0.75 - 0.55, ...) = 0.2, 0.2, 0.15, 0.2, 0.18
    assert expected["per_seed"] == pytest.approx(np.subtract(two[0.025], two[0.05]), abs=1e-12)
    check(found.comparisons[0], comparison, verdict=AGREES, **expected)


def test_the_smallest_effect_is_taken_at_the_comparisons_own_holm_level(cfg):
    """A gap, a trend over N and a trend over the radius decided with a null comparison (light's gap is exactly 0
    on every seed: p = 1, ranked last at 0.95): Holm decides the three at 1 - 0.05 / 4, / 3 and / 2, and each
    one's smallest resolvable effect is the power code's at that level's z, not at 95%'s."""
    small, large = [0.5, 0.4, 0.55, 0.45, 0.5], [0.8, 0.75, 0.9, 0.8, 0.85]
    rows = rows_of({"train": TRAIN, "camera_pos": PER_RADIUS[0.025], "table_pos": small, "light": TRAIN}, radius=0.025)
    rows += rows_of({"train": TRAIN, "table_pos": large}, n=20)
    for w, rad in list(WIDTHS.items())[1:]:
        rows += rows_of({"train": TRAIN, "camera_pos": PER_RADIUS[rad]}, widths=w, radius=rad)
    found = decide(
        [
            claim("gap_opens", factors=["camera_pos"]),
            claim("trend", factors=["table_pos"], over="n", direction="shrinks"),
            claim("trend", factors=["camera_pos"], over="radius", direction="grows"),
            claim("gap_opens", factors=["light"]),
        ],
        cfg,
        rows,
    )
    (gap,), (over_n,), (over_radius,), (null,) = (v.comparisons for v in found)
    assert (null.p_value, null.level) == (1.0, pytest.approx(0.95))
    assert sorted(d.level for d in (gap, over_n, over_radius)) == pytest.approx(
        [1 - 0.05 / 2, 1 - 0.05 / 3, 1 - 0.05 / 4]
    )
    radii = list(PER_RADIUS)
    # 5 seeds x 100 episodes per side; P_T for the gap, the four cells' rate for N, the widest radius's for the slope
    assert gap.smallest == pytest.approx(power.mean_resolvable_gap(500, np.mean(TRAIN), z_at(gap.level)), abs=1e-12)
    p_n = np.mean(small + large)
    assert over_n.smallest == pytest.approx(power.difference_resolvable(500, p_n, z_at(over_n.level)), abs=1e-12)
    p_r, z_r = np.mean(PER_RADIUS[0.075]), z_at(over_radius.level)
    assert over_radius.smallest == pytest.approx(power.slope_resolvable(500, radii, p_r, z_r) * 0.025, abs=1e-12)


ALL, NONE, HALF = [1.0] * 5, [0.0] * 5, [0.5] * 5


def _first_seed(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["seed"] == SEEDS[0]]


def _two_episodes(condition: str, **where) -> list[dict]:
    """``condition``'s row of one success in two episodes (train: one of one), without its train row."""
    rows = rows_of({"train": ALL, condition: HALF}, episodes=2, **where)
    return [r for r in _first_seed(rows) if r["condition"] == condition]


ONE_EPISODE = {  # one seed, one episode per cell (two in one cell of the pair and of the sweep, for a rate of 0.5)
    # a gap of 1 at P_T = 1 over one episode pair
    "gap": (
        claim("gap_opens", factors=["camera_pos"]),
        lambda: rows_of({"train": ALL, "camera_pos": NONE}, episodes=1),
        lambda z: power.mean_resolvable_gap(1, 1.0, z),
    ),
    # the gap closes from 1 at N = 5 to 0 at N = 20: the two cells' rate is (0 + 1) / 2
    "over N": (
        claim("trend", factors=["table_pos"], over="n", direction="shrinks"),
        lambda: (
            rows_of({"train": ALL, "table_pos": NONE}, episodes=1)
            + rows_of({"train": ALL, "table_pos": ALL}, episodes=1, n=20)
        ),
        lambda z: power.difference_resolvable(1, 0.5, z),
    ),
    # camera_pos succeeds at 0.025, fails at 0.05, succeeds once in two at 0.075 (median of 1, 1, 1, 1, 1, 2: 1)
    "over the radius": (
        claim("trend", factors=["camera_pos"], over="radius", direction="grows"),
        lambda: (
            rows_of({"train": ALL, "camera_pos": ALL}, episodes=1, radius=0.025)
            + rows_of({"train": ALL, "camera_pos": NONE}, episodes=1, widths="camera_pos=medium", radius=0.05)
            + rows_of({"train": ALL}, episodes=1, widths="camera_pos=wide")
            + _two_episodes("camera_pos", widths="camera_pos=wide", radius=0.075)
        ),
        lambda z: power.slope_resolvable(1, list(PER_RADIUS), 0.5, z) * 0.025,
    ),
    # camera_pos fails, light succeeds: the two cells' rate is (0 + 1) / 2
    "difference": (
        claim("gap_exceeds", factors=["camera_pos", "light"]),
        lambda: rows_of({"train": ALL, "camera_pos": NONE, "light": ALL}, episodes=1),
        lambda z: power.difference_resolvable(1, 0.5, z),
    ),
    # light, the harder factor, succeeds once in two: P_min 0.5 (median count of 1, 1, 1, 2: 1)
    "pair": (
        claim("pair", pair="camera_pos+light", relation="synergistic"),
        lambda: (
            rows_of({"train": ALL, "camera_pos": ALL, "camera_pos+light": NONE}, episodes=1) + _two_episodes("light")
        ),
        lambda z: power.pair_metric_resolvable(1, 0.5, z),
    ),
}


@pytest.mark.parametrize("kind", list(ONE_EPISODE))
def test_one_seed_of_one_episode_per_cell_resolves_what_one_episode_pair_does(cfg, kind):
    """One seed (so no interval), one cell per side of one episode: the smallest effect is the power code's for
    one episode pair, not two."""
    c, make_rows, resolvable = ONE_EPISODE[kind]
    (found,) = decide([c], cfg, _first_seed(make_rows()))
    (d,) = found.comparisons
    assert (d.seeds, d.level, d.low) == (1, pytest.approx(0.95), pytest.approx(math.nan, nan_ok=True))
    assert d.smallest == pytest.approx(resolvable(z_at(0.95)), abs=1e-12)


def test_a_pair_run_on_some_of_the_tasks_of_its_factors_has_no_comparison(cfg):
    """camera_pos and light on both tasks, their pair on door-open alone: the cells do not line up (2, 2, 1), so
    there is no comparison; nor for a method without any rows."""
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT}, task="pick-place")
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT, "camera_pos+light": CAMERA})
    for c in (claim("pair", pair="camera_pos+light"), claim("pair", pair="camera_pos+light", method="bc_shift")):
        (found,) = decide([c], cfg, rows)
        assert (found.comparisons, found.verdict) == ([], NOT_RESOLVED)


def test_a_pairs_smallest_effect_is_at_the_harder_factor_whichever_is_named_second(cfg):
    """The pair's second factor (light) is the harder: P_min is light's rate, 0.48, not camera_pos's 0.78 (nor the
    table's mean rate, (0.896 + 0.78 + 0.48 + 0.204) / 4 = 0.59)."""
    worse = [0.2, 0.25, 0.15, 0.2, 0.22]
    rates = {"train": TRAIN, "camera_pos": LIGHT, "light": CAMERA, "camera_pos+light": worse}
    c = claim("pair", pair="camera_pos+light", relation="synergistic", task="door-open", tolerance=0.1)
    found, (comparison,) = decide_one(c, cfg, rows_of(rates, episodes=PAIR_EPISODES))
    p_min = np.mean(CAMERA)
    check(found.comparisons[0], comparison, label="camera_pos+light metric < -0.1", threshold=-0.1, sign=-1,
          point=float(_pair_metric(np.mean(worse), np.mean(LIGHT), np.mean(CAMERA))),
          per_seed=_pair_metric(worse, LIGHT, CAMERA), headroom=0.9,
          resolvable=lambda e, z: power.pair_metric_resolvable(max(1, round(5 * e)), p_min, z), verdict=AGREES,
          level=0.95, episodes=PAIR_EPISODES)  # fmt: skip


def test_a_pair_is_matched_to_its_factors_cell_by_cell_whatever_order_the_rows_come_in(cfg):
    """Pair rows of pick-place seen before door-open's rows (a merged or hand-made results file): each task's
    pair is still compared with that task's factors. door-open: pair 0.3 against camera_pos 0.5 and light 0.8,
    metric (0.3 - 0.5) / 0.5 = -0.4; pick-place: pair 0.6 against 0.7 and 0.9, (0.6 - 0.7) / 0.7 = -1/7; the
    point is their mean, -0.2714. Matched by position in first-seen order, the pair of one task met the other's."""
    door = {"train": [0.95] * 5, "camera_pos": [0.5] * 5, "light": [0.8] * 5, "camera_pos+light": [0.3] * 5}
    pick = {"train": [0.95] * 5, "camera_pos": [0.7] * 5, "light": [0.9] * 5, "camera_pos+light": [0.6] * 5}
    rows_door, rows_pick = rows_of(door), rows_of(pick, task="pick-place")
    in_plan_order = rows_door + rows_pick
    is_pair = [r["condition"] == "camera_pos+light" for r in rows_pick]
    pair_first = (
        [r for r, p in zip(rows_pick, is_pair) if p] + rows_door + [r for r, p in zip(rows_pick, is_pair) if not p]
    )
    c = claim("pair", pair="camera_pos+light", relation="within", tolerance=0.06)
    expected = (-0.4 - 1 / 7) / 2
    for rows in (in_plan_order, pair_first):
        (found,) = decide([c], cfg, rows)
        assert found.comparisons[0].point == pytest.approx(expected, abs=1e-12)


def test_a_claim_on_rows_without_episode_counts_is_decided_without_a_resolvable_effect(cfg):
    """Rows whose episode counts are unknown (0) still give a point and a seed-level interval; the smallest
    resolvable effect needs counts, so it is NaN (it raised on round(NaN))."""
    rows = rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT}, episodes=0)
    for row in rows:
        row["successes"] = None
    (found,) = decide([claim("gap_opens", factors=["camera_pos"])], cfg, rows)
    (comparison,) = found.comparisons
    assert comparison.point == pytest.approx(float(np.mean(np.subtract(TRAIN, CAMERA))), abs=1e-12)
    assert math.isnan(comparison.smallest)


def test_a_gap_claim_leaves_out_shifted_rows_without_a_gap(cfg):
    """``test_a_gap_that_opens``'s rows, after (placed first) a run at N = 20 whose camera_pos rows have no gap (its
    train suite ran on other episode seeds): those cells are left out, as the gap summaries leave them out, though
    their train cells are in the table (their gap from the rates would be 0.5 - 0.1 = 0.4 on every seed)."""
    no_gap = rows_of({"train": [0.5] * 5, "camera_pos": [0.1] * 5}, n=20)
    rows = [{**r, "gap": None} if r["condition"] == "camera_pos" else r for r in no_gap]
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT})
    found, (c,) = decide_one(claim("gap_opens", factors=["camera_pos"]), cfg, rows)
    gaps = np.subtract(TRAIN, CAMERA)  # N = 5 alone: 0.5, 0.35, 0.5, 0.35, 0.38
    p_train = np.mean(TRAIN)  # P_T of the cells compared: N = 5's train cells alone
    check(found.comparisons[0], c, label="camera_pos", threshold=0.0, sign=1, point=gaps.mean(), per_seed=gaps,
          headroom=p_train, resolvable=lambda e, z: power.mean_resolvable_gap(max(1, round(5 * e)), p_train, z),
          verdict=AGREES, level=0.95)  # fmt: skip


THIN_TABLE = [0.6, 0.55, 0.65, 0.6, 0.6]  # table_pos on door-open: mean 0.6
PICK_CAMERA, PICK_LIGHT = [0.3, 0.4, 0.35, 0.45, 0.4], [0.7, 0.75, 0.7, 0.8, 0.75]  # means 0.38 and 0.74


def test_an_orderings_differences_pair_the_factors_with_rows_each_resolving_its_thinner_side_at_its_holm_level():
    """Tiers [camera_pos, distractors] > [table_pos] > [light]: distractors has no rows of the claim's method (only
    another method's, placed first and left out, as is that method's table_pos on pick-place), so its two
    differences are left out and three remain. camera_pos and light ran on both tasks (10 cells of 5 seeds each),
    table_pos on door-open alone (5): each difference's smallest resolvable effect is that of its thinner side's
    cells (5 per side whether table_pos is the first or the second factor), at the Holm level it is decided at."""
    study = StudyConfig(
        name="synthetic", tasks=["door-open", "pick-place"], seeds=list(SEEDS),
        factors=["camera_pos", "table_pos", "light", "distractors"], methods=[MethodConfig("bc", {"type": "bc"})],
    )  # fmt: skip
    shift = {"train": TRAIN, "table_pos": CAMERA, "distractors": CAMERA}
    rows = rows_of(shift, method="bc_shift", task="pick-place") + rows_of(shift, method="bc_shift")
    rows += rows_of({"train": TRAIN, "camera_pos": CAMERA, "table_pos": THIN_TABLE, "light": LIGHT})
    rows += rows_of({"train": PICK_TRAIN, "camera_pos": PICK_CAMERA, "light": PICK_LIGHT}, task="pick-place")
    c = claim("ordering", tiers=[["camera_pos", "distractors"], ["table_pos"], ["light"]])
    (found,) = decide([c], study, rows)
    decided = {d.label: d for d in found.comparisons}
    assert list(decided) == ["camera_pos - table_pos", "camera_pos - light", "table_pos - light"]
    assert sorted(d.level for d in decided.values()) == pytest.approx([0.95, 1 - 0.05 / 2, 1 - 0.05 / 3])
    # (cells per side, pooled rate of the cells compared: each cell's mean over its 5 seeds of 100 episodes)
    expected = {
        "camera_pos - table_pos": (5, (0.48 + 0.38 + 0.6) / 3),  # min(10, 5)
        "camera_pos - light": (10, (0.48 + 0.38 + 0.78 + 0.74) / 4),  # min(10, 10)
        "table_pos - light": (5, (0.6 + 0.78 + 0.74) / 3),  # min(5, 10)
    }
    for label, (m, p) in expected.items():
        d = decided[label]
        assert d.smallest == pytest.approx(power.difference_resolvable(m * EPISODES, p, z_at(d.level)), abs=1e-12)


def test_a_claim_on_shifted_rows_without_their_train_rows_has_no_gap_and_warns_nothing(cfg):
    """A results file of the shifted suites alone (the train suite's rows filtered out), gaps still in it: no gap
    can be computed from the rates, so the points and the headroom (from P_T) are NaN, without a warning of a mean
    of nothing."""
    rows = [r for r in rows_of({"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT}) if r["condition"] != "train"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = decide(
            [claim("gap_opens", factors=["camera_pos"]), claim("gap_exceeds", factors=["camera_pos", "light"])],
            cfg,
            rows,
        )
    (gap,), (difference,) = (v.comparisons for v in found)
    assert all(math.isnan(v) for d in (gap, difference) for v in (d.point, d.low, d.high, d.headroom))
    assert difference.verdict == NOT_RESOLVED


def test_a_study_tests_its_own_claims_else_the_papers_ordering_over_its_factors(cfg):
    own = claim("gap_opens", factors=["light"])
    with_claims = StudyConfig(
        name="synthetic", tasks=["door-open"], seeds=list(SEEDS), factors=["camera_pos", "table_pos", "light"],
        methods=[MethodConfig("bc", {"type": "bc"})], claims=[own],
    )  # fmt: skip
    assert claims.study_claims(with_claims) == [own]
    stated, fig3a = claims.study_claims(cfg)  # factors camera_pos, table_pos, light
    assert stated.tiers == [["camera_pos", "table_pos"], ["light"]]
    assert fig3a.tiers == [["camera_pos"], ["table_pos"], ["light"]]


@pytest.mark.parametrize(
    "door_only",
    [["camera_pos"], ["camera_pos", "camera_pos+light"]],
    ids=["first factor on one task", "first factor and pair on one task"],
)
def test_a_pair_whose_first_factor_ran_on_fewer_tasks_than_another_condition_has_no_comparison(cfg, door_only):
    """The pair's conditions on both tasks (pick-place's rows first) but ``door_only`` on door-open alone: the first
    factor's cells (1) differ from the second factor's (2), whether or not the pair's match either, so there is
    no comparison (its cells do not line up)."""
    rates = {"train": TRAIN, "camera_pos": CAMERA, "light": LIGHT, "camera_pos+light": CAMERA}
    rows = rows_of({c: v for c, v in rates.items() if c not in door_only}, task="pick-place") + rows_of(rates)
    (found,) = decide([claim("pair", pair="camera_pos+light")], cfg, rows)
    assert (found.comparisons, found.verdict) == ([], NOT_RESOLVED)
