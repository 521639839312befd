"""``--eval.episodes=auto``: a profile evaluated in blocks of paired seeds until each shifted condition is decided
(study/sequential.py, study/run/blocks.py): every episode run is kept, each condition says why it stopped, the
rule is in the keys (and absent from them without auto), a rerun runs nothing, and a study whose claims need
fixed-n intervals refuses auto in one line."""

import csv
import json
import time

import pytest

from lerobot_factorworld.core import machine

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
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.eval_settings import EvalSettings
    from lerobot_factorworld.study.plan.method_config import MethodConfig

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
    from lerobot_factorworld.study.run.result import is_done, read_result
    from lerobot_factorworld.study.runner import run_study

    out = tmp_path / "auto"
    profile = _config(
        factorworld_checkpoint, out, *AUTO, "--eval.tolerance=0.6", "--hub_benchmark=someone/factor-world"
    )
    start = time.perf_counter()
    outcome = run_study(profile.study(), profile.options(), "factorworld profile ...")
    wall = time.perf_counter() - start
    assert outcome.ran["eval"] == 3 and not outcome.failed
    plan = make_plan(profile.study())
    results = {r["condition"]: r for r in (read_result(s, out) for s in plan.evaluations())}
    # an untrained policy fails everywhere: every gap is 0, so each condition stops within the tolerance, at 6 of 8
    for condition in ("light", "table_texture"):
        stop = results[condition]["sequential"]
        assert stop["reason"] == "within tolerance" and -0.6 <= stop["gap_low"] <= 0 <= stop["gap_high"] <= 0.6
        assert stop["episodes"] == 6 and results[condition]["seeds"] == list(range(1000, 1006))
    assert results["train"]["sequential"]["episodes"] == max(r["sequential"]["episodes"] for r in results.values())
    for result in results.values():  # each condition's own cost (the cost model's refit), not the group's
        assert (
            result["env_steps"] == sum(result["lengths"])
            and 0 < round(result["timings"]["total"], 2) == result["seconds"]
        )
        assert result["timings"]["env_step"] + result["timings"]["policy"] < result["timings"]["total"]
        assert result["episodes_run"] == len(result["successes"]) == 6
        assert result["machine"] == machine.current()  # the CPU that ran it, as every step records
    assert sum(r["seconds"] for r in results.values()) <= wall  # the group's time split, never counted twice
    from lerobot_factorworld.study.plan.cost import fit_constants

    # every episode runs to its 4-step limit: the refit's fraction of the horizon counts the episodes each ran
    assert fit_constants(plan, out)["eval"]["episode_fraction"]["pick-place"] == 1.0
    rows = {r["condition"]: r for r in csv.DictReader(open(out / "results.csv"))}
    assert float(rows["light"]["gap_ci_low"]) == results["light"]["sequential"]["gap_low"]  # the anytime interval
    episodes = read_episodes(out / "episodes.parquet")
    assert len(episodes) == sum(len(r["seeds"]) for r in results.values())  # every episode run
    report = (out / "report.md").read_text()
    assert "## How each condition stopped" in report and "anytime-valid" in report and "within tolerance" in report
    assert "bootstrap" not in report.split("## How each condition stopped")[1]  # no fixed-n interval shown
    page = (out / "report.html").read_text()  # the page: how each stopped, the stages, the paired viewer; no bootstrap
    assert "How each condition stopped" in page and "within tolerance" in page and "Paired episodes" in page
    assert "bootstrap" not in page and "The paper&#x27;s claims" not in page and "The paper's claims" not in page
    blocks = sorted(p.name for p in plan.evaluations()[1].folder(out).joinpath("blocks").iterdir())
    assert blocks[0] == "1000.json" and json.loads(
        (plan.evaluations()[1].folder(out) / "blocks" / blocks[0]).read_text()
    )
    # the same command again: every evaluation cached
    assert all(is_done(step, out) for step in plan.steps)
    again = run_study(profile.study(), profile.options(), "factorworld profile ...")
    assert again.ran["eval"] == 0
    # a group interrupted after its blocks but before its results: rerun, it reads every block back and runs
    # none again, and its cost says so (the cost model's refit counts only the episodes a run ran)
    for step in plan.evaluations():
        (step.folder(out) / "result.json").unlink()
    resumed = run_study(profile.study(), profile.options(), "factorworld profile ...")
    assert resumed.ran["eval"] == 3
    reread = {r["condition"]: r for r in (read_result(s, out) for s in plan.evaluations())}
    for condition, result in reread.items():
        assert result["successes"] == results[condition]["successes"] and result["seeds"] == results[condition]["seeds"]
        assert result["episodes_run"] == 0 and result["env_steps"] == 0
    assert fit_constants(plan, out)["eval"]["episode_fraction"].get("pick-place") != 0

    # results where the Hub shows them: one entry per task and condition, the documented fields
    import yaml

    from lerobot_factorworld import __version__
    from lerobot_factorworld.study.results.eval_results import ENTRY_FIELDS, card_problems, entry_problems

    entries = yaml.safe_load((out / ".eval_results" / "factorworld.yaml").read_text())
    assert [e["dataset"]["task_id"] for e in entries] == [
        "pick-place/train",
        "pick-place/light",
        "pick-place/table_texture",
    ]
    for entry in entries:
        assert tuple(entry) == ENTRY_FIELDS and set(entry["dataset"]) == {"id", "task_id"}
        assert entry["value"] == 0.0 and isinstance(entry["value"], float)  # success in percent
        assert "6 episodes" in entry["notes"] and "anytime-valid 95% interval" in entry["notes"]
        assert f"lerobot_factorworld {__version__}" in entry["notes"]
    assert "stopped: within tolerance" in entries[1]["notes"]
    card = yaml.safe_load((out / "eval.yaml").read_text())
    assert {t["id"] for t in card["tasks"]} == {e["dataset"]["task_id"] for e in entries}
    assert card_problems(card) == [] and entry_problems(entries, [t["id"] for t in card["tasks"]]) == []
    assert {e["dataset"]["id"] for e in entries} == {"someone/factor-world"}  # --hub_benchmark
    # factorworld report, from the written files alone, writes the same Hub files
    from lerobot_factorworld.study.report.write import regenerate_report

    written = {p: p.read_bytes() for p in [out / "eval.yaml", *(out / ".eval_results").glob("*.yaml")]}
    for path in written:
        path.unlink()
    regenerate_report(str(out / "results.csv"), None, None)
    assert {p: p.read_bytes() for p in written} == written
    import datasets

    loaded = datasets.load_dataset("parquet", data_files=str(out / "episodes.parquet"), split="train")
    assert loaded.num_rows == len(episodes) and "success" in loaded.column_names


def test_push_opens_a_pull_request_on_the_model_repo_and_offline_loses_nothing(tmp_path, monkeypatch):
    """The pull request's files and ``create_pr`` through a stand-in for the Hub client; then the real path with
    ``HF_HUB_OFFLINE=1`` (read when huggingface_hub is imported: a new process): one line, files unchanged."""
    import subprocess
    import sys

    import huggingface_hub

    from lerobot_factorworld.study.results import eval_results

    (tmp_path / ".eval_results").mkdir()
    (tmp_path / ".eval_results" / "factorworld.yaml").write_text("- value: 1.0\n")
    (tmp_path / "episodes.parquet").write_bytes(b"PAR1")
    calls = []

    class Api:
        def create_commit(self, repo_id, operations, commit_message, create_pr):
            calls.append((repo_id, sorted(o.path_in_repo for o in operations), create_pr))
            return type("Commit", (), {"pr_url": f"https://huggingface.co/{repo_id}/discussions/1"})()

    monkeypatch.setattr(huggingface_hub, "HfApi", Api)
    monkeypatch.setattr(eval_results, "check_hub_reachable", lambda: None)
    opened, line = eval_results.open_model_pr(tmp_path, "someone/bc")
    assert opened and calls == [
        ("someone/bc", [".eval_results/factorworld.yaml", "factorworld/episodes.parquet"], True)
    ]
    assert line.endswith("/discussions/1")

    code = (
        "from lerobot_factorworld.study.results.eval_results import open_model_pr\n"
        f"print(*open_model_pr({str(tmp_path)!r}, 'someone/bc'), sep='\\n')\n"
    )
    env = {**__import__("os").environ, "HF_HUB_OFFLINE": "1", "HF_TOKEN": "hf_not_a_token"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    opened, line = proc.stdout.strip().splitlines()[-2:]
    assert opened == "False" and line.startswith("warning: no pull request opened on someone/bc: could not reach")
    assert "nothing was lost" in line and (tmp_path / "episodes.parquet").read_bytes() == b"PAR1"
