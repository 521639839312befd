"""End-to-end demo-collection throughput: Factor World's collector vs. a naive Meta-World loop, in frames/s.

What is measured
    Frames per second of a whole collection run: simulation, scripted expert, rendering, video encoding and
    writing a LeRobotDataset (v3) to disk, from the first environment being built to the finalized dataset.
    Only successful episodes are kept, as by the collector; every mode collects the same number of demos D.

    * ``Factor World, 1 worker``: ``collect(CollectConfig(task, n_envs=2, demos=D, workers=1, ...))``, Factor
      World's defaults (camera ``front``, quality ``fast``, 84x84); everything runs in one process.
    * ``Factor World, all workers``: the same with ``workers=0`` (one worker process per core, forkserver);
      the shards are merged with LeRobot's ``aggregate_datasets`` (included in the timing).
    * ``Meta-World, naive``: one process, ``gymnasium.make("Meta-World/MT1", env_name=f"{task}-v3",
      render_mode="rgb_array", camera_name="corner2", width=84, height=84)`` at Meta-World's default
      rendering, the same scripted expert (acting on the 39-dim observation, same action noise), ``env.render()``
      every step, and ``LeRobotDataset.create`` / ``add_frame`` / ``save_episode`` / ``finalize`` with the same
      features (``observation.images.front`` video 84x84x3, ``observation.state`` float32 (8,) =
      ``obs[0:4] + obs[18:22]``, ``action`` float32 (4,), ``task``) at 80 fps. Episodes end at the first success
      or at the task's horizon; a failed attempt is retried (``max_attempts`` per demo, as the collector).

    Factor World modes: frames/s = ``report.frames / report.seconds`` (``CollectReport``). Meta-World: frames
    written / seconds from ``gym.make`` to ``finalize()`` returning. Python imports are done before the clock
    starts in every mode (the collector's worker processes still import in their own time: that is real cost).

    Each mode runs in a fresh Python process (``subprocess``), one after the other: gymnasium's
    ``OffScreenViewer`` makes its EGL context current only when it is created, so sharing a process with
    Factor World's ``mujoco.Renderer`` would make Meta-World draw through the wrong GL context (black frames,
    far too fast; see ``scripts/bench_env.py``). The naive loop checks that its frames are not blank. With
    ``--rounds N`` the modes are run N times, in alternating order, and the median frames/s per mode is reported.

    python scripts/bench_collect.py [--task pick-place] [--demos 40] [--rounds 1] [--seed 0] [--quick] [--keep]

The last line printed is exactly ``ratio: <float>`` = Factor World (all workers) frames/s / Meta-World naive
frames/s (target: >= 10).
"""

from __future__ import annotations

import os

import _bench

_bench.setup_headless_gl()  # before anything imports mujoco (Meta-World's side included); children inherit it
_bench.add_repo_to_path()
os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 otherwise prints its whole configuration per video

import argparse  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

SCRIPT = Path(__file__).resolve()

TARGET_RATIO = 10.0
IMAGE_SIZE = 84
N_ENVS = 2
ACTION_NOISE = 0.002  # the collector's default (public Factor World's value)
MAX_ATTEMPTS = 3  # the collector's default
FW_ONE = "fw1"
FW_ALL = "fwall"
META_WORLD = "metaworld"
MODES = (FW_ONE, FW_ALL, META_WORLD)
MODE_LABELS = {
    FW_ONE: "Factor World, 1 worker",
    FW_ALL: "Factor World, all workers",
    META_WORLD: "Meta-World, naive",
}


def run_factorworld(task: str, demos: int, workers: int, root: Path, seed: int) -> dict:
    """One collection with Factor World's collector; returns its counts and timing."""
    # Imports first, so that the report's clock (started inside collect()) does not time them.
    import lerobot.datasets.aggregate  # noqa: F401
    import lerobot.datasets.lerobot_dataset  # noqa: F401

    import lerobot_factorworld.envs.factor_env  # noqa: F401
    from lerobot_factorworld.datasets.collect import CollectConfig, collect

    cfg = CollectConfig(
        task=task,
        n_envs=N_ENVS,
        demos=demos,
        seed=seed,
        workers=workers,
        root=str(root),
        repo_id=f"local/bench_{root.name}",
        mode="overwrite",
    )
    report = collect(cfg)
    return {
        "episodes": report.episodes,
        "frames": report.frames,
        "seconds": report.seconds,
        "failures": sum(report.failures.values()),
        "workers": workers or os.cpu_count() or 1,
    }


def run_metaworld(task: str, demos: int, root: Path, seed: int) -> dict:
    """The naive loop: plain Meta-World, render every step, write a LeRobotDataset in the same process."""
    import gymnasium as gym
    import metaworld  # noqa: F401  (registers the Meta-World/* gymnasium ids)
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE
    from tqdm import tqdm

    from lerobot_factorworld.datasets.collect import episode_seed
    from lerobot_factorworld.datasets.schema import frame_features
    from lerobot_factorworld.envs.factor_env import CONTROL_FPS
    from lerobot_factorworld.experts import expert_action, expert_policy, noise_rng
    from lerobot_factorworld.tasks import get_task

    warnings.filterwarnings("ignore", module=r"gymnasium\..*")  # env-checker chatter about Meta-World's spaces
    spec = get_task(task)
    image_key = f"{OBS_IMAGES}.front"
    if root.exists():
        shutil.rmtree(root)

    start = time.perf_counter()
    env = gym.make(
        "Meta-World/MT1",
        env_name=spec.metaworld_name,
        seed=seed,
        render_mode="rgb_array",
        camera_name="corner2",
        width=IMAGE_SIZE,
        height=IMAGE_SIZE,
    )
    policy = expert_policy(task)
    dataset = LeRobotDataset.create(
        repo_id=f"local/bench_{root.name}",
        fps=CONTROL_FPS,
        features=frame_features(("front",), (IMAGE_SIZE, IMAGE_SIZE)),
        root=root,
        robot_type="sawyer",
    )
    episodes = frames_written = failures = 0
    blank = True
    try:
        with tqdm(total=demos, desc="collecting demos (Meta-World)", unit="demo", file=sys.stderr) as bar:
            for demo in range(demos):
                for attempt in range(MAX_ATTEMPTS):
                    ep_seed = episode_seed(seed, 0, 0, demo, attempt)
                    rng = noise_rng(ep_seed)  # the collector's own noise stream, independent of the env's
                    obs, _ = env.reset(seed=ep_seed)
                    image = env.render()
                    frames, success = [], False
                    for _ in range(spec.max_episode_steps):
                        action = expert_action(policy, obs, rng, ACTION_NOISE)
                        state = np.concatenate([obs[0:4], obs[18:22]]).astype(np.float32)
                        frames.append({image_key: image, OBS_STATE: state, ACTION: action, "task": spec.instruction})
                        obs, _, terminated, truncated, info = env.step(action)
                        image = env.render()
                        success = bool(info["success"])
                        if success or terminated or truncated:
                            break
                    if success:
                        break
                    failures += 1
                else:
                    bar.update(1)
                    continue
                blank = blank and int(image.max()) == int(image.min())
                for frame in frames:
                    dataset.add_frame(frame)
                dataset.save_episode()
                episodes += 1
                frames_written += len(frames)
                bar.update(1)
    finally:
        dataset.finalize()
        env.close()
    seconds = time.perf_counter() - start
    if episodes and blank:
        raise RuntimeError("Meta-World rendered blank frames; the benchmark would not be measuring rendering")
    return {"episodes": episodes, "frames": frames_written, "seconds": seconds, "failures": failures, "workers": 1}


def worker_main(args: argparse.Namespace) -> int:
    """Child process: run one mode and write its result as JSON to ``args.result``."""
    root = Path(args.root)
    if args.worker == META_WORLD:
        result = run_metaworld(args.task, args.demos, root, args.seed)
    else:
        result = run_factorworld(args.task, args.demos, 1 if args.worker == FW_ONE else 0, root, args.seed)
    _bench.write_result(args.result, result)
    return 0


def run_mode(mode: str, args: argparse.Namespace, out_dir: Path, round_index: int) -> dict:
    """Run ``mode`` in a fresh interpreter; its stdout goes to our stderr so that ours stays a clean report."""
    root = out_dir / f"{mode}_r{round_index}"
    result_path = out_dir / f"{mode}_r{round_index}.json"
    command = [
        sys.executable,
        str(SCRIPT),
        "--worker",
        mode,
        "--root",
        str(root),
        "--result",
        str(result_path),
        "--task",
        args.task,
        "--demos",
        str(args.demos),
        "--seed",
        str(args.seed),
    ]
    result = _bench.run_child(command, result_path, MODE_LABELS[mode])
    if not args.keep:
        shutil.rmtree(root, ignore_errors=True)
    if result["frames"] <= 0 or result["seconds"] <= 0:
        raise RuntimeError(f"{MODE_LABELS[mode]} wrote no frames: {result}")
    return result


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="pick-place", help="task name, e.g. pick-place")
    parser.add_argument("--demos", type=int, default=40, help="successful demos per mode (D)")
    parser.add_argument("--rounds", type=int, default=1, help="runs of every mode (median frames/s over rounds)")
    parser.add_argument("--seed", type=int, default=0, help="collection seed (environments and episodes)")
    parser.add_argument("--quick", action="store_true", help="fast smoke run: --demos 2 --rounds 1")
    parser.add_argument("--keep", action="store_true", help="keep the output datasets (printed folder)")
    parser.add_argument("--out", default=None, help="output folder (default: a temporary folder)")
    # Internal: run one mode in this (child) process.
    parser.add_argument("--worker", choices=MODES, help=argparse.SUPPRESS)
    parser.add_argument("--root", help=argparse.SUPPRESS)
    parser.add_argument("--result", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:
        args.demos, args.rounds = 2, 1
    if args.demos < N_ENVS or args.rounds < 1:  # the collector takes at least one demo per environment
        parser.error(f"--demos must be at least {N_ENVS} (one per environment) and --rounds at least 1")
    _bench.check_tasks(parser, args.task)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.worker:
        return worker_main(args)
    from tqdm import tqdm

    if args.out:
        out_dir = Path(args.out).resolve()
        out_dir.mkdir(parents=True, exist_ok=True)
    else:
        out_dir = Path(tempfile.mkdtemp(prefix="bench_collect_"))
    print(
        f"collecting {args.demos} demos of {args.task} per mode at {IMAGE_SIZE}x{IMAGE_SIZE} "
        f"({os.cpu_count()} cores, MUJOCO_GL={os.environ['MUJOCO_GL']}) into {out_dir}",
        flush=True,
    )
    results: dict[str, list[dict]] = {mode: [] for mode in MODES}
    try:
        with tqdm(total=args.rounds * len(MODES), desc="modes", unit="mode", file=sys.stderr) as bar:
            for r in range(args.rounds):
                for mode in _bench.round_order(MODES, r):
                    bar.set_postfix_str(f"round {r + 1}/{args.rounds} {mode}")
                    results[mode].append(run_mode(mode, args, out_dir, r))
                    bar.update(1)
    finally:
        if not args.keep and not args.out:
            shutil.rmtree(out_dir, ignore_errors=True)

    fps = {mode: statistics.median(r["frames"] / r["seconds"] for r in results[mode]) for mode in MODES}
    ratio = fps[FW_ALL] / fps[META_WORLD]

    print()
    print(f"task: {args.task} | {args.demos} demos per mode | {args.rounds} round(s) | seed {args.seed}")
    header = f"{'mode':<28}{'workers':>8}{'demos':>7}{'failed':>8}{'frames':>8}{'seconds':>10}{'frames/s':>10}"
    print(header)
    print("-" * len(header))
    for mode in MODES:
        runs = results[mode]
        last = runs[-1]
        seconds = statistics.median(r["seconds"] for r in runs)
        print(
            f"{MODE_LABELS[mode]:<28}{last['workers']:>8}{last['episodes']:>7}{last['failures']:>8}"
            f"{last['frames']:>8}{seconds:>10.2f}{fps[mode]:>10.1f}"
        )
    print("-" * len(header))
    if args.keep or args.out:
        print(f"datasets kept in {out_dir}")
    print(f"Factor World 1 worker / Meta-World naive: {fps[FW_ONE] / fps[META_WORLD]:.2f}x")
    verdict = "meets" if ratio >= TARGET_RATIO else "BELOW"
    print(f"Factor World all workers / Meta-World naive: {ratio:.2f}x ({verdict} the >= {TARGET_RATIO:g}x target)")
    print(_bench.ratio_line(ratio))
    return 0


if __name__ == "__main__":
    sys.exit(main())
