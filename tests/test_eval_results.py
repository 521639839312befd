"""The Hub files of a profile (study/results/eval_results.py) against the Hub's documented format: the examples
of hub-docs' ``eval_results.yaml`` and ``docs/hub/eval-results.md`` pass the checks, each departure is named, and
the files written hold one model's results per set-up, with every task they name declared in ``eval.yaml``.
Fast: no simulation (rows as results.csv holds them)."""

import math

import pytest
import yaml

from lerobot_factorworld.study.plan.config import HUB_BENCHMARK, StudyConfig
from lerobot_factorworld.study.results import eval_results
from lerobot_factorworld.study.results.eval_results import card_problems, entry_problems

# Transcribed from the Hub's documentation (hub-docs: eval_results.yaml, docs/hub/eval-results.md)
HUB_ENTRIES = """
- dataset:
    id: cais/hle
    task_id: default
    revision: 5503434ddd753f426f4b38109466949a1217c2bb
  value: 20.90
  verifyToken: some-token
  date: "2025-01-15"
  source:
    url: https://huggingface.co/spaces/SaylorTwift/smollm3-mmlu-pro
    name: Eval traces
    user: SaylorTwift
  notes: "no-tools"
- dataset:
    id: Idavidrein/gpqa
    task_id: gpqa_diamond
  value: 0.412
"""
HUB_CARDS = [
    """
name: MathArena AIME 2026
description: The American Invitational Mathematics Exam (AIME).
evaluation_framework: math-arena
tasks:
  - id: MathArena/aime_2026
""",
    """
name: MathArena AIME 2026
description: The American Invitational Mathematics Exam (AIME).
evaluation_framework: "math-arena"
tasks:
  - id: MathArena/aime_2026
    config: default
    split: test
""",
    """
name: Humanity's Last Exam
description: A multi-modal benchmark.
evaluation_framework: "inspect-ai"
tasks:
  - id: hle
    config: default
    split: test
    field_spec: {input: question, input_image: image, target: answer}
    solvers: [{name: generate}]
    scorers: [{name: model_graded_fact, args: {model: openai/o3-mini}}]
""",
]


def test_the_hubs_documented_examples_pass_and_each_departure_is_named():
    assert entry_problems(yaml.safe_load(HUB_ENTRIES), ["default", "gpqa_diamond"]) == []
    for card in HUB_CARDS:
        assert card_problems(yaml.safe_load(card)) == []
    entries = yaml.safe_load(HUB_ENTRIES)
    del entries[1]["value"]
    entries[0]["dataset"]["split"] = "test"
    entries[0]["value"] = "20.9"
    entries[0]["source"] = {"name": "no url"}
    assert entry_problems(entries, ["default"]) == [
        "entry 0's dataset has split, not a documented field",
        "entry 0's value is not a finite number",
        "entry 0's source lacks url",
        "entry 1 lacks value",
        "entry 1 names task 'gpqa_diamond', which the benchmark's eval.yaml does not declare",
    ]
    assert entry_problems([]) == ["an .eval_results file is a non-empty list of entries"]
    assert entry_problems([{"dataset": {"id": "a/b", "task_id": "t"}, "value": math.nan}]) == [
        "entry 0's value is not a finite number"
    ]
    twice = yaml.safe_load(HUB_ENTRIES)[1:] * 2
    assert entry_problems(twice) == [
        "entry 1 names task 'gpqa_diamond' again: a variant of a benchmark goes in a file of its own"
    ]
    card = yaml.safe_load(HUB_CARDS[0])
    del card["evaluation_framework"]
    card["tasks"] += [{"id": "MathArena/aime_2026", "name": "AIME", "metric": "accuracy"}]
    assert card_problems(card) == [
        "eval.yaml lacks evaluation_framework",
        "eval.yaml's task 1 has name, not a documented field",
        "eval.yaml's task 1 has metric, not a documented field",
        "eval.yaml declares task 'MathArena/aime_2026' more than once",
    ]
    inspect = yaml.safe_load(HUB_CARDS[2])
    del inspect["tasks"][0]["scorers"]
    assert card_problems(inspect) == ["eval.yaml's task 0 lacks scorers (inspect-ai)"]


def _row(method: str, condition: str, widths: str = "default", successes: int = 6) -> dict:
    return {
        "study": "profile", "method": method, "policy": "bc", "task": "pick-place", "n_train_envs": 5, "seed": 0,
        "widths": widths, "condition": condition, "episodes": 10, "successes": successes,
        "success_rate": successes / 10, "ci_low": 0.3, "ci_high": 0.8, "gap": 0.0 if condition == "train" else 0.2,
        "gap_ci_low": math.nan, "gap_ci_high": math.nan,
    }  # fmt: skip


def test_one_file_per_model_and_set_up_every_task_declared_and_stale_files_removed(tmp_path):
    cfg = StudyConfig(
        tasks=["pick-place"], factors=["camera_pos", "light"], radius_factors=["camera_pos"],
        methods=[{"name": "bc", "policy": {"type": "bc"}}], hub_benchmark="someone/factor-world",
    )  # fmt: skip
    rows = [_row("bc", "train"), _row("bc", "camera_pos"), _row("bc", "light"), _row("bc", "train", "camera_pos=wide")]
    rows.append(_row("bc", "camera_pos", "camera_pos=wide", successes=2))
    written = eval_results.write_eval_results(cfg, rows, tmp_path)
    assert [p.relative_to(tmp_path).as_posix() for p in written] == [
        ".eval_results/factorworld.yaml",
        ".eval_results/factorworld_camera_pos-wide.yaml",  # a variant of the benchmark: its own file
        "eval.yaml",
    ]
    main, wide = (yaml.safe_load(p.read_text()) for p in written[:2])
    card = yaml.safe_load(written[2].read_text())
    assert [e["dataset"]["task_id"] for e in main] == ["pick-place/train", "pick-place/camera_pos", "pick-place/light"]
    assert [e["value"] for e in wide] == [60.0, 20.0] and "widths camera_pos=wide" in wide[1]["notes"]
    assert {e["dataset"]["id"] for e in main + wide} == {"someone/factor-world"}
    assert card["evaluation_framework"] == eval_results.EVALUATION_FRAMEWORK and card_problems(card) == []
    assert [t["id"] for t in card["tasks"]] == ["pick-place/train", "pick-place/camera_pos", "pick-place/light"]
    assert (
        entry_problems(main, [t["id"] for t in card["tasks"]])
        == entry_problems(wide, [t["id"] for t in card["tasks"]])
        == []
    )

    # two given checkpoints: each model's entries in its own folder, never in one file; the flat files are gone,
    # a file of the user's own stays, and a method's name cannot lead outside the folder
    (tmp_path / ".eval_results" / "mine.yaml").write_text("- value: 1\n")
    two = [*rows[:3], *(dict(r, method="../act") for r in rows[:3])]
    written = eval_results.write_eval_results(cfg, two, tmp_path)
    assert sorted(p.relative_to(tmp_path).as_posix() for p in written) == [
        ".eval_results/_act/factorworld.yaml",
        ".eval_results/bc/factorworld.yaml",
        "eval.yaml",
    ]
    assert sorted(p.relative_to(tmp_path).as_posix() for p in (tmp_path / ".eval_results").rglob("*.yaml")) == [
        ".eval_results/_act/factorworld.yaml",
        ".eval_results/bc/factorworld.yaml",
        ".eval_results/mine.yaml",
    ]
    # one checkpoint at two N: two set-ups of the benchmark, a file each
    two_n = [*rows[:3], *(dict(r, n_train_envs=10) for r in rows[:3])]
    assert sorted(eval_results.eval_files(cfg, two_n)) == [
        ".eval_results/factorworld_n10.yaml",
        ".eval_results/factorworld_n5.yaml",
    ]
    opened, line = eval_results.open_model_pr(tmp_path, "someone/bc")  # no one model's results: before the Hub
    assert not opened and line.startswith("warning: no pull request opened on someone/bc") and "\n" not in line


def test_the_benchmark_and_the_model_repo_are_checked_before_any_work(tmp_path):
    from lerobot_factorworld.study.run.options import RunOptions
    from lerobot_factorworld.study.runner import run_study

    trained = StudyConfig(methods=[{"name": "bc", "policy": {"type": "bc"}}], out_dir=str(tmp_path / "study"))
    assert trained.hub_benchmark == HUB_BENCHMARK
    with pytest.raises(ValueError, match="hub_benchmark: repo_id must look like 'user/name'"):
        StudyConfig(methods=[{"name": "bc", "policy": {"type": "bc"}}], hub_benchmark="factor world")
    with pytest.raises(ValueError, match="one given checkpoint's results .* 1 method\\(s\\), 1 of them trained"):
        run_study(trained, RunOptions(push_to_hub=True, model_repo_id="someone/bc"))
    assert not (tmp_path / "study").exists()
