"""``factorworld profile`` and given checkpoints in a study: an existing LeRobot checkpoint evaluated on the
unshifted condition and under factors, written as a study (report.md, results.csv, plots, episodes.parquet) with
no collection and no training; a study mixing a trained and a given method; bad input refused in one line."""

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

FACTORWORLD = Path(sys.executable).with_name("factorworld")
# tiny_dataset's environments (conftest.py): pick-place, one environment, the light factor, seed 0
PROFILE = ["--task=pick-place", "--n_train_envs=1", "--train_factors=[light]", "--factors=[light,table_texture]"]
EVAL = ["--eval.n_test_envs=2", "--eval.episodes=2", "--eval.max_episode_steps=4"]


def _profile_config(checkpoint: Path, out: Path, *args: str):
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.study.plan.policy_profile import ProfileConfig

    flags = [f"--policy.path={checkpoint}", *PROFILE, *EVAL, f"--out_dir={out}", *args]
    return parse_config(ProfileConfig, flags, "profile")


@pytest.mark.slow
def test_profile_writes_a_studys_outputs_without_collecting_or_training(bc_checkpoint, tmp_path):
    from lerobot_factorworld.study.results.episodes import read_episodes
    from lerobot_factorworld.study.results.rows import RESULT_COLUMNS

    out = tmp_path / "profile"
    cmd = [str(FACTORWORLD), "profile", f"--policy.path={bc_checkpoint}", *PROFILE, *EVAL, f"--out_dir={out}"]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "ran 0 collect, 0 train, 3 eval" in result.stdout
    assert sorted(p.name for p in (out / "steps").iterdir()) == ["eval"]  # nothing collected, nothing trained

    rows = list(csv.DictReader(open(out / "results.csv")))
    assert tuple(rows[0]) == RESULT_COLUMNS
    assert [r["condition"] for r in rows] == ["train", "light", "table_texture"]
    for row in rows:
        assert (row["study"], row["method"], row["policy"], row["task"]) == ("profile", "bc", "bc", "pick-place")
        assert (row["n_train_envs"], row["seed"], row["episodes"]) == ("1", "0", "2")
        assert row["n_envs"] == ("1" if row["condition"] == "train" else "2") == row["envs_visited"]
        assert float(row["gap"]) == pytest.approx(float(row["train_success_rate"]) - float(row["success_rate"]))
        assert row["stages"].startswith("none:") and row["commit"]
    episodes = read_episodes(out / "episodes.parquet")
    assert [(e["condition"], e["episode_seed"]) for e in episodes] == [
        (c, s) for c in ("train", "light", "table_texture") for s in (1000, 1001)
    ]  # paired: episode i is reset with start_seed + i in every condition
    assert all(e["factors"] and e["policy"] == "bc" and e["n_steps"] for e in episodes)
    report = (out / "report.md").read_text()
    assert "Given checkpoint(s), evaluated as they are" in report and str(bc_checkpoint) in report
    assert "demos per dataset" not in report and "## Where episodes fail" in report
    assert {"success_rates.png", "methods.png"} <= {p.name for p in out.glob("*.png")}

    # the same command again: every evaluation cached, the same results
    cfg = _profile_config(bc_checkpoint, out).study()
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.result import is_done

    assert all(is_done(step, out) for step in make_plan(cfg).steps)


@pytest.mark.slow
def test_train_defaults_to_the_checkpoints_own_dataset(bc_checkpoint, tiny_dataset, factorworld_checkpoint, tmp_path):
    """A checkpoint trained here on a Factor World dataset (its train_config.json names it) is profiled on that
    dataset's training environments without --n_train_envs/--train_factors/--seed; disagreeing settings, or a
    --dataset_root that is not a Factor World dataset, are refused in one line."""
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.protocol.sampling import sample_configs
    from lerobot_factorworld.protocol.sidecar import SIDECAR, read_dataset_condition
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.plan.policy_profile import ProfileConfig
    from lerobot_factorworld.study.run.inputs import EvalInputs

    def profile(checkpoint, *args: str) -> ProfileConfig:
        flags = [f"--policy.path={checkpoint}", "--task=pick-place", "--factors=[light]", *EVAL, *args]
        return parse_config(ProfileConfig, [*flags, f"--out_dir={tmp_path / 'out'}"], "profile")

    cfg = profile(bc_checkpoint)
    assert cfg.dataset_root == str(tiny_dataset)
    study = cfg.study()
    assert (study.n_train_envs, study.train_factors, study.seeds) == ([1], ["light"], [0])
    train = next(s for s in make_plan(study).of_kind("eval") if s.meta["condition"] == "train")
    env = EvalInputs.from_dict(train.inputs).environments  # the recipe the evaluation samples them with
    sampled = sample_configs(env.task, env.n_envs, env.seed, "train", env.train_factors, env.sampling_options())
    assert sampled == read_dataset_condition(tiny_dataset).train_configs("pick-place")
    assert profile(bc_checkpoint, "--n_train_envs=1", "--seed=0").study().train_factors == ["light"]  # agree
    with pytest.raises(ValueError, match=r"disagrees with dataset .*n_train_envs=5 but the dataset has 1"):
        profile(bc_checkpoint, "--n_train_envs=5")
    with pytest.raises(ValueError, match="is not a Factor World dataset"):  # SettingError: one line at the CLI
        profile(bc_checkpoint, f"--dataset_root={tmp_path}")
    lod = tmp_path / "lod"  # its side-car, as if rendered at lod: the profile renders at lod too
    (lod / SIDECAR).parent.mkdir(parents=True)
    sidecar = json.loads((tiny_dataset / SIDECAR).read_text())
    (lod / SIDECAR).write_text(json.dumps({**sidecar, "settings": {**sidecar["settings"], "quality": "lod"}}))
    at_lod = profile(bc_checkpoint, f"--dataset_root={lod}").study()
    assert at_lod.collect.quality == "lod" and cfg.study().collect.quality == "fast"
    given = next(s for s in make_plan(at_lod).of_kind("eval") if s.meta["condition"] == "train")
    assert EvalInputs.from_dict(given.inputs).environments.quality == "lod"
    # no train_config.json (not trained by lerobot-train here): the defaults, 5 environments, the paper's factors
    flags = [f"--policy.path={factorworld_checkpoint}", "--task=pick-place", "--eval.n_test_envs=5"]
    untrained = parse_config(ProfileConfig, [*flags, "--eval.episodes=5", f"--out_dir={tmp_path / 'out'}"], "profile")
    assert untrained.dataset_root is None and untrained.study().n_train_envs == [5]
    assert untrained.study().seeds == [0]


def test_a_checkpoints_key_is_its_content(factorworld_checkpoint, tmp_path):
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.checkpoint import checkpoint_folder
    from lerobot_factorworld.study.run.inputs import EvalInputs

    def keys(checkpoint: Path) -> set[str]:
        plan = make_plan(_profile_config(checkpoint, tmp_path / "out").study())
        assert set(plan.counts()) == {"eval"} and all(not step.deps for step in plan.steps)
        return {step.key for step in plan.steps}

    copy = tmp_path / "copy"
    shutil.copytree(factorworld_checkpoint, copy)
    assert keys(copy) == keys(factorworld_checkpoint)  # the same files elsewhere: the same evaluations
    planned = EvalInputs.from_dict(make_plan(_profile_config(copy, tmp_path / "out").study()).steps[0].inputs)
    assert checkpoint_folder(str(copy), planned.checkpoint) == copy
    (copy / "model.safetensors").write_bytes((copy / "model.safetensors").read_bytes() + b"\0")
    assert not keys(copy) & keys(factorworld_checkpoint)  # changed weights are never taken for the old ones
    with pytest.raises(RuntimeError, match="changed after the study was planned"):
        checkpoint_folder(str(copy), planned.checkpoint)  # an evaluation planned before the change refuses it


def test_a_hub_id_in_the_local_cache_is_used_offline(factorworld_checkpoint, tmp_path, monkeypatch):
    """A Hub model id already in the Hugging Face cache resolves there with the Hub unreachable (nothing is
    downloaded), keyed by content as the same files in a folder are; the profile plans it."""
    import huggingface_hub

    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.checkpoint import fetch_checkpoint, keyed_checkpoint, local_folder

    cache, revision = tmp_path / "hub", "0123456789abcdef0123456789abcdef01234567"
    repo = cache / "models--someone--bc_pick_place"
    shutil.copytree(factorworld_checkpoint, repo / "snapshots" / revision)
    (repo / "refs").mkdir()
    (repo / "refs" / "main").write_text(revision)
    monkeypatch.setattr(huggingface_hub.constants, "HF_HUB_CACHE", str(cache))
    monkeypatch.setattr(huggingface_hub.constants, "HF_HUB_OFFLINE", True)

    assert local_folder("someone/bc_pick_place") == repo / "snapshots" / revision
    assert fetch_checkpoint("someone/bc_pick_place") == repo / "snapshots" / revision
    assert keyed_checkpoint("someone/bc_pick_place") == keyed_checkpoint(str(factorworld_checkpoint))
    assert local_folder("someone/not_cached") is None
    cfg = _profile_config("someone/bc_pick_place", tmp_path / "out").study()
    assert cfg.methods[0].checkpoint == "someone/bc_pick_place" and cfg.methods[0].name == "bc"
    plan = make_plan(cfg)
    assert set(plan.counts()) == {"eval"} and len(plan.steps) == 3


def test_a_study_mixing_a_trained_and_a_given_method_plans_both(factorworld_checkpoint, tmp_path):
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.cost import describe
    from lerobot_factorworld.study.plan.eval_settings import EvalSettings
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.plan.method_config import MethodConfig
    from lerobot_factorworld.study.run.executors import task_units
    from lerobot_factorworld.study.run.inputs import CollectInputs, EvalInputs
    from lerobot_factorworld.study.run.options import RunOptions

    cfg = StudyConfig(
        out_dir=str(tmp_path / "mixed"),
        tasks=["pick-place"],
        n_train_envs=[1, 2],
        seeds=[0, 1],
        train_factors=["light", "table_texture"],
        factors=["light"],
        methods=[
            MethodConfig("bc", {"type": "bc"}),
            MethodConfig("given", checkpoint=str(factorworld_checkpoint)),
        ],
        eval=EvalSettings(n_test_envs=2, episodes=2),
    )
    plan = make_plan(cfg)
    # 2 N x 2 seeds datasets and trainings; evaluations: 4 trained cells x 2 conditions + 2 given cells (N) x 2
    assert dict(plan.counts()) == {"collect": 4, "train": 4, "eval": 12}
    given = [s for s in plan.of_kind("eval") if s.meta["method"] == "given"]
    assert len(given) == 4 and all(not s.deps and s.meta["seed"] == 0 for s in given)  # first seed only
    collects = {(s.meta["n_train_envs"], s.meta["seed"]): s for s in plan.of_kind("collect")}
    for step in given:  # the environments the trained method's dataset of the same cell has
        environments = EvalInputs.from_dict(step.inputs).environments
        collect = collects[(step.meta["n_train_envs"], 0)]
        assert environments == CollectInputs.from_dict(collect.inputs).environments()
    units = task_units(given, free=1, grouped=True)
    assert sorted(len(u) for u in units) == [2, 2]  # one task per given checkpoint's cell
    text = describe(cfg, plan, RunOptions())
    assert "collect       4 steps" in text and "eval         12 steps" in text and "not startable" not in text

    with pytest.raises(ValueError, match="names a checkpoint and policy settings"):
        MethodConfig("both", {"type": "bc"}, checkpoint=str(factorworld_checkpoint))
    with pytest.raises(ValueError, match="name the same checkpoint"):
        StudyConfig(
            methods=[
                MethodConfig("a", checkpoint=str(factorworld_checkpoint)),
                MethodConfig("b", checkpoint=str(factorworld_checkpoint)),
            ]
        )
    with pytest.raises(ValueError, match="applies to a given checkpoint only"):
        MethodConfig("bc", {"type": "bc"}, obs="lerobot_metaworld")


def _one_line_error(capsys, args: list[str]) -> tuple[int, str]:
    from lerobot_factorworld.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["profile", *args])
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    return exit_.value.code, err


def test_bad_input_is_refused_in_one_line_before_any_work(
    factorworld_checkpoint, lerobot_metaworld_checkpoint, tmp_path, capsys, monkeypatch
):
    import huggingface_hub

    out = tmp_path / "out"
    base = [*PROFILE, *EVAL, f"--out_dir={out}"]
    status, err = _one_line_error(capsys, [f"--policy.path={tmp_path / 'nope'}", *base])
    assert status == 1 and "does not exist: give a LeRobot pretrained_model folder" in err
    (tmp_path / "empty").mkdir()
    status, err = _one_line_error(capsys, [f"--policy.path={tmp_path / 'empty'}", *base])
    assert "is not a LeRobot pretrained_model folder: no config.json, model.safetensors" in err
    # trained at 84 px on Factor World's camera, evaluated with LeRobot's metaworld observation
    _, err = _one_line_error(capsys, [f"--policy.path={factorworld_checkpoint}", *base, "--env.obs=lerobot_metaworld"])
    assert "expects action (4,), observation.images.front (3, 84, 84), observation.state (8,)" in err
    assert "the env (obs=lerobot_metaworld) gives action (4,), observation.image (3, 480, 480)" in err
    assert err.rstrip().endswith("it was made for obs=factorworld, cameras=front, image_size=84")
    # ... and the other way round, and at another image size
    _, err = _one_line_error(capsys, [f"--policy.path={lerobot_metaworld_checkpoint}", *base])
    assert (
        "observation.image (3, 480, 480)" in err and "made for LeRobot's metaworld env (obs=lerobot_metaworld)" in err
    )
    _, err = _one_line_error(capsys, [f"--policy.path={factorworld_checkpoint}", *base, "--env.image_size=48"])
    assert "gives action (4,), observation.images.front (3, 48, 48)" in err
    # settings: the existing checks, exit status 2
    status, err = _one_line_error(capsys, [f"--policy.path={factorworld_checkpoint}", *base, "--task=pick-plac"])
    assert status == 2 and "unknown task 'pick-plac'; valid tasks: pick-place" in err
    status, err = _one_line_error(capsys, [f"--policy.path={factorworld_checkpoint}", *base, "--factors=[lights]"])
    assert status == 2 and "unknown factor(s) 'lights'; valid factors" in err
    # a Hub id is fetched only when the Hub answers
    monkeypatch.setattr(huggingface_hub.constants, "HF_HUB_OFFLINE", True)
    _, err = _one_line_error(capsys, ["--policy.path=someone/no-such-model", *base])
    assert "checkpoint someone/no-such-model is not a local folder, and could not reach the Hugging Face Hub" in err
    assert not out.exists()  # nothing was written


@pytest.mark.slow
def test_profile_of_a_lerobot_metaworld_checkpoint(lerobot_metaworld_checkpoint, tmp_path):
    out = tmp_path / "profile"
    cmd = [
        str(FACTORWORLD),
        "profile",
        f"--policy.path={lerobot_metaworld_checkpoint}",
        "--env.obs=lerobot_metaworld",
        "--task=button-press",
        "--factors=[light]",
        "--eval.n_test_envs=1",
        "--eval.episodes=1",
        "--eval.max_episode_steps=3",
        f"--out_dir={out}",
    ]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = list(csv.DictReader(open(out / "results.csv")))
    # Meta-World's unshifted scene (one environment, no training factor) and the light shift on top of it
    assert [(r["condition"], r["n_envs"], r["policy"]) for r in rows] == [("train", "1", "act"), ("light", "1", "act")]
