"""How many pixels the textured object covers, per task, camera and image size (docs/factors.md).

Each task gets ``--n_envs`` environments sampled as a study samples its training environments (the
paper's seven factors by default, so camera and table position, distractors and the rest vary) and
``--starts`` episode starts in each (reset seeds: the object's start drawn as in collection and
evaluation). In each start, MuJoCo's segmentation rendering counts the pixels in which the object (the
geoms the object-texture factor paints: ``lerobot_factorworld.scene.footprint``) is the front-most thing,
so the arm or a distractor in front of it hides what it covers. For ``pick`` every object of the scene is
counted on its own (the texture paints each): its row is per object.

    MUJOCO_GL=egl .venv/bin/python scripts/object_footprint.py --cameras=front
    MUJOCO_GL=egl .venv/bin/python scripts/object_footprint.py --tasks=pick-place,bin-picking,door-open
"""

from __future__ import annotations

import argparse
import time

import _bench

_bench.setup_headless_gl()
_bench.add_repo_to_path()

import numpy as np  # noqa: E402
from tqdm import tqdm  # noqa: E402

from lerobot_factorworld.envs.factor_env import FactorWorldEnv  # noqa: E402
from lerobot_factorworld.factors.registry import PAPER_STUDY_FACTORS, check_factors  # noqa: E402
from lerobot_factorworld.pick.scene import body_name  # noqa: E402
from lerobot_factorworld.protocol.sampling import sample_configs  # noqa: E402
from lerobot_factorworld.scene.cameras import CAMERAS, check_cameras  # noqa: E402
from lerobot_factorworld.scene.footprint import PixelCounter, visible_geoms  # noqa: E402
from lerobot_factorworld.tasks import TASKS, get_task  # noqa: E402

STUDY_IMAGE_SIZE = 84


def textured_objects(config) -> list[tuple[str, ...]]:
    """The body groups the object-texture factor paints, one group per object: the task's object, or
    each object of a pick scene."""
    task = get_task(config.task)
    if task.object_bodies:
        return [task.object_bodies]
    return [(body_name(item.name),) for item in config.content.objects]


def measure(task: str, cameras: tuple[str, ...], sizes: tuple[int, ...], args, bar) -> dict[tuple[str, int], list[int]]:
    """(camera, size) -> object pixels of every object, environment and start."""
    configs = sample_configs(task, args.n_envs, args.seed, factors=args.factors)
    env = FactorWorldEnv(task, configs, cameras=cameras, image_size=STUDY_IMAGE_SIZE, scene_cache_size=1)
    counts: dict[tuple[str, int], list[int]] = {(camera, size): [] for camera in cameras for size in sizes}
    try:
        model, counter = None, None
        for index in range(len(configs)):
            for start in range(args.starts):
                env.reset(seed=index * args.starts + start, options={"env_index": index})
                if env.model is not model:  # a new compiled scene (one per environment): renderers of its own
                    if counter is not None:
                        counter.close()
                    model, counter = env.model, PixelCounter(env.model, sizes)
                groups = [visible_geoms(model, bodies) for bodies in textured_objects(env.config)]
                for camera in cameras:
                    for geoms in groups:
                        for size, pixels in counter.count(env.data, camera, geoms).items():
                            counts[camera, size].append(pixels)
            bar.update(1)
    finally:
        if counter is not None:
            counter.close()
        env.close()
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=",".join(TASKS), help="comma-separated tasks (default: all)")
    parser.add_argument("--cameras", default=",".join(CAMERAS), help="comma-separated cameras (default: all)")
    parser.add_argument("--sizes", default="84,128,224", help="square image sides in pixels")
    parser.add_argument("--n_envs", type=int, default=5, help="environments per task")
    parser.add_argument("--starts", type=int, default=4, help="episode starts per environment")
    parser.add_argument("--seed", type=int, default=0, help="seed of the environments")
    parser.add_argument(
        "--factors", default=",".join(PAPER_STUDY_FACTORS), help="factors varied (default: the study's)"
    )
    args = parser.parse_args()
    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()]
    _bench.check_tasks(parser, tasks)
    try:
        cameras = check_cameras(args.cameras)
        sizes = tuple(dict.fromkeys(int(s) for s in args.sizes.split(",") if s.strip()))
        args.factors = tuple(f.strip() for f in args.factors.split(",") if f.strip())
        check_factors(args.factors, tasks)
    except ValueError as err:
        parser.error(str(err))
    if not sizes or min(sizes) < 1 or args.n_envs < 1 or args.starts < 1:
        parser.error("sizes, n_envs and starts must be positive")

    begin = time.perf_counter()
    header = "| task | camera | " + " | ".join(f"{s} px: mean [min, max]" for s in sizes) + " |"
    rows = []
    with tqdm(total=len(tasks) * args.n_envs, desc="environments", unit="env") as bar:
        for task in tasks:
            try:
                counts = measure(task, cameras, sizes, args, bar)
            except ValueError as err:  # e.g. an image size beyond the scene's offscreen buffer
                parser.error(str(err))
            label = f"{task} (per object)" if not get_task(task).object_bodies else task
            for camera in cameras:
                cells = []
                for size in sizes:
                    values = np.asarray(counts[camera, size])
                    cells.append(f"{values.mean():.1f} [{values.min()}, {values.max()}]")
                rows.append(f"| {label} | {camera} | " + " | ".join(cells) + " |")
    _bench.print_table(header, rows)
    print(
        f"\n{args.n_envs} environments x {args.starts} starts per task (seed {args.seed}; factors "
        f"{', '.join(args.factors) or 'none'}), {time.perf_counter() - begin:.0f} s"
    )


if __name__ == "__main__":
    main()
