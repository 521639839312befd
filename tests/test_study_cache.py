"""The study's step keys, paths, executors' resource checks and settings (fast: no step is really run)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.cost import describe, fit_cost_model
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.run.eval_env import env_config
from lerobot_factorworld.study.run.inputs import CollectInputs
from lerobot_factorworld.study.run.options import RunOptions

ROOT = Path(__file__).resolve().parents[1]
BC = {"name": "bc", "policy": {"type": "bc"}}


def _cfg(**overrides) -> StudyConfig:
    settings = {
        "tasks": ["door-open"],
        "n_train_envs": [1, 2],
        "train_factors": ["light", "table_texture", "camera_pos"],
        "factors": ["light", "table_texture"],
        "methods": [BC],
        "collect": {"demos": 2},
        "eval": {"n_test_envs": 2, "episodes": 2},
    }
    settings.update(overrides)
    from lerobot_factorworld.study.plan.collect_settings import CollectSettings
    from lerobot_factorworld.study.plan.eval_settings import EvalSettings
    from lerobot_factorworld.study.plan.train_settings import TrainSettings

    for name, cls in (("collect", CollectSettings), ("train", TrainSettings), ("eval", EvalSettings)):
        if isinstance(settings.get(name), dict):
            settings[name] = cls(**settings[name])
    return StudyConfig(**settings)


def _keys(cfg: StudyConfig, kind: str) -> set[str]:
    return {s.key for s in make_plan(cfg).of_kind(kind)}


def _eval_keys(cfg: StudyConfig) -> dict[tuple, str]:
    return {(s.meta["n_train_envs"], s.meta["condition"]): s.key for s in make_plan(cfg).of_kind("eval")}


# --- 1. what is in a key ------------------------------------------------------------------------


def test_collect_key_holds_the_data_version_and_package_versions_not_the_factor_order(monkeypatch):
    from lerobot_factorworld.datasets.version import DATA_VERSION
    from lerobot_factorworld.study.plan import grid as plan_module

    cfg = _cfg()
    collect = make_plan(cfg).of_kind("collect")[0]
    assert collect.inputs["data_version"] == DATA_VERSION
    assert {"lerobot_factorworld", "lerobot"} <= set(collect.inputs["versions"])
    reordered = _cfg(train_factors=["camera_pos", "table_texture", "light"])
    assert _keys(reordered, "collect") == _keys(cfg, "collect")
    every = {kind: _keys(cfg, kind) for kind in ("collect", "train", "eval")}
    monkeypatch.setattr(plan_module, "DATA_VERSION", DATA_VERSION + 1)
    assert not _keys(cfg, "collect") & every["collect"] and not _keys(cfg, "eval") & every["eval"]
    monkeypatch.undo()
    monkeypatch.setattr(plan_module, "versions", lambda: {"lerobot_factorworld": "9.9", "lerobot": "0.6.1"})
    for kind, keys in every.items():
        assert not _keys(cfg, kind) & keys, kind


def test_eval_key_ignores_threads_and_recorded_episodes_holds_a_batch_above_one_and_train_ignores_n_test_envs():
    cfg = _cfg()
    keys = _eval_keys(cfg)
    assert all("batch_size" not in s.inputs for s in make_plan(cfg).of_kind("eval"))  # one at a time: keys as before
    threads = replace(cfg, eval=replace(cfg.eval, threads=2, record_episodes=0))
    assert _eval_keys(threads) == keys  # how an evaluation runs and what it records for viewing change no key
    step = next(s for s in make_plan(threads).of_kind("eval"))
    assert step.run == {"threads": 2, "record_episodes": 0} and "threads" not in step.label
    batched = replace(cfg, eval=replace(cfg.eval, batch_size=2))
    assert not set(_eval_keys(batched).values()) & set(keys.values())  # a batch changes the actions' last bits
    assert {s.inputs["batch_size"] for s in make_plan(batched).of_kind("eval")} == {2}
    assert _keys(batched, "train") == _keys(cfg, "train")
    four = _cfg(eval={"n_test_envs": 2, "episodes": 4})
    keys = _eval_keys(four)
    changed = _eval_keys(replace(four, eval=replace(four.eval, n_test_envs=4)))
    assert changed[(1, "train")] == keys[(1, "train")] and changed[(2, "train")] == keys[(2, "train")]
    assert changed[(1, "light")] != keys[(1, "light")] and changed[(2, "table_texture")] != keys[(2, "table_texture")]
    assert _eval_keys(cfg)[(1, "train")] != keys[(1, "train")]  # other episodes: another evaluation


def test_a_render_quality_other_than_fast_is_in_every_key_and_fast_keeps_them(tmp_path):
    cfg = _cfg()
    assert all("quality" not in s.inputs for s in make_plan(cfg).of_kind("collect"))  # fast: keys as before
    lod = replace(cfg, collect=replace(cfg.collect, quality="lod"))
    for kind in ("collect", "train", "eval"):
        assert not _keys(lod, kind) & _keys(cfg, kind), kind
    inputs = CollectInputs.from_dict(make_plan(lod).of_kind("collect")[0].inputs)
    assert inputs.quality == "lod"
    # a given checkpoint's environments (no dataset to read the quality from): lod, and LeRobot's view its own
    assert env_config(inputs.environments()).quality == "lod"
    assert (
        env_config(CollectInputs.from_dict(make_plan(cfg).of_kind("collect")[0].inputs).environments()).quality
        == "fast"
    )
    assert inputs.environments("lerobot_metaworld").quality is None
    assert env_config(inputs.environments("lerobot_metaworld")).quality == "full"
    # the cost model is fast's: a dry run says so, and it is never refitted from another quality
    assert "(the model renders at fast; at lod frames cost about half as much" in describe(
        lod, make_plan(lod), RunOptions()
    )
    with pytest.raises(ValueError, match="this study renders at lod: fit it on a study at fast"):
        fit_cost_model(lod, make_plan(lod), tmp_path, RunOptions(), path=tmp_path / "model.json")
    assert not (tmp_path / "model.json").exists()
    with pytest.raises(ValueError, match="unknown collect.quality 'ultra'; valid: fast, full, lod"):
        replace(cfg.collect, quality="ultra")


def test_eval_device_is_a_setting_in_the_eval_key_only():
    cfg = _cfg()
    assert cfg.eval.device == "cpu"
    assert all(s.inputs["device"] == "cpu" for s in make_plan(cfg).of_kind("eval"))
    on_gpu = replace(cfg, eval=replace(cfg.eval, device="cuda"))
    assert _keys(on_gpu, "train") == _keys(cfg, "train")
    assert not _keys(on_gpu, "eval") & _keys(cfg, "eval")
    with pytest.raises(ValueError, match="unknown eval.device 'gpu'; valid: cpu, cuda"):
        replace(cfg, eval=replace(cfg.eval, device="gpu"))


# --- 2. paths -----------------------------------------------------------------------------------


def _r3m(path: str, name: str = "r3m") -> dict:
    return {"name": name, "policy": {"type": "bc", "encoder": "r3m_rn50", "encoder_weights_path": path}}


def test_relative_weights_path_is_resolved_and_keyed_by_its_content(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "weights").mkdir()
    (tmp_path / "weights" / "r3m.pt").write_bytes(b"one")
    cfg = _cfg(methods=[_r3m("weights/r3m.pt")], train={"extra_args": ["--x.y_root=data", "--optimizer.lr=1e-3"]})
    assert cfg.methods[0].policy["encoder_weights_path"] == str(tmp_path / "weights" / "r3m.pt")
    assert cfg.train.extra_args == [f"--x.y_root={tmp_path / 'data'}", "--optimizer.lr=1e-3"]
    train = make_plan(cfg).of_kind("train")[0]
    assert train.run["policy"]["encoder_weights_path"] == str(tmp_path / "weights" / "r3m.pt")
    sha = hashlib.sha256(b"one").hexdigest()
    assert train.inputs["policy"]["encoder_weights_path"] == f"sha256:{sha}"
    keys = _keys(cfg, "train")
    (tmp_path / "elsewhere").mkdir()
    shutil.copy(tmp_path / "weights" / "r3m.pt", tmp_path / "elsewhere" / "r3m.pt")
    moved = _cfg(methods=[_r3m(str(tmp_path / "elsewhere" / "r3m.pt"))], train=cfg.train)
    assert _keys(moved, "train") == keys  # the same content elsewhere: the same checkpoints
    (tmp_path / "weights" / "r3m.pt").write_bytes(b"two")
    assert not _keys(_cfg(methods=[_r3m("weights/r3m.pt")], train=cfg.train), "train") & keys


def test_missing_weights_file_is_refused_before_any_step_runs(tmp_path, monkeypatch, capsys):
    from lerobot_factorworld.cli import main
    from lerobot_factorworld.study.plan.cost import describe
    from lerobot_factorworld.study.runner import run_study

    monkeypatch.chdir(tmp_path)
    cfg = _cfg(methods=[_r3m("weights/none.pt")], out_dir=str(tmp_path / "study"))
    with pytest.raises(FileNotFoundError, match=r"weights file\(s\) not found: method 'r3m': encoder_weights_path"):
        run_study(cfg)
    assert not (tmp_path / "study").exists()
    assert "not startable yet" in describe(cfg, make_plan(cfg), RunOptions())
    config = tmp_path / "s.yaml"
    config.write_text(
        json.dumps(
            {
                "tasks": ["door-open"],
                "n_train_envs": [1],
                "factors": ["light"],
                "out_dir": "study",
                "methods": [_r3m("weights/none.pt")],
                "collect": {"demos": 1},
                "eval": {"n_test_envs": 1, "episodes": 1},
            }
        )
    )
    with pytest.raises(SystemExit):
        main(["study", f"--config={config}"])
    err = capsys.readouterr().err
    assert err.startswith("error: weights file(s) not found") and len(err.splitlines()) == 1
    assert str(tmp_path / "weights" / "none.pt") in err and not (tmp_path / "study" / "steps").exists()


# --- 4. Ray resources ---------------------------------------------------------------------------


def test_ray_requests_are_checked_against_the_cluster():
    from lerobot_factorworld.study.run.executors import check_feasible, local_cpus, step_resources

    cfg = _cfg(
        train={"threads": 4, "device": "cuda"},
        eval={"n_test_envs": 2, "episodes": 2, "threads": 3},
        collect={"demos": 2, "workers": 2},
    )
    plan = make_plan(cfg)
    requests = {kind: step_resources(plan.of_kind(kind)[0]) for kind in ("collect", "train", "eval")}
    assert requests == {
        "collect": {"num_cpus": 2, "num_gpus": 0},
        "train": {"num_cpus": 4, "num_gpus": 1},
        "eval": {"num_cpus": 3, "num_gpus": 0},
    }
    assert local_cpus(2, list(requests.values())) == 4 and local_cpus(8, list(requests.values())) == 8
    with pytest.raises(ValueError, match="asks Ray for 4 CPUs .* the cluster has 2"):
        check_feasible(list(requests.values()), {"CPU": 2.0, "GPU": 1.0})
    with pytest.raises(ValueError, match="asks Ray for a GPU .* the cluster has 0"):
        check_feasible(list(requests.values()), {"CPU": 16.0})
    check_feasible(list(requests.values()), {"CPU": 4.0, "GPU": 1.0})
    check_feasible([], {})


# --- 5. methods ---------------------------------------------------------------------------------


def test_duplicate_method_names_and_duplicate_policy_settings_are_refused():
    with pytest.raises(ValueError, match="method names must be distinct: bc given more than once"):
        _cfg(methods=[BC, {"name": "bc", "policy": {"type": "bc", "augmentation": "shift"}}])
    with pytest.raises(ValueError, match="methods 'bc' and 'bc_again' have the same policy settings"):
        _cfg(methods=[BC, {"name": "bc_again", "policy": {"type": "bc"}}])
    cfg = _cfg(methods=[BC, {"name": "bc_shift", "policy": {"type": "bc", "augmentation": "shift"}}])
    assert len(make_plan(cfg).of_kind("train")) == 4


# --- 6. results in a moved study folder ---------------------------------------------------------


def test_results_name_paths_relative_to_the_study_folder_and_a_moved_study_still_reads_them(tmp_path, monkeypatch):
    from lerobot_factorworld.study.run.result import read_result
    from lerobot_factorworld.study.run.worker import RUNNERS, run_step

    def fake_collect(step, folder, deps):
        (folder / "data").mkdir()
        return {"root": str(folder / "data"), "repo_id": "x", "episodes": 1, "frames": 1, "failures": {}}

    monkeypatch.setitem(RUNNERS, "collect", fake_collect)
    cfg = _cfg(out_dir=str(tmp_path / "a"))
    step = make_plan(cfg).of_kind("collect")[0]
    run_step(step.to_dict(), str(tmp_path / "a"))
    stored = json.loads((step.folder(tmp_path / "a") / "result.json").read_text())
    assert stored["root"] == f"steps/collect/{step.key}/data"
    shutil.move(tmp_path / "a", tmp_path / "b")
    assert read_result(step, tmp_path / "b")["root"] == str(tmp_path / "b" / "steps" / "collect" / step.key / "data")
    # a result of the first format (absolute paths) in a folder that has moved since
    stored["root"] = str(tmp_path / "a" / "steps" / "collect" / step.key / "data")
    (step.folder(tmp_path / "b") / "result.json").write_text(json.dumps(stored))
    assert read_result(step.folder(tmp_path / "b"))["root"] == str(step.folder(tmp_path / "b") / "data")


# --- 7. the pick family's language conditions ---------------------------------------------------


def test_pick_language_conditions_and_n_objects_in_a_study():
    from lerobot_factorworld.pick.family import PICK_FAMILY
    from lerobot_factorworld.study.run.collect_step import collect_config

    factors = ["light", "table_texture", "held_out_phrasings", "held_out_objects"]
    cfg = _cfg(tasks=["pick"], n_train_envs=[2], factors=factors, pairs=["all"], collect={"demos": 2, "n_objects": 3})
    assert cfg.pair_conditions() == ["light+table_texture"]
    conditions = {s.meta["condition"] for s in make_plan(cfg).of_kind("eval")}
    assert conditions == {"train", *factors, "light+table_texture"}
    collect = make_plan(cfg).of_kind("collect")[0]
    assert collect.inputs["n_objects"] == 3
    assert collect_config(collect.inputs, Path("/tmp/x"), collect.key).sampling.n_objects == 3
    default = _cfg(tasks=["pick"], n_train_envs=[2], factors=factors)
    assert make_plan(default).of_kind("collect")[0].inputs["n_objects"] == PICK_FAMILY.n_objects[1]
    assert collect.key not in _keys(default, "collect")
    assert "n_objects" not in make_plan(_cfg()).of_kind("collect")[0].inputs  # door-open: not in its key
    # a fixed phrasing is in the key only when set: every pick collection keyed before it existed keeps its key
    assert "template" not in collect.inputs
    fixed = _cfg(
        tasks=["pick"], n_train_envs=[2], factors=factors, collect={"demos": 2, "template": "pick up the {noun}"}
    )
    fixed_collect = make_plan(fixed).of_kind("collect")[0]
    assert fixed_collect.inputs["template"] == "pick up the {noun}"
    dataset = collect_config(fixed_collect.inputs, Path("/tmp/x"), fixed_collect.key)
    assert dataset.sampling.template == "pick up the {noun}" and "template" in dataset.fingerprint()["sampling"]
    assert "template" not in collect_config(collect.inputs, Path("/tmp/x"), collect.key).fingerprint()["sampling"]
    with pytest.raises(ValueError, match="collect.template must be one of the training phrasings"):
        _cfg(tasks=["pick"], n_train_envs=[2], collect={"demos": 2, "template": "take the {colour} {noun}"})
    with pytest.raises(ValueError, match="applies to the pick family only .* not to door-open"):
        _cfg(factors=["light", "held_out_objects"])
    with pytest.raises(ValueError, match="collect.n_objects applies to the pick family only"):
        _cfg(collect={"demos": 2, "n_objects": 3})
    with pytest.raises(ValueError, match="stand alone"):
        _cfg(tasks=["pick"], n_train_envs=[2], factors=factors, pairs=["light+held_out_objects"])


def test_pick_study_config_plans_the_real_robot_conditions():
    from lerobot_factorworld.core.settings import parse_config

    cfg = parse_config(StudyCommand, [f"--config_path={ROOT / 'configs' / 'study' / 'pick.yaml'}"], "study")
    conditions = [s.meta["condition"] for s in make_plan(cfg).of_kind("eval")]
    assert conditions[0] == "train" and len(conditions) == 10
    assert {"held_out_phrasings", "held_out_objects", "table_texture+floor_texture"} <= set(conditions)
    assert cfg.methods[0].policy["use_language"] is True and cfg.collect.n_objects == 3


# --- 8. cost ------------------------------------------------------------------------------------


def test_frozen_resnet_encoders_cost_more_than_the_conv_encoder(tmp_path, monkeypatch):
    from lerobot_factorworld.study.plan.cost import estimate

    monkeypatch.chdir(tmp_path)
    (tmp_path / "w.pt").write_bytes(b"w")
    for policy in ({"type": "bc", "augmentation": "none"}, {"type": "bc", "augmentation": "shift"}):
        conv = _cfg(methods=[{"name": "conv", "policy": policy}], train={"steps": 1000})
        r3m = _cfg(
            methods=[{"name": "r3m", "policy": {**policy, "encoder": "r3m_rn50", "encoder_weights_path": "w.pt"}}],
            train={"steps": 1000},
        )
        hours = {name: estimate(make_plan(c), list(make_plan(c).steps)) for name, c in (("conv", conv), ("r3m", r3m))}
        for profile in hours["conv"]:
            assert hours["r3m"][profile] > 1.5 * hours["conv"][profile], (policy, profile)


def test_reused_steps_are_linked_by_key_and_a_dangling_link_is_relinked_or_dropped(tmp_path):
    """study/run/reuse.py without running a step: a finished step (its result.json) of another folder is linked
    (relatively: both folders may move together); an unfinished one is not; when that folder moves alone, the
    dangling link is replaced from the new place, or removed so that the step runs here."""
    from lerobot_factorworld.study.run.result import is_done
    from lerobot_factorworld.study.run.reuse import link_reused_steps, reusable_steps

    other, here = tmp_path / "other", tmp_path / "here"
    cfg = _cfg(out_dir=str(here))
    train = make_plan(cfg).of_kind("train")
    finished, unfinished = train[0], train[1]
    finished.folder(other).mkdir(parents=True)
    (finished.folder(other) / "result.json").write_text("{}")
    unfinished.folder(other).mkdir(parents=True)
    assert set(reusable_steps(train, here, [str(other)])) == {finished.key}
    assert link_reused_steps(train, here, [str(other)]) == 1
    assert finished.folder(here).is_symlink() and is_done(finished, here) and not unfinished.folder(here).exists()
    assert link_reused_steps(train, here, [str(other)]) == 0  # already linked: nothing to do
    assert not os.path.isabs(os.readlink(finished.folder(here)))
    together = tmp_path / "together"
    together.mkdir()
    other, here = other.rename(together / "other"), here.rename(together / "here")
    assert is_done(finished, here)  # moved together: the link still holds
    moved = tmp_path / "moved"
    other.rename(moved)
    assert not is_done(finished, here)
    assert link_reused_steps(train, here, [str(moved)]) == 1 and is_done(finished, here)
    shutil.rmtree(moved)
    assert link_reused_steps(train, here, [str(tmp_path)]) == 0
    assert not finished.folder(here).is_symlink() and not finished.folder(here).exists()


def test_a_per_task_step_limit_changes_only_that_tasks_evaluations():
    """``eval.max_episode_steps_per_task``: bin-picking at 500 steps beside door-open at 200 keeps door-open's
    evaluation keys (a finished study's steps stay reusable) and changes bin-picking's; a task the study leaves
    out is ignored (``--tasks`` narrows a config), an unknown one refused."""
    from lerobot_factorworld.study.report.markdown import _step_limits

    tasks = ["door-open", "bin-picking"]
    common = _cfg(tasks=tasks, n_train_envs=[1], eval={"n_test_envs": 2, "episodes": 2, "max_episode_steps": 200})
    longer = replace(common, eval=replace(common.eval, max_episode_steps_per_task={"bin-picking": 500}))

    def by_task(cfg):
        return {(s.meta["task"], s.meta["condition"]): s for s in make_plan(cfg).of_kind("eval")}

    before, after = by_task(common), by_task(longer)
    for (task, condition), step in after.items():
        assert (step.key == before[(task, condition)].key) == (task == "door-open")
        assert step.inputs["max_episode_steps"] == (500 if task == "bin-picking" else 200)
    assert _keys(longer, "train") == _keys(common, "train")
    assert _step_limits(common) == "200 steps" and _step_limits(longer) == "200 steps (bin-picking: 500)"
    unset = replace(common, eval=replace(common.eval, max_episode_steps=None))
    assert _step_limits(unset) == "500 steps"  # both tasks' own horizon is Meta-World's 500
    narrowed = replace(common, eval=replace(common.eval, max_episode_steps_per_task={"pick-place": 500}))
    assert {s.key for s in by_task(narrowed).values()} == {s.key for s in before.values()}  # not in the study
    with pytest.raises(ValueError, match="unknown task 'pick-plaice'"):
        replace(common, eval=replace(common.eval, max_episode_steps_per_task={"pick-plaice": 500}))
    with pytest.raises(ValueError, match=r"max_episode_steps_per_task\[bin-picking\] must be at least 1"):
        replace(common, eval=replace(common.eval, max_episode_steps_per_task={"bin-picking": 0}))
    v3 = replace(common, eval=replace(common.eval, max_episode_steps_per_task={"bin-picking-v3": 500}))
    assert {s.key for s in by_task(v3).values()} == {s.key for s in after.values()}  # Meta-World's spelling folded


def test_per_task_demos_fold_the_v3_spelling_and_refuse_unknown_tasks():
    """``collect.demos_per_task`` names tasks like ``eval.max_episode_steps_per_task``: the ``-v3`` spelling is
    the same task, a typo is refused naming the valid tasks (it used to fall back to ``demos`` silently)."""
    common = _cfg(tasks=["door-open"], n_train_envs=[1], eval={"n_test_envs": 2, "episodes": 2})
    more = replace(common, collect=replace(common.collect, demos_per_task={"door-open": 7}))
    assert more.collect.demos_for("door-open") == 7 and more.collect.demos_for("door-open-v3") == 7
    spelled = replace(common, collect=replace(common.collect, demos_per_task={"door-open-v3": 7}))
    assert _keys(spelled, "collect") == _keys(more, "collect") != _keys(common, "collect")
    with pytest.raises(ValueError, match="collect.demos_per_task: unknown task 'door-opne'; valid tasks: .*door-open"):
        replace(common, collect=replace(common.collect, demos_per_task={"door-opne": 7}))
