"""The round trip of issue 20, item 1: a policy trained on LeRobot's own Meta-World data evaluates here unchanged.

1. ``--demos`` demonstrations of ``--task`` are recorded through LeRobot 0.6.1's own ``metaworld`` env
   (``lerobot.envs.metaworld.MetaworldEnv``, 480 x 480 ``corner2`` frames and the 4-number ``agent_pos``),
   driven by Meta-World's scripted expert (LeRobot's ``TASK_POLICY_MAPPING``), demo ``d`` reset with seed
   ``--seed + d``, into a ``LeRobotDataset`` with LeRobot's keys (``observation.image``,
   ``observation.state``, ``action``);
2. ``lerobot-train`` trains a small ``bc`` policy on it (``--policy_arg`` adds flags; the default CNN takes
   480 px frames in 4 x 4 non-overlapping patches, so it trains in seconds per hundred steps on a CPU);
3. ``lerobot-eval`` evaluates that checkpoint twice on the same episode seeds (episode ``i`` reset with
   ``--eval_seed + i``): under ``--env.type=metaworld`` and under ``--env.type=factorworld
   --env.obs=lerobot_metaworld`` (Meta-World's unshifted scene), both with LeRobot's 500-step horizon.

Prints a table of both success rates with their Wilson 95% intervals, whether they agree (intervals overlap)
and whether every episode ended alike, and writes ``round_trip_seed<eval_seed>_n<episodes>.json`` to ``--out``.
Exit status 1 when the intervals do not overlap. ``--eval_seed`` defaults to ``--seed``: the episodes start
where the demonstrations started (the training starts); another value evaluates on new starts.

Resumable: rerunning into the same ``--out`` reuses the recorded demonstrations, the checkpoint and finished
evaluations (the recording and training settings must be the same; ``--eval_seed`` and ``--episodes`` may
change, so one checkpoint can be evaluated on new starts afterwards).

LeRobot's env draws through gymnasium's viewer, whose GL context is made current only when it is created,
so this process renders nothing else, and each evaluation runs in its own ``lerobot-eval`` process.

    MUJOCO_GL=egl .venv/bin/python scripts/lerobot_metaworld_round_trip.py --task handle-press --demos 3 \
        --steps 300 --episodes 3 --out outputs/round_trip
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np
from _bench import add_repo_to_path, run_logged, setup_headless_gl

setup_headless_gl()
add_repo_to_path()

from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: E402
from lerobot.envs.metaworld import TASK_POLICY_MAPPING, MetaworldEnv  # noqa: E402
from lerobot.utils.constants import ACTION, OBS_IMAGE, OBS_STATE  # noqa: E402

from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig  # noqa: E402
from lerobot_factorworld.stats.proportions import wilson_interval  # noqa: E402

BIN = Path(sys.executable).parent
DEFAULT_POLICY_ARGS = (
    "--policy.conv_stride=4",
    "--policy.conv_channels=[16,32,32]",
    "--policy.latent_dim=64",
    "--policy.hidden_dim=128",
    "--policy.optimizer_lr=0.001",
)
ENVS = {
    "lerobot": ("--env.type=metaworld", "--env.task={task}-v3"),
    "factorworld": ("--env.type=factorworld", "--env.obs=lerobot_metaworld", "--env.task={task}"),
}


def record(task: str, demos: int, seed: int, root: Path) -> None:
    """Scripted demonstrations through LeRobot's own env into a LeRobotDataset at ``root``.
    A demonstration the expert does not finish within the horizon is an error (it would teach failure)."""
    env = MetaworldEnv(f"{task}-v3", obs_type="pixels_agent_pos")
    dataset = LeRobotDataset.create(
        repo_id=f"local/lerobot_metaworld_{task}",
        fps=env.metadata["render_fps"],
        root=root,
        features={
            OBS_IMAGE: {"dtype": "image", "shape": (480, 480, 3), "names": ["height", "width", "channels"]},
            OBS_STATE: {"dtype": "float32", "shape": (4,), "names": ["x", "y", "z", "gripper"]},
            ACTION: {"dtype": "float32", "shape": (4,), "names": ["dx", "dy", "dz", "grip"]},
        },
        use_videos=False,
    )
    try:
        for demo in range(demos):
            expert = TASK_POLICY_MAPPING[f"{task}-v3"]()
            obs, _ = env.reset(seed=seed + demo)
            for _ in range(env._max_episode_steps):
                action = expert.get_action(env._env._get_obs()).astype(np.float32)
                frame = {OBS_IMAGE: obs["pixels"], OBS_STATE: obs["agent_pos"].astype(np.float32), ACTION: action}
                dataset.add_frame({**frame, "task": env.task_description})
                obs, _, terminated, _, info = env.step(action)
                if terminated:
                    break
            if not info["is_success"]:
                raise SystemExit(f"error: the expert did not finish {task} from seed {seed + demo}")
            dataset.save_episode()
    finally:
        dataset.finalize()
        env.close()


def check_settings(args: argparse.Namespace) -> None:
    """Reuse ``--out``'s demonstrations and checkpoint only for the same recording and training settings (the
    evaluation's ``--eval_seed`` and ``--episodes`` may change); otherwise one line."""
    path = args.out / "settings.json"
    settings = {k: getattr(args, k) for k in ("task", "demos", "seed", "steps", "batch_size", "policy_arg")}
    if path.is_file():
        old = json.loads(path.read_text())
        changed = ", ".join(f"{k}: {old.get(k)} -> {v}" for k, v in settings.items() if old.get(k) != v)
        if changed:
            raise SystemExit(f"error: {args.out} holds a run with other settings ({changed}); choose another --out")
    path.write_text(json.dumps(settings, indent=1))


def train(args: argparse.Namespace, data: Path, out: Path, log: Path) -> Path:
    run_logged([str(BIN / "lerobot-train"), "--policy.type=bc", "--policy.device=cpu", "--policy.push_to_hub=false",
         *(args.policy_arg or DEFAULT_POLICY_ARGS), f"--dataset.repo_id=local/lerobot_metaworld_{args.task}",
         f"--dataset.root={data}", f"--steps={args.steps}", f"--batch_size={args.batch_size}", "--num_workers=0",
         f"--save_freq={args.steps}", f"--log_freq={min(100, args.steps)}", "--seed=0", "--wandb.enable=false",
         f"--output_dir={out}"], log)  # fmt: skip
    return out / "checkpoints" / "last" / "pretrained_model"


def evaluate(args: argparse.Namespace, env: str, checkpoint: Path, out: Path, log: Path) -> list[bool]:
    """Per-episode successes of ``checkpoint`` under one env, the LeRobot way (``eval_info.json``, reused when
    this evaluation already ran)."""
    if not (out / "eval_info.json").is_file():
        shutil.rmtree(out, ignore_errors=True)
        run_logged([str(BIN / "lerobot-eval"), f"--policy.path={checkpoint}", *(a.format(task=args.task) for a in ENVS[env]),
             f"--eval.n_episodes={args.episodes}", "--eval.batch_size=1", f"--seed={args.eval_seed}",
             f"--output_dir={out}"], log)  # fmt: skip
        shutil.rmtree(out / "videos", ignore_errors=True)  # lerobot-eval's videos of the first episodes
    info = json.loads((out / "eval_info.json").read_text())
    return [bool(s) for task in info["per_task"] for s in task["metrics"]["successes"]]


def summary(successes: dict[str, list[bool]]) -> dict:
    rows = {}
    for env, values in successes.items():
        low, high = wilson_interval(sum(values), len(values))
        rows[env] = {"successes": sum(values), "episodes": len(values), "pc_success": 100 * sum(values) / len(values),
                     "ci_low": low, "ci_high": high, "per_episode": values}  # fmt: skip
    (a, b) = rows.values()
    return {
        "envs": rows,
        "intervals_overlap": a["ci_low"] <= b["ci_high"] and b["ci_low"] <= a["ci_high"],
        "same_episodes": a["per_episode"] == b["per_episode"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", default="handle-press")
    parser.add_argument("--demos", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0, help="demo d is reset with seed --seed + d")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--batch_size", type=int, default=16)
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--eval_seed", type=int, default=None, help="episode i reset with --eval_seed + i")
    parser.add_argument("--policy_arg", action="append", help="a lerobot-train --policy.* flag (replaces defaults)")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    args.eval_seed = args.seed if args.eval_seed is None else args.eval_seed
    FactorWorldEnvConfig(task=args.task, obs="lerobot_metaworld")  # an unknown task or pick: one line, no work
    if f"{args.task}-v3" not in TASK_POLICY_MAPPING:
        raise SystemExit(f"error: LeRobot has no Meta-World expert for {args.task}")
    args.out.mkdir(parents=True, exist_ok=True)
    check_settings(args)
    log = args.out / "log.txt"
    data, checkpoint = args.out / "data", args.out / "train" / "checkpoints" / "last" / "pretrained_model"
    if not (data / "meta" / "info.json").is_file():
        shutil.rmtree(data, ignore_errors=True)  # an interrupted recording: record again
        record(args.task, args.demos, args.seed, data)
    if not checkpoint.is_dir():
        shutil.rmtree(args.out / "train", ignore_errors=True)  # an interrupted training (lerobot-train refuses it)
        train(args, data, args.out / "train", log)
    name = f"seed{args.eval_seed}_n{args.episodes}"
    successes = {env: evaluate(args, env, checkpoint, args.out / f"eval_{env}_{name}", log) for env in ENVS}
    frames = json.loads((data / "meta" / "info.json").read_text())["total_frames"]
    result = {"settings": {k: str(v) if isinstance(v, Path) else v for k, v in vars(args).items()},
              "frames": frames, **summary(successes)}  # fmt: skip
    (args.out / f"round_trip_{name}.json").write_text(json.dumps(result, indent=1))
    print("| env | successes | pc_success | 95% interval |\n|---|---|---|---|")
    for env, row in result["envs"].items():
        print(f"| {env} | {row['successes']}/{row['episodes']} | {row['pc_success']:.1f} | "
              f"[{100 * row['ci_low']:.1f}, {100 * row['ci_high']:.1f}] |")  # fmt: skip
    print(f"intervals overlap: {result['intervals_overlap']}; every episode ended alike: {result['same_episodes']}")
    if not result["intervals_overlap"]:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
