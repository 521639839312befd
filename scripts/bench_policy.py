"""RT-1 policy cost per preset: parameters, training throughput, and ``select_action`` latency with and
without token reuse; then both policies' training throughput at ``speed=default`` and ``speed=fast``.

What is measured
    For each preset of ``RT1Config`` (``rt1``, ``lite0``, ``small``; see ``configuration_rt1.py``) one
    ``RT1Policy`` is built without a dataset: one camera ``observation.images.front`` of 3x84x84 (the
    Factor World default; each preset resizes it to its own ``image_size``), a 4-D action, a 384-D
    sentence embedding (MiniLM-L6). Inputs are random tensors already on the device (no data loading,
    no host-to-device copy), so only the model's own cost is timed.

    * ``params (M)``: every parameter of the policy, in millions.
    * ``train samples/s``: windows of ``n_obs_steps`` (6) frames per second through one full training
      step = ``policy.forward(batch)`` (in ``train()`` mode: crop and photometric augmentation, dropout)
      + ``loss.backward()`` + ``torch.optim.AdamW(policy.parameters(), lr=cfg.optimizer_lr).step()``
      + ``zero_grad(set_to_none=True)`` (``_bench.optimizer_step``). The batch size is per preset and device
      (below).
    * ``select_action ms``: wall time of one ``policy.select_action(batch)`` call, i.e. one control step
      with one new frame (batch of 1), median over the timed calls. With ``token_reuse`` ON only the new
      frame goes through the FiLM-EfficientNet + TokenLearner and the window's earlier tokens are reused;
      OFF re-tokenizes the whole 6-frame window every call. Both run on the same policy (the flag is
      flipped on ``policy.config``); each measurement starts with ``policy.reset()`` and ``--warmup``
      untimed calls (>= 6, so the window holds real history), then times ``--infer-steps`` calls, each on a
      different frame. ``speedup`` = latency OFF / latency ON.

    The machine is noisy, so each preset's measurements run in ``--rounds`` interleaved rounds: every
    round times one training segment and one ON and one OFF inference segment, the ON/OFF order
    alternating between rounds (ON OFF, OFF ON, ...). Training reports the median of the per-round rates;
    latency the median over all timed calls of that mode. On CUDA every timed region ends with
    ``torch.cuda.synchronize()``. ``torch.set_num_threads`` is left at PyTorch's default; on a machine shared
    with other work, ``OMP_NUM_THREADS=1`` gives steadier rounds (two threads wait on each other when one is
    descheduled).

    Batch sizes (training), CPU / CUDA: small 16 / 128, lite0 8 / 64, rt1 2 / 16 (``--batch-size`` overrides
    all). The ``rt1`` preset (FiLM-EfficientNet-B3 at 300 px, ~34M params) is slow on CPU, so it gets a
    small batch and few iterations; ``--skip-slow`` drops it.

Training speed setting (``speed``, ``policies/common/speed.py``)
    Two policies, each built twice with identical weights, at ``speed=default`` (float32, today's
    computation) and ``speed=fast`` (channels-last encoder input, bfloat16 autocast):

    * ``bc conv``: ``BCPolicy`` with the paper's CNN, one 3x84x84 camera and a 4-D state (the env's hand
      position and gripper), no augmentation; batch 32 on CPU (256 on CUDA), 8 (20) timed steps per round.
      Its rate is in samples/s.
    * ``rt1 <preset>``: ``RT1Policy`` at ``--speed-preset`` (default ``small``, the CPU preset), the inputs
      above; the preset's batch and steps (table above). Its rate is in windows/s (windows of 6 frames).

    One update is the training step above (forward in ``train()`` mode, backward, optimizer step:
    bc's ``Adam`` at its preset learning rate, rt1's ``AdamW``); one untimed update per setting first, then
    ``--rounds`` rounds, each timing both settings, their order alternating between rounds. Reported: the
    median of the per-round rates per setting, and ``fast / default`` of those medians (``--batch-size`` and
    ``--train-steps`` override these workloads too).

A frozen trunk on real frames (``--frames <LeRobotDataset root>``, e.g. a pick study's collect step)
    ``lite0_frozen`` (its trunk computed once per frame through the feature cache) against ``small`` (every frame
    through its trainable CNN), both at ``speed=default``, on the first ``--frames-limit`` frames of the dataset
    (whole episodes, PNG decoded once, held in memory: data loading is not timed). Each frame starts a window of
    ``n_obs_steps`` frames padded with the episode's first frame, as LeRobot pads; the windows are shuffled once
    (``--seed``) and cut into batches of ``--frames-batch``. Two epochs over them, batch by batch with the two
    policies alternating (which one goes first alternates too), so both see the same load: epoch 1 is the first
    epoch (the cache fills: every frame goes through the trunk once), epoch 2 is every epoch after it (every
    frame a cache hit). Reported: windows/s per policy and epoch, and ``lite0_frozen / small`` per epoch.

    python scripts/bench_policy.py [--presets small,lite0,rt1] [--skip-slow] [--device cpu|cuda]
                                   [--rounds 3] [--train-steps N] [--infer-steps N] [--batch-size N]
                                   [--speed-preset small] [--quick]
                                   [--frames <dataset root> [--frames-limit 1600] [--frames-batch 16]]

``--quick`` is a smoke run (small preset only, 1 round, a few iterations; the speed comparison at the small
preset and the quick batch too). The last line printed is exactly
``ratio: <float>`` = the token-reuse speedup (latency OFF / latency ON) of the ``small`` preset, or of the
first preset measured when ``small`` is not selected; with ``--frames-only``, ``lite0_frozen / small`` windows/s
after the first epoch.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys
from dataclasses import dataclass, field
from pathlib import Path

import _bench
import numpy as np
import pyarrow.parquet as pq
import torch
from PIL import Image
from tqdm import tqdm

_bench.add_repo_to_path()

from lerobot.configs import FeatureType, PolicyFeature  # noqa: E402

from lerobot_factorworld.policies.bc.configuration_bc import BCConfig  # noqa: E402
from lerobot_factorworld.policies.bc.modeling_bc import BCPolicy  # noqa: E402
from lerobot_factorworld.policies.common.language import LANGUAGE_EMBEDDING_KEY  # noqa: E402
from lerobot_factorworld.policies.common.speed import SPEEDS  # noqa: E402
from lerobot_factorworld.policies.rt1.configuration_rt1 import PRESETS, RT1Config  # noqa: E402
from lerobot_factorworld.policies.rt1.modeling_rt1 import RT1Policy  # noqa: E402

IMAGE_KEY = "observation.images.front"
IMAGE_SHAPE = (3, 84, 84)
STATE_KEY = "observation.state"
STATE_DIM = 4  # the env's observation.state: hand x, y, z and gripper opening
ACTION_DIM = 4
LANGUAGE_DIM = 384
FRAME_POOL = 16  # distinct inference frames cycled through (so no call sees the same input twice in a row)
SLOW_PRESETS = ("rt1",)
SPEED_POLICIES = ("bc", "rt1")  # the speed=default / speed=fast comparison, in this order
DEFAULT_ORDER = ("small", "lite0", "rt1")


@dataclass(frozen=True)
class Plan:
    """Per-preset workload: training batch size and timed iterations per round, per device type."""

    batch: dict[str, int]
    train_steps: dict[str, int]  # timed training steps per round
    infer_steps: dict[str, int]  # timed select_action calls per round and mode


PLANS: dict[str, Plan] = {
    "small": Plan({"cpu": 16, "cuda": 128}, {"cpu": 8, "cuda": 20}, {"cpu": 40, "cuda": 100}),
    "lite0": Plan({"cpu": 8, "cuda": 64}, {"cpu": 4, "cuda": 20}, {"cpu": 20, "cuda": 100}),
    "rt1": Plan({"cpu": 2, "cuda": 16}, {"cpu": 2, "cuda": 10}, {"cpu": 6, "cuda": 60}),
}
QUICK = dict(rounds=1, batch=4, train_steps=2, infer_steps=8, warmup=6)
BC_SPEED_PLAN = Plan({"cpu": 32, "cuda": 256}, {"cpu": 8, "cuda": 20}, {})  # bc conv's update (no inference here)


@dataclass
class Result:
    preset: str
    params_m: float
    image_size: int
    batch: int
    train_rates: list[float] = field(default_factory=list)  # samples/s per round
    latency_ms: dict[bool, list[float]] = field(default_factory=lambda: {True: [], False: []})  # per call

    @property
    def train_rate(self) -> float:
        return statistics.median(self.train_rates)

    def latency(self, reuse: bool) -> float:
        return statistics.median(self.latency_ms[reuse])

    @property
    def speedup(self) -> float:
        return self.latency(False) / self.latency(True)


@dataclass
class SpeedResult:
    """Training throughput of one policy at each ``speed`` value, per round."""

    label: str  # "bc conv", "rt1 small"
    unit: str  # "samples/s" (bc) or "windows/s" (rt1)
    batch: int
    steps: int  # timed updates per round and setting
    rates: dict[str, list[float]] = field(default_factory=lambda: {speed: [] for speed in SPEEDS})

    def rate(self, speed: str) -> float:
        return statistics.median(self.rates[speed])

    @property
    def ratio(self) -> float:
        return self.rate("fast") / self.rate("default")


def build_policy(preset: str, device: str, speed: str = "default") -> RT1Policy:
    cfg = RT1Config(
        preset=preset,
        device=device,
        input_features={IMAGE_KEY: PolicyFeature(FeatureType.VISUAL, IMAGE_SHAPE)},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))},
        speed=speed,
    )
    return RT1Policy(cfg).to(device)


def build_bc(device: str, speed: str) -> BCPolicy:
    cfg = BCConfig(
        device=device,
        input_features={
            IMAGE_KEY: PolicyFeature(FeatureType.VISUAL, IMAGE_SHAPE),
            STATE_KEY: PolicyFeature(FeatureType.STATE, (STATE_DIM,)),
        },
        output_features={"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))},
        speed=speed,
    )
    return BCPolicy(cfg).to(device)


def bc_batch(batch_size: int, device: str) -> dict[str, torch.Tensor]:
    return {
        IMAGE_KEY: torch.rand(batch_size, *IMAGE_SHAPE, device=device),
        STATE_KEY: torch.randn(batch_size, STATE_DIM, device=device),
        "action": torch.rand(batch_size, ACTION_DIM, device=device) * 2 - 1,
    }


def train_batch(policy: RT1Policy, batch_size: int, device: str) -> dict[str, torch.Tensor]:
    t = policy.config.n_obs_steps
    return {
        IMAGE_KEY: torch.rand(batch_size, t, *IMAGE_SHAPE, device=device),
        LANGUAGE_EMBEDDING_KEY: torch.randn(batch_size, LANGUAGE_DIM, device=device),
        "action": torch.rand(batch_size, t, ACTION_DIM, device=device) * 2 - 1,
        "action_is_pad": torch.zeros(batch_size, t, dtype=torch.bool, device=device),
    }


def time_training(policy, optimizer, batch, steps: int, clock: _bench.Clock, bar: tqdm) -> float:
    """Seconds for ``steps`` training steps (summed per step, so the progress bar is not timed)."""
    policy.train()  # select_action switches the policy to eval()
    total = 0.0
    for _ in range(steps):
        start = clock()
        _bench.optimizer_step(policy, optimizer, batch)
        total += clock() - start
        bar.update(1)
    return total


def workload(preset: str, args: argparse.Namespace, kind: str) -> tuple[int, int, int]:
    """(batch size, timed training steps per round, timed select_action calls per round and mode)."""
    if args.quick:
        return QUICK["batch"], QUICK["train_steps"], QUICK["infer_steps"]
    plan = PLANS[preset]
    return (
        args.batch_size or plan.batch[kind],
        args.train_steps or plan.train_steps[kind],
        args.infer_steps or plan.infer_steps[kind],
    )


def speed_workload(policy: str, args: argparse.Namespace, kind: str) -> tuple[int, int]:
    """(batch size, timed updates per round and setting) of the speed comparison: ``bc`` or ``rt1``."""
    if args.quick:
        return QUICK["batch"], QUICK["train_steps"]
    plan = BC_SPEED_PLAN if policy == "bc" else PLANS[args.speed_preset]
    return args.batch_size or plan.batch[kind], args.train_steps or plan.train_steps[kind]


def bench_speed(policy_name: str, args: argparse.Namespace, bar: tqdm) -> SpeedResult:
    """Updates per second of ``bc`` (conv) or ``rt1`` (``--speed-preset``) at each ``speed``, rounds interleaved."""
    device, clock = args.device, _bench.Clock(args.device)
    batch_size, steps = speed_workload(policy_name, args, _bench.device_kind(device))
    bc = policy_name == "bc"
    label = "bc conv" if bc else f"rt1 {args.speed_preset}"
    result = SpeedResult(label, "samples/s" if bc else "windows/s", batch_size, steps)
    policies, optimizers = {}, {}
    for speed in SPEEDS:
        bar.set_postfix_str(f"{label} speed={speed}: building")
        torch.manual_seed(args.seed)  # the same weights under every setting
        policy = build_bc(device, speed) if bc else build_policy(args.speed_preset, device, speed)
        optimizer_class = torch.optim.Adam if bc else torch.optim.AdamW  # each policy's optimizer preset
        policies[speed] = policy
        optimizers[speed] = optimizer_class(policy.get_optim_params(), lr=policy.config.optimizer_lr)
    torch.manual_seed(args.seed)
    batch = bc_batch(batch_size, device) if bc else train_batch(policies["default"], batch_size, device)
    for speed in SPEEDS:  # warm-up (untimed): memory, kernels, the optimizer's state
        bar.set_postfix_str(f"{label} speed={speed}: warm-up")
        time_training(policies[speed], optimizers[speed], batch, 1, clock, bar)
    for r in range(args.rounds):
        for speed in _bench.round_order(SPEEDS, r):
            bar.set_postfix_str(f"{label} round {r + 1}/{args.rounds} speed={speed}")
            seconds = time_training(policies[speed], optimizers[speed], batch, steps, clock, bar)
            result.rates[speed].append(batch_size * steps / seconds)
    del policies, optimizers, batch
    _bench.release_device_memory(device)
    return result


def bench_preset(preset: str, args: argparse.Namespace, bar: tqdm) -> Result:
    device, clock = args.device, _bench.Clock(args.device)
    batch_size, train_steps, infer_steps = workload(preset, args, _bench.device_kind(device))
    torch.manual_seed(args.seed)
    bar.set_postfix_str(f"{preset}: building")
    policy = build_policy(preset, device)
    cfg = policy.config
    result = Result(preset, sum(p.numel() for p in policy.parameters()) / 1e6, cfg.image_size, batch_size)

    optimizer = torch.optim.AdamW(policy.parameters(), lr=cfg.optimizer_lr)
    batch = train_batch(policy, batch_size, device)
    language = torch.randn(1, LANGUAGE_DIM, device=device)
    frames = [
        {IMAGE_KEY: torch.rand(1, *IMAGE_SHAPE, device=device), LANGUAGE_EMBEDDING_KEY: language}
        for _ in range(FRAME_POOL)
    ]

    # Warm-up (untimed): first passes allocate memory / pick kernels; the optimizer creates its state.
    bar.set_postfix_str(f"{preset}: warm-up")
    time_training(policy, optimizer, batch, 1, clock, bar)
    for r in range(args.rounds):
        tag = f"{preset} round {r + 1}/{args.rounds}"
        bar.set_postfix_str(f"{tag} train")
        seconds = time_training(policy, optimizer, batch, train_steps, clock, bar)
        result.train_rates.append(batch_size * train_steps / seconds)
        for reuse in _bench.round_order((True, False), r):
            bar.set_postfix_str(f"{tag} reuse {'ON' if reuse else 'OFF'}")
            policy.config.token_reuse = reuse
            result.latency_ms[reuse] += _bench.select_action_latencies(
                policy, frames, args.warmup, infer_steps, clock, lambda: bar.update(1)
            )
    policy.config.token_reuse = True
    del policy, optimizer, batch
    _bench.release_device_memory(device)
    return result


# --- a frozen trunk against small on real frames (--frames) ----------------------------------------

FROZEN_PAIR = ("small", "lite0_frozen")  # the baseline first: the ratio is lite0_frozen / small


@dataclass
class FrameBench:
    """Windows/s of each policy in FROZEN_PAIR at epoch 1 (the cache fills) and epoch 2 (every frame cached)."""

    frames: int
    windows: int
    batch: int
    seconds: dict[tuple[str, int], float] = field(default_factory=dict)  # (preset, epoch) -> timed seconds
    misses: dict[int, int] = field(default_factory=dict)  # epoch -> frames the frozen trunk computed

    def rate(self, preset: str, epoch: int) -> float:
        return self.windows / self.seconds[(preset, epoch)]

    def ratio(self, epoch: int) -> float:
        return self.rate(FROZEN_PAIR[1], epoch) / self.rate(FROZEN_PAIR[0], epoch)


def read_frames(root: Path, limit: int) -> tuple[torch.Tensor, np.ndarray]:
    """The first whole episodes of a LeRobotDataset at ``root`` up to ``limit`` frames: frames (F, 3, H, W) in
    [0, 1] and each frame's episode index (F,)."""
    files = sorted((root / "data").rglob("*.parquet"))
    if not files:
        raise SystemExit(f"--frames {root}: no data/**/*.parquet (a LeRobotDataset root with image frames)")
    images, episodes = [], []
    for file in files:
        table = pq.read_table(file, columns=[IMAGE_KEY, "episode_index"]).to_pydict()
        for image, episode in zip(table[IMAGE_KEY], table["episode_index"], strict=True):
            if len(images) >= limit and episode != episodes[-1]:
                break
            images.append(np.asarray(Image.open(io.BytesIO(image["bytes"])).convert("RGB")))
            episodes.append(episode)
    frames = torch.from_numpy(np.stack(images)).permute(0, 3, 1, 2).float().div(255.0)
    return frames.contiguous(), np.asarray(episodes)


def frame_windows(episodes: np.ndarray, steps: int) -> torch.Tensor:
    """(F, steps) frame indices: each frame's window of ``steps`` frames, padded with its episode's first frame."""
    starts = {}
    for i, episode in enumerate(episodes):
        starts.setdefault(episode, i)
    first = np.array([starts[e] for e in episodes])
    offsets = np.arange(1 - steps, 1)
    return torch.from_numpy(np.maximum(np.arange(len(episodes))[:, None] + offsets, first[:, None]))


def bench_frames(args: argparse.Namespace, bar: tqdm) -> FrameBench:
    frames, episodes = read_frames(Path(args.frames), args.frames_limit)
    features = {IMAGE_KEY: PolicyFeature(FeatureType.VISUAL, tuple(frames.shape[1:]))}
    policies, optimizers = {}, {}
    for preset in FROZEN_PAIR:
        torch.manual_seed(args.seed)
        cfg = RT1Config(
            preset=preset,
            device=args.device,
            input_features=features,
            output_features={"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))},
        )
        policies[preset] = RT1Policy(cfg).to(args.device).train()
        optimizers[preset] = torch.optim.AdamW(policies[preset].get_optim_params(), lr=cfg.optimizer_lr)
    steps = policies[FROZEN_PAIR[0]].config.n_obs_steps
    windows = frame_windows(episodes, steps)
    generator = torch.Generator().manual_seed(args.seed)
    order = torch.randperm(len(windows), generator=generator)
    language = torch.randn(int(episodes.max()) + 1, LANGUAGE_DIM, generator=generator)  # one instruction each
    actions = torch.rand(len(windows), steps, ACTION_DIM, generator=generator) * 2 - 1
    batches = [order[i : i + args.frames_batch] for i in range(0, len(order), args.frames_batch)]
    result = FrameBench(len(frames), len(windows), args.frames_batch)
    cache = policies[FROZEN_PAIR[1]].model.encoder.cache
    clock = _bench.Clock(args.device)
    for epoch in (1, 2):
        misses_before = cache.misses
        for preset in FROZEN_PAIR:
            result.seconds[(preset, epoch)] = 0.0
        for b, rows in enumerate(batches):
            batch = {
                IMAGE_KEY: frames[windows[rows]].to(args.device),
                LANGUAGE_EMBEDDING_KEY: language[torch.from_numpy(episodes[rows.numpy()])].to(args.device),
                "action": actions[rows].to(args.device),
                "action_is_pad": torch.zeros(len(rows), steps, dtype=torch.bool, device=args.device),
            }
            for preset in _bench.round_order(FROZEN_PAIR, b):
                bar.set_postfix_str(f"frames: epoch {epoch} {preset}")
                start = clock()
                _bench.optimizer_step(policies[preset], optimizers[preset], batch)
                result.seconds[(preset, epoch)] += clock() - start
                bar.update(1)
        result.misses[epoch] = cache.misses - misses_before
    return result


def print_frame_bench(res: FrameBench, args: argparse.Namespace) -> None:
    print()
    print(
        f"Frozen trunk on real frames: {res.frames} frames of {args.frames} ({res.windows} windows, batch {res.batch}), "
        "speed=default, the two policies alternating batch by batch"
    )
    header = f"| {'epoch':<12} | {'small windows/s':>15} | {'lite0_frozen windows/s':>22} | {'trunk runs':>10} | {'ratio':>7} |"
    _bench.print_table(
        header,
        (
            f"| {label:<12} | {res.rate('small', epoch):>15.1f} | {res.rate('lite0_frozen', epoch):>22.1f} "
            f"| {res.misses[epoch]:>10} | {res.ratio(epoch):>6.2f}x |"
            for epoch, label in ((1, "1 (fills)"), (2, "2 and after"))
        ),
    )
    print("trunk runs: frames lite0_frozen's trunk computed in that epoch (the rest came from its cache)")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", default=",".join(DEFAULT_ORDER), help="comma-separated presets, in order")
    parser.add_argument("--skip-slow", action="store_true", help=f"drop the slow preset(s): {', '.join(SLOW_PRESETS)}")
    parser.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu", help="cpu or cuda")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds per preset")
    parser.add_argument("--train-steps", type=int, default=0, help="timed training steps per round (0: per preset)")
    parser.add_argument("--infer-steps", type=int, default=0, help="timed select_action calls per round and mode")
    parser.add_argument(
        "--batch-size", type=int, default=0, help="training batch size for every preset (0: per preset)"
    )
    parser.add_argument("--warmup", type=int, default=8, help="untimed select_action calls after each reset (>= 6)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--speed-preset",
        default="small",
        choices=list(PRESETS),
        help="rt1 preset of the speed=default / speed=fast comparison",
    )
    parser.add_argument("--quick", action="store_true", help="smoke run: small preset, 1 round, few iterations")
    parser.add_argument("--frames", default="", help="LeRobotDataset root: lite0_frozen against small on its frames")
    parser.add_argument("--frames-limit", type=int, default=1600, help="--frames: frames read (whole episodes)")
    parser.add_argument("--frames-batch", type=int, default=16, help="--frames: training batch (windows)")
    parser.add_argument("--frames-only", action="store_true", help="--frames: measure only that comparison")
    args = parser.parse_args(argv)
    if args.frames and not (Path(args.frames) / "data").is_dir():
        parser.error(f"--frames {args.frames}: not a LeRobotDataset root (no data/ folder)")
    if args.frames_only and not args.frames:
        parser.error("--frames-only needs --frames")

    presets = _bench.parse_names(parser, args.presets, list(PRESETS), "preset(s)")
    if args.quick:
        presets = ["small"]
        args.speed_preset = "small"
        args.rounds, args.warmup = QUICK["rounds"], QUICK["warmup"]
    if args.skip_slow:
        presets = [p for p in presets if p not in SLOW_PRESETS]
    if not presets:
        parser.error("no preset left to measure")
    args.preset_list = presets
    if min(args.rounds, args.warmup) < 1 or min(args.train_steps, args.infer_steps, args.batch_size) < 0:
        parser.error("--rounds and --warmup must be >= 1; step counts and batch size >= 0")
    if args.device.startswith("cuda") and not torch.cuda.is_available():
        parser.error("--device cuda requested but CUDA is not available")
    return args


def main_frames(args: argparse.Namespace) -> int:
    """``--frames-only``: the frozen trunk against small on real frames; the last line is epoch 2's ratio."""
    load_start = os.getloadavg()
    with tqdm(desc="frames", unit="step", file=sys.stderr) as bar:
        result = bench_frames(args, bar)
    print_frame_bench(result, args)
    print(_bench.load_average_line(load_start, os.getloadavg()))
    print(f"lite0_frozen / small after the first epoch: {result.ratio(2):.2f}x (windows/s)")
    print(_bench.ratio_line(result.ratio(2)))
    return 0


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    kind = _bench.device_kind(args.device)
    device_name = torch.cuda.get_device_name(args.device) if kind == "cuda" else "cpu"
    machine = f"{args.device} ({device_name}, torch {torch.__version__}, {torch.get_num_threads()} threads)"
    if args.frames_only:
        print(f"RT-1 {' against '.join(FROZEN_PAIR)} on real frames on {machine}", flush=True)
        return main_frames(args)
    print(f"RT-1 presets {', '.join(args.preset_list)} on {machine}, {args.rounds} round(s)", flush=True)

    total = 0
    for preset in args.preset_list:
        _, train_steps, infer_steps = workload(preset, args, kind)
        total += 1 + args.rounds * (train_steps + 2 * (args.warmup + infer_steps))
    for policy in SPEED_POLICIES:
        total += len(SPEEDS) * (1 + args.rounds * speed_workload(policy, args, kind)[1])
    load_start = os.getloadavg()
    results: list[Result] = []
    with tqdm(total=total, desc="policy steps", unit="step", file=sys.stderr) as bar:
        for preset in args.preset_list:
            results.append(bench_preset(preset, args, bar))
        speeds = [bench_speed(policy, args, bar) for policy in SPEED_POLICIES]

    print()
    header = (
        f"| {'preset':<7} | {'params (M)':>10} | {'img px':>6} | {'batch':>5} | {'train samples/s':>15} "
        f"| {'ms/train step':>13} | {'select_action ON ms':>19} | {'OFF ms':>8} | {'speedup OFF/ON':>14} |"
    )
    _bench.print_table(
        header,
        (
            f"| {res.preset:<7} | {res.params_m:>10.2f} | {res.image_size:>6} | {res.batch:>5} "
            f"| {res.train_rate:>15.1f} | {1000.0 * res.batch / res.train_rate:>13.1f} "
            f"| {res.latency(True):>19.2f} | {res.latency(False):>8.2f} | {res.speedup:>13.2f}x |"
            for res in results
        ),
    )
    print()
    for res in results:
        _, train_steps, infer_steps = workload(res.preset, args, kind)
        rates = ", ".join(f"{rate:.1f}" for rate in res.train_rates)
        print(
            f"{res.preset}: train samples/s per round [{rates}] ({train_steps} steps each); "
            f"select_action {len(res.latency_ms[True])} timed calls per mode ({infer_steps} per round, "
            f"{args.warmup} warm-up after each reset)"
        )
    print()
    print("Training speed setting: updates at speed=default (float32) and speed=fast (channels-last, bf16 autocast)")
    header = f"| {'policy':<9} | {'batch':>5} | {'unit':<9} | {'default':>9} | {'fast':>9} | {'fast / default':>14} |"
    _bench.print_table(
        header,
        (
            f"| {res.label:<9} | {res.batch:>5} | {res.unit:<9} | {res.rate('default'):>9.2f} "
            f"| {res.rate('fast'):>9.2f} | {res.ratio:>13.2f}x |"
            for res in speeds
        ),
    )
    print()
    for res in speeds:
        rates = "; ".join(f"{speed} [{', '.join(f'{r:.2f}' for r in res.rates[speed])}]" for speed in SPEEDS)
        print(f"{res.label}: {res.unit} per round, {rates} ({res.steps} steps each)")
    if args.frames:
        with tqdm(total=4 * -(-args.frames_limit // args.frames_batch), desc="frames", file=sys.stderr) as bar:
            print_frame_bench(bench_frames(args, bar), args)
    print(_bench.load_average_line(load_start, os.getloadavg()))
    headline = next((res for res in results if res.preset == "small"), results[0])
    print(f"token-reuse speedup of {headline.preset}: {headline.speedup:.2f}x (select_action latency OFF / ON)")
    print(_bench.ratio_line(headline.speedup))
    return 0


if __name__ == "__main__":
    sys.exit(main())
