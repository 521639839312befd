"""Verdicts on the paper's claims (study/results/claims.py) where mutation testing found the suite silent (docs/testing.md).

tests/test_claims.py checks each kind's four verdicts; the numbers a claims table prints were not checked. Here
every comparison of every kind (both trend directions, over N and over the radius, both pair relations) is
decided on synthetic rows whose per-seed statistic is computed by hand, and each field of its ``Decided`` is
checked against the module docstring's recipe: the point, the hull of the bootstrap's percentile interval and the
t-interval over seeds at Holm's level, the larger of the two p-values, the headroom the success rates leave, the
smallest effect the power code resolves, and the episodes and seeds that would resolve the observed effect."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from lerobot_factorworld.study import metrics
from lerobot_factorworld.study.plan import power
from lerobot_factorworld.study.plan.claim_config import ClaimConfig
from lerobot_factorworld.study.plan.config import MethodConfig, StudyConfig
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
    while e <= claims.MAX_EPISODES:
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
    low, high = (float(v) for v in metrics.percentile_interval(reps, level=level))
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
