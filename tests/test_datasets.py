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
from lerobot_factorworld.factors.sampling import sample_configs

FACTORS = ["table_texture", "light", "distractors", "camera_pos"]


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


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("collect") / "tiny"
    report = collect(tiny(root))
    return root, report


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


def test_episode_factors_match_the_environments_that_produced_them(dataset):
    root, _ = dataset
    configs = {c.env_id: c for c in sample_configs("pick-place", 2, seed=3, factors=FACTORS)}
    records = episode_records("local/tiny", root)
    assert sorted(r["env_id"] for r in records) == sorted([*configs] * 2)
    for record in records:
        config = configs[record["env_id"]]
        for name in FACTORS:
            assert record["factors"][name] == getattr(config.factors, name), name
        assert record["split"] == "train" and len(record["factors"]["object_pos"]) == 2
        assert record["factors"]["object_size"] == 1.0  # typed default, as the scene really was


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


def test_offline_push_fails_clearly_and_loses_nothing(dataset):
    root, _ = dataset
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
def test_lerobot_train_runs_on_the_collected_dataset(dataset, tmp_path):
    root, _ = dataset
    cmd = [
        str(Path(sys.executable).with_name("lerobot-train")),
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
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    assert (tmp_path / "train" / "checkpoints" / "000003" / "pretrained_model" / "model.safetensors").is_file()


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
