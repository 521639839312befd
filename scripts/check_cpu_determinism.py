"""Which layers of a study give bit-identical results on another CPU: a fingerprint to compare machines by.

A study step is deterministic on one machine (the same key gives byte-identical datasets, checkpoints and
``results.csv``: ``scripts/bench_study.py`` checks it). Across machines, three layers could differ: MuJoCo's
physics, Mesa's software rasteriser (llvmpipe compiles its shaders for the CPU it runs on) and torch's CPU
kernels (oneDNN picks AVX-512, AVX2 or SSE4.1 code by what the CPU offers, and they sum in different orders).
This script hashes each one in fresh processes under the instruction-set caps a machine can be limited to:
``ONEDNN_MAX_CPU_ISA`` for torch's oneDNN kernels, ``LP_NATIVE_VECTOR_WIDTH`` for llvmpipe's vectors.

- weights: the recipe's bc policy (paper CNN, random shift) after 5 Adam steps at batch 32 on seeded data,
  one thread, as a study trains;
- pixels and physics: 20 steps of pick-place at 84 px (front camera) under a fixed action, as a study
  evaluates.

Run it on two machines: equal hashes in the ``default`` row mean their steps are byte-identical; where the
weights differ, the machines train different checkpoints from the same data, and a rerun lands within the
committed intervals rather than on the committed numbers (``factorworld compare-reruns``).

    MUJOCO_GL=egl .venv/bin/python scripts/check_cpu_determinism.py           # about 40 s on 2 cores
    MUJOCO_GL=egl .venv/bin/python scripts/check_cpu_determinism.py --quick   # the machine and oneDNN SSE4.1 only
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys

import _bench

CAPS = (  # (label, environment): the machine as it is, then narrower instruction sets
    ("default", {}),
    ("oneDNN AVX2", {"ONEDNN_MAX_CPU_ISA": "AVX2"}),
    ("oneDNN SSE4.1", {"ONEDNN_MAX_CPU_ISA": "SSE41"}),
    ("llvmpipe 128-bit", {"LP_NATIVE_VECTOR_WIDTH": "128"}),
)


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def fingerprint() -> dict[str, str]:
    """The three hashes, in this process (run as a child under one cap)."""
    _bench.setup_headless_gl()
    _bench.add_repo_to_path()
    # Imported in the child only: the caps must be in the environment before torch and Mesa load.
    import numpy as np
    import torch
    from lerobot.configs import FeatureType, PolicyFeature

    from lerobot_factorworld.envs.factor_env import FactorWorldEnv
    from lerobot_factorworld.policies.bc.configuration_bc import BCConfig
    from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy
    from lerobot_factorworld.protocol.sampling import sample_configs

    torch.set_num_threads(1)
    torch.manual_seed(0)
    camera, state = "observation.images.front", "observation.state"
    features = {camera: PolicyFeature(FeatureType.VISUAL, (3, 84, 84)), state: PolicyFeature(FeatureType.STATE, (8,))}
    config = BCConfig(
        device="cpu",
        augmentation="shift",
        input_features=features,
        output_features={"action": PolicyFeature(FeatureType.ACTION, (4,))},
    )
    policy = BCPolicy(config)
    optimizer = torch.optim.Adam(policy.parameters(), lr=3e-4)
    g = torch.Generator().manual_seed(0)
    batch = {
        camera: torch.rand(32, 3, 84, 84, generator=g),
        state: torch.randn(32, 8, generator=g),
        "action": torch.rand(32, 4, generator=g) * 2 - 1,
    }
    policy.train()
    for _ in range(5):
        loss, _ = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    weights = digest(b"".join(t.detach().numpy().tobytes() for t in policy.state_dict().values()))

    env = FactorWorldEnv("pick-place", sample_configs("pick-place", n=5, seed=0), cameras=("front",), image_size=84)
    env.reset(seed=3)
    pixels, physics = hashlib.sha256(), hashlib.sha256()
    for _ in range(20):
        obs, *_ = env.step(np.full(4, 0.3, dtype=np.float32))
        pixels.update(obs["pixels"]["front"].tobytes())
        physics.update(obs["agent_pos"].tobytes())
    env.close()
    return {"weights": weights, "pixels": pixels.hexdigest()[:16], "physics": physics.hexdigest()[:16]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="two runs: the machine as it is and oneDNN at SSE4.1")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(fingerprint()))
        return
    _bench.add_repo_to_path()
    from lerobot_factorworld.core import machine  # noqa: PLC0415 - the checkout's package, once on the path

    print(f"CPU: {machine.describe(machine.current())}")
    rows = {}
    caps = [CAPS[0], CAPS[2]] if args.quick else CAPS
    for label, env in caps:
        proc = subprocess.run(
            [sys.executable, __file__, "--child"],
            capture_output=True,
            text=True,
            env={**os.environ, **env},
            timeout=600,
        )
        if proc.returncode != 0:
            sys.exit(f"error: the {label} run failed:\n{proc.stderr[-2000:]}")
        rows[label] = json.loads(proc.stdout.strip().splitlines()[-1])
    print()
    print("| instruction-set cap | weights after 5 steps | pixels, 20 steps | physics, 20 steps |")
    print("|---|---|---|---|")
    for label, found in rows.items():
        print(f"| {label} | {found['weights']} | {found['pixels']} | {found['physics']} |")
    print()
    default = rows["default"]
    for layer in ("weights", "pixels", "physics"):
        differ = [label for label in rows if rows[label][layer] != default[layer]]
        print(f"{layer}: " + (f"differ under {', '.join(differ)}" if differ else "the same under every cap"))


if __name__ == "__main__":
    main()
