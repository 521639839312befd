"""The pick expert's success table (docs/pick.md): default scenes and every applicable single-factor shift.

Cells: ``default`` = N training environments of ``pick`` (seeded layouts, no factor varied); one cell
per applicable factor = the same environments with that factor re-drawn from the held-out split
(``shift_configs``, as an evaluation does); the two language conditions; 3 and 6 objects per scene; the
medium object-position range. Every cell runs ``--episodes`` seeded episodes with the collection's
Gaussian action noise (std 0.002); physics only (visual factors leave it bit-identical, tested).

    .venv/bin/python scripts/pick_expert_table.py --episodes=40
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.experts import expert_policy, rollout
from lerobot_factorworld.factors.registry import supported_factors
from lerobot_factorworld.pick.sampling import CONDITIONS, language_shift
from lerobot_factorworld.protocol.sampling import SamplingOptions, sample_configs, shift_configs

TASK = "pick"
NOISE = 0.002


def run_cell(configs, episodes: int, object_pos_width: str | None = None) -> tuple[int, float]:
    env = FactorWorldEnv(TASK, configs, cameras=(), scene_cache_size=len(configs), object_pos_width=object_pos_width)
    policy = expert_policy(TASK)
    successes, steps = 0, []
    for seed in range(episodes):
        episode = rollout(env, policy, seed, NOISE)  # the collection's episode loop and action-noise stream
        successes += episode.success
        steps.append(len(episode))
    env.close()
    return successes, float(np.mean(steps))


def cells(n_envs: int, seed: int) -> dict[str, list]:
    base = sample_configs(TASK, n_envs, seed, factors=())
    out = {"default": base}
    for factor in supported_factors(TASK):
        out[factor] = shift_configs(base, factor, n_envs, seed + 1)
    for condition in CONDITIONS:
        out[condition] = language_shift(base, condition, n_envs, seed + 1)
    for k in (3, 6):
        out[f"{k} objects"] = sample_configs(TASK, n_envs, seed, factors=(), options=SamplingOptions(n_objects=k))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--n_envs", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    start = time.perf_counter()
    print("| cell | success | 95% interval | mean steps |\n|---|---|---|---|")
    rows = list(cells(args.n_envs, args.seed).items())
    rows.append(("object_pos (medium range)", sample_configs(TASK, args.n_envs, args.seed, factors=())))
    for name, configs in rows:
        width = "medium" if name.startswith("object_pos (medium") else None
        k, mean_steps = run_cell(configs, args.episodes, width)
        lo, hi = _wilson(k, args.episodes)
        print(f"| {name} | {k}/{args.episodes} ({k / args.episodes:.0%}) | [{lo:.0%}, {hi:.0%}] | {mean_steps:.0f} |")
    print(
        f"\n{len(rows)} cells x {args.episodes} episodes, {args.n_envs} environments per cell, "
        f"{time.perf_counter() - start:.0f} s"
    )


def _wilson(k: int, n: int) -> tuple[float, float]:
    from lerobot_factorworld.stats.proportions import wilson_interval

    return wilson_interval(k, n)


if __name__ == "__main__":
    main()
