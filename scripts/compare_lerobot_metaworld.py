"""``--env.obs=lerobot_metaworld`` against LeRobot 0.6.1's own ``metaworld`` env, task by task: the numbers of
docs/lerobot_metaworld.md ("What matches LeRobot's metaworld env").

1. **Frames.** Per task and seed: LeRobot's env is reset with the seed and stepped ``--steps`` times with
   Meta-World's scripted expert (LeRobot's ``TASK_POLICY_MAPPING``); Factor World's env (``obs=lerobot_metaworld``,
   the unshifted scene) is reset with the same seed and given the same actions, at ``quality=full`` (the mode's
   default) and ``quality=fast``. Per quality: the mean absolute difference of the 480 x 480 frames (0-255),
   the share of pixels that differ at all and by more than 16 levels, and whether ``agent_pos`` is identical.
   Also the wall time per rendered step of each (LeRobot's env, ours at ``full``, ours at ``fast``).
2. **Simulation.** Per task and ``--state_seeds`` seeds: both envs reset with the seed, then the expert's
   actions (computed on LeRobot's side) are given to both underlying Meta-World envs without rendering, up to
   ``--max_steps`` steps or success: whether Meta-World's state (the first 36 numbers of its observation, the
   goal left out) is identical at every step, and the step each side first succeeds.

LeRobot's env draws through gymnasium's viewer, whose GL context is made current only when it is created, so
its episodes are recorded in a child process first (``--record``), and ours are then run in this one.

    MUJOCO_GL=egl .venv/bin/python scripts/compare_lerobot_metaworld.py                 # all 20 tasks, ~10 min
    MUJOCO_GL=egl .venv/bin/python scripts/compare_lerobot_metaworld.py --tasks button-press --seeds 0 --quick
"""

from __future__ import annotations

import _bench

_bench.setup_headless_gl()  # before anything imports mujoco
_bench.add_repo_to_path()

import argparse  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from lerobot_factorworld.envs.factor_env import FactorWorldEnv  # noqa: E402
from lerobot_factorworld.envs.lerobot_obs import check_lerobot_task  # noqa: E402
from lerobot_factorworld.tasks import TASKS, get_task  # noqa: E402

DIFF_LEVELS = 16  # "off by more than 16 levels" (of 255), as docs/factors.md counts pixel changes
STATE_NUMBERS = 36  # Meta-World's observation without its 3-number goal (pick-place's goal differs by design)


def lerobot_tasks() -> list[str]:
    """Every Factor World task with a LeRobot Meta-World counterpart (``check_lerobot_task``'s rule)."""
    valid = []
    for name, spec in TASKS.items():
        try:
            check_lerobot_task(spec)
        except ValueError:  # a family's task: no counterpart
            continue
        valid.append(name)
    return valid


def record_lerobot(tasks: list[str], seeds: list[int], steps: int, state_seeds: int, max_steps: int, out: Path):
    """LeRobot's side of both comparisons, written to ``out`` (an .npz), one env at a time."""
    # Only the recording child imports LeRobot (seconds): the parent compares through our env alone, and a bad
    # argument is refused before either pays for it.
    from lerobot.envs.metaworld import TASK_POLICY_MAPPING  # noqa: PLC0415
    from lerobot.envs.metaworld import MetaworldEnv as LeRobotMetaworldEnv  # noqa: PLC0415

    arrays: dict[str, np.ndarray] = {}
    for task in tasks:
        name = get_task(task).metaworld_name
        for seed in seeds:
            env = LeRobotMetaworldEnv(name, obs_type="pixels_agent_pos")
            expert = TASK_POLICY_MAPPING[name]()
            obs, _ = env.reset(seed=seed)
            frames, positions, actions, seconds = [obs["pixels"].copy()], [obs["agent_pos"].copy()], [], []
            for _ in range(steps):
                actions.append(expert.get_action(env._env._get_obs()).astype(np.float32))
                env._env.mujoco_renderer.viewer.make_context_current()
                start = time.perf_counter()
                obs, *_ = env.step(actions[-1])
                seconds.append(time.perf_counter() - start)
                frames.append(obs["pixels"].copy())
                positions.append(obs["agent_pos"].copy())
            env.close()
            key = f"{task}/{seed}"
            arrays[f"frames/{key}"], arrays[f"agent_pos/{key}"] = np.stack(frames), np.stack(positions)
            arrays[f"actions/{key}"], arrays[f"seconds/{key}"] = np.stack(actions), np.array(seconds)
        for seed in range(state_seeds):
            env = LeRobotMetaworldEnv(name, obs_type="pixels_agent_pos")
            expert = TASK_POLICY_MAPPING[name]()
            env.reset(seed=seed)
            raw = env._env._get_obs()
            # Copies: an expert may edit the array it is given (door-open's does), so keep none of them.
            states, actions, success = [raw[:STATE_NUMBERS].copy()], [], -1
            for step in range(1, max_steps + 1):
                actions.append(expert.get_action(raw).astype(np.float32))
                raw, _, _, _, info = env._env.step(actions[-1])  # Meta-World's own step: no frame rendered
                states.append(raw[:STATE_NUMBERS].copy())
                if info["success"]:
                    success = step
                    break
            env.close()
            key = f"{task}/{seed}"
            arrays[f"states/{key}"], arrays[f"state_actions/{key}"] = np.stack(states), np.stack(actions)
            arrays[f"success_step/{key}"] = np.array(success)
    np.savez_compressed(out, **arrays)


def compare_frames(task: str, seeds: list[int], lerobot: dict, quality: str) -> dict:
    """Our frames at ``quality`` against LeRobot's recorded ones: pixel statistics and seconds per step."""
    env = FactorWorldEnv(task, obs="lerobot_metaworld", quality=quality)
    diffs, differ, far, same_pos, seconds = [], [], [], True, []
    for seed in seeds:
        key = f"{task}/{seed}"
        obs, _ = env.reset(seed=seed)
        ours = [obs]
        for action in lerobot[f"actions/{key}"]:
            start = time.perf_counter()
            ours.append(env.step(action)[0])
            seconds.append(time.perf_counter() - start)
        for mine, theirs, pos in zip(ours, lerobot[f"frames/{key}"], lerobot[f"agent_pos/{key}"], strict=True):
            channels = np.abs(mine["pixels"].astype(np.int16) - theirs.astype(np.int16))
            delta = channels.max(axis=-1)  # a pixel's largest channel difference
            diffs.append(float(channels.mean()))
            differ.append(float((delta > 0).mean()))
            far.append(float((delta > DIFF_LEVELS).mean()))
            same_pos &= bool(np.array_equal(mine["agent_pos"], pos))
    env.close()
    return {"mean_abs": diffs, "differ": differ, "far": far, "same_agent_pos": same_pos, "seconds": seconds}


def compare_states(task: str, state_seeds: int, lerobot: dict) -> list[tuple[bool, int, int]]:
    """Per seed: (our states identical at every step, LeRobot's success step, ours; -1 = none)."""
    env = FactorWorldEnv(task, obs="lerobot_metaworld", quality="fast")
    out = []
    for seed in range(state_seeds):
        key = f"{task}/{seed}"
        env.reset(seed=seed)
        raw = env.state_observation
        identical, success = np.array_equal(raw[:STATE_NUMBERS], lerobot[f"states/{key}"][0]), -1
        for step, action in enumerate(lerobot[f"state_actions/{key}"], start=1):
            raw, _, _, _, info = env.metaworld_env.step(action)  # the same raw step as LeRobot's side
            identical &= np.array_equal(raw[:STATE_NUMBERS], lerobot[f"states/{key}"][step])
            if info["success"] and success < 0:
                success = step
        out.append((bool(identical), int(lerobot[f"success_step/{key}"]), success))
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tasks", nargs="*", help="default: the 20 tasks with a LeRobot counterpart")
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2], help="seeds of the frame comparison")
    parser.add_argument("--steps", type=int, default=3, help="expert steps after the reset (480 px frames are slow)")
    parser.add_argument("--state_seeds", type=int, default=5, help="seeds 0..n-1 of the simulation comparison")
    parser.add_argument("--max_steps", type=int, default=500, help="LeRobot's horizon")
    parser.add_argument("--quick", action="store_true", help="1 step, 1 state seed of 50 steps (a smoke test)")
    parser.add_argument("--record", type=Path, help=argparse.SUPPRESS)  # the child process: LeRobot's side only
    args = parser.parse_args()
    if args.quick:
        args.steps, args.state_seeds, args.max_steps = 1, 1, 50
    valid = lerobot_tasks()
    tasks = args.tasks or valid
    unknown = [t for t in tasks if t not in valid]
    if unknown:
        raise SystemExit(f"error: no LeRobot counterpart for {', '.join(unknown)}; valid: {', '.join(valid)}")
    if args.record:
        record_lerobot(tasks, args.seeds, args.steps, args.state_seeds, args.max_steps, args.record)
        return

    with tempfile.TemporaryDirectory() as tmp:
        recorded = Path(tmp) / "lerobot.npz"
        child = [
            sys.executable,
            __file__,
            "--record",
            str(recorded),
            "--tasks",
            *tasks,
            "--seeds",
            *map(str, args.seeds),
        ]
        child += [
            "--steps",
            str(args.steps),
            "--state_seeds",
            str(args.state_seeds),
            "--max_steps",
            str(args.max_steps),
        ]
        print(f"recording LeRobot's env: {len(tasks)} task(s) x {len(args.seeds)} seed(s), 480 x 480 ...", flush=True)
        subprocess.run(child, check=True)
        lerobot = dict(np.load(recorded))

    print(f"\nframes: reset + {args.steps} expert step(s), seeds {args.seeds}, 480 x 480, ours against LeRobot's env")
    print("| task | quality | mean abs. difference (max over frames) | pixels that differ | off by > 16 | agent_pos |")
    print("|---|---|---|---|---|---|")
    seconds = {"lerobot": [], "full": [], "fast": []}
    for task in tasks:
        seconds["lerobot"] += [float(s) for seed in args.seeds for s in lerobot[f"seconds/{task}/{seed}"]]
        for quality in ("full", "fast"):
            r = compare_frames(task, args.seeds, lerobot, quality)
            seconds[quality] += r["seconds"]
            print(
                f"| {task} | {quality} | {np.mean(r['mean_abs']):.2f} ({max(r['mean_abs']):.2f}) | "
                f"{np.mean(r['differ']):.2%} | {np.mean(r['far']):.2%} | "
                f"{'identical' if r['same_agent_pos'] else 'DIFFERS'} |",
                flush=True,
            )
    print("\nseconds per rendered 480 x 480 step (median): " + ", ".join(
        f"{name} {np.median(values) * 1000:.0f} ms" for name, values in
        (("LeRobot's env", seconds["lerobot"]), ("ours at full", seconds["full"]), ("ours at fast", seconds["fast"]))
    ))  # fmt: skip

    print(f"\nsimulation: seeds 0-{args.state_seeds - 1}, the expert up to {args.max_steps} steps or success")
    print("| task | episodes with identical states | successes (LeRobot / ours) | same success step |")
    print("|---|---|---|---|")
    totals = [0, 0, 0, 0]
    for task in tasks:
        rows = compare_states(task, args.state_seeds, lerobot)
        same = sum(r[0] for r in rows)
        successes = (sum(r[1] > 0 for r in rows), sum(r[2] > 0 for r in rows))
        same_step = sum(r[1] == r[2] for r in rows if r[1] > 0)
        totals = [totals[0] + same, totals[1] + successes[0], totals[2] + successes[1], totals[3] + same_step]
        print(f"| {task} | {same}/{len(rows)} | {successes[0]} / {successes[1]} | {same_step}/{successes[0]} |")
    print(
        f"\nall: identical states in {totals[0]} of {len(tasks) * args.state_seeds} episodes; "
        f"{totals[1]} LeRobot successes, {totals[2]} ours, {totals[3]} at the same step"
    )


if __name__ == "__main__":
    main()
