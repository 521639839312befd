"""``--eval.episodes=auto``: a profile evaluated in blocks of paired seeds until each shifted condition is decided
(study/sequential.py, study/run/blocks.py): every episode run is kept, each condition says why it stopped, the
rule is in the keys (and absent from them without auto), a rerun runs nothing, and a study whose claims need
fixed-n intervals refuses auto in one line."""

import csv
import json

import pytest

PROFILE = ["--task=pick-place", "--n_train_envs=1", "--train_factors=[light]", "--factors=[light,table_texture]"]
AUTO = ["--eval.n_test_envs=2", "--eval.episodes=auto", "--eval.block=2", "--eval.max_episodes=8",
        "--eval.max_episode_steps=4"]  # fmt: skip


def _config(checkpoint, out, *args):
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.study.plan.policy_profile import ProfileConfig

    return parse_config(ProfileConfig, [f"--policy.path={checkpoint}", *PROFILE, f"--out_dir={out}", *args], "profile")


def test_the_rule_is_in_the_keys_only_with_auto(factorworld_checkpoint, tmp_path):
    from lerobot_factorworld.study.plan.grid import make_plan

    auto = make_plan(_config(factorworld_checkpoint, tmp_path, *AUTO, "--eval.tolerance=0.5").study())
    fixed = make_plan(_config(factorworld_checkpoint, tmp_path, "--eval.n_test_envs=2", "--eval.episodes=8").study())
    rules = [s.inputs["sequential"] for s in auto.evaluations()]
    assert rules[0]["conditions"] == ["light", "table_texture"] and rules[0]["tolerance"] == 0.5
    assert all(r == rules[0] for r in rules) and all(s.inputs["episodes"] == 8 for s in auto.evaluations())
    assert all("sequential" not in s.inputs for s in fixed.evaluations())
    other = make_plan(_config(factorworld_checkpoint, tmp_path, *AUTO, "--eval.tolerance=0.2").study())
    assert not {s.key for s in other.steps} & {s.key for s in auto.steps}  # a rule setting changes every key


def test_auto_is_refused_where_claims_need_fixed_n_intervals(factorworld_checkpoint, tmp_path):
    from lerobot_factorworld.study.plan.config import EvalSettings, MethodConfig, StudyConfig

    given = [MethodConfig("given", checkpoint=str(factorworld_checkpoint))]
    base = {"tasks": ["pick-place"], "n_train_envs": [1], "train_factors": ["light"], "factors": ["light"],
            "methods": given}  # fmt: skip
    auto = EvalSettings(n_test_envs=2, episodes="auto", block=2, max_episodes=8)
    with pytest.raises(ValueError, match=r"^eval.episodes=auto stops .* claims over seeds \[0, 1\] .*give eval"):
        StudyConfig(**base, seeds=[0, 1], eval=auto)
    with pytest.raises(ValueError, match="multiple of eval.block=2"):
        StudyConfig(**base, eval=EvalSettings(n_test_envs=2, episodes="auto", block=2, max_episodes=7))
    with pytest.raises(ValueError, match="whole number or auto"):
        EvalSettings(episodes="many")
    assert StudyConfig(**base, eval=auto).eval.stop_rule().block == 2  # one seed, no claims: allowed


@pytest.mark.slow
def test_an_auto_profile_stops_each_condition_keeps_every_episode_and_says_why(factorworld_checkpoint, tmp_path):
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.results.episodes import read_episodes
    from lerobot_factorworld.study.run.steps import is_done, read_result
    from lerobot_factorworld.study.runner import run_study

    out = tmp_path / "auto"
    profile = _config(factorworld_checkpoint, out, *AUTO, "--eval.tolerance=0.5")
    outcome = run_study(profile.study(), profile.options(), "factorworld profile ...")
    assert outcome.ran["eval"] == 3 and not outcome.failed
    plan = make_plan(profile.study())
    results = {r["condition"]: r for r in (read_result(s, out) for s in plan.evaluations())}
    # an untrained policy fails everywhere: every gap is 0, so each condition stops within the tolerance
    for condition in ("light", "table_texture"):
        stop = results[condition]["sequential"]
        assert stop["reason"] == "within tolerance" and -0.5 <= stop["gap_low"] <= 0 <= stop["gap_high"] <= 0.5
        assert stop["episodes"] % 2 == 0 and results[condition]["seeds"] == list(range(1000, 1000 + stop["episodes"]))
    assert results["train"]["sequential"]["episodes"] == max(r["sequential"]["episodes"] for r in results.values())
    rows = {r["condition"]: r for r in csv.DictReader(open(out / "results.csv"))}
    assert float(rows["light"]["gap_ci_low"]) == results["light"]["sequential"]["gap_low"]  # the anytime interval
    episodes = read_episodes(out / "episodes.parquet")
    assert len(episodes) == sum(len(r["seeds"]) for r in results.values())  # every episode run
    report = (out / "report.md").read_text()
    assert "## How each condition stopped" in report and "anytime-valid" in report and "within tolerance" in report
    assert "bootstrap" not in report.split("## How each condition stopped")[1]  # no fixed-n interval shown
    blocks = sorted(p.name for p in plan.evaluations()[1].folder(out).joinpath("blocks").iterdir())
    assert blocks[0] == "1000.json" and json.loads(
        (plan.evaluations()[1].folder(out) / "blocks" / blocks[0]).read_text()
    )
    # the same command again: every evaluation cached
    assert all(is_done(step, out) for step in plan.steps)
    again = run_study(profile.study(), profile.options(), "factorworld profile ...")
    assert again.ran["eval"] == 0
