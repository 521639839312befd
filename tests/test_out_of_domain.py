"""Out-of-domain data (the paper's section 5.4, finding F8): a method's ``extra_tasks`` join other tasks'
demos to each task's training data, at equal in-task demos and gradient steps."""

from __future__ import annotations

import pytest

from lerobot_factorworld.datasets.merge import features_mismatch, merge_datasets
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.cost import load_model, step_cost
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.plan.method_config import MethodConfig
from lerobot_factorworld.study.plan.train_settings import TrainSettings
from lerobot_factorworld.study.run.inputs import TrainInputs
from lerobot_factorworld.study.run.train_schedule import epoch_frames, train_steps
from lerobot_factorworld.tasks import get_task

BC = {"name": "bc", "policy": {"type": "bc"}}
OOD = {"name": "bc_ood", "policy": {"type": "bc"}, "extra_tasks": ["pick-place", "door-open"]}


def _cfg(**overrides) -> StudyConfig:
    settings = {"tasks": ["pick-place", "door-open"], "n_train_envs": [5], "seeds": [0], "factors": ["light"]}
    cfg = StudyConfig(**{**settings, **overrides})
    cfg.methods = [m if not isinstance(m, dict) else _method(m) for m in cfg.methods]
    cfg.validate()
    return cfg


def _method(settings: dict) -> MethodConfig:
    return MethodConfig(**settings)


def test_each_task_trains_on_its_own_data_plus_the_other_tasks_collected_once():
    plan = make_plan(_cfg(methods=[BC, OOD]))
    collects = {s.inputs["task"]: s for s in plan.of_kind("collect")}
    assert sorted(collects) == ["door-open", "pick-place"]  # the other task's data is its own cell's: one key
    trains = {(s.meta["method"], s.meta["task"]): s for s in plan.of_kind("train")}
    assert trains["bc", "pick-place"].deps == (collects["pick-place"].key,)
    assert trains["bc_ood", "pick-place"].deps == (collects["pick-place"].key, collects["door-open"].key)
    assert trains["bc_ood", "door-open"].deps == (collects["door-open"].key, collects["pick-place"].key)
    assert trains["bc_ood", "pick-place"].inputs == trains["bc", "pick-place"].inputs  # same recipe, other data
    assert trains["bc_ood", "pick-place"].key != trains["bc", "pick-place"].key
    index = {s.key: s for s in plan.steps}
    costs = {m: step_cost(trains[m, "pick-place"], index, load_model()) for m in ("bc", "bc_ood")}
    assert costs["bc"] == costs["bc_ood"]  # gradient steps count the task's own frames
    evals = [s for s in plan.of_kind("eval") if s.meta["method"] == "bc_ood" and s.meta["task"] == "door-open"]
    assert {s.deps[1] for s in evals} == {collects["door-open"].key}  # evaluated in its own task's environments


def test_extra_demos_make_their_own_dataset_and_bad_settings_are_refused():
    plan = make_plan(_cfg(tasks=["pick-place"], methods=[BC, {**OOD, "extra_demos": 7}]))
    demos = sorted((s.inputs["task"], s.inputs["demos"]) for s in plan.of_kind("collect"))
    assert demos == [("door-open", 7), ("pick-place", 50)]
    with pytest.raises(ValueError, match="extra task 'pick' is of the pick family"):
        _cfg(methods=[{**OOD, "extra_tasks": ["pick"]}])
    with pytest.raises(ValueError, match="extra_tasks: unknown task 'doors'; valid tasks: pick-place"):
        _cfg(methods=[{**OOD, "extra_tasks": ["doors"]}])
    with pytest.raises(ValueError, match="with extra_tasks, task 'pick' is of the pick family"):
        _cfg(tasks=["pick"], factors=["light"], methods=[OOD])
    with pytest.raises(ValueError, match="a given checkpoint is not trained"):
        _method({"name": "given", "checkpoint": "x", "extra_tasks": ["door-open"]})
    with pytest.raises(ValueError, match="have the same policy settings .* and training data"):
        _cfg(methods=[OOD, {**OOD, "name": "bc_ood_again"}])
    assert len(make_plan(_cfg(methods=[BC, OOD])).of_kind("train")) == 4  # same policy, other data: two methods


def test_epochs_over_merged_data_keeps_in_task_passes_and_scales_the_gradient_steps():
    """``epochs_over: merged``: each own frame is seen as often as without extra tasks (F8's pick-place got 13 of
    60 passes at equal steps), in more steps; the default's keys are unchanged, and bad settings are refused."""
    merged = {**OOD, "name": "bc_ood_merged", "epochs_over": "merged"}
    cfg = _cfg(methods=[BC, OOD, merged], train=TrainSettings(epochs=60, batch_size=32))
    plan = make_plan(cfg)
    trains = {(s.meta["method"], s.meta["task"]): s for s in plan.of_kind("train")}
    assert "epochs_over" not in trains["bc_ood", "pick-place"].inputs  # the default: earlier studies' keys
    assert trains["bc_ood_merged", "pick-place"].inputs == {
        **trains["bc_ood", "pick-place"].inputs,
        "epochs_over": "merged",
    }
    assert trains["bc_ood_merged", "pick-place"].deps == trains["bc_ood", "pick-place"].deps
    inputs = {m: TrainInputs.from_dict(trains[m, "pick-place"].inputs) for m in ("bc_ood", "bc_ood_merged")}
    own, other = 5018, 8167  # pick-place's and door-open's frames in F8's cell (seed 0)
    assert train_steps(inputs["bc_ood"], epoch_frames(inputs["bc_ood"], [own, other])) == 9409  # F8's steps
    assert (
        train_steps(inputs["bc_ood_merged"], epoch_frames(inputs["bc_ood_merged"], [own, other])) == 24722
    )  # ceil(60 * 13185 / 32)
    index = {s.key: s for s in plan.steps}
    cost = {m: step_cost(trains[m, "pick-place"], index, load_model())[1] for m in ("bc", "bc_ood", "bc_ood_merged")}
    demo = {t: get_task(t).demo_steps for t in ("pick-place", "door-open")}
    assert cost["bc_ood"] == cost["bc"]
    assert cost["bc_ood_merged"] == pytest.approx(
        cost["bc"] * (demo["pick-place"] + demo["door-open"]) / demo["pick-place"]
    )
    with pytest.raises(ValueError, match="unknown epochs_over 'all'; valid: task, merged"):
        _method({**OOD, "epochs_over": "all"})
    with pytest.raises(ValueError, match="epochs_over=merged counts epochs over merged data: it needs extra_tasks"):
        _method({**BC, "epochs_over": "merged"})
    with pytest.raises(ValueError, match="set train.epochs instead of train.steps"):
        _cfg(methods=[merged], train=TrainSettings(steps=100))


def test_merged_training_data_holds_every_source_and_is_made_once(tiny_dataset, tmp_path):
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

    source = LeRobotDatasetMetadata("local/pp", root=tiny_dataset)
    root = tmp_path / "merged"
    frames = merge_datasets([("local/pp", tiny_dataset), ("local/pp", tiny_dataset)], "local/merged", root)
    assert frames == 2 * source.total_frames
    merged = LeRobotDatasetMetadata("local/merged", root=root)
    assert merged.total_episodes == 2 * source.total_episodes and merged.features == source.features
    stamp = (root / "meta" / "info.json").stat().st_mtime_ns
    assert merge_datasets([("local/pp", tiny_dataset), ("local/pp", tiny_dataset)], "local/merged", root) == frames
    assert (root / "meta" / "info.json").stat().st_mtime_ns == stamp and not root.with_name("merged.tmp").exists()


def test_datasets_with_other_features_are_named_before_a_merge():
    image = {"dtype": "image", "shape": [84, 84, 3]}
    state = {"dtype": "float32", "shape": [8]}
    assert features_mismatch({"img": image, "state": state}, {"img": image, "state": state}) is None
    assert "'img' is image [84, 84, 3] in one and image [48, 48, 3]" in features_mismatch(
        {"img": image}, {"img": {**image, "shape": [48, 48, 3]}}
    )
    assert "['wrist'] are in one dataset only" in features_mismatch({"img": image}, {"img": image, "wrist": image})
