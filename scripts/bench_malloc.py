"""glibc's default malloc against :func:`~lerobot_factorworld.core.memory.keep_freed_memory` (what a study's
``grouped`` workers set), side by side: CPU training updates of the paper's CNN (``bc``, its defaults, 84 px
front camera, 8-number state, batch ``--batch-size``, one thread as a study trains), each way in its own fresh
process, in alternating order over ``--rounds`` rounds. Prints ms per update (median over rounds) per way, the
ratio, and whether the weights after the last update are byte-identical both ways (they must be: the
setting moves memory, not arithmetic).

    .venv/bin/python scripts/bench_malloc.py             # about a minute on 2 cores
    .venv/bin/python scripts/bench_malloc.py --quick     # the smoke test's scale

The last line printed is exactly ``ratio: <float>`` = default ms per update / kept-memory ms per update
(what it measured: docs/study.md, Throughput).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import statistics
import subprocess
import sys
import time

from _bench import add_repo_to_path, optimizer_step, print_table, ratio_line, round_order

add_repo_to_path()

WAYS = ("default", "keep_freed")
GRAD_CLIP_NORM = 10.0


def child(way: str, steps: int, batch_size: int) -> dict:
    """Time ``steps`` updates after 3 untimed ones, in this fresh process, with malloc set as ``way`` says."""
    # Deliberately here: the parent only starts processes; each child's malloc must be set before torch allocates.
    from lerobot_factorworld.core.memory import keep_freed_memory  # noqa: PLC0415

    if way == "keep_freed" and not keep_freed_memory():
        raise SystemExit("error: this C library has no mallopt (not glibc): nothing to compare")
    import torch  # noqa: PLC0415
    from lerobot.configs import FeatureType, PolicyFeature  # noqa: PLC0415

    from lerobot_factorworld.policies.bc.configuration_bc import BCConfig  # noqa: PLC0415
    from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy  # noqa: PLC0415

    torch.set_num_threads(1)
    torch.manual_seed(0)
    camera, state = "observation.images.front", "observation.state"
    features = {camera: PolicyFeature(FeatureType.VISUAL, (3, 84, 84)), state: PolicyFeature(FeatureType.STATE, (8,))}
    config = BCConfig(
        device="cpu", input_features=features, output_features={"action": PolicyFeature(FeatureType.ACTION, (4,))}
    )
    policy = BCPolicy(config)
    optimizer = torch.optim.Adam(policy.parameters(), lr=3e-4)
    g = torch.Generator().manual_seed(0)
    batches = [
        {
            camera: torch.rand(batch_size, 3, 84, 84, generator=g),
            state: torch.randn(batch_size, 8, generator=g),
            "action": torch.rand(batch_size, 4, generator=g) * 2 - 1,
        }
        for _ in range(4)
    ]
    policy.train()
    for i in range(3):
        optimizer_step(policy, optimizer, batches[i % len(batches)], GRAD_CLIP_NORM)
    start = time.perf_counter()
    for i in range(steps):
        optimizer_step(policy, optimizer, batches[i % len(batches)], GRAD_CLIP_NORM)
    seconds = time.perf_counter() - start
    weights = hashlib.sha256(b"".join(t.detach().numpy().tobytes() for t in policy.state_dict().values()))
    return {"ms": 1000 * seconds / steps, "weights": weights.hexdigest()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=60, help="timed updates per process")
    parser.add_argument("--batch-size", type=int, default=16)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="5 updates, one round: the smoke test's scale")
    parser.add_argument("--child", choices=WAYS, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.steps < 1 or args.batch_size < 1 or args.rounds < 1:
        parser.error("--steps, --batch-size and --rounds must be >= 1")
    if args.child:
        print(json.dumps(child(args.child, args.steps, args.batch_size)))
        return
    if args.quick:
        args.steps, args.rounds = 5, 1
    runs: dict[str, list[dict]] = {way: [] for way in WAYS}
    for round_index in range(args.rounds):
        for way in round_order(WAYS, round_index):
            command = [sys.executable, __file__, f"--child={way}", f"--steps={args.steps}"]
            proc = subprocess.run([*command, f"--batch-size={args.batch_size}"], capture_output=True, text=True)
            if proc.returncode != 0:
                raise SystemExit(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else f"{way} failed")
            runs[way].append(json.loads(proc.stdout.strip().splitlines()[-1]))
    ms = {way: statistics.median(r["ms"] for r in runs[way]) for way in WAYS}
    print_table(
        "| malloc | ms per update (median of rounds) | rounds |",
        (f"| {way} | {ms[way]:.1f} | {', '.join(f'{r["ms"]:.1f}' for r in runs[way])} |" for way in WAYS),
    )
    identical = len({r["weights"] for way in WAYS for r in runs[way]}) == 1
    print(f"bc conv, batch {args.batch_size}, {args.steps} updates per process, one thread")
    print("identical weights" if identical else "DIFFERENT weights: the setting changed results")
    print(ratio_line(ms["default"] / ms["keep_freed"]))
    if not identical:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
