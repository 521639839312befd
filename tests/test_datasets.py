"""Collected demos are real LeRobotDatasets: loadable offline, annotated with the factor values of the
environments that produced them, selectable by factor, resumable after a kill, mergeable, trainable."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from lerobot_factorworld.datasets.collect import CollectConfig, collect, staging_dir
from lerobot_factorworld.datasets.query import episode_records, select_episodes
from lerobot_factorworld.datasets.schema import decode_factors, encode_factors
from lerobot_factorworld.factors.registry import FACTORS as ALL_FACTORS
from lerobot_factorworld.protocol.sampling import sample_configs

FACTORS = list(ALL_FACTORS)  # every factor varies in the tiny dataset: each column holds a drawn value


def tiny(root: Path, **overrides) -> CollectConfig:
    settings = dict(
        task="pick-place",
        factors=FACTORS,
        n_envs=2,
        demos_per_env=2,
        seed=3,
        root=str(root),
        repo_id=f"local/{root.name}",
        workers=1,
        episodes_per_shard=1,
        use_videos=False,
    )
    return CollectConfig(**{**settings, **overrides})


def _collect_tiny(folder: Path):
    root = folder / "tiny"
    return root, collect(tiny(root))


@pytest.fixture(scope="session")
def dataset(build_once):
    """Collected once per run and read by every xdist worker: a test that writes into it works on a copy."""
    return build_once("datasets_tiny", _collect_tiny)


def test_dataset_loads_offline_with_lerobot(dataset):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root, report = dataset
    ds = LeRobotDataset("local/tiny", root=root)
    assert ds.num_episodes == report.episodes == 4 and len(ds) == report.frames
    item = ds[0]
    assert item["observation.images.front"].shape == (3, 84, 84)
    assert item["observation.state"].shape == (8,) and item["action"].shape == (4,)
    assert item["task"] == "pick up the puck and place it at the blue goal"
    assert not staging_dir(root).exists()  # shards were merged and cleaned up


def test_episode_factors_match_the_environments_that_produced_them(dataset, make_env):
    """Every factor's column holds the value its environment drew, read back typed, and no column holds the
    default scene's value (so a column left at its default, or blanked, would show)."""
    root, _ = dataset
    configs = {c.env_id: c for c in sample_configs("pick-place", 2, seed=3, factors=FACTORS)}
    _, info = make_env("pick-place", cameras=()).reset(seed=0)
    default = decode_factors(encode_factors(info["factors"]))  # the default scene's values, as a row reads back
    records = episode_records("local/tiny", root)
    assert sorted(r["env_id"] for r in records) == sorted([*configs] * 2)
    assert set(records[0]["factors"]) == set(ALL_FACTORS)
    for record in records:
        config = configs[record["env_id"]]
        for name in ALL_FACTORS:
            drawn = getattr(config.factors, name)
            assert drawn is not None and drawn != default[name], name
            assert record["factors"][name] == drawn, name
        assert record["split"] == "train" and len(record["factors"]["object_pos"]) == 2
        assert len(record["factors"]["distractors"]) == 1  # SamplingOptions' default count


def test_select_episodes_by_factor_value(dataset):
    root, _ = dataset
    records = episode_records("local/tiny", root)
    texture = records[0]["factors"]["table_texture"]
    chosen = select_episodes("local/tiny", root, table_texture=texture)
    assert chosen == [r["episode_index"] for r in records if r["factors"]["table_texture"] == texture]
    assert select_episodes("local/tiny", root, where=lambda f: f["light"][0] > 2) == []
    with pytest.raises(ValueError, match="valid factors"):
        select_episodes("local/tiny", root, lighting=0.3)


def test_different_settings_are_refused_without_touching_the_dataset(dataset):
    root, _ = dataset
    before = {p: p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}
    with pytest.raises(FileExistsError, match="--mode=overwrite"):
        collect(tiny(root, seed=4))
    assert before == {p: p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


@pytest.mark.slow
def test_killed_collection_resumes_without_duplicates(tmp_path):
    root = tmp_path / "killed"
    cmd = [
        sys.executable,
        "-m",
        "lerobot_factorworld.cli",
        "collect",
        "--task=door-open",
        "--n_envs=2",
        "--demos_per_env=2",
        "--workers=1",
        "--episodes_per_shard=1",
        "--use_videos=false",
        f"--root={root}",
        "--repo_id=local/killed",
        "--factors=[light]",
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    parts = staging_dir(root)
    deadline = time.time() + 240
    while time.time() < deadline and not any(p.is_dir() and not p.name.endswith(".tmp") for p in parts.glob("*")):
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = [p for p in parts.glob("*") if p.is_dir() and not p.name.endswith(".tmp")]
    assert finished and not root.exists(), "the kill should land mid-collection"
    subprocess.run(cmd, check=True, capture_output=True, timeout=600)
    records = episode_records("local/killed", root)
    keys = [(r["env_id"], r["episode_index"]) for r in records]
    assert len(records) == 4 and len({k[1] for k in keys}) == 4
    sidecar = json.loads((root / "meta" / "factorworld.json").read_text())
    assert len(sidecar["environments"]) == 2


@pytest.mark.slow
def test_shards_from_several_machines_merge_keeping_factors(tmp_path):
    from lerobot.datasets.aggregate import aggregate_datasets

    a, b = tmp_path / "machine_a", tmp_path / "machine_b"
    collect(tiny(a, n_envs=1, demos_per_env=1, factors=["light"]))
    collect(tiny(b, n_envs=1, demos_per_env=1, factors=["light"], seed=9))
    merged = tmp_path / "merged"
    aggregate_datasets(["local/machine_a", "local/machine_b"], "local/merged", roots=[a, b], aggr_root=merged)
    lights = [r["factors"]["light"] for r in episode_records("local/merged", merged)]
    assert lights == [
        episode_records("local/machine_a", a)[0]["factors"]["light"],
        episode_records("local/machine_b", b)[0]["factors"]["light"],
    ]


@pytest.mark.slow
def test_offline_push_fails_clearly_and_loses_nothing(dataset, tmp_path):
    import shutil

    root = tmp_path / "tiny"
    shutil.copytree(dataset[0], root)  # the push writes the dataset card into it
    code = (
        "from lerobot_factorworld.datasets.hub import push_dataset, HubUnreachableError\n"
        f"try:\n    push_dataset({str(root)!r}, 'someone/factorworld_tiny')\n"
        "except HubUnreachableError as e:\n    print('UNREACHABLE', e)\n"
    )
    env = {**os.environ, "HF_HUB_OFFLINE": "1"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert "UNREACHABLE" in out.stdout and "Nothing was lost" in out.stdout, out.stderr[-2000:]
    card = (root / "README.md").read_text()
    assert "factorworld" in card and "pick-place" in card and "Environments (N):** 2" in card


@pytest.mark.slow
def test_lerobot_train_runs_on_the_collected_dataset(dataset, tmp_path, run_lerobot):
    root, _ = dataset
    run_lerobot(
        "lerobot-train",
        "--dataset.repo_id=local/tiny",
        f"--dataset.root={root}",
        "--policy.type=act",
        "--policy.pretrained_backbone_weights=null",
        "--policy.device=cpu",
        "--policy.push_to_hub=false",
        "--policy.dim_model=64",
        "--policy.n_heads=2",
        "--policy.dim_feedforward=128",
        "--policy.chunk_size=4",
        "--policy.n_action_steps=4",
        "--steps=3",
        "--batch_size=2",
        "--num_workers=0",
        "--save_freq=3",
        f"--output_dir={tmp_path / 'train'}",
        "--log_freq=1",
    )
    assert (tmp_path / "train" / "checkpoints" / "000003" / "pretrained_model" / "model.safetensors").is_file()


@pytest.mark.slow
def test_full_disk_keeps_finished_shards_and_a_rerun_completes(tmp_path, monkeypatch):
    import errno

    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = tmp_path / "disk"
    original, calls = LeRobotDataset.save_episode, []

    def failing_save(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(LeRobotDataset, "save_episode", failing_save)
    with pytest.raises(RuntimeError, match="re-run the same command to resume"):
        collect(tiny(root, factors=["light"]))
    finished = [p for p in staging_dir(root).glob("*") if p.is_dir() and not p.name.endswith(".tmp")]
    assert len(finished) == 1 and not root.exists()
    monkeypatch.setattr(LeRobotDataset, "save_episode", original)
    report = collect(tiny(root, factors=["light"]))
    assert report.episodes == 4


@pytest.mark.slow
def test_several_tasks_in_one_video_dataset_and_append(tmp_path):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = tmp_path / "multi"
    settings = dict(task="pick-place,door-open", n_envs=1, demos_per_env=1, factors=["table_texture"], use_videos=True)
    collect(tiny(root, **settings))
    ds = LeRobotDataset("local/multi", root=root)
    assert ds.meta.features["observation.images.front"]["dtype"] == "video"
    assert {ds[int(i)]["task"] for i in (0, len(ds) - 1)} == {
        "pick up the puck and place it at the blue goal",
        "open the door",
    }
    assert [r["tasks"] for r in episode_records("local/multi", root)] == [
        ["pick up the puck and place it at the blue goal"],
        ["open the door"],
    ]
    collect(tiny(root, **settings, seed=5, mode="append"))
    records = episode_records("local/multi", root)
    assert len(records) == 4 and len(json.loads((root / "meta" / "factorworld.json").read_text())["history"]) == 1


def cli_refusal(argv: list[str], capsys) -> tuple[int, str]:
    from lerobot_factorworld.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith("error: ") and "Traceback" not in err, err
    return exit_info.value.code, err


def test_every_refusal_leaves_the_existing_dataset_untouched(dataset, capsys):
    root, _ = dataset
    same = [
        "collect",
        "--task=pick-place",
        f"--factors=[{','.join(FACTORS)}]",
        "--n_envs=2",
        "--demos_per_env=2",
        "--seed=3",
        f"--root={root}",
        "--repo_id=local/tiny",
        "--workers=1",
        "--episodes_per_shard=1",
        "--use_videos=false",
    ]
    before = {p: p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}
    refusals = [
        (["--task=pick-plac"], 2, "valid tasks"),
        (["--image_size=2"], 2, "image_size must be"),
        (["--cameras=wrist"], 2, "valid cameras"),
        (["--sampling.texture_folder=/nonexistent"], 2, "does not exist"),
        (["--mode=overwrite", "--bogus=1"], 2, "unknown setting(s) --bogus"),
        (["--seed=4"], 1, "collected with other settings (seed: 3 -> 4); nothing was changed"),
        ([], 1, "already complete with these settings"),
        (["--mode=append", "--cameras=side"], 1, "cannot append"),
        (["--mode=append", "--use_videos=true"], 1, "use_videos: False -> True"),
        (["--mode=append", "--quality=lod"], 1, "quality: 'fast' -> 'lod'"),  # lod and fast frames never mix
    ]
    for extra, status, expected in refusals:
        code, err = cli_refusal([*same, *extra], capsys)
        assert code == status and expected in err, (extra, err)
    assert before == {p: p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}
    assert not staging_dir(root).exists()


def test_a_folder_that_is_not_a_dataset_is_never_overwritten(tmp_path, capsys):
    folder = tmp_path / "my_work"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep me")
    for mode in ("new", "overwrite", "append"):
        code, err = cli_refusal(["collect", f"--root={folder}", "--repo_id=local/x", f"--mode={mode}"], capsys)
        assert code == 1 and "holds no factorworld dataset" in err, err
    code, err = cli_refusal(["collect", f"--root={folder / 'notes.txt'}", "--repo_id=local/x"], capsys)
    assert code == 2 and "is a file, not a folder" in err
    assert [p.name for p in folder.iterdir()] == ["notes.txt"] and (folder / "notes.txt").read_text() == "keep me"
    assert not staging_dir(folder).exists()


def test_action_noise_stream_is_independent_of_the_env_stream(make_env):
    import numpy as np
    from gymnasium.utils.seeding import np_random

    from lerobot_factorworld.datasets.collect import episode_seed
    from lerobot_factorworld.experts import noise_rng, rollout

    env = make_env("pick-place", cameras=("front",), image_size=8, max_episode_steps=3)
    handed = []

    def spy(policy, state, rng, noise):  # records the noise generator the collector hands the expert
        handed.append(rng)
        return np.zeros(4, dtype=np.float32)

    seed = episode_seed(3, 0, 1, 0, 0)
    frames = rollout(env, None, seed, 0.002, act=spy).actions
    assert len(frames) == 3 and all(rng is handed[0] for rng in handed)
    env_rng, _ = np_random(seed)  # what env.reset(seed=seed) seeds the env's own generator with
    assert handed[0].bit_generator.state == noise_rng(seed).bit_generator.state != env_rng.bit_generator.state
    for s in (0, 1, seed):
        env_draws, noise_draws = np_random(s)[0].random(256), noise_rng(s).random(256)
        assert not np.isin(noise_draws, env_draws).any()  # no shared numbers, not even shifted
        assert abs(np.corrcoef(env_draws, noise_draws)[0, 1]) < 0.25
    assert np.array_equal(noise_rng(seed).normal(size=8), noise_rng(seed).normal(size=8))


def test_the_same_seed_gives_identical_datasets(tmp_path):
    import torch
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    roots = [tmp_path / "first", tmp_path / "second"]
    for root in roots:
        collect(tiny(root, n_envs=1, demos_per_env=1, factors=["light"], repo_id="local/same"))
    first, second = (LeRobotDataset("local/same", root=root) for root in roots)
    assert len(first) == len(second) > 1
    for i in range(len(first)):
        a, b = first[i], second[i]
        for key in ("action", "observation.state", "observation.images.front"):
            assert torch.equal(a[key], b[key]), (i, key)
    assert episode_records("local/same", roots[0]) == episode_records("local/same", roots[1])


def test_data_of_another_version_is_never_appended_to_or_resumed(dataset, tmp_path, capsys):
    import shutil

    from lerobot_factorworld.datasets.version import DATA_VERSION, DATA_VERSION_KEY

    source, _ = dataset
    settings = json.loads((source / "meta" / "factorworld.json").read_text())["settings"]
    assert settings[DATA_VERSION_KEY] == DATA_VERSION == 3
    old = tmp_path / "old"
    shutil.copytree(source, old)
    sidecar = json.loads((old / "meta" / "factorworld.json").read_text())
    del sidecar["settings"][DATA_VERSION_KEY]  # as version 1 (world-frame state, old pick-place goal) wrote it
    (old / "meta" / "factorworld.json").write_text(json.dumps(sidecar))
    same = [
        "collect",
        "--task=pick-place",
        f"--factors=[{','.join(FACTORS)}]",
        "--n_envs=2",
        "--demos_per_env=2",
        "--seed=3",
        "--workers=1",
        "--episodes_per_shard=1",
        "--use_videos=false",
        "--repo_id=local/tiny",
    ]
    before = {p: p.stat().st_mtime_ns for p in old.rglob("*") if p.is_file()}
    for mode in ("append", "new"):
        code, err = cli_refusal([*same, f"--root={old}", f"--mode={mode}"], capsys)
        assert code == 1 and f"{old} holds data version 1 (observation.state in the table's frame" in err, err
        assert "writes data version 3 (observation.state in the robot's frame" in err and "--mode=overwrite" in err
    assert before == {p: p.stat().st_mtime_ns for p in old.rglob("*") if p.is_file()}
    assert not staging_dir(old).exists()

    fresh = tmp_path / "fresh"  # an unfinished collection that version 1 staged: never resumed by this code
    parts = staging_dir(fresh)
    parts.mkdir()
    (parts / "plan.json").write_text(json.dumps({"settings": sidecar["settings"], "mode": "new"}))
    code, err = cli_refusal([*same, f"--root={fresh}"], capsys)
    assert code == 1 and f"the unfinished collection staged in {parts} is data version 1" in err, err
    assert [p.name for p in parts.iterdir()] == ["plan.json"] and not fresh.exists()


def test_push_settings_are_checked_before_collecting(tmp_path, capsys, monkeypatch):
    import huggingface_hub

    root = tmp_path / "pushed"
    tiny_args = ["collect", f"--root={root}", "--n_envs=1", "--demos=1", "--factors=[light]", "--workers=1"]
    monkeypatch.setattr(huggingface_hub, "get_token", lambda: None)  # not logged in
    refusals = [
        (["--repo_id=someone/x", "--private=true"], "private=true only applies to a push: add --push_to_hub=true"),
        (["--repo_id=local/x", "--push_to_hub=true"], "needs a Hub repo_id ('user/name' with your user or"),
        (["--repo_id=someone/x", "--push_to_hub=true"], "needs a Hugging Face token with write access"),
    ]
    for extra, expected in refusals:
        code, err = cli_refusal([*tiny_args, *extra], capsys)
        assert code == 2 and expected in err, (extra, err)
    assert not root.exists() and not staging_dir(root).exists()
    monkeypatch.setattr(huggingface_hub, "get_token", lambda: "hf_token")
    assert tiny(root, repo_id="someone/x", push_to_hub=True, private=True).private  # all prerequisites met


def test_a_training_s_cached_frames_give_every_sample_value_for_value(tiny_dataset):
    """``datasets/frame_cache.py``: with RT-1's six-frame window, every sample of the cached dataset equals the
    dataset's own (keys, dtypes, values, padding masks, task); a dataset too large for the cache is read as before."""
    import torch
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from lerobot_factorworld.datasets.frame_cache import CachedRows, cache_rows, cached_frames

    window = [i / 80 for i in range(-5, 1)]
    delta = {"observation.images.front": window, "action": window}
    plain = LeRobotDataset("local/pp", root=tiny_dataset, delta_timestamps=delta)
    with cached_frames():
        cached = LeRobotDataset("local/pp", root=tiny_dataset, delta_timestamps=delta)
    assert isinstance(cached.reader.hf_dataset, CachedRows) and not isinstance(plain.reader.hf_dataset, CachedRows)
    for i in range(len(plain)):
        mine, theirs = cached[i], plain[i]
        assert list(mine) == list(theirs)
        for key, value in theirs.items():
            if isinstance(value, torch.Tensor):
                assert mine[key].dtype == value.dtype and torch.equal(mine[key], value), (i, key)
            else:
                assert mine[key] == value, (i, key)
    mine["observation.images.front"] += 1  # a sample is the caller's: the cache keeps its own
    assert torch.equal(
        cached[len(plain) - 1]["observation.images.front"], plain[len(plain) - 1]["observation.images.front"]
    )
    assert cache_rows(plain.reader.hf_dataset, ["observation.images.front"], max_bytes=1000) is None
