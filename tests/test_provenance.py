"""Provenance of study results: what a step records about the code that made it (commit, clean tree, source
hash), the ``commit`` of ``results.csv`` rows, and the runner's handling of cached steps made by other code
(one warning line, ``--strict`` refusing, ``--rerun_stale`` redoing them and their dependents with the old
folders kept). Fast: the steps run in this process with fake runners (as in test_study_cache.py)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from lerobot_factorworld.core import machine, provenance
from lerobot_factorworld.core.provenance import Provenance, git_state, source_hash
from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study import runner
from lerobot_factorworld.study.plan import stale
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.grid import Plan, make_plan
from lerobot_factorworld.study.report.write import load_config
from lerobot_factorworld.study.results.rows import RESULT_COLUMNS, Evaluation, commits_of, csv_text, result_rows
from lerobot_factorworld.study.run.executors import InlineExecutor
from lerobot_factorworld.study.run.result import (
    INPUTS_FILE,
    MACHINE,
    PROVENANCE,
    RESULT_FILE,
    provenance_of,
    read_result,
)
from lerobot_factorworld.study.run.step import KINDS, RUN_CONFIG_FILE, Step
from lerobot_factorworld.study.run.worker import RUNNERS, run_step

GIT = shutil.which("git")
DOCS_RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
OTHER = "826fe542cafcf25ef4dd4d5f7e92595c9abe6388"  # a commit that is not this checkout's code
OTHER_HASH = "0" * 64
SETTINGS = {
    "tasks": ["door-open"],
    "n_train_envs": [1, 2],
    "train_factors": ["light", "table_texture", "camera_pos"],
    "factors": ["light", "table_texture"],
    "methods": [{"name": "bc", "policy": {"type": "bc"}}],
    "collect": {"demos": 2},
    "eval": {"n_test_envs": 2, "episodes": 2},
}


# --- the module: source hash, git state -------------------------------------------------------------


def test_source_hash_covers_the_packages_py_and_json_files_only(tmp_path):
    package = tmp_path / "pkg"
    (package / "study").mkdir(parents=True)
    (package / "__pycache__").mkdir()
    (package / "a.py").write_text("x = 1\n")
    (package / "study" / "b.json").write_text("{}")
    first = source_hash.__wrapped__(package)
    (package / "notes.txt").write_text("not source")
    (package / "__pycache__" / "a.cpython-312.pyc").write_bytes(b"\0")
    (package / "study" / "cost_model.json").write_text('{"refitted": true}')  # UNHASHED: changes no result
    assert source_hash.__wrapped__(package) == first
    (package / "a.py").write_text("x = 2\n")
    assert source_hash.__wrapped__(package) != first
    (package / "a.py").write_text("x = 1\n")
    (package / "study" / "b.json").rename(package / "b.json")  # the same content elsewhere: other code
    assert source_hash.__wrapped__(package) != first


def _git(repo: Path, *args: str) -> None:
    subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo, check=True, capture_output=True
    )


@pytest.mark.skipif(GIT is None, reason="needs git")
def test_git_state_is_the_head_clean_unless_the_package_source_changed(tmp_path, monkeypatch):
    repo = tmp_path / "repo"
    package = repo / "pkg"
    (package / "study").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "mod.py").write_text("")
    (package / "study" / "cost_model.json").write_text("{}")
    (repo / "README.md").write_text("readme\n")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "commit", "-q", "-m", "one")
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True).stdout.strip()
    assert git_state(package) == (head, True)
    (package / "results.csv").write_text("an output\n")  # untracked, not source
    (repo / "README.md").write_text("edited outside the package\n")
    (package / "study" / "cost_model.json").write_text('{"refitted": true}')
    assert git_state(package) == (head, True)
    (package / "new.py").write_text("")  # untracked source: the commit alone no longer gives the code
    assert git_state(package) == (head, False)
    (package / "new.py").unlink()
    _git(repo, "mv", "pkg/mod.py", "pkg/moved.py")  # a staged rename
    assert git_state(package) == (head, False)
    _git(repo, "mv", "pkg/moved.py", "pkg/mod.py")
    assert git_state(package) == (head, True)
    (package / "__init__.py").write_text("x = 1\n")
    assert git_state(package) == (head, False)
    outside = tmp_path / "not_a_checkout"
    outside.mkdir()
    assert git_state(outside) == (None, None)
    untracked = repo / "copy"  # a copy inside a checkout that does not track it (an installed package)
    untracked.mkdir()
    (untracked / "__init__.py").write_text("")
    assert git_state(untracked) == (None, None)
    monkeypatch.setenv("PATH", str(tmp_path / "no_bin"))  # no git at all: never an error
    assert git_state(package) == (None, None)


def test_this_checkout_is_named_by_its_head_and_its_source():
    now = provenance.current()
    assert now.source_hash == source_hash() and len(now.source_hash) == 64
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=provenance.PACKAGE_DIR, capture_output=True, text=True)
    if GIT is None or head.returncode != 0:
        assert now.commit is None and now.clean is None
    else:
        assert now.commit == head.stdout.strip() and now.clean in (True, False)
    assert Provenance.from_dict(now.to_dict()) == now
    dirty = Provenance(OTHER, False, OTHER_HASH)
    assert dirty.revision() == OTHER + "-dirty" and dirty.revision(short=True) == "826fe54-dirty"
    assert dirty.name == "826fe54-dirty (source 000000000000)"
    assert Provenance(OTHER, True, OTHER_HASH).name == "826fe54"
    assert Provenance(None, None, OTHER_HASH).name == "unknown (source 000000000000)"


# --- steps record it, keys do not hold it ---------------------------------------------------------------


def _fake_result(step: Step, folder: Path) -> dict:
    if step.kind == "collect":
        (folder / "data").mkdir()
        (folder / "data" / "marker").write_text(step.key)
        return {"root": str(folder / "data"), "repo_id": "x", "episodes": 2, "frames": 2, "failures": {}}
    if step.kind == "train":
        return {"checkpoint": str(folder / "train"), "steps": 1}
    return {
        "condition": step.meta["condition"],
        "successes": [True, False],
        "seeds": [1000, 1001],
        "n_envs": 2,
        "envs_visited": 2,
        "equal_visits": True,
        "fingerprint": "f" * 16,
        "checkpoint": str(folder),
    }


@pytest.fixture
def ran(monkeypatch) -> list[Step]:
    """The steps the fake runners ran, in order; every study of the test runs in this process."""
    out: list[Step] = []

    def fake(step, folder, deps):
        out.append(step)
        return _fake_result(step, folder)

    for kind in KINDS:
        monkeypatch.setitem(RUNNERS, kind, fake)
    monkeypatch.setattr(runner, "make_executor", lambda kind, study_dir, *a: InlineExecutor(study_dir, a[-1]))
    monkeypatch.setattr(runner, "write_report", lambda *a: (None, None, []))  # report/write.py: tested elsewhere
    return out


def _study(tmp_path: Path, *flags: str) -> tuple[StudyConfig, Path]:
    config = tmp_path / "study.yaml"
    config.write_text(json.dumps({**SETTINGS, "out_dir": str(tmp_path / "study")}))
    return parse_config(StudyCommand, [f"--config_path={config}", *flags], "study"), config


def test_a_step_records_its_provenance_and_its_key_does_not_hold_it(tmp_path, ran, monkeypatch):
    cfg, _ = _study(tmp_path)
    plan = make_plan(cfg)
    collect = plan.of_kind("collect")[0]
    run_step(collect.to_dict(), cfg.out_dir)
    stored = json.loads((collect.folder(cfg.out_dir) / RESULT_FILE).read_text())
    assert stored[PROVENANCE] == provenance.current().to_dict()
    assert provenance_of(stored) == provenance.current()
    assert stored[MACHINE] == machine.current() and stored[MACHINE]["cpus"] == len(os.sched_getaffinity(0))
    inputs_text = (collect.folder(cfg.out_dir) / INPUTS_FILE).read_text()
    assert "provenance" not in inputs_text and MACHINE not in inputs_text
    monkeypatch.setattr(provenance, "current", lambda: Provenance(OTHER, False, OTHER_HASH))
    assert [s.key for s in make_plan(cfg).steps] == [s.key for s in plan.steps]  # other code: the same keys
    train = plan.of_kind("train")[0]
    run_step(train.to_dict(), cfg.out_dir)
    assert read_result(train, cfg.out_dir)[PROVENANCE] == {
        "commit": OTHER,
        "clean": False,
        "source_hash": OTHER_HASH,
    }


def test_results_rows_carry_the_commit_and_commits_of_names_the_commits(tmp_path):
    cfg, _ = _study(tmp_path)
    evals = make_plan(cfg).of_kind("eval")[:3]
    made = [
        Provenance(OTHER, True, OTHER_HASH).to_dict(),
        Provenance("a" * 40, False, "b" * 64).to_dict(),
        None,  # made before provenance was recorded
    ]
    evaluations = [
        Evaluation(step, {**_fake_result(step, tmp_path), **({PROVENANCE: p} if p else {})})
        for step, p in zip(evals, made)
    ]
    rows = result_rows(cfg, evaluations)
    assert [(r["commit"], r["source_hash"]) for r in rows] == [
        (OTHER, "000000000000"),
        ("a" * 40 + "-dirty", "bbbbbbbbbbbb"),
        ("", ""),
    ]
    assert RESULT_COLUMNS[-2:] == ("commit", "source_hash")
    text = csv_text(rows, RESULT_COLUMNS)
    assert text.splitlines()[0].endswith(",commit,source_hash") and f",{OTHER},000000000000" in text
    assert commits_of(rows) == ["826fe54", "aaaaaaa-dirty (source bbbbbbbbbbbb)", "unknown"]
    assert commits_of(rows, short=False) == [OTHER, "a" * 40 + "-dirty (source bbbbbbbbbbbb)", "unknown"]
    assert commits_of(rows[:1] * 3) == ["826fe54"]
    other_changes = {**rows[1], "source_hash": "cccccccccccc"}  # other uncommitted changes on the same commit
    assert commits_of([rows[1], other_changes]) == [
        "aaaaaaa-dirty (source bbbbbbbbbbbb)",
        "aaaaaaa-dirty (source cccccccccccc)",
    ]
    assert result_rows(cfg, evaluations) == rows  # the same steps, the same rows (a rerun rewrites the same file)


# --- the runner: cached steps made by other code ----------------------------------------------------------


def _made_by(step: Step, study_dir: str, made: Provenance | None) -> None:
    """Rewrite a cached step's recorded provenance (``None``: a result from before it was recorded)."""
    path = step.folder(study_dir) / RESULT_FILE
    result = json.loads(path.read_text())
    result.pop(PROVENANCE)
    if made is not None:
        result[PROVENANCE] = made.to_dict()
    path.write_text(json.dumps(result))


def _collect_n1(plan: Plan) -> Step:
    return next(s for s in plan.of_kind("collect") if s.meta["n_train_envs"] == 1)


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("warning:")]


@pytest.fixture
def finished(tmp_path, ran, capsys) -> tuple[StudyConfig, Plan]:
    """The study run once with the current code (2 collections, 2 trainings, 6 evaluations)."""
    cfg, _ = _study(tmp_path)
    outcome = runner.run_study(*cfg.parts(), command="test")
    assert outcome.ran == {"collect": 2, "train": 2, "eval": 6} and not outcome.failed
    capsys.readouterr()
    ran.clear()
    return cfg, make_plan(cfg)


def test_cached_steps_of_the_current_code_give_no_warning(finished, ran, capsys):
    cfg, _ = finished
    outcome = runner.run_study(*cfg.parts(), command="again")
    assert outcome.ran == {"collect": 0, "train": 0, "eval": 0} and outcome.stale == 0 and not ran
    assert _warnings(capsys.readouterr().err) == []


def test_a_cached_step_made_by_other_code_is_named_in_one_warning_line(finished, ran, capsys):
    cfg, plan = finished
    collect = _collect_n1(plan)
    _made_by(collect, cfg.out_dir, Provenance(OTHER, True, OTHER_HASH))
    old_eval = plan.of_kind("eval")[-1]
    _made_by(old_eval, cfg.out_dir, None)
    outcome = runner.run_study(*cfg.parts(), command="again")
    assert outcome.stale == 2 and not ran and not outcome.set_aside  # warned, cached steps still used
    (line,) = _warnings(capsys.readouterr().err)
    assert line.startswith(
        f"warning: 2 cached steps were made by other code than the current, {provenance.current().name}: "
        "collect x1 at 826fe54, eval x1 at unknown (e.g. collect task=door-open n_train_envs=1 seed=0 "
        f"widths=default; {old_eval.label}); --rerun_stale=true redoes them, --strict=true refuses"
    ), line
    assert collect.folder(cfg.out_dir).is_dir()


def test_the_warning_names_a_few_labels_and_counts_the_rest(finished, capsys):
    cfg, plan = finished
    for step in plan.of_kind("eval"):
        _made_by(step, cfg.out_dir, Provenance(OTHER, False, OTHER_HASH))
    found = stale.stale_steps(plan, Path(cfg.out_dir))
    text = stale.stale_summary(found, provenance.current())
    assert "eval x6 at 826fe54-dirty (source 000000000000) (e.g. " in text and text.endswith("; +3 more)")
    assert text.count("eval method=bc") == stale.STALE_LABELS


def test_dry_run_prints_the_stale_line_and_changes_nothing(finished, ran, capsys):
    cfg, plan = finished
    _made_by(_collect_n1(plan), cfg.out_dir, Provenance(OTHER, True, OTHER_HASH))
    text = runner.inspect_study(*replace(cfg, dry_run=True, rerun_stale=True).parts())
    assert "collect" in text and not ran
    (line,) = _warnings(capsys.readouterr().err)
    assert "1 cached step was made by other code" in line and "collect x1 at 826fe54" in line
    assert "they and the 4 cached step(s) depending on them are redone" in line  # 1 training, 3 evaluations
    assert _collect_n1(plan).folder(cfg.out_dir).is_dir()


def test_strict_refuses_with_one_line_before_any_work(finished, ran, capsys):
    from lerobot_factorworld.cli import main

    cfg, plan = finished
    collect = _collect_n1(plan)
    _made_by(collect, cfg.out_dir, Provenance(OTHER, True, OTHER_HASH))
    config_json = (Path(cfg.out_dir) / RUN_CONFIG_FILE).read_text()
    strict = replace(cfg, strict=True)
    with pytest.raises(ValueError, match="1 cached step was made by other code") as err:
        runner.run_study(*strict.parts(), command="strict")
    assert "\n" not in str(err.value) and "collect x1 at 826fe54" in str(err.value)
    assert "--strict=true refuses" in str(err.value)
    assert not ran and (Path(cfg.out_dir) / RUN_CONFIG_FILE).read_text() == config_json  # nothing written
    _, path = _study(Path(cfg.out_dir).parent)
    for flag in ("--strict=true", "--strict"):  # the spelling is an alias
        with pytest.raises(SystemExit) as exit_:
            main(["study", f"--config={path}", flag])
        assert exit_.value.code != 0
        err_text = capsys.readouterr().err
        assert err_text.startswith("error: 1 cached step was made by other code") and len(err_text.splitlines()) == 1
    assert "collect task=door-open n_train_envs=1" in err_text and not ran
    assert collect.folder(cfg.out_dir).is_dir() and (collect.folder(cfg.out_dir) / "data" / "marker").is_file()


def test_rerun_stale_redoes_the_step_and_its_dependents_and_keeps_the_old_folders(finished, ran, capsys):
    cfg, plan = finished
    collect = _collect_n1(plan)
    _made_by(collect, cfg.out_dir, Provenance(OTHER, True, OTHER_HASH))
    dependents = stale.dependents(plan, {collect.key})
    assert {s.kind for s in dependents} == {"train", "eval"} and len(dependents) == 4
    outcome = runner.run_study(*replace(cfg, rerun_stale=True).parts(), command="rerun")
    assert {s.key for s in ran} == {collect.key} | {s.key for s in dependents}  # the n=2 cell untouched
    assert outcome.ran == {"collect": 1, "train": 1, "eval": 3} and outcome.stale == 1
    (line,) = _warnings(capsys.readouterr().err)
    assert "they and the 4 cached step(s) depending on them are redone" in line
    now = provenance.current()
    old = collect.folder(cfg.out_dir).with_name(f"{collect.key}.stale-826fe54")
    assert old in outcome.set_aside and len(outcome.set_aside) == 5
    assert provenance_of(json.loads((old / RESULT_FILE).read_text())).commit == OTHER
    assert (old / "data" / "marker").read_text() == collect.key  # the old dataset is kept
    for step in [collect, *dependents]:
        assert provenance_of(read_result(step, cfg.out_dir)) == now
    for step in dependents:  # made by the current code from the old dataset: kept under their own commit
        assert step.folder(cfg.out_dir).with_name(f"{step.key}.stale-{now.revision(short=True)}").is_dir()
    ran.clear()
    again = runner.run_study(*cfg.parts(), command="again")
    assert not ran and again.stale == 0 and _warnings(capsys.readouterr().err) == []


def test_rerun_stale_redoes_dependents_of_dependents(tmp_path, ran, capsys):
    """A chain of three: another task's dataset (out-of-domain data) -> the training that merges it -> that
    checkpoint's evaluations, which depend on the training and the task's own dataset but not on the other
    task's. When the other task's dataset is stale, the evaluations are redone too, through the training."""
    config = tmp_path / "study.yaml"
    ood = {"name": "bc_ood", "policy": {"type": "bc"}, "extra_tasks": ["pick-place"]}
    config.write_text(json.dumps({**SETTINGS, "n_train_envs": [1], "methods": [ood], "out_dir": str(tmp_path / "s")}))
    cfg = parse_config(StudyCommand, [f"--config_path={config}"], "study")
    assert runner.run_study(*cfg.parts(), command="first").ran == {"collect": 2, "train": 1, "eval": 3}
    plan = make_plan(cfg)
    own, other = (next(s for s in plan.of_kind("collect") if s.meta["task"] == t) for t in ("door-open", "pick-place"))
    (train,) = plan.of_kind("train")
    evals = plan.of_kind("eval")
    assert train.deps == (own.key, other.key) and all(e.deps == (train.key, own.key) for e in evals)  # the chain
    assert stale.dependents(plan, {other.key}) == [train, *evals]
    _made_by(other, cfg.out_dir, Provenance(OTHER, True, OTHER_HASH))
    capsys.readouterr()
    ran.clear()
    outcome = runner.run_study(*replace(cfg, rerun_stale=True).parts(), command="rerun")
    assert [s.key for s in ran] == [other.key, train.key, *(e.key for e in evals)]  # the first, its dependents'
    assert outcome.ran == {"collect": 1, "train": 1, "eval": 3} and len(outcome.set_aside) == 5
    assert "they and the 4 cached step(s) depending on them are redone" in _warnings(capsys.readouterr().err)[0]
    now = provenance.current()
    assert all(provenance_of(read_result(s, cfg.out_dir)) == now for s in plan.steps)
    kept = own.folder(cfg.out_dir)  # the task's own dataset is not redone
    assert kept.is_dir() and not kept.with_name(f"{own.key}.stale-826fe54").exists()


def test_a_second_set_aside_of_one_step_keeps_both_old_folders(tmp_path):
    folder = tmp_path / "steps" / "eval" / "abc"
    for expected in ("abc.stale-826fe54", "abc.stale-826fe54-2"):
        folder.mkdir(parents=True)
        assert stale._move_aside(folder, "826fe54").name == expected
    assert sorted(p.name for p in folder.parent.iterdir()) == ["abc.stale-826fe54", "abc.stale-826fe54-2"]


def test_a_dirty_tree_is_named_when_steps_run_and_recorded(finished, ran, capsys, monkeypatch):
    cfg, plan = finished
    dirty = replace(provenance.current(), commit=OTHER, clean=False)  # the same source: nothing is stale
    monkeypatch.setattr(provenance, "current", lambda: dirty)
    runner.run_study(*cfg.parts(), command="nothing to run")
    assert _warnings(capsys.readouterr().err) == []  # nothing runs: nothing to warn about
    step = plan.of_kind("eval")[0]
    (step.folder(cfg.out_dir) / RESULT_FILE).unlink()
    runner.run_study(*cfg.parts(), command="one to run")
    (line,) = _warnings(capsys.readouterr().err)
    assert line == (
        f"warning: the current code, 826fe54-dirty (source {dirty.source_hash[:12]}), has uncommitted changes: "
        "steps run now are not reproducible from a commit"
    )
    assert [s.key for s in ran] == [step.key]
    assert read_result(step, cfg.out_dir)[PROVENANCE]["clean"] is False


def test_strict_and_rerun_stale_together_are_refused(tmp_path):
    from lerobot_factorworld.core.settings import SettingError

    with pytest.raises(SettingError, match="strict=true refuses .* rerun_stale=true redoes them: set one"):
        _study(tmp_path, "--strict=true", "--rerun_stale=true")


CPUINFO = """processor\t: 0
model name\t: Intel(R) Xeon(R) Processor
flags\t\t: fpu sse4_1 avx2 fma avx512f avx512_bf16 amx_tile amx_bf16

processor\t: 1
model name\t: Intel(R) Xeon(R) Processor
flags\t\t: fpu sse4_1 avx2 fma avx512f avx512_bf16 amx_tile amx_bf16
"""


def test_the_machine_is_named_by_its_cpu_and_the_extensions_that_choose_torch_s_kernels(monkeypatch):
    assert machine.cpu_of(CPUINFO) == (
        "Intel(R) Xeon(R) Processor",
        ["amx_bf16", "amx_tile", "avx512_bf16", "avx512f", "avx2", "fma"],
    )
    assert machine.cpu_of("processor : 0\nflags : fpu sse4_1\n") == ("", [])  # no model name, no AVX2
    here = {"cpu": "Xeon", "isa": ["avx2", "fma"], "isa_cap": None, "cpus": 2}
    assert machine.describe(here) == "Xeon; avx2, fma; 2 CPUs"
    assert (
        machine.describe({**here, "isa": [], "isa_cap": "SSE41"}) == "Xeon; no AVX2; 2 CPUs; ONEDNN_MAX_CPU_ISA=SSE41"
    )
    monkeypatch.setenv(machine.ISA_CAP_ENV, "AVX2")
    machine.current.cache_clear()
    try:
        assert machine.current()["isa_cap"] == "AVX2" and machine.current()["cpus"] == len(os.sched_getaffinity(0))
    finally:
        monkeypatch.delenv(machine.ISA_CAP_ENV)
        machine.current.cache_clear()


def test_a_training_at_speed_fast_on_a_cpu_that_emulates_bf16_is_warned_of_before_it_runs(
    tmp_path, monkeypatch, capsys
):
    """AVX2 without AVX-512 BF16 or AMX (or a cap below them) emulates bf16, several times slower than float32: a
    study about to train at ``speed=fast`` there says so in one line; with native bf16, on another architecture, or
    with its trainings finished, nothing."""
    avx2 = {"cpu": "EPYC", "isa": ["avx2", "fma"], "isa_cap": None, "cpus": 2}
    assert machine.lacks_native_bf16(avx2)
    assert machine.lacks_native_bf16({**avx2, "isa": ["avx512_bf16", "avx2"], "isa_cap": "AVX2"})  # capped below
    assert not machine.lacks_native_bf16({**avx2, "isa": ["avx512_bf16", "avx512f", "avx2"]})
    assert not machine.lacks_native_bf16({**avx2, "isa": []})  # aarch64: no x86 extensions listed
    plan = make_plan(load_config(DOCS_RESULTS / "rt1_curve_pick_160" / "config.yaml"))  # rt1 small at speed=fast
    monkeypatch.setattr(machine, "current", lambda: avx2)
    runner._warn_emulated_bf16(plan, tmp_path)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(
        "warning: 10 training(s) at speed=fast to run on EPYC; avx2, fma; 2 CPUs"
    )
    assert machine.EMULATED_BF16_COST in err[0]
    monkeypatch.setattr(machine, "current", lambda: {**avx2, "isa": ["avx512_bf16", "avx2"]})
    runner._warn_emulated_bf16(plan, tmp_path)
    assert capsys.readouterr().err == ""
