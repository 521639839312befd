"""How much action noise the scripted experts tolerate (docs/findings.md, "Recipe").

Demonstrations with noisier actions visit states off the expert's path and show how it recovers (the idea of
DART, Laskin et al. 2017), which a cloned policy needs once its own small errors accumulate; the public Factor
World collects with std 0.002, which leaves almost none. This prints, per task and noise std, the expert's
successes on its N training environments (seeded as ``factorworld collect`` seeds them, seed 0; episode
``i`` reset with seed ``i``) with a Wilson 95% interval and its mean episode length. Physics only (no
cameras): visual factors leave the physics bit-identical.

    MUJOCO_GL=egl .venv/bin/python scripts/expert_noise_table.py --episodes 30
"""

from __future__ import annotations

import argparse

import numpy as np
from _bench import add_repo_to_path, check_tasks, setup_headless_gl
from tqdm import tqdm

setup_headless_gl()
add_repo_to_path()

from lerobot_factorworld.envs.factor_env import FactorWorldEnv  # noqa: E402
from lerobot_factorworld.experts import expert_policy, rollout  # noqa: E402
from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs  # noqa: E402
from lerobot_factorworld.stats.proportions import wilson_interval  # noqa: E402


def cell(task: str, n_envs: int, noise: float, episodes: int, options: SamplingOptions) -> tuple[int, float]:
    """Successes and mean length of ``episodes`` expert episodes at action-noise std ``noise``."""
    configs = sample_configs(task, n_envs, 0, options=options)
    env = FactorWorldEnv(task, configs, cameras=(), scene_cache_size=len(configs))
    policy = expert_policy(task)
    runs = [rollout(env, policy, seed, noise) for seed in range(episodes)]
    env.close()
    return sum(r.success for r in runs), float(np.mean([len(r) for r in runs]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tasks", default="pick-place,bin-picking,door-open,pick")
    parser.add_argument("--noise", default="0.002,0.05,0.1,0.2,0.3", help="action-noise stds, comma-separated")
    parser.add_argument("--n", type=int, default=5, help="training environments (pick: twice this, as pick.yaml)")
    parser.add_argument("--episodes", type=int, default=30)
    args = parser.parse_args()
    tasks = args.tasks.split(",")
    check_tasks(parser, tasks)
    stds = [float(s) for s in args.noise.split(",")]
    print("| task | N | action noise std | expert successes | rate [Wilson 95%] | mean steps |")
    print("|---|---|---|---|---|---|")
    for task in tasks:
        n, options = (2 * args.n, SamplingOptions(n_objects=3)) if task == "pick" else (args.n, SamplingOptions())
        for std in tqdm(stds, desc=task, leave=False):
            wins, steps = cell(task, n, std, args.episodes, options)
            low, high = wilson_interval(wins, args.episodes)
            rate = f"{wins / args.episodes:.2f} [{low:.2f}, {high:.2f}]"
            print(f"| {task} | {n} | {std:g} | {wins}/{args.episodes} | {rate} | {steps:.0f} |", flush=True)


if __name__ == "__main__":
    main()
