"""``episodes.parquet`` (one row per evaluated episode, ``study/results/episodes.py``), its dataset card and its push.

Fast: a small study runs in this process with fake collect and eval runners (as in test_provenance.py) and
the real report. The fake collection writes the side-car ``factorworld collect`` would (the real sampling,
no demos), and the fake evaluation builds its environments with the real ``FactorWorldEnvConfig`` of the
evaluation step and records made-up outcomes, so the environments the records rebuild are checked against
an independent path. Nothing here reaches the network: the Hub is faked, or offline."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import httpx
import huggingface_hub
import pandas as pd
import pyarrow.parquet as pq
import pytest
from huggingface_hub.errors import HfHubHTTPError

from lerobot_factorworld.core.settings import SettingError, parse_config
from lerobot_factorworld.datasets import hub
from lerobot_factorworld.protocol.conditions import fingerprint
from lerobot_factorworld.protocol.sidecar import SIDECAR
from lerobot_factorworld.study import runner
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.report.write import regenerate_report
from lerobot_factorworld.study.results import episodes
from lerobot_factorworld.study.results.episodes import (
    EPISODE_COLUMN_NAMES,
    EPISODES_FILE,
    SCHEMA,
    dataset_card,
    evaluation_episodes,
    push_results,
    read_episodes,
    read_episodes_table,
)
from lerobot_factorworld.study.results.rows import (
    RESULTS_FILE,
    Evaluation,
    commits_of,
    finished_evaluations,
    read_results,
)
from lerobot_factorworld.study.run.collect_step import collect_config
from lerobot_factorworld.study.run.eval_env import eval_env_config
from lerobot_factorworld.study.run.executors import InlineExecutor
from lerobot_factorworld.study.run.inputs import CollectInputs, EvalInputs
from lerobot_factorworld.study.run.result import DATA_DIR, INPUTS_FILE, read_result
from lerobot_factorworld.study.run.step import Step
from lerobot_factorworld.study.run.worker import RUNNERS

SETTINGS = {
    "name": "records",
    "tasks": ["door-open"],
    "n_train_envs": [1, 2],
    "train_factors": ["light", "table_texture", "camera_pos"],
    "factors": ["light", "table_texture"],
    "pairs": ["light+table_texture"],
    "methods": [{"name": "bc", "policy": {"type": "bc"}}],
    "collect": {"demos": 2},
    "eval": {"n_test_envs": 2, "episodes": 4},
}
SUCCESSES = {"train": 3, "light": 2, "table_texture": 1, "light+table_texture": 0}  # of 4 episodes, the first k
REPO = "someone/factorworld_records"
DATASETS = "https://huggingface.co/datasets/"  # what HfApi.create_repo answers: a repo URL


def _fake_collect(step: Step, folder: Path, deps: list[Path]) -> dict:
    """The side-car of the dataset ``factorworld collect`` would make (its settings and environments), no demos."""
    from lerobot_factorworld.datasets.collect import plan_jobs

    root = folder / DATA_DIR
    cfg = collect_config(CollectInputs.from_dict(step.inputs), root, step.key)
    sidecar = {
        "settings": cfg.fingerprint(),
        "history": [],
        "environments": [job.config for job in plan_jobs(cfg)],
        "failures": {},
    }
    (root / SIDECAR).parent.mkdir(parents=True)
    (root / SIDECAR).write_text(json.dumps(sidecar))
    return {"root": str(root), "repo_id": cfg.repo_id, "episodes": 2, "frames": 2, "failures": {}}


def _fake_eval(step: Step, folder: Path, deps: list[Path]) -> dict:
    """The environments as ``run_eval`` builds them (its env config), made-up outcomes: the first k succeed."""
    collect = next(d for d in deps if d.parent.name == "collect")
    inputs = EvalInputs.from_dict(step.inputs)
    collect_inputs = CollectInputs.from_dict(json.loads((collect / INPUTS_FILE).read_text())["inputs"])
    env_cfg = eval_env_config(collect_inputs, read_result(collect)["root"], inputs)
    configs = env_cfg.suites(env_cfg.task_names[0])[inputs.condition]
    k = SUCCESSES[inputs.condition]
    successes = [i < k for i in range(inputs.episodes)]
    return {
        "condition": inputs.condition,
        "successes": successes,
        "seeds": [inputs.start_seed + i for i in range(inputs.episodes)],
        "stages": ["succeeded" if s else "reached" for s in successes],
        "lengths": [40 + i for i in range(inputs.episodes)],
        "n_envs": len(configs),
        "envs_visited": len(configs),
        "equal_visits": True,
        "fingerprint": fingerprint(configs, env_cfg.sampling.widths.get("object_pos")),
        "checkpoint": str(folder),
        "configs": [c.to_dict() for c in configs],  # for the test only: what the records must rebuild
    }


def _fake_train(step: Step, folder: Path, deps: list[Path]) -> dict:
    return {"checkpoint": str(folder / "train"), "steps": 1}


def _fake_steps(mp: pytest.MonkeyPatch) -> None:
    for kind, fake in (("collect", _fake_collect), ("train", _fake_train), ("eval", _fake_eval)):
        mp.setitem(RUNNERS, kind, fake)
    mp.setattr(runner, "make_executor", lambda kind, study_dir, *a: InlineExecutor(study_dir, a[-1]))


def _config(folder: Path, **overrides) -> tuple[StudyConfig, Path]:
    path = folder / "records.yaml"
    path.write_text(json.dumps({**SETTINGS, "out_dir": str(folder / "study"), **overrides}))
    return parse_config(StudyCommand, [f"--config_path={path}"], "study"), path


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> tuple[StudyConfig, runner.StudyOutcome]:
    """The small study run once (2 datasets, 2 checkpoints, 8 evaluations of 4 episodes), report included."""
    cfg, _ = _config(tmp_path_factory.mktemp("records"))
    with pytest.MonkeyPatch.context() as mp:
        _fake_steps(mp)
        outcome = runner.run_study(*cfg.parts(), command="test")
    assert not outcome.failed and outcome.ran == {"collect": 2, "train": 2, "eval": 8}
    return cfg, outcome


def _copy(study, tmp_path: Path) -> tuple[StudyConfig, Path]:
    """The finished study in a folder of the test's own (step results name their files relative to it)."""
    cfg, outcome = study
    shutil.copytree(outcome.study_dir, tmp_path / "study")
    return _config(tmp_path)


# --- the rows --------------------------------------------------------------------------------------


def test_one_row_per_episode_with_its_environment_outcome_and_code(study):
    cfg, outcome = study
    path = outcome.study_dir / EPISODES_FILE
    assert pq.read_schema(path).remove_metadata() == SCHEMA
    rows = read_episodes(path)
    cells = read_results(outcome.results)
    assert len(rows) == sum(c["episodes"] for c in cells) == 8 * 4
    by_step = {c["step"]: c for c in cells}
    for step in make_plan(cfg).of_kind("eval"):
        result = read_result(step, cfg.out_dir)
        mine = [r for r in rows if r["step"] == step.key]
        cell = by_step[step.key]
        assert [r["episode_ix"] for r in mine] == [0, 1, 2, 3]
        assert [r["episode_seed"] for r in mine] == [1000, 1001, 1002, 1003] == result["seeds"]
        assert [r["success"] for r in mine] == result["successes"]
        assert sum(r["success"] for r in mine) == cell["successes"] == SUCCESSES[cell["condition"]]
        assert [r["stage"] for r in mine] == result["stages"]
        assert [r["n_steps"] for r in mine] == result["lengths"] == [40, 41, 42, 43]
        for row in mine:
            assert {k: row[k] for k in ("study", "method", "policy", "task")} == {
                "study": "records",
                "method": "bc",
                "policy": "bc",
                "task": "door-open",
            }
            for column in ("n_train_envs", "seed", "widths", "condition", "n_factors"):
                assert row[column] == cell[column], column
            assert (row["commit"] or "", row["source_hash"]) == (cell["commit"], cell["source_hash"])
            assert row["env_index"] == row["episode_seed"] % cell["n_envs"]
            env = result["configs"][row["env_index"]]  # as the evaluation's own env config built it
            assert row["env_id"] == env["env_id"]
            assert json.loads(row["factors"]) == env["factors"]
            assert row["content"] is None  # door-open: no family records
    light = next(r for r in rows if r["condition"] == "light")
    train = next(r for r in rows if r["condition"] == "train" and r["n_train_envs"] == light["n_train_envs"])
    assert json.loads(light["factors"])["light"] != json.loads(train["factors"])["light"]  # the shifted factor
    assert json.loads(light["factors"])["table_texture"] == json.loads(train["factors"])["table_texture"]
    assert all(len(r["source_hash"]) == 12 for r in rows)


def test_the_file_loads_with_datasets_and_pandas_and_a_rewrite_is_byte_identical(study, tmp_path):
    import datasets

    _, outcome = study
    path = outcome.study_dir / EPISODES_FILE
    loaded = datasets.load_dataset("parquet", data_files=str(path), split="train", cache_dir=str(tmp_path / "cache"))
    assert loaded.num_rows == 32 and tuple(loaded.column_names) == EPISODE_COLUMN_NAMES
    assert loaded.features["success"].dtype == "bool" and loaded.features["episode_seed"].dtype == "int64"
    assert loaded.features["factors"].dtype == "string" and loaded[0]["condition"] == "train"
    frame = pd.read_parquet(path)
    assert frame.shape == (32, len(EPISODE_COLUMN_NAMES)) and frame["success"].dtype == bool
    assert frame.groupby("condition")["success"].sum().to_dict() == {c: 2 * k for c, k in SUCCESSES.items()}
    again = episodes.write_episodes(read_episodes(path), tmp_path / EPISODES_FILE)
    assert again.read_bytes() == path.read_bytes()  # a rerun rewrites the same file
    chunks = tmp_path / "chunks.parquet"  # rows stream in, a chunk at a time (a generator, as a study gives them)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(episodes, "CHUNK_ROWS", 5)
        episodes.write_episodes((row for row in read_episodes(path)), chunks)
    assert pq.ParquetFile(chunks).num_row_groups == 7 and read_episodes(chunks) == read_episodes(path)
    empty = episodes.write_episodes([], tmp_path / "none.parquet")
    assert read_episodes(empty) == [] and pq.read_schema(empty).remove_metadata() == SCHEMA
    published = tmp_path / "published"  # `factorworld report --out=` carries the episodes with the results
    regenerate_report(outcome.study_dir / "results.csv", out=published)
    assert (published / EPISODES_FILE).read_bytes() == path.read_bytes()
    pq.write_table(pq.read_table(path).drop(["stage"]), tmp_path / "other.parquet")
    with pytest.raises(ValueError, match=r"other.parquet is not an episodes file: no column\(s\) stage"):
        read_episodes(tmp_path / "other.parquet")


def test_environments_are_never_guessed(study, tmp_path):
    """Factor values come from the evaluation's own environments or are null: another fingerprint (sampling
    changed since) or a deleted dataset gives null, never other values."""
    cfg, outcome = study
    evaluation = next(e for e in _evaluations(cfg) if e.labels["condition"] == "light")
    rebuild = episodes.environment_rebuilder(outcome.study_dir)
    configs = episodes.condition_environments(evaluation.step, evaluation.result, rebuild)
    assert [c.to_dict() for c in configs] == evaluation.result["configs"]
    other = {**evaluation.result, "fingerprint": "0" * 16}
    assert episodes.condition_environments(evaluation.step, other, rebuild) is None
    cfg, _ = _copy(study, tmp_path)
    copied = [e for e in _evaluations(cfg) if e.labels["condition"] == "light"]
    collect = next(s for s in make_plan(cfg).of_kind("collect") if s.key in copied[0].step.deps)
    shutil.rmtree(collect.folder(cfg.out_dir) / DATA_DIR)  # datasets deleted to save space
    rows = list(episodes.episode_rows(cfg, copied, cfg.out_dir))
    assert rows[0]["factors"] is None and rows[0]["env_id"] is None and rows[0]["env_index"] == 1000 % 2
    assert [r["success"] for r in rows[:4]] == [True, True, False, False]


def _evaluations(cfg: StudyConfig) -> list[Evaluation]:
    return finished_evaluations(make_plan(cfg), cfg.out_dir)


def test_a_familys_episode_records_are_the_content_column():
    pick = [
        {"instruction": "pick up the red mug", "target": "mug_red"},
        {"instruction": "grab the ball", "target": "b"},
    ]
    result = {"successes": [True, False], "seeds": [7, 8], "n_envs": 2, "pick": pick}
    labels = {"method": "m", "task": "pick", "n_train_envs": 2, "seed": 0, "widths": "default"}
    rows = evaluation_episodes(
        {**labels, "condition": "held_out_objects"}, result, None, study="s", policy="bc", step="k"
    )
    assert [json.loads(r["content"]) for r in rows] == pick
    assert [r["env_index"] for r in rows] == [1, 0] and rows[0]["n_factors"] == 1
    assert rows[0]["stage"] is None and rows[0]["n_steps"] is None and rows[0]["commit"] is None  # recorded later
    with pytest.raises(ValueError, match="3 environments given for an evaluation of 2"):
        evaluation_episodes({**labels, "condition": "train"}, result, [None] * 3, study="s", policy="bc", step="k")


# --- the card ------------------------------------------------------------------------------------------


def test_the_card_names_the_study_and_gives_wilson_intervals_per_condition(study):
    _, outcome = study
    table = read_episodes_table(outcome.study_dir / EPISODES_FILE)
    card = dataset_card(table, REPO)
    front, body = card.split("---\n")[1:3]
    assert "configs:\n- config_name: default\n  data_files:\n  - split: train\n    path: episodes.parquet" in front
    assert "- door-open" in front and "license: apache-2.0" in front
    assert "- **Tasks:** door-open" in body
    assert "- **Factors shifted:** light, table_texture" in body
    assert "- **Conditions:** train, light, table_texture, light+table_texture" in body
    assert "- **Methods (LeRobot policy type):** bc (`bc`)" in body
    assert "- **N (training environments):** 1, 2; **seeds:** 0" in body
    assert "- **Episodes:** 32, 12 successful" in body
    rows = table.to_pylist()
    assert f"- **Made at commit(s):** {commits_of(rows)[0]}\n" in body and len(commits_of(rows)) == 1
    assert f'load_dataset("{REPO}", split="train")' in body
    assert "| `episode_seed` | its reset seed" in body
    assert "| method | task | N | widths | condition | n_episodes | n_success | pc_success | pc_success_ci95 |" in body
    # 2 of 4: centre 0.5, half-width 1.96 * sqrt(0.0625 + 0.0600) / 1.9604 = 0.3500 -> [15.0, 85.0]
    assert "| bc | door-open | 1 | default | light | 4 | 2 | 50.0 | [15.0, 85.0] |" in body
    # 0 of 4: [0, 1.96^2 / (4 + 1.96^2)] = [0, 0.4899]
    assert "| bc | door-open | 2 | default | light+table_texture | 4 | 0 | 0.0 | [0.0, 49.0] |" in body
    assert dataset_card(episodes.episodes_table(rows), REPO) == card  # from the rows as from the file
    summary = episodes.condition_summary(table)
    assert len(summary) == 8 and set(summary[0]) >= {"n_episodes", "n_success", "pc_success", "pc_success_ci95"}


# --- settings ------------------------------------------------------------------------------------------


def test_push_settings_are_checked_in_one_line_before_any_work(tmp_path, monkeypatch):
    for flags, message in (
        (["--push_to_hub=true"], "push_to_hub=true needs --hub_repo_id=<user>/<name>"),
        (["--push_to_hub=true", "--hub_repo_id=noslash"], "hub_repo_id: repo_id must look like 'user/name'"),
        (["--push_to_hub=true", "--hub_repo_id=local/x"], "needs a Hub hub_repo_id ('user/name'"),
    ):
        path = tmp_path / "c.yaml"
        path.write_text(json.dumps({**SETTINGS, "out_dir": str(tmp_path / "s")}))
        with pytest.raises(SettingError, match=re.escape(message)) as err:
            parse_config(StudyCommand, [f"--config_path={path}", *flags], "study")
        assert "\n" not in str(err.value)
    cfg, _ = _config(tmp_path, hub_repo_id="local/kept")  # not pushing: the repo id is not used
    assert not cfg.push_to_hub
    cfg, _ = _config(tmp_path, push_to_hub=True, hub_repo_id=REPO)
    ran = []
    monkeypatch.setitem(RUNNERS, "collect", lambda *a: ran.append(a))
    monkeypatch.setattr(huggingface_hub, "get_token", lambda: None)  # not logged in
    with pytest.raises(ValueError, match="push_to_hub=true needs a Hugging Face token with write access"):
        runner.run_study(*cfg.parts(), command="no token")
    assert not ran and not Path(cfg.out_dir).exists()


# --- the push ---------------------------------------------------------------------------------------------


class FakeHub:
    """The Hub's answers, recorded: reachable, and a commit that succeeds or raises ``error``."""

    def __init__(self, error: Exception | None = None) -> None:
        self.error, self.commits, self.probes = error, [], []

    def install(self, monkeypatch: pytest.MonkeyPatch) -> FakeHub:
        hub_session = type("Session", (), {"head": self.head})()
        monkeypatch.setattr(huggingface_hub, "get_session", lambda: hub_session)
        monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", lambda _, repo_id, **kw: DATASETS + repo_id)
        monkeypatch.setattr(huggingface_hub.HfApi, "create_commit", lambda _api, *a, **kw: self.commit(*a, **kw))
        return self

    def head(self, url: str, timeout: float) -> httpx.Response:
        assert timeout == hub.PROBE_TIMEOUT_S <= 10  # the probe never waits long
        self.probes.append(url)
        return httpx.Response(200)

    def commit(self, repo_id, operations, **kw):
        if self.error is not None:
            raise self.error
        self.commits.append((repo_id, {op.path_in_repo: op.path_or_fileobj for op in operations}, kw))


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_a_push_sends_the_episodes_the_results_and_the_card(study, monkeypatch):
    _, outcome = study
    fake = FakeHub().install(monkeypatch)
    before = _files(outcome.study_dir)
    pushed, line = push_results(outcome.study_dir, REPO)
    assert pushed, line
    assert line == (
        f"pushed episodes.parquet (32 episodes), results.csv and the card to https://huggingface.co/datasets/{REPO}"
    )
    ((repo, files, kw),) = fake.commits
    assert fake.probes == [huggingface_hub.constants.ENDPOINT]
    assert repo == REPO and kw["repo_type"] == "dataset" and set(files) == {EPISODES_FILE, RESULTS_FILE, "README.md"}
    assert Path(files[EPISODES_FILE]).read_bytes() == before[EPISODES_FILE]
    assert files["README.md"].decode() == dataset_card(read_episodes_table(outcome.study_dir / EPISODES_FILE), REPO)
    assert _files(outcome.study_dir) == before and "README.md" not in before


@pytest.mark.parametrize(
    ("error", "says"),
    [
        (httpx.ConnectError("[Errno -3] Temporary failure in name resolution"), "lost the Hugging Face Hub while"),
        (
            HfHubHTTPError("403 Forbidden", response=httpx.Response(403, request=httpx.Request("POST", DATASETS))),
            "failed (HfHubHTTPError: 403 Forbidden)",
        ),
    ],
)
def test_a_failed_upload_is_one_line_and_loses_nothing(study, monkeypatch, error, says):
    _, outcome = study
    FakeHub(error).install(monkeypatch)
    before = _files(outcome.study_dir)
    pushed, line = push_results(outcome.study_dir, REPO)
    assert not pushed and "\n" not in line and line.startswith("warning: ") and says in line, line
    assert f"nothing was lost: episodes.parquet and results.csv are complete in {outcome.study_dir}" in line
    assert _files(outcome.study_dir) == before


def test_the_study_pushes_after_its_report_and_an_unreachable_hub_is_one_warning(study, tmp_path, monkeypatch, capsys):
    from lerobot_factorworld.cli import main

    _, path = _copy(study, tmp_path)
    _fake_steps(monkeypatch)
    monkeypatch.setattr(huggingface_hub, "get_token", lambda: "hf_token")
    FakeHub(httpx.ConnectError("[Errno -2] Name or service not known")).install(monkeypatch)
    before = _files(tmp_path / "study")
    main(["study", f"--config={path}", "--push_to_hub=true", f"--hub_repo_id={REPO}"])  # returns: exit status 0
    out, err = capsys.readouterr()
    warnings = [line for line in err.splitlines() if REPO in line]
    assert len(warnings) == 1 and warnings[0].startswith(f"warning: not pushed to {REPO}: lost the Hugging Face Hub")
    assert "Traceback" not in err and "ran 0 collect, 0 train, 0 eval" in out
    after = _files(tmp_path / "study")
    assert {name: after[name] for name in (EPISODES_FILE, RESULTS_FILE)} == {
        name: before[name] for name in (EPISODES_FILE, RESULTS_FILE)
    }
    fake = FakeHub().install(monkeypatch)
    outcome = runner.run_study(*_config(tmp_path, push_to_hub=True, hub_repo_id=REPO)[0].parts(), command="again")
    assert (
        outcome.pushed and len(fake.commits) == 1 and "pushed episodes.parquet (32 episodes)" in capsys.readouterr().out
    )


def test_offline_the_push_says_so_in_one_line(study, tmp_path):
    """The real path, no fake: ``HF_HUB_OFFLINE=1`` (read when huggingface_hub is imported: a new process)."""
    _, outcome = study
    code = (
        "from lerobot_factorworld.study.results.episodes import push_results\n"
        f"pushed, line = push_results({str(outcome.study_dir)!r}, {REPO!r})\n"
        "print(pushed)\nprint(line)\n"
    )
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "HF_TOKEN": "hf_not_a_token"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    pushed, line = proc.stdout.strip().splitlines()[-2:]
    assert pushed == "False" and "Traceback" not in proc.stderr
    assert line.startswith(f"warning: not pushed to {REPO}: could not reach the Hugging Face Hub at "), line
    assert "OfflineModeIsEnabled" in line and "nothing was lost" in line
