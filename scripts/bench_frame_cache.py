"""Samples/s of a LeRobot dataset read as ``lerobot-train`` reads it, with and without the study's frame cache.

What is measured
    A PNG dataset (``--root``; else ``factorworld collect --task=<task> --n_envs=<N> --demos=<D> --seed=0``
    into a temporary folder first) opened twice as ``LeRobotDataset(repo_id, root, delta_timestamps)`` with
    RT-1's window (the front camera's and the action's last ``--window`` frames): as LeRobot reads it, and
    inside ``datasets.frame_cache.cached_frames()`` (how ``factorworld study`` trains in process). Each reads
    the same ``--samples`` shuffled indices (seed 0) in this process, one at a time, as a loader worker does;
    every sample is compared value for value. The cache's build time (decoding every frame once) is printed
    apart: a training pays it once, before its first step.

    python scripts/bench_frame_cache.py [--root DIR] [--task pick] [--n_envs 10] [--demos 20] [--window 6]
                                        [--samples 2000]

The last line printed is exactly ``ratio: <float>`` = samples/s cached / samples/s as LeRobot reads them.
"""

from __future__ import annotations

import argparse
import json
import platform
import random
import sys
import tempfile
import time
from pathlib import Path

import torch
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from lerobot_factorworld.datasets.collect import CollectConfig, collect
from lerobot_factorworld.datasets.frame_cache import cached_frames


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=None, help="a PNG LeRobotDataset (else one is collected)")
    parser.add_argument("--task", default="pick")
    parser.add_argument("--n_envs", type=int, default=10)
    parser.add_argument("--demos", type=int, default=20)
    parser.add_argument("--window", type=int, default=6)
    parser.add_argument("--samples", type=int, default=2000)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.root or _collected(Path(tmp) / "data", args)
        info = json.loads((root / "meta" / "info.json").read_text())
        fps, camera = info["fps"], next(k for k, f in info["features"].items() if f["dtype"] == "image")
        delta = {key: [i / fps for i in range(1 - args.window, 1)] for key in (camera, "action")}
        plain = LeRobotDataset("local/bench", root=root, delta_timestamps=delta)
        start = time.perf_counter()
        with cached_frames():
            cached = LeRobotDataset("local/bench", root=root, delta_timestamps=delta)
        build = time.perf_counter() - start
        indices = [random.Random(0).randrange(len(plain)) for _ in range(args.samples)]
        print(f"dataset: {info['total_episodes']} episodes, {len(plain)} frames | window {args.window} | "
              f"{args.samples} samples | {platform.processor() or platform.machine()}")  # fmt: skip
        print(f"cache built in {build:.2f} s (opening the dataset included)")
        rates = {}
        print("| reader | seconds | samples/s |")
        print("|---|---|---|")
        for label, dataset in (("as LeRobot reads it", plain), ("frame cache", cached)):
            start = time.perf_counter()
            samples = [dataset[i] for i in indices]
            seconds = time.perf_counter() - start
            rates[label] = args.samples / seconds
            print(f"| {label} | {seconds:.2f} | {rates[label]:.1f} |")
            if label == "frame cache":
                _check_equal(samples, [plain[i] for i in indices])
        print("samples: identical")
        print(f"ratio: {rates['frame cache'] / rates['as LeRobot reads it']:.4f}")


def _collected(root: Path, args: argparse.Namespace) -> Path:
    cfg = CollectConfig(task=args.task, n_envs=args.n_envs, demos=args.demos, seed=0, root=str(root), use_videos=False)
    collect(cfg)
    return root


def _check_equal(mine: list[dict], theirs: list[dict]) -> None:
    for a, b in zip(mine, theirs, strict=True):
        assert list(a) == list(b)
        for key, value in b.items():
            same = torch.equal(a[key], value) if isinstance(value, torch.Tensor) else a[key] == value
            if not same:
                sys.exit(f"error: the cached dataset's {key!r} differs from LeRobot's")


if __name__ == "__main__":
    main()
