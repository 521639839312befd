"""Verdicts that nothing but generalization can move, on results whose truth is known (issue 56):

- a gap that shrinks because success fell everywhere is **confounded (P_T fell)**, not "agrees"; one that
  shrinks because success under the shifts rose agrees, also when P_T rises with it;
- a finding decided over two studies that share cells is corrected once, its shared comparison counted once
  and decided on the same cells in both reports;
- a comparison capped the paper's way whose estimate leans the other way, with room there, is not resolved and
  says so;
- a method merged on part of the grid is compared on the cells both methods have;
- a cell has one interval in every table that holds it;
- degenerate results (P_T = 0, every episode a success, one episode per cell, one seed, a condition one method
  lacks) still give a report, and a bug at the command line says it is one.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import stats
from test_claims import _row, rows_of

from lerobot_factorworld import cli
from lerobot_factorworld.stats import proportions
from lerobot_factorworld.study.plan.claim_config import ClaimConfig
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.report.claims_markdown import claims_section, to_resolve
from lerobot_factorworld.study.report.markdown import render
from lerobot_factorworld.study.results import aggregate
from lerobot_factorworld.study.results.claims import (
    AGREES,
    CAPPED,
    CONFOUNDED,
    NOT_RESOLVED,
    VERDICTS,
    decide,
    decide_together,
    study_claims,
)

SEEDS = (0, 1, 2, 3, 4)
ALL = ["camera_pos", "light"]


def _two_methods(cfg_name: str = "known") -> StudyConfig:
    return StudyConfig(
        name=cfg_name,
        tasks=["door-open", "pick-place"],
        seeds=list(SEEDS),
        factors=ALL,
        methods=[MethodConfig("base", {"type": "bc"}), MethodConfig("treat", {"type": "bc", "augmentation": "shift"})],
    )


SHRINKS = ClaimConfig(kind="method_shrinks", text="treat shrinks the gap", source="test", method="treat",
                      baseline="base", factors=ALL)  # fmt: skip


def _arm(method: str, p_train: float, p_shift: float, task: str = "door-open", spread: float = 0.02) -> list[dict]:
    """One method on one task at five seeds: P_T and P_F near the given rates (a small spread between seeds)."""
    wobble = np.array([0.0, 1.0, -1.0, 0.5, -0.5]) * spread
    return rows_of(
        {c: list(np.clip(p_shift + wobble, 0, 1)) for c in ALL},
        train=list(np.clip(p_train + wobble, 0, 1)), method=method, task=task,
    )  # fmt: skip


def _shrink(base: tuple[float, float], treat: tuple[float, float]):
    (verdict,) = decide([SHRINKS], _two_methods(), _arm("base", *base) + _arm("treat", *treat))
    return verdict, verdict.comparisons[0]


def test_a_gap_that_shrinks_because_success_collapsed_is_confounded_not_agrees():
    """P_T 0.95 -> 0.35, P_F 0.45 -> 0.30: the gap falls from 0.50 to 0.05 (resolved), but only because success fell."""
    verdict, d = _shrink((0.95, 0.45), (0.35, 0.30))
    assert d.point == pytest.approx(-0.45, abs=0.01) and d.high < 0  # the gap difference alone is resolved
    assert verdict.verdict == CONFOUNDED != AGREES
    assert d.p_t_change[0] == pytest.approx(-0.60, abs=0.01) and d.p_t_change[2] < 0
    assert d.p_f_change[0] == pytest.approx(-0.15, abs=0.01) and d.p_f_change[1] < 0
    assert "success fell" in to_resolve(d)
    section = "\n".join(claims_section([verdict]))
    assert "**confounded (P_T fell)**" in section and "P_T -0.600" in section and "P_F -0.150" in section


def test_a_gap_that_shrinks_because_success_under_the_shifts_rose_agrees():
    """P_T equal at 0.95, P_F 0.45 -> 0.75: a real shrink."""
    verdict, d = _shrink((0.95, 0.45), (0.95, 0.75))
    assert verdict.verdict == AGREES and d.point == pytest.approx(-0.30, abs=0.01)
    assert d.p_f_change[1] > 0


def test_a_gap_that_shrinks_while_both_rates_rise_agrees():
    verdict, d = _shrink((0.70, 0.30), (0.95, 0.85))
    assert verdict.verdict == AGREES and d.p_t_change[1] > 0 and d.p_f_change[1] > 0


def test_a_shrink_whose_sign_p_t_forces_needs_p_f_to_agree():
    """The treatment's P_T (0.15) is below the baseline's gap (0.50): the gap difference cannot be positive. Even
    resolved, with P_F unchanged, it is confounded; and with one seed the text says the sign is forced."""
    verdict, d = _shrink((0.95, 0.45), (0.15, 0.10))
    assert d.forced and verdict.verdict == CONFOUNDED
    cfg = _two_methods()
    one_seed = [r for r in _arm("base", 0.95, 0.45) + _arm("treat", 0.15, 0.10) if r["seed"] == 0]
    (alone,) = decide([SHRINKS], cfg, one_seed)
    assert alone.verdict == NOT_RESOLVED and "its sign is forced" in to_resolve(alone.comparisons[0])


def test_a_shrink_over_n_while_p_t_falls_is_confounded():
    cfg = StudyConfig(name="known", tasks=["door-open"], n_train_envs=[5, 10], seeds=list(SEEDS), factors=ALL,
                      methods=[MethodConfig("bc", {"type": "bc"})])  # fmt: skip
    rows = _arm("bc", 0.95, 0.45)
    for r in _arm("bc", 0.35, 0.30):
        r["n_train_envs"], r["step"] = 10, r["step"] + "-10"
        rows.append(r)
    trend = ClaimConfig(kind="trend", text="N shrinks it", source="test", factors=ALL, over="n", direction="shrinks")
    (verdict,) = decide([trend], cfg, rows)
    assert verdict.verdict == CONFOUNDED and verdict.comparisons[0].p_t_change[2] < 0


def test_a_finding_over_two_studies_that_share_cells_is_corrected_once_on_the_same_cells():
    """Study A has the claim on two tasks; study B is A's door-open rows (the same evaluation steps) plus a method of
    its own. The shared claim is one comparison, decided on A's cells in both reports (B alone would decide it on
    door-open only), and Holm covers 2 comparisons, not 3."""
    big = _two_methods("a")
    rows_a = [r for task in ("door-open", "pick-place") for m, rates in (("base", (0.9, 0.5)), ("treat", (0.9, 0.6)))
              for r in _arm(m, *rates, task=task, spread=0.05)]  # fmt: skip
    for r in rows_a:
        r["study"] = "a"
    third = MethodConfig("other", {"type": "bc", "augmentation": "color"})
    small = StudyConfig(name="b", tasks=["door-open"], seeds=list(SEEDS), factors=ALL,
                        methods=[*big.methods, third])  # fmt: skip
    rows_b = [dict(r, study="b") for r in rows_a if r["task"] == "door-open"]
    rows_b += [dict(r, study="b") for r in _arm("other", 0.9, 0.4)]
    other_claim = ClaimConfig(kind="method_shrinks", text="other shrinks it", source="test", method="other",
                              baseline="base", factors=ALL)  # fmt: skip
    together = decide_together([([SHRINKS], big, rows_a), ([SHRINKS, other_claim], small, rows_b)])
    (a_shrink,), (b_shrink, b_other) = together
    assert a_shrink.comparisons[0] == b_shrink.comparisons[0]  # one comparison, one decision, in both reports
    assert a_shrink.corrected_over == b_other.corrected_over == 2
    assert b_shrink.studies == ("a", "b") and b_other.studies == ("b",)
    (alone,) = decide([SHRINKS], small, rows_b)
    assert alone.comparisons[0].cells < b_shrink.comparisons[0].cells  # B alone has half the cells
    # a study sharing only some of A's cells (door-open) and adding its own (bin-picking) tests another comparison:
    # each keeps its own cells, and the correction counts both
    third_task = StudyConfig(name="c", tasks=["door-open", "bin-picking"], seeds=list(SEEDS), factors=ALL,
                             methods=big.methods)  # fmt: skip
    rows_c = [dict(r, study="c") for r in rows_a if r["task"] == "door-open"]
    rows_c += [dict(r, study="c") for m in ("base", "treat") for r in _arm(m, 0.9, 0.3, task="bin-picking")]
    (a_again,), (c_shrink,) = decide_together([([SHRINKS], big, rows_a), ([SHRINKS], third_task, rows_c)])
    assert a_again.corrected_over == c_shrink.corrected_over == 2 and c_shrink.studies == ("c",)
    (c_alone,) = decide([SHRINKS], third_task, rows_c)
    assert (c_shrink.comparisons[0].point, c_shrink.comparisons[0].cells) == (
        c_alone.comparisons[0].point,
        c_alone.comparisons[0].cells,
    )


def test_a_capped_comparison_leaning_the_other_way_is_not_resolved_and_says_which_way():
    """Object texture's gap against table texture's at P_T 0.30: at most 0.07 (P_T minus table texture's gap) the
    paper's way, below what 20 episodes resolve; the estimate, -0.15, leans the other way, where the room is large: not resolved, toward
    disagrees, with the seeds and episodes that would resolve it."""
    cfg = StudyConfig(name="known", tasks=["pick-place"], seeds=[0, 1, 2], factors=["object_texture", "table_texture"],
                      methods=[MethodConfig("bc", {"type": "bc"})])  # fmt: skip
    rows = rows_of({"object_texture": [0.25, 0.15, 0.25], "table_texture": [0.05, 0.1, 0.05]}, episodes=20,
                   train=[0.3, 0.3, 0.3], seeds=(0, 1, 2), task="pick-place")  # fmt: skip
    exceeds = ClaimConfig(kind="gap_exceeds", text="object texture's gap exceeds table texture's", source="test",
                          factors=["object_texture", "table_texture"])  # fmt: skip
    (verdict,) = decide([exceeds], cfg, rows)
    d = verdict.comparisons[0]
    assert d.point == pytest.approx(-0.15) and d.leans_other_way
    assert d.headroom < d.smallest  # capped the paper's way ...
    assert verdict.verdict == NOT_RESOLVED != CAPPED  # ... but not the other way
    text = to_resolve(d)
    assert "toward disagrees" in text and "seeds" in text and "episodes per cell" in text


def test_a_method_merged_on_part_of_the_grid_is_compared_on_the_cells_both_have():
    """The treatment ran on door-open seed 0 only; the baseline on both tasks and five seeds, with a much larger
    gap on pick-place. The claim compares door-open seed 0 alone: the baseline's gap there, not its mean."""
    rows = _arm("base", 0.9, 0.5) + _arm("base", 0.9, 0.1, task="pick-place")
    rows += [r for r in _arm("treat", 0.9, 0.6) if r["seed"] == 0]
    (verdict,) = decide([SHRINKS], _two_methods(), rows)
    d = verdict.comparisons[0]
    base0 = [r for r in rows if r["method"] == "base" and r["seed"] == 0 and r["task"] == "door-open"]
    treat0 = [r for r in rows if r["method"] == "treat"]
    gap = lambda rs: np.mean([r["gap"] for r in rs if r["condition"] != "train"])  # noqa: E731
    assert d.point == pytest.approx(gap(treat0) - gap(base0))
    assert d.cells == 2 * 3  # two methods x (train + two factors), one seed, one task
    # with no shared cell the claim is n/a, and so are the per-task Spearman differences
    apart = [r for r in rows if not (r["method"] == "base" and r["task"] == "door-open")]
    (none,) = decide([SHRINKS], _two_methods(), apart)
    assert none.comparisons == [] and "share no cell" in "\n".join(claims_section([none]))
    assert aggregate.method_rho_differences([r for r in rows if r["task"] == "pick-place"], ["base", "treat"],
                                            ALL, {"camera_pos": 1, "light": 2}) == {}  # fmt: skip


def test_a_cell_has_one_interval_in_every_table_that_holds_it():
    """bc's pick-place table_pos cell pooled with two other columns, and with five: the same interval."""
    cell = rows_of({"table_pos": [0.3, 0.35]}, episodes=20, train=[0.9, 0.8], seeds=(0, 1), task="pick-place")
    few = cell + rows_of({"light": [0.5, 0.6]}, episodes=20, seeds=(0, 1), method="other")
    many = few + rows_of({c: [0.4, 0.7] for c in ("camera_pos", "light", "distractors")}, episodes=20, seeds=(0, 1))
    keys = ["method", "task", "n_train_envs", "condition"]
    key = ("bc", "pick-place", 5, "table_pos")
    assert aggregate.pooled_success(few, keys)[key] == aggregate.pooled_success(many, keys)[key]
    # and a gap's interval: the factor ordering over one factor, or over four
    one = aggregate.factor_gap_intervals(many, "bc", ["table_pos"])["table_pos"]
    four = aggregate.factor_gap_intervals(many, "bc", ["camera_pos", "table_pos", "light", "distractors"])
    assert one == four["table_pos"]


# --- degenerate results still give a report ------------------------------------------------------------------


def _results(draw_rate, seeds, episodes, drop_condition: bool) -> list[dict]:
    cfg_methods = ("base", "treat")
    out = []
    for method in cfg_methods:
        for task in ("door-open", "pick-place"):
            for seed in seeds:
                k_train = draw_rate()
                for condition in ("train", "camera_pos", "light", "table_texture"):
                    if drop_condition and method == "treat" and condition == "light":
                        continue
                    k = k_train if condition == "train" else draw_rate()
                    out.append(_row(method, task, 5, seed, condition, round(k * episodes), episodes,
                                    round(k_train * episodes)))  # fmt: skip
    return out


DEGENERATE_CFG = StudyConfig(
    name="synthetic", tasks=["door-open", "pick-place"], seeds=[0, 1, 2], factors=["camera_pos", "light", "table_texture"],
    methods=[MethodConfig("base", {"type": "bc"}), MethodConfig("treat", {"type": "bc", "augmentation": "shift"})],
    claims=[SHRINKS.__class__(**{**SHRINKS.__dict__, "factors": ["camera_pos", "light", "table_texture"]}),
            ClaimConfig(kind="ordering", text="an ordering of three", source="test",
                        tiers=[["table_texture"], ["camera_pos"], ["light"]]),
            ClaimConfig(kind="gap_opens", text="camera opens a gap", source="test", factors=["camera_pos"])],
)  # fmt: skip


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    level=st.sampled_from(["zero", "one", "random"]),
    seeds=st.sampled_from([(0,), (0, 1), (0, 1, 2)]),
    episodes=st.sampled_from([1, 3, 20]),
    drop=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_degenerate_results_still_give_a_report(level, seeds, episodes, drop, seed):
    """P_T = 0 everywhere, every episode a success, random rates; one episode per cell or 20; one seed or three;
    a condition one method lacks: the report (and the claims both reports print) is written without an exception,
    and every verdict is one of the verdicts."""
    rng = np.random.default_rng(seed)
    draw = {"zero": lambda: 0.0, "one": lambda: 1.0, "random": lambda: float(rng.integers(0, 3)) / 2}[level]
    rows = _results(draw, seeds, episodes, drop)
    text = render(DEGENERATE_CFG, rows, [], "test", len(rows))
    assert "## The paper's claims" in text
    for verdict in decide(study_claims(DEGENERATE_CFG), DEGENERATE_CFG, rows):
        assert verdict.verdict in VERDICTS
        for d in verdict.comparisons:
            assert isinstance(to_resolve(d), str) and not math.isnan(d.level)


def test_an_ordering_whose_gaps_are_all_zero_gives_a_claims_table():
    """Every episode fails: three factors' gaps are all 0, so every comparison has the same estimate; it is not a
    band (that was a crash: too many values to unpack)."""
    rows = _results(lambda: 0.0, (0, 1), 20, False)
    section = "\n".join(claims_section(decide(study_claims(DEGENERATE_CFG), DEGENERATE_CFG, rows)))
    assert "an ordering of three" in section and "0 of 3 comparisons agree" in section


# --- the command line: a bug says it is one ------------------------------------------------------------------


def test_a_bug_at_the_command_line_is_an_internal_error_with_its_traceback_in_a_log(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("FACTORWORLD_ERROR_DIR", str(tmp_path))

    def buggy(args):
        first, second = (1, 2, 3)  # noqa: F841  (the bug: an unpacking that fails)

    def refusing(args):
        proportions.wilson_interval(11, 10)  # a deliberate refusal inside the package

    monkeypatch.setitem(cli.COMMANDS, "buggy", buggy)
    monkeypatch.setitem(cli.COMMANDS, "refusing", refusing)
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["buggy"])
    err = capsys.readouterr().err.strip()
    assert exit_info.value.code == cli.INTERNAL_ERROR_STATUS and len(err.splitlines()) == 1
    assert err.startswith("internal error: ValueError: too many values to unpack") and "a bug" in err
    (log,) = tmp_path.glob("factorworld-internal-error-*.log")
    assert str(log) in err and "first, second = (1, 2, 3)" in log.read_text() and "Traceback" in log.read_text()
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["refusing"])
    assert exit_info.value.code == cli.FAILURE_STATUS
    assert capsys.readouterr().err == "error: successes must be in [0, 10], got 11\n"


def test_the_quick_reports_from_a_results_file_where_every_episode_fails(tmp_path):
    """The quick study's committed results with every success set to 0: `factorworld report` writes its report."""
    root = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
    lines = (root / "results.csv").read_text().splitlines()
    header = lines[0].split(",")
    columns = {name: i for i, name in enumerate(header)}
    failing = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[columns["successes"]] = "0"
        for name in ("success_rate", "train_success_rate", "gap"):
            cells[columns[name]] = "0.000000"
        failing.append(",".join(cells))
    results = tmp_path / "results.csv"
    results.write_text("\n".join(failing) + "\n")
    (tmp_path / "config.yaml").write_text((root / "config.yaml").read_text())
    cli.main(["report", f"--results={results}"])
    report = (tmp_path / "report.md").read_text()
    assert "## The paper's claims" in report and (tmp_path / "report.html").is_file()


# --- the rules' edges (what mutation testing of claims.py asks of them) -------------------------------------------


def test_a_p_t_that_falls_without_forcing_the_sign_still_confounds_and_a_resolved_p_f_rise_clears_it():
    """P_T 0.95 -> 0.70 stays above the baseline's gap (0.50), so the sign is free; the gap shrinks -0.50 -> -0.30.
    With P_F 0.45 -> 0.40 the fall alone confounds it; with P_T 0.95 -> 0.85 and P_F 0.45 -> 0.70 (resolved higher)
    it agrees though P_T fell."""
    verdict, d = _shrink((0.95, 0.45), (0.70, 0.40))
    assert not d.forced and d.p_t_change[2] < 0 and d.high < 0
    assert verdict.verdict == CONFOUNDED
    verdict, d = _shrink((0.95, 0.45), (0.85, 0.70))
    assert not d.forced and d.p_t_change[2] < 0 < d.p_f_change[1]
    assert verdict.verdict == AGREES
    # P_F unchanged (its interval holds 0 inside): P_F is not resolved higher, so the fall confounds it
    verdict, d = _shrink((0.95, 0.45), (0.75, 0.45))
    assert d.p_f_change[1] < 0 < d.p_f_change[2] and not d.forced and verdict.verdict == CONFOUNDED


def test_a_shrinks_success_changes_are_the_treatments_minus_the_baselines_at_the_comparisons_level():
    """Their points are the mean P_T (and P_F) differences; their intervals the hull of the bootstrap's and the
    t-interval at the comparison's level, or with one seed the bootstrap's alone."""
    base, treat = _arm("base", 0.9, 0.5), _arm("treat", 0.7, 0.6)
    rows = base + treat
    (verdict,) = decide([SHRINKS], _two_methods(), rows)
    d = verdict.comparisons[0]
    mean = lambda m, cond: np.mean([r["success_rate"] for r in rows if r["method"] == m and cond(r["condition"])])  # noqa: E731
    assert d.p_t_change[0] == pytest.approx(
        mean("treat", lambda c: c == "train") - mean("base", lambda c: c == "train")
    )
    assert d.p_f_change[0] == pytest.approx(
        mean("treat", lambda c: c != "train") - mean("base", lambda c: c != "train")
    )
    per_seed = [np.mean([r["success_rate"] for r in treat if r["seed"] == s and r["condition"] == "train"])
                - np.mean([r["success_rate"] for r in base if r["seed"] == s and r["condition"] == "train"]) for s in SEEDS]  # fmt: skip
    half = stats.t.ppf(1 - (1 - d.level) / 2, df=4) * np.std(per_seed, ddof=1) / math.sqrt(5)
    assert d.p_t_change[1] <= np.mean(per_seed) - half + 1e-12 and d.p_t_change[2] >= np.mean(per_seed) + half - 1e-12
    one = [r for r in rows if r["seed"] == 0]
    (alone,) = decide([SHRINKS], _two_methods(), one)
    low, high = alone.comparisons[0].p_t_change[1:]
    assert np.isfinite(low) and np.isfinite(high) and low < alone.comparisons[0].p_t_change[0] < high


def test_headroom_on_both_sides_is_the_room_each_bound_leaves():
    """A shrink's headroom is the baseline's gap and its contrary room the treatment's P_T minus that gap; an
    exceeds claim's headroom is P_T minus the second factor's gap, its contrary room the second's gap plus 1 - P_T;
    a gap's contrary room is 1 - P_T. Only a comparison between two methods that shrinks carries success changes."""
    from lerobot_factorworld.study.results.claims import comparisons

    rows = _arm("base", 0.9, 0.5, spread=0.0) + _arm("treat", 0.7, 0.6, spread=0.0)
    (shrink,) = comparisons(SHRINKS, _two_methods(), rows)
    assert (shrink.headroom, shrink.contrary) == pytest.approx((0.4, 0.7 - 0.4)) and shrink.success is not None
    cfg = StudyConfig(name="known", tasks=["door-open"], seeds=list(SEEDS), factors=ALL,
                      methods=[MethodConfig("base", {"type": "bc"})])  # fmt: skip
    one = rows_of({"camera_pos": 0.5, "light": 0.8}, train=0.9)
    exceeds = ClaimConfig(kind="gap_exceeds", text="t", source="t", factors=["camera_pos", "light"])
    (c,) = comparisons(exceeds, cfg, [dict(r, method="base") for r in one])
    assert (c.headroom, c.contrary) == pytest.approx((0.9 - 0.1, 0.1 + 1 - 0.9)) and c.success is None
    opens = ClaimConfig(kind="gap_opens", text="t", source="t", factors=["camera_pos"])
    (g,) = comparisons(opens, cfg, [dict(r, method="base") for r in one])
    assert g.contrary == pytest.approx(1 - 0.9)
    trend = ClaimConfig(kind="trend", text="t", source="t", factors=ALL, over="n", direction="shrinks")
    two_n = StudyConfig(name="known", tasks=["door-open"], n_train_envs=[5, 10], seeds=list(SEEDS), factors=ALL,
                        methods=[MethodConfig("bc", {"type": "bc"})])  # fmt: skip
    at5, at10 = _arm("bc", 0.9, 0.5, spread=0.0), _arm("bc", 0.6, 0.4, spread=0.0)
    for r in at10:
        r["n_train_envs"] = 10
    other_task = [dict(r, task="pick-place") for r in _arm("bc", 0.9, 0.9, spread=0.0)]  # only at N = 5: left out
    (t,) = comparisons(trend, two_n, at5 + at10 + other_task)
    assert (t.headroom, t.contrary) == pytest.approx((0.4, 0.6 - 0.4)) and t.success is not None
    assert int(np.sum(~np.isnan(t.table.rates))) == 2 * 3 * 5  # both N of door-open: pick-place has no N = 10


def test_a_capped_comparison_that_does_not_lean_the_other_way_or_has_no_room_there_stays_capped():
    """At P_T 0.30 the paper's way is capped. An estimate on the paper's side, or exactly 0, stays capped; one that
    leans the other way stays capped when the room there (contrary) is below what the design resolves."""
    from lerobot_factorworld.study.results.claims import Comparison, _uncapped_the_other_way

    def comparison(contrary: float) -> Comparison:
        return Comparison("c", None, None, 0.0, +1, 0.05, lambda e, z: 0.2, contrary)

    assert _uncapped_the_other_way(comparison(0.9), -0.1, 0.2)  # leans, with room
    assert not _uncapped_the_other_way(comparison(0.9), +0.1, 0.2)  # the paper's side
    assert not _uncapped_the_other_way(comparison(0.9), 0.0, 0.2)  # on the threshold
    assert not _uncapped_the_other_way(comparison(0.1), -0.1, 0.2)  # leans, but no room the design resolves
    assert _uncapped_the_other_way(comparison(0.2), -0.1, 0.2)  # room exactly what it resolves
    assert _uncapped_the_other_way(comparison(math.nan), -0.1, 0.2)  # unbounded room
    assert not _uncapped_the_other_way(comparison(0.9), -0.1, math.nan)  # nothing resolvable at all
    band = Comparison("c", None, None, 0.06, +1, 0.05, lambda e, z: 0.2, 0.9)  # a threshold that is not 0
    assert _uncapped_the_other_way(band, 0.03, 0.2) and not _uncapped_the_other_way(band, 0.09, 0.2)
