"""Verdicts on the paper's claims (study/results/claims.py) from synthetic results.csv files whose truth is known:
each kind of claim gives each of the four verdicts, Holm's correction turns a borderline verdict, and the
committed quick study's ordering is not resolved."""

from __future__ import annotations

from pathlib import Path

import pytest

from lerobot_factorworld.study.paper import PAPER_FACTOR_RANKS
from lerobot_factorworld.study.plan.claim_config import ClaimConfig
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.report.claims_markdown import to_resolve
from lerobot_factorworld.study.report.write import load_config, regenerate_report
from lerobot_factorworld.study.results.aggregate import method_rho_differences
from lerobot_factorworld.study.results.claims import AGREES, CAPPED, DISAGREES, NOT_RESOLVED, decide, study_claims
from lerobot_factorworld.study.results.rows import read_results, write_results

ROOT = Path(__file__).resolve().parents[1]
SEEDS = (0, 1, 2, 3, 4)
FACTORS = ["camera_pos", "table_pos", "table_texture", "light"]


def _row(method: str, task: str, n: int, seed: int, condition: str, successes: int, episodes: int, train: int):
    rate, p_train = successes / episodes, train / episodes
    return {
        "study": "synthetic",
        "method": method,
        "policy": "bc",
        "task": task,
        "n_train_envs": n,
        "seed": seed,
        "widths": "default",
        "condition": condition,
        "n_factors": 0 if condition == "train" else condition.count("+") + 1,
        "radius_m": None,
        "n_envs": n if condition == "train" else 20,
        "episodes": episodes,
        "successes": successes,
        "success_rate": rate,
        "ci_low": 0.0,
        "ci_high": 1.0,
        "train_success_rate": p_train,
        "gap": p_train - rate,
        "gap_ci_low": -1.0,
        "gap_ci_high": 1.0,
        "envs_visited": n if condition == "train" else 20,
        "fingerprint": "f",
        "stages": "",
        "step": f"{method}-{task}-{n}-{seed}-{condition}",
        "commit": "",
        "source_hash": "",
    }


def rows_of(rates: dict, episodes: int = 100, train: float = 0.9, seeds=SEEDS, method="bc", task="door-open", n=5):
    """Rows of one method x task x N: ``rates[condition]`` is the success rate (a number, or one per seed); the
    ``train`` condition's rate is ``train`` unless given."""
    rates = {"train": train, **rates}
    out = []
    for s, seed in enumerate(seeds):
        per_seed = {c: (r[s] if isinstance(r, (list, tuple)) else r) for c, r in rates.items()}
        k_train = round(per_seed["train"] * episodes)
        for condition, rate in per_seed.items():
            out.append(_row(method, task, n, seed, condition, round(rate * episodes), episodes, k_train))
    return out


@pytest.fixture(scope="module")
def cfg() -> StudyConfig:
    return StudyConfig(
        name="synthetic",
        tasks=["door-open"],
        seeds=list(SEEDS),
        factors=FACTORS,
        pairs=["camera_pos+table_texture"],
        methods=[MethodConfig("bc", {"type": "bc"}), MethodConfig("bc_shift", {"type": "bc", "augmentation": "shift"})],
    )


def verdict(claim: ClaimConfig, cfg: StudyConfig, rows: list[dict]) -> str:
    return decide([claim], cfg, rows)[0].verdict


def claim(kind: str, **settings) -> ClaimConfig:
    return ClaimConfig(kind=kind, text=f"a {kind} claim", source="test", **settings)


# --- each kind, each verdict -------------------------------------------------------------------------------------

CASES = {
    "gap_opens": (
        {"factors": ["camera_pos"]},
        {
            AGREES: {"camera_pos": 0.4},
            DISAGREES: {"camera_pos": 1.0},  # P_T 0.9: the shifted condition succeeds more
            NOT_RESOLVED: {"camera_pos": [0.9, 0.8, 1.0, 0.85, 0.95]},
            CAPPED: {"camera_pos": 0.0, "train": 0.0},
        },
    ),
    "gap_exceeds": (
        {"factors": ["camera_pos", "light"]},
        {
            AGREES: {"camera_pos": 0.3, "light": 0.8},
            DISAGREES: {"camera_pos": 0.8, "light": 0.3},
            NOT_RESOLVED: {"camera_pos": [0.5, 0.6, 0.4, 0.55, 0.45], "light": 0.5},
            CAPPED: {"camera_pos": 0.0, "light": 0.0},  # light already fails every episode: nothing to exceed
        },
    ),
    "ordering": (
        {"tiers": [["camera_pos"], ["table_texture"], ["light"]]},
        {
            AGREES: {"camera_pos": 0.2, "table_texture": 0.5, "light": 0.8},
            DISAGREES: {"camera_pos": 0.8, "table_texture": 0.5, "light": 0.2},
            NOT_RESOLVED: {"camera_pos": 0.5, "table_texture": 0.5, "light": 0.5},
            CAPPED: {"camera_pos": 0.0, "table_texture": 0.0, "light": 0.0, "train": 0.0},
        },
    ),
    "method_shrinks": (
        {"factors": ["camera_pos"], "method": "bc_shift", "baseline": "bc"},
        {  # bc's rates here, bc_shift's in TWO_METHODS
            AGREES: {"camera_pos": 0.3},
            DISAGREES: {"camera_pos": 0.9},
            NOT_RESOLVED: {"camera_pos": 0.6},
            CAPPED: {"camera_pos": 0.9},
        },
    ),
}
TWO_METHODS = {  # bc_shift's rates against bc's above
    AGREES: {"camera_pos": 0.85},
    DISAGREES: {"camera_pos": 0.3},
    NOT_RESOLVED: {"camera_pos": [0.6, 0.5, 0.7, 0.55, 0.65]},
    CAPPED: {"camera_pos": 0.9},  # no gap to shrink: bc's gap is 0 (and so is bc_shift's)
}


@pytest.mark.parametrize("expected", [AGREES, DISAGREES, NOT_RESOLVED, CAPPED])
@pytest.mark.parametrize("kind", list(CASES))
def test_each_kind_gives_each_verdict(cfg, kind, expected):
    settings, cases = CASES[kind]
    rows = rows_of(cases[expected])
    if kind == "method_shrinks":
        rows += rows_of(TWO_METHODS[expected], method="bc_shift")
    assert verdict(claim(kind, **settings), cfg, rows) == expected


@pytest.mark.parametrize(
    ("expected", "gap_at", "train"),
    [
        (AGREES, {5: 0.5, 20: 0.1}, 0.9),
        (DISAGREES, {5: 0.1, 20: 0.5}, 0.9),
        (NOT_RESOLVED, {5: 0.3, 20: 0.3}, 0.9),
        (CAPPED, {5: 0.0, 20: 0.0}, 0.0),  # no gap at the smallest N: none can close
    ],
)
def test_a_trend_over_n_gives_each_verdict(cfg, expected, gap_at, train):
    rows = [r for n, gap in gap_at.items() for r in rows_of({"table_pos": train - gap}, train=train, n=n)]
    shrinks = claim("trend", factors=["table_pos"], over="n", direction="shrinks")
    assert verdict(shrinks, cfg, rows) == expected


@pytest.mark.parametrize(
    ("expected", "rates", "episodes"),
    [
        (AGREES, {"camera_pos": 0.6, "table_texture": 0.8, "camera_pos+table_texture": 0.6}, 1000),
        (DISAGREES, {"camera_pos": 0.6, "table_texture": 0.8, "camera_pos+table_texture": 0.3}, 100),
        (NOT_RESOLVED, {"camera_pos": 0.6, "table_texture": 0.8, "camera_pos+table_texture": 0.6}, 10),
        (CAPPED, {"camera_pos": 0.0, "table_texture": 0.8, "camera_pos+table_texture": 0.0}, 100),
    ],
)
def test_a_pair_within_the_band_gives_each_verdict(cfg, expected, rates, episodes):
    within = claim("pair", pair="camera_pos+table_texture", relation="within")
    assert verdict(within, cfg, rows_of(rates, episodes=episodes)) == expected


def test_a_synergistic_pair(cfg):
    rates = {"camera_pos": 0.6, "table_texture": 0.8}
    synergistic = claim("pair", pair="camera_pos+table_texture", relation="synergistic")
    assert verdict(synergistic, cfg, rows_of({**rates, "camera_pos+table_texture": 0.2})) == AGREES
    assert verdict(synergistic, cfg, rows_of({**rates, "camera_pos+table_texture": 0.6}, episodes=1000)) == DISAGREES


def test_the_verdict_follows_from_the_printed_interval(cfg):
    """Whatever the data, agrees / disagrees only where the decision interval lies on one side of 0."""
    rows = rows_of({"camera_pos": [0.5, 0.7, 0.6, 0.4, 0.8], "light": [0.6, 0.5, 0.9, 0.7, 0.6]})
    for found in decide([claim("gap_exceeds", factors=["camera_pos", "light"])], cfg, rows)[0].comparisons:
        if found.verdict in (AGREES, DISAGREES):
            assert found.low > 0 or found.high < 0
        else:
            assert not (found.low > 0 or found.high < 0)


def test_one_seed_resolves_nothing(cfg):
    """One training seed has no seed-level interval: a gap its episodes alone resolve is still not resolved."""
    rows = rows_of({"camera_pos": 0.2}, seeds=(0,))
    found = decide([claim("gap_opens", factors=["camera_pos"])], cfg, rows)[0]
    assert found.verdict == NOT_RESOLVED
    assert found.comparisons[0].bootstrap[0] > 0  # the episodes' own interval excludes 0


def test_unknown_episode_counts_leave_an_unresolved_comparison_not_resolved_and_zero_rates_capped(cfg):
    """Without episode counts the design's power is unknown, which is not the same as P_T = 0 (nothing to
    resolve): the first stays "not resolved" with the interval the counts do not enter, the second is capped."""
    gap = claim("gap_opens", factors=["camera_pos"])
    counted = rows_of({"camera_pos": [0.8, 1.0, 0.85, 0.95, 0.9]})
    uncounted = [{**r, "episodes": 0, "successes": None} for r in counted]
    with_counts, without = decide([gap], cfg, counted)[0], decide([gap], cfg, uncounted)[0]
    assert with_counts.verdict == without.verdict == NOT_RESOLVED
    (a,), (b,) = with_counts.comparisons, without.comparisons
    assert (b.low, b.high) == pytest.approx((a.low, a.high)) and b.low < 0 < b.high
    assert to_resolve(a).startswith("resolves 0.") and to_resolve(b).startswith("episode counts unknown")
    zero = decide([gap], cfg, rows_of({"camera_pos": 0.0, "train": 0.0}))[0]
    assert zero.verdict == CAPPED
    assert to_resolve(zero.comparisons[0]) == "these success rates leave no effect this design resolves"


def test_the_t_interval_widens_what_the_bootstrap_would_resolve(cfg):
    """Three seeds that disagree among themselves: the bootstrap alone (10 distinct seed sets) resolves the gap,
    the t-interval over seeds does not, and the verdict is decided on the wider."""
    rows = rows_of({"camera_pos": [0.4, 0.75, 0.45]}, train=0.9, episodes=200, seeds=(0, 1, 2))
    found = decide([claim("gap_opens", factors=["camera_pos"])], cfg, rows)[0].comparisons[0]
    assert found.bootstrap[0] > 0
    assert found.low < 0 and found.verdict == NOT_RESOLVED


def test_holm_turns_a_borderline_verdict(cfg):
    """A gap resolved on its own is not, once the study tests it together with many null comparisons."""
    rates = {"camera_pos": [0.80, 0.88, 0.72, 0.84, 0.76], "table_pos": 0.9, "table_texture": 0.9, "light": 0.9}
    rows = rows_of(rates, episodes=1000)
    alone = claim("gap_opens", factors=["camera_pos"])
    assert verdict(alone, cfg, rows) == AGREES
    nulls = [claim("gap_exceeds", factors=[a, b]) for a in FACTORS[1:] for b in FACTORS[1:] if a != b]
    together = decide([alone, *nulls], cfg, rows)
    assert together[0].verdict == NOT_RESOLVED
    assert together[0].comparisons[0].level > 0.99  # decided at 1 - 0.05 / (its rank from the end)


def test_a_claim_is_decided_the_same_from_a_results_file(cfg, tmp_path):
    """Written to results.csv and read back (as ``factorworld report`` reads it), the verdicts are the same."""
    rows = rows_of({"camera_pos": 0.3, "light": 0.8})
    claims = [claim("gap_exceeds", factors=["camera_pos", "light"]), claim("gap_opens", factors=["light"])]
    read = read_results(write_results(rows, tmp_path / "results.csv"))
    assert [v.verdict for v in decide(claims, cfg, read)] == [v.verdict for v in decide(claims, cfg, rows)]
    assert [v.verdict for v in decide(claims, cfg, read)] == [AGREES, AGREES]


def test_a_bad_claim_is_refused_naming_the_valid_choices(cfg):
    with pytest.raises(ValueError, match="valid: gap_opens, gap_exceeds, ordering"):
        StudyConfig(**{**_settings(cfg), "claims": [{"kind": "gap_grows", "text": "x", "source": "y"}]})
    with pytest.raises(ValueError, match="valid: camera_pos, table_pos, table_texture, light"):
        StudyConfig(
            **{**_settings(cfg), "claims": [{"kind": "gap_opens", "text": "x", "source": "y", "factors": ["floor"]}]}
        )
    with pytest.raises(ValueError, match=r"needs factors: \[harder, easier\]"):
        StudyConfig(
            **{**_settings(cfg), "claims": [{"kind": "gap_exceeds", "text": "x", "source": "y", "factors": ["light"]}]}
        )


def _settings(cfg: StudyConfig) -> dict:
    return {"name": cfg.name, "tasks": cfg.tasks, "seeds": cfg.seeds, "factors": cfg.factors, "methods": cfg.methods}


# --- the committed quick study -------------------------------------------------------------------------------------


def test_the_quick_studys_ordering_is_not_resolved(tmp_path):
    """The quick study (one seed, 10 episodes per cell) used to print that its ordering agrees with the paper's."""
    published = ROOT / "docs/results/quick"
    cfg = load_config(published / "config.yaml")
    verdicts = decide(study_claims(cfg), cfg, read_results(published / "results.csv"))
    assert [v.claim.kind for v in verdicts] == ["ordering", "ordering"]
    assert {v.verdict for v in verdicts} == {NOT_RESOLVED}
    report, _ = regenerate_report(published / "results.csv", out=tmp_path)
    text = report.read_text()
    assert "agrees with the paper" not in text
    assert "the factor ordering, the text's tiers: **not resolved**" in text


def test_the_spearman_difference_between_two_methods():
    """How much a method moves the ordering: one ordering as the paper's, the other reversed."""
    paper_order = {"camera_pos": 0.2, "table_texture": 0.4, "floor_texture": 0.6, "light": 0.8}  # hardest first
    reversed_order = {f: 1.0 - r for f, r in paper_order.items()}
    rows = rows_of(paper_order, episodes=200) + rows_of(reversed_order, episodes=200, method="bc_none")
    factors = list(paper_order)
    (own, diff) = method_rho_differences(rows, ["bc", "bc_none"], factors, PAPER_FACTOR_RANKS)["bc_none"]
    assert own[0] == pytest.approx(-1.0)
    assert diff[0] == pytest.approx(-2.0)
    assert diff[2] < 0  # the whole interval: bc_none's ordering is resolvably further from the paper's


def test_one_claim_for_two_methods_lists_each_method_s_comparisons(cfg):
    """The same ordering claimed for two methods: the comparisons table has each method's rows, the second's named
    with its method (the same labels must not hide one method's comparisons behind the other's)."""
    from lerobot_factorworld.study.report.claims_markdown import comparison_rows

    tiers = {"tiers": [["camera_pos"], ["table_texture"], ["light"]]}
    claims = [claim("ordering", **tiers), claim("ordering", method="bc_shift", **tiers)]
    rows = rows_of({"camera_pos": 0.2, "table_texture": 0.5, "light": 0.8})
    rows += rows_of({"camera_pos": 0.8, "table_texture": 0.5, "light": 0.2}, method="bc_shift")
    found = {row[0]: row[4] for row in comparison_rows(decide(claims, cfg, rows))}
    assert found == {
        "camera_pos - table_texture": AGREES,
        "camera_pos - light": AGREES,
        "table_texture - light": AGREES,
        "camera_pos - table_texture (bc_shift)": DISAGREES,
        "camera_pos - light (bc_shift)": DISAGREES,
        "table_texture - light (bc_shift)": DISAGREES,
    }
    alone = {row[0] for row in comparison_rows(decide(claims[1:], cfg, rows))}
    assert alone == {
        "camera_pos - table_texture",
        "camera_pos - light",
        "table_texture - light",
    }  # nothing to tell apart
