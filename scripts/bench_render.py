"""Render quality ``lod`` vs ``fast``, side by side: ms per frame, speed ratio and pixel difference.

What is measured
    For each task and image size, the scenes of both qualities (default factor values, camera ``front``) are
    set to the same simulator states, taken from one expert episode (seed 0, ``FULLPHYSICS`` state every few
    steps), and drawn with ``mujoco.Renderer`` exactly as ``CompiledScene.render_all`` does
    (``update_scene`` + ``render``, the read-back included). Timing is interleaved round by round with the
    order of the qualities alternating (this machine is noisy); the figure per cell is the median of the
    per-round means. Pixel differences compare the two qualities' frames of the same states: the mean
    absolute difference in levels of 255 (over all pixels and channels) and the share of pixels with a
    channel off by more than 16 levels.

    Then the rest of a frame, for both qualities: the split of a frame into ``update_scene``
    (``mjv_updateScene``), drawing (``mjr_render`` then ``mjr_finish``, so that the rasteriser's work is
    counted here) and read-back (``mjr_readPixels``), the number of geoms drawn and their mesh triangles;
    and Mesa llvmpipe's rasteriser threads: the same frames in a second worker process started with
    ``LP_NUM_THREADS=1`` against the default (one thread per CPU), interleaved with the first.

    python scripts/bench_render.py [--task door-open pick-place] [--size 84 224] [--rounds 5] [--quick]

The last line printed is exactly ``ratio: <float>`` = the geometric mean over tasks and sizes of
fast ms per frame / lod ms per frame (default threads).
"""

from __future__ import annotations

import _bench

_bench.setup_headless_gl()  # before anything imports mujoco; spawned workers inherit it
_bench.add_repo_to_path()

import argparse  # noqa: E402
import math  # noqa: E402
import multiprocessing as mp  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

QUALITIES = ("fast", "lod")
CAMERA = "front"
STATES = 24  # simulator states per task (evenly spaced over one expert episode)
DEFAULT_THREADS = "default"
ONE_THREAD = "LP_NUM_THREADS=1"


def _worker(conn, threads: str, tasks: list[str], sizes: list[int]) -> None:
    """One process (one llvmpipe thread setting): a renderer per (task, size, quality), then timed requests."""
    if threads == ONE_THREAD:
        os.environ["LP_NUM_THREADS"] = "1"  # read by Mesa when the first GL context is created

    def start():
        import mujoco

        from lerobot_factorworld.envs.factor_env import FactorWorldEnv
        from lerobot_factorworld.experts import expert_policy, rollout
        from lerobot_factorworld.factors.values import FactorValues
        from lerobot_factorworld.scene.build import build_model

        warnings.filterwarnings("ignore", module=r"metaworld\..*")
        full = mujoco.mjtState.mjSTATE_FULLPHYSICS
        cells, states = {}, {}
        for task in tasks:
            env = FactorWorldEnv(task, cameras=())  # physics only: the states are quality-independent
            grabbed: list[np.ndarray] = []

            def grab(e, grabbed=grabbed):
                state = np.empty(mujoco.mj_stateSize(e.model, full))
                mujoco.mj_getState(e.model, e.data, state, full)
                grabbed.append(state)

            rollout(env, expert_policy(task), seed=0, after_step=grab)
            env.close()
            states[task] = grabbed[:: max(1, len(grabbed) // STATES)][:STATES]
            for size in sizes:
                for quality in QUALITIES:
                    model = build_model(task, FactorValues(), (CAMERA,), quality, (size, size))
                    data = mujoco.MjData(model)
                    renderer = mujoco.Renderer(model, height=size, width=size)
                    cells[task, size, quality] = (model, data, renderer)
        return (cells, states), None

    def set_state(cells, states, key, i):
        import mujoco

        model, data, renderer = cells[key]
        mujoco.mj_setState(model, data, states[key[0]][i], mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_forward(model, data)
        return model, data, renderer

    def handle(state, msg, progress):
        import mujoco

        cells, states = state
        kind, key = msg[0], msg[1]
        n = len(states[key[0]])
        if kind == "frames":
            out = []
            for i in range(n):
                _, data, renderer = set_state(cells, states, key, i)
                renderer.update_scene(data, camera=CAMERA)
                out.append(renderer.render().copy())
            return np.stack(out)
        if kind == "time":  # mean ms per frame of update_scene + render (read-back included), as the env
            reps, total = msg[2], 0.0
            for _ in range(reps):
                for i in range(n):
                    _, data, renderer = set_state(cells, states, key, i)
                    t0 = time.perf_counter()
                    renderer.update_scene(data, camera=CAMERA)
                    renderer.render()
                    total += time.perf_counter() - t0
            progress(1)
            return 1000.0 * total / (reps * n)
        if kind == "split":  # mean ms of each phase, geoms drawn, mesh triangles drawn
            reps = msg[2]
            phases = np.zeros(3)
            geoms = triangles = 0
            for _ in range(reps):
                for i in range(n):
                    model, data, renderer = set_state(cells, states, key, i)
                    t0 = time.perf_counter()
                    renderer.update_scene(data, camera=CAMERA)
                    t1 = time.perf_counter()
                    renderer._gl_context.make_current()
                    mujoco.mjr_render(renderer._rect, renderer._scene, renderer._mjr_context)
                    mujoco.mjr_finish()
                    t2 = time.perf_counter()
                    pixels = np.empty((renderer.height, renderer.width, 3), np.uint8)
                    mujoco.mjr_readPixels(pixels, None, renderer._rect, renderer._mjr_context)
                    t3 = time.perf_counter()
                    phases += (t1 - t0, t2 - t1, t3 - t2)
                    scene = renderer._scene
                    geoms = scene.ngeom
                    triangles = sum(
                        int(model.mesh_facenum[scene.geoms[g].dataid // 2])
                        for g in range(scene.ngeom)
                        if scene.geoms[g].type == mujoco.mjtGeom.mjGEOM_MESH
                    )
            progress(1)
            return [*(1000.0 * phases / (reps * n)).tolist(), geoms, triangles]
        raise ValueError(f"unknown request {kind!r}")

    def stop(state):
        for _, _, renderer in state[0].values():
            renderer.close()

    _bench.serve(conn, start, handle, stop)


def pixel_difference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(mean absolute difference in levels of 255, % of pixels with a channel off by more than 16 levels)."""
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return float(diff.mean()), 100.0 * float((diff.max(axis=-1) > 16).mean())


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", nargs="+", default=["door-open", "pick-place"], help="task name(s)")
    parser.add_argument("--size", nargs="+", type=int, default=[84, 224], help="square image size(s), pixels")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds (median over rounds)")
    parser.add_argument("--reps", type=int, default=2, help="passes over the states per timed cell and round")
    parser.add_argument("--no-threads", action="store_true", help="skip the LP_NUM_THREADS=1 comparison")
    parser.add_argument("--quick", action="store_true", help="smoke run: pick-place at 84 px, 1 round, 1 pass")
    args = parser.parse_args(argv)
    if args.quick:
        args.task, args.size, args.rounds, args.reps = ["pick-place"], [84], 1, 1
    if args.rounds < 1 or args.reps < 1:
        parser.error("--rounds and --reps must be at least 1")
    _bench.check_tasks(parser, args.task)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    cells = [(task, size) for task in args.task for size in args.size]
    modes = [DEFAULT_THREADS] if args.no_threads else [DEFAULT_THREADS, ONE_THREAD]
    print(
        f"rendering {', '.join(args.task)} at {', '.join(f'{s}x{s}' for s in args.size)}, camera {CAMERA}, "
        f"qualities {' vs '.join(QUALITIES)} (MUJOCO_GL={os.environ['MUJOCO_GL']})",
        file=sys.stderr,
        flush=True,
    )
    load_start = os.getloadavg()
    ctx = mp.get_context("spawn")
    workers = {mode: _bench.PipeWorker(ctx, mode, _worker, (mode, args.task, args.size)) for mode in modes}
    ms: dict[tuple, list[float]] = {}
    try:
        for worker in workers.values():
            worker.ready()
        main_worker = workers[DEFAULT_THREADS]
        diffs = {}
        for task, size in cells:
            frames = [main_worker.request(("frames", (task, size, q))) for q in QUALITIES]
            diffs[task, size] = pixel_difference(*frames)
        runs = [(mode, q) for mode in modes for q in QUALITIES]
        for r in range(args.rounds):
            for task, size in cells:
                for mode, quality in _bench.round_order(runs, r + cells.index((task, size))):
                    t = workers[mode].request(("time", (task, size, quality), args.reps))
                    ms.setdefault((mode, task, size, quality), []).append(t)
            print(f"round {r + 1}/{args.rounds} done", file=sys.stderr, flush=True)
        splits = {}
        for r in range(max(1, args.rounds // 2)):
            for task, size in cells:
                for quality in _bench.round_order(QUALITIES, r):
                    split = main_worker.request(("split", (task, size, quality), args.reps))
                    splits.setdefault((task, size, quality), []).append(split)
    finally:
        for worker in workers.values():
            worker.close()

    med = {key: statistics.median(values) for key, values in ms.items()}
    print(f"\n{args.rounds} interleaved rounds x {args.reps} passes over {STATES} states of one expert episode")
    print(_bench.load_average_line(load_start, os.getloadavg()))
    print("\nms per frame (update_scene + render + read-back), llvmpipe default threads:\n")
    ratios = []
    rows = []
    for task, size in cells:
        fast, lod = med[DEFAULT_THREADS, task, size, "fast"], med[DEFAULT_THREADS, task, size, "lod"]
        ratios.append(fast / lod)
        mean_diff, share = diffs[task, size]
        rows.append(
            f"| {task:<11} | {size:>4} | {fast:>7.2f} | {lod:>7.2f} | {fast / lod:>7.2f}x "
            f"| {mean_diff:>13.3f} | {share:>12.2f}% |"
        )
    _bench.print_table("| task        | size | fast ms | lod ms  | fast/lod | mean abs diff | pixels > 16   |", rows)

    print("\nwhere a frame goes (ms; drawing includes mjr_finish, so the rasteriser's work lands there):\n")
    rows = []
    for task, size in cells:
        for quality in QUALITIES:
            values = np.median(np.array(splits[task, size, quality]), axis=0)
            update, draw, read, geoms, triangles = values.tolist()
            rows.append(
                f"| {task:<11} | {size:>4} | {quality:<7} | {update:>12.2f} | {draw:>7.2f} | {read:>9.2f} "
                f"| {int(geoms):>5} | {int(triangles):>9} |"
            )
    _bench.print_table(
        "| task        | size | quality | update_scene | drawing | read-back | geoms | triangles |", rows
    )

    if ONE_THREAD in modes:
        print("\nllvmpipe threads: ms per frame with the default (one per CPU) vs LP_NUM_THREADS=1:\n")
        rows = []
        for task, size in cells:
            for quality in QUALITIES:
                default, one = med[DEFAULT_THREADS, task, size, quality], med[ONE_THREAD, task, size, quality]
                rows.append(
                    f"| {task:<11} | {size:>4} | {quality:<7} | {default:>7.2f} | {one:>8.2f} | {one / default:>4.2f}x |"
                )
        _bench.print_table("| task        | size | quality | default | 1 thread | 1/def |", rows)

    ratio = math.exp(sum(math.log(x) for x in ratios) / len(ratios))
    print(f"\nlod speed-up over fast (geometric mean of {len(ratios)} cells): {ratio:.2f}x")
    print(_bench.ratio_line(ratio))
    return 0


if __name__ == "__main__":
    sys.exit(main())
