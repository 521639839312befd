"""Rendered environment steps per second: Factor World (its defaults) vs. plain Meta-World (its defaults), at 84x84.

What is measured
    One "rendered env step" is everything a pixel-based policy needs per control step:

    * Factor World: ``FactorWorldEnv(task, image_size=84)`` at its defaults (camera ``front``, quality
      ``fast``); ``env.step(action)`` simulates and renders ``obs["pixels"]`` every step.
    * Meta-World: ``gymnasium.make("Meta-World/MT1", env_name=f"{task}-v3", render_mode="rgb_array",
      camera_name="corner2", width=84, height=84)`` at Meta-World's defaults; ``env.step(action)`` followed
      by ``env.render()``.

    Both modes run the same task(s) with the same seeded random actions (``np.random.default_rng``) and reset
    when an episode ends (the reset is counted in the timed cost, as in a real rollout). Both are warmed up
    (first reset, a few steps) before timing, and measurements are interleaved, round by round, with the
    order alternating (A B, B A, A B, ...) because this machine is noisy; the reported figure per mode is
    the median of the per-round rates.

    Each mode runs in its own persistent worker process (it idles, blocked on a pipe, while the other one is
    timed). That is how each would be used, and it matters: gymnasium's ``OffScreenViewer`` makes its EGL
    context current only when it is created, so in a process that also renders with ``mujoco.Renderer``
    (Factor World) Meta-World's ``env.render()`` would draw through the wrong GL context and return black
    frames about 5x faster than it really renders. Each worker checks that its last frame is not blank.

Why
    Physics is cheap: on a CPU-only machine (MuJoCo through EGL on Mesa's llvmpipe) rendering dominates the
    cost of a step. Meta-World renders with a 4096x4096 shadow map, 4x multisampling and reflective
    materials; Factor World's ``fast`` quality compiles its scenes with no shadows (``shadowsize=0``, lights
    with ``castshadow=False``), no multisampling (``offsamples=0``) and no reflections (``reflectance=0``).

    python scripts/bench_env.py [--task pick-place] [--steps 200] [--rounds 3] [--seed 0] [--quick]

The last line printed is exactly ``ratio: <float>`` = Factor World median steps/s / Meta-World median steps/s
(target: >= 8).
"""

from __future__ import annotations

import _bench

_bench.setup_headless_gl()  # before anything imports mujoco (Meta-World's side included); workers inherit it
_bench.add_repo_to_path()

import argparse  # noqa: E402
import multiprocessing as mp  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from tqdm import tqdm  # noqa: E402

TARGET_RATIO = 8.0
IMAGE_SIZE = 84
WARMUP_STEPS = 5
PROGRESS_EVERY = 10  # steps between progress messages from a worker
FACTOR_WORLD = "factorworld"
META_WORLD = "metaworld"
MODES = (FACTOR_WORLD, META_WORLD)
MODE_LABELS = {
    FACTOR_WORLD: "Factor World (front, fast)",
    META_WORLD: "Meta-World (corner2, defaults)",
}


@dataclass
class Runner:
    """One env for one (mode, task): steps it with given actions, resetting at episode end."""

    mode: str
    task: str
    env: Any
    step_fn: Callable[[np.ndarray], bool]  # one rendered step; returns True when the episode ended
    reset_fn: Callable[[int | None], None]
    seed: int
    episodes: int = 0
    last_frame: np.ndarray | None = None  # the latest rendered frame (keeps the render from being skipped)

    def reset(self) -> None:
        # Seed only the first reset; later episodes follow from the env's RNG (same scheme for both modes).
        self.reset_fn(self.seed if self.episodes == 0 else None)
        self.episodes += 1

    def run(self, actions: np.ndarray, on_step: Callable[[], None] | None = None) -> float:
        """Time ``len(actions)`` rendered steps (resets included); returns the summed seconds."""
        total = 0.0
        for action in actions:
            t0 = time.perf_counter()
            done = self.step_fn(action)
            if done:
                self.reset()
            total += time.perf_counter() - t0
            if on_step is not None:
                on_step()
        return total


def make_factorworld(task: str, seed: int) -> Runner:
    from lerobot_factorworld.envs.factor_env import FactorWorldEnv

    env = FactorWorldEnv(task, image_size=IMAGE_SIZE)
    runner: Runner

    def step(action: np.ndarray) -> bool:
        obs, _, terminated, truncated, _ = env.step(action)
        runner.last_frame = obs["pixels"][env.cameras[0]]
        return terminated or truncated

    def reset(s: int | None) -> None:
        obs, _ = env.reset(seed=s)
        runner.last_frame = obs["pixels"][env.cameras[0]]

    runner = Runner(FACTOR_WORLD, task, env, step, reset, seed)
    return runner


def make_metaworld(task: str, seed: int) -> Runner:
    import gymnasium as gym
    import metaworld  # noqa: F401  (registers the Meta-World/* gymnasium ids)

    env = gym.make(
        "Meta-World/MT1",
        env_name=f"{task}-v3",
        seed=seed,
        render_mode="rgb_array",
        camera_name="corner2",
        width=IMAGE_SIZE,
        height=IMAGE_SIZE,
    )
    runner: Runner

    def step(action: np.ndarray) -> bool:
        _, _, terminated, truncated, _ = env.step(action)
        runner.last_frame = env.render()
        return bool(terminated or truncated)

    def reset(s: int | None) -> None:
        env.reset(seed=s)
        runner.last_frame = env.render()

    runner = Runner(META_WORLD, task, env, step, reset, seed)
    return runner


def render_settings(runner: Runner) -> str:
    """The render settings the compiled model really has (shadow map size, MSAA samples, frame shape)."""
    env = runner.env
    model = env.model if runner.mode == FACTOR_WORLD else env.unwrapped.model
    quality = model.vis.quality
    frame = runner.last_frame
    if frame is None or int(frame.max()) == int(frame.min()):
        raise RuntimeError(f"{runner.mode}: rendered frame is blank; the benchmark would not be measuring rendering")
    return (
        f"shadowsize={quality.shadowsize} offsamples={quality.offsamples} "
        f"frame={tuple(frame.shape)} mean_px={float(frame.mean()):.1f}"
    )


def _worker(conn, mode: str, tasks: list[str], seed: int, actions: dict[str, np.ndarray]) -> None:
    """One mode in its own process: build and warm up its envs, then run timed segments on request.

    Requests are ``("run", lo, hi)``: time ``actions[task][lo:hi]`` on every task's env; the reply is the
    summed seconds (progress is reported every ``PROGRESS_EVERY`` steps). See ``_bench.serve``.
    """

    def start() -> tuple[list[Runner], str]:
        warnings.filterwarnings("ignore", module=r"gymnasium\..*")  # env-checker chatter about Meta-World's spaces
        maker = make_factorworld if mode == FACTOR_WORLD else make_metaworld
        runners = [maker(task, seed) for task in tasks]
        # Warm-up (not timed): the first reset compiles the scene and uploads it to the GL context, the
        # first renders allocate the framebuffers / shadow map.
        for runner in runners:
            runner.reset()
            runner.run(actions[runner.task][:WARMUP_STEPS])
        return runners, [render_settings(runner) for runner in runners][0]

    def handle(runners: list[Runner], msg: tuple, progress: Callable[[int], None]) -> float:
        _, lo, hi = msg
        pending = 0

        def on_step() -> None:
            nonlocal pending
            pending += 1
            if pending >= PROGRESS_EVERY:
                progress(pending)
                pending = 0

        seconds = sum(runner.run(actions[runner.task][lo:hi], on_step=on_step) for runner in runners)
        for runner in runners:
            render_settings(runner)  # raises if the last frame came out blank
        if pending:
            progress(pending)
        return seconds

    def stop(runners: list[Runner]) -> None:
        for runner in runners:
            runner.env.close()

    _bench.serve(conn, start, handle, stop)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", nargs="+", default=["pick-place"], help="task name(s), e.g. pick-place reach")
    parser.add_argument("--steps", type=int, default=200, help="timed steps per round, per mode and task")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (median over rounds)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the action sequence and of the first reset")
    parser.add_argument("--quick", action="store_true", help="fast smoke run: --steps 30 --rounds 1")
    args = parser.parse_args(argv)
    if args.quick:
        args.steps, args.rounds = 30, 1
    if args.steps < 1 or args.rounds < 1:
        parser.error("--steps and --rounds must be at least 1")
    _bench.check_tasks(parser, args.task)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    tasks: list[str] = list(args.task)

    # Same random actions for both modes: one stream per task, warm-up first, then one slice per round.
    rng = np.random.default_rng(args.seed)
    actions = {
        task: rng.uniform(-1.0, 1.0, size=(WARMUP_STEPS + args.rounds * args.steps, 4)).astype(np.float32)
        for task in tasks
    }

    print(
        f"building envs for {', '.join(tasks)} at {IMAGE_SIZE}x{IMAGE_SIZE} (MUJOCO_GL={os.environ['MUJOCO_GL']})",
        flush=True,
    )
    ctx = mp.get_context("spawn")  # fresh interpreters: no GL state inherited through fork
    workers = {mode: _bench.PipeWorker(ctx, mode, _worker, (mode, tasks, args.seed, actions)) for mode in MODES}
    try:
        settings = {mode: workers[mode].ready() for mode in MODES}

        rates: dict[str, list[float]] = {mode: [] for mode in MODES}
        total = args.rounds * len(MODES) * len(tasks) * args.steps
        with tqdm(total=total, desc="rendered steps", unit="step", file=sys.stderr) as bar:
            for r in range(args.rounds):
                lo = WARMUP_STEPS + r * args.steps
                for mode in _bench.round_order(MODES, r):
                    bar.set_postfix_str(f"round {r + 1}/{args.rounds} {mode}")
                    seconds = workers[mode].request(("run", lo, lo + args.steps), bar.update)
                    rates[mode].append(len(tasks) * args.steps / seconds)
    finally:
        for worker in workers.values():
            worker.close()

    medians = {mode: statistics.median(rates[mode]) for mode in MODES}
    ratio = medians[FACTOR_WORLD] / medians[META_WORLD]

    print()
    print(f"tasks: {', '.join(tasks)} | {args.steps} steps x {args.rounds} rounds per mode | seed {args.seed}")
    for mode in MODES:
        print(f"  {MODE_LABELS[mode]:<32} {settings[mode]}")
    print()
    round_cols = [f"r{i + 1} steps/s" for i in range(args.rounds)]
    header = f"{'mode':<32}" + "".join(f"{c:>14}" for c in round_cols) + f"{'median':>12}{'ms/step':>10}"
    print(header)
    print("-" * len(header))
    for mode in MODES:
        cells = "".join(f"{rate:>14.1f}" for rate in rates[mode])
        print(f"{MODE_LABELS[mode]:<32}{cells}{medians[mode]:>12.1f}{1000.0 / medians[mode]:>10.2f}")
    print("-" * len(header))
    verdict = "meets" if ratio >= TARGET_RATIO else "BELOW"
    print(f"Factor World / Meta-World: {ratio:.2f}x ({verdict} the >= {TARGET_RATIO:g}x target)")
    print(_bench.ratio_line(ratio))
    return 0


if __name__ == "__main__":
    sys.exit(main())
