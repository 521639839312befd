"""Training throughput through LeRobot's dataloader and select_action latency of bc, per encoder, next to ACT.

What is measured
    Datasets: ``factorworld collect --task=<task> --n_envs=2 --demos=<D> --seed=0`` twice, identical except
    for the storage: video (LeRobot's default, AV1 mp4, decoded by torchcodec) and image (``--use_videos=false``,
    PNG). Collected before any timing, in this process (``--data DIR`` keeps and reuses them).

    One training step is what ``lerobot-train`` does (``lerobot/scripts/lerobot_train.py``), on the same
    objects: ``LeRobotDataset(repo_id, root, delta_timestamps)`` from the policy's delta indices, a
    ``torch.utils.data.DataLoader`` with LeRobot's ``EpisodeAwareSampler`` (shuffled), ``--batch-size`` and
    ``--num-workers`` (with workers: prefetch 4, persistent, spawn, as lerobot-train), the policy built by
    ``make_policy`` from the dataset metadata, its preprocessor from ``make_pre_post_processors`` with the
    dataset statistics, its optimizer preset. Per step, *data* = ``next(dataloader)`` + uint8 -> float + the
    preprocessor (lerobot-train's ``dataloading_s``); *update* = forward, backward, ``clip_grad_norm_`` at the
    preset's norm, ``optimizer.step()``, ``zero_grad()`` (its ``update_s``). samples/s = batch x steps /
    (data + update); "data %" = data / (data + update). On CUDA each step ends with a synchronize.

    Policies: ``bc`` with each encoder (``conv``, ``lite0``, ``clip_rn50``, ``r3m_rn50``); the frozen ResNets
    read weight files written here with random values in their published layouts (speed does not depend on
    the values), and run with ``feature_cache_size=0`` so every step really runs the backbone (with the
    cache, after the first epoch a frozen encoder costs about what the head costs). ``act``: LeRobot's ACT at
    its defaults (``ACTConfig()``; only ``pretrained_backbone_weights=None``, since its ImageNet ResNet-18
    would be downloaded: same architecture, same cost).

    select_action latency: the policy in eval mode, one frame at a time (frames of the image dataset after
    the preprocessor), median and mean over ``--infer-calls`` calls after ``reset()`` and 3 warm-up calls.
    ACT computes a 100-step chunk and then pops its queue, so its median is a queue pop; its mean is the
    amortised cost.

    Each (policy, storage) pair is timed in ``--rounds`` rounds (order alternating between rounds, 2 untimed
    warm-up steps per block, fresh dataloader per block); the per-round samples/s are summarised by their
    median. Devices: ``cpu``, plus ``cuda`` when available (``--devices``).

    python scripts/bench_bc.py [--task door-open] [--demos 10] [--policies conv,lite0,clip_rn50,r3m_rn50,act]
                               [--devices cpu,cuda] [--batch-size 8] [--num-workers 0] [--rounds 3]
                               [--train-steps N] [--infer-calls N] [--data DIR] [--quick]

The last line printed is exactly ``ratio: <float>`` = training samples/s of bc ``conv`` / ACT's, image storage,
on the first device (target: >= 5).
"""

from __future__ import annotations

import _bench

_bench.setup_headless_gl()  # before anything imports mujoco: the collector renders in this process
_bench.add_repo_to_path()

import argparse  # noqa: E402
import os  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

import torch  # noqa: E402
from lerobot.datasets import EpisodeAwareSampler  # noqa: E402
from lerobot.datasets.factory import resolve_delta_timestamps  # noqa: E402
from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: E402
from lerobot.policies.act.configuration_act import ACTConfig  # noqa: E402
from lerobot.policies.factory import make_policy, make_pre_post_processors  # noqa: E402
from tqdm import tqdm  # noqa: E402

import lerobot_factorworld.lerobot_plugin  # noqa: E402, F401  (registers bc)
from lerobot_factorworld.datasets.collect import CollectConfig, collect  # noqa: E402
from lerobot_factorworld.policies.bc.backbones import (  # noqa: E402
    CLIP_VISUAL_PREFIX,
    R3M_KEY,
    R3M_PREFIX,
    clip_rn50_image_tower,
    r3m_resnet50,
)
from lerobot_factorworld.policies.bc.configuration_bc import BCConfig  # noqa: E402

TARGET_RATIO = 5.0
BC_ENCODERS = ("conv", "lite0", "clip_rn50", "r3m_rn50")
ACT = "act"
POLICIES = (*BC_ENCODERS, ACT)
STORAGES = ("video", "image")
DEVICES = ("cpu", "cuda")
RATIO_STORAGE = "image"
WARMUP_STEPS = 2
WARMUP_CALLS = 3
FRAME_POOL = 16
N_ENVS = 2


@dataclass(frozen=True)
class Plan:
    """Timed training steps per block and select_action calls per round, per device type."""

    train_steps: dict[str, int]
    infer_calls: dict[str, int]


PLANS: dict[str, Plan] = {
    "conv": Plan({"cpu": 30, "cuda": 100}, {"cpu": 50, "cuda": 200}),
    "lite0": Plan({"cpu": 6, "cuda": 50}, {"cpu": 20, "cuda": 100}),
    "clip_rn50": Plan({"cpu": 3, "cuda": 50}, {"cpu": 6, "cuda": 100}),
    "r3m_rn50": Plan({"cpu": 3, "cuda": 50}, {"cpu": 6, "cuda": 100}),
    ACT: Plan({"cpu": 3, "cuda": 50}, {"cpu": 100, "cuda": 200}),
}
QUICK = dict(demos=2, rounds=1, batch_size=2, train_steps=1, infer_calls=5, policies=("conv", ACT))


@dataclass
class Result:
    device: str
    policy: str
    storage: str
    batch: int
    params_m: float
    trainable_m: float
    rates: list[float] = field(default_factory=list)  # samples/s per round
    data_s: float = 0.0
    update_s: float = 0.0
    latency_ms: list[float] = field(default_factory=list)

    @property
    def rate(self) -> float:
        return statistics.median(self.rates)

    @property
    def data_share(self) -> float:
        return self.data_s / (self.data_s + self.update_s)


# --- datasets --------------------------------------------------------------------------------------


def collect_datasets(args: argparse.Namespace, data_dir: Path) -> dict[str, Path]:
    """The two datasets (same demos, video vs image storage), collected as ``factorworld collect`` does, in
    this process and one worker (``workers`` never changes what is collected): no process to start and import."""
    roots = {}
    for storage in STORAGES:
        root = data_dir / storage
        collect(
            CollectConfig(
                task=args.task,
                n_envs=N_ENVS,
                demos=args.demos,
                seed=0,
                use_videos=storage == "video",
                root=str(root),
                repo_id=f"local/bench_bc_{storage}",
                workers=1,
            )
        )
        roots[storage] = root
    return roots


# --- policies --------------------------------------------------------------------------------------


def write_weight_files(out: Path) -> dict[str, Path]:
    """Randomly initialised weights in each frozen ResNet's published layout (speed does not depend on values)."""
    paths = {"clip_rn50": out / "open_clip_pytorch_model.bin", "r3m_rn50": out / "model.pt"}
    clip = {CLIP_VISUAL_PREFIX + k: v for k, v in clip_rn50_image_tower().state_dict().items()}
    torch.save(clip, paths["clip_rn50"])
    torch.save({R3M_KEY: {R3M_PREFIX + k: v for k, v in r3m_resnet50().state_dict().items()}}, paths["r3m_rn50"])
    return paths


def policy_config(name: str, device: str, weights: dict[str, Path]):
    if name == ACT:
        return ACTConfig(device=device, pretrained_backbone_weights=None, push_to_hub=False)
    path = weights.get(name)
    return BCConfig(
        device=device,
        encoder=name,
        encoder_weights_path=str(path) if path else None,
        feature_cache_size=0,
        push_to_hub=False,
    )


@dataclass
class Trainee:
    """A policy with what lerobot-train builds around it (processors per storage, optimizer, clip norm)."""

    name: str
    policy: torch.nn.Module
    preprocessors: dict[str, object]
    optimizer: torch.optim.Optimizer
    grad_clip_norm: float
    camera_keys: list[str]


def build_trainee(name: str, device: str, metas: dict, weights: dict[str, Path]) -> Trainee:
    cfg = policy_config(name, device, weights)
    policy = make_policy(cfg, ds_meta=metas[RATIO_STORAGE])
    preprocessors = {
        storage: make_pre_post_processors(cfg, dataset_stats=meta.stats)[0] for storage, meta in metas.items()
    }
    preset = cfg.get_optimizer_preset()
    optimizer = preset.build(policy.get_optim_params())
    return Trainee(name, policy, preprocessors, optimizer, preset.grad_clip_norm, metas[RATIO_STORAGE].camera_keys)


# --- timing ----------------------------------------------------------------------------------------


def make_loader(dataset, batch_size: int, workers: int, device: str, seed: int):
    """The DataLoader lerobot-train builds (EpisodeAwareSampler, worker options) for a map-style dataset."""
    sampler = EpisodeAwareSampler(
        dataset.meta.episodes["dataset_from_index"],
        dataset.meta.episodes["dataset_to_index"],
        episode_indices_to_use=dataset.episodes,
        shuffle=True,
        seed=seed,
        absolute_to_relative_idx=dataset.absolute_to_relative_idx,
    )
    extra = {"prefetch_factor": 4, "persistent_workers": True, "multiprocessing_context": "spawn"} if workers else {}
    return torch.utils.data.DataLoader(
        dataset,
        batch_size=batch_size,
        sampler=sampler,
        num_workers=workers,
        pin_memory=device.startswith("cuda"),
        drop_last=False,
        **extra,
    )


def forever(loader):
    while True:
        yield from loader


def time_training(trainee: Trainee, storage: str, dataset, args, device: str, steps: int, bar) -> tuple[float, float]:
    """(data seconds, update seconds) summed over ``steps`` timed steps after ``WARMUP_STEPS`` untimed ones."""
    policy, pre, clock = trainee.policy, trainee.preprocessors[storage], _bench.Clock(device)
    batches = forever(make_loader(dataset, args.batch_size, args.num_workers, device, args.seed))
    policy.train()  # select_action switched it to eval()
    data_s = update_s = 0.0
    for i in range(WARMUP_STEPS + steps):
        t0 = clock()
        batch = next(batches)
        for key in trainee.camera_keys:
            if key in batch and batch[key].dtype == torch.uint8:
                batch[key] = batch[key].to(dtype=torch.float32) / 255.0
        batch = pre(batch)
        t1 = clock()
        _bench.optimizer_step(policy, trainee.optimizer, batch, trainee.grad_clip_norm)
        t2 = clock()
        if i >= WARMUP_STEPS:
            data_s += t1 - t0
            update_s += t2 - t1
        bar.update(1)
    return data_s, update_s


def inference_frames(dataset, pre, device: str) -> list[dict]:
    """Single frames (batch of 1) of the dataset, through the preprocessor: what lerobot-eval feeds."""
    frames = []
    for i in range(0, len(dataset), max(1, len(dataset) // FRAME_POOL))[:FRAME_POOL]:
        item = dataset[i]
        obs = {k: v.unsqueeze(0) for k, v in item.items() if k.startswith("observation.") and torch.is_tensor(v)}
        obs["task"] = [item["task"]]
        frames.append(pre(obs))
    return frames


def workload(name: str, args: argparse.Namespace, device: str) -> tuple[int, int]:
    """(timed training steps per block, timed select_action calls per round)."""
    if args.quick:
        return QUICK["train_steps"], QUICK["infer_calls"]
    plan, kind = PLANS[name], _bench.device_kind(device)
    return args.train_steps or plan.train_steps[kind], args.infer_calls or plan.infer_calls[kind]


def bench_device(device: str, args: argparse.Namespace, datasets: dict, weights: dict[str, Path]) -> list[Result]:
    metas = {storage: ds.meta for storage, ds in datasets.items()}
    results: dict[tuple[str, str], Result] = {}
    total = sum(
        args.rounds
        * (len(STORAGES) * (WARMUP_STEPS + workload(p, args, device)[0]) + WARMUP_CALLS + workload(p, args, device)[1])
        for p in args.policy_list
    )
    with tqdm(total=total, desc=f"bench {device}", unit="step", file=sys.stderr) as bar:
        for name in args.policy_list:
            bar.set_postfix_str(f"{name}: building")
            torch.manual_seed(args.seed)
            trainee = build_trainee(name, device, metas, weights)
            params = sum(p.numel() for p in trainee.policy.parameters()) / 1e6
            trainable = sum(p.numel() for p in trainee.policy.parameters() if p.requires_grad) / 1e6
            cfg = trainee.policy.config
            per_policy = {
                storage: LeRobotDataset(
                    ds.repo_id, root=ds.root, delta_timestamps=resolve_delta_timestamps(cfg, ds.meta)
                )
                for storage, ds in datasets.items()
            }
            frames = inference_frames(datasets[RATIO_STORAGE], trainee.preprocessors[RATIO_STORAGE], device)
            steps, calls = workload(name, args, device)
            for storage in STORAGES:
                results[name, storage] = Result(device, name, storage, args.batch_size, params, trainable)
            for r in range(args.rounds):
                for storage in _bench.round_order(STORAGES, r):
                    bar.set_postfix_str(f"{name} {storage} round {r + 1}/{args.rounds}")
                    data_s, update_s = time_training(trainee, storage, per_policy[storage], args, device, steps, bar)
                    res = results[name, storage]
                    res.rates.append(args.batch_size * steps / (data_s + update_s))
                    res.data_s += data_s
                    res.update_s += update_s
                bar.set_postfix_str(f"{name} select_action round {r + 1}/{args.rounds}")
                latencies = _bench.select_action_latencies(
                    trainee.policy, frames, WARMUP_CALLS, calls, _bench.Clock(device), lambda: bar.update(1)
                )
                for storage in STORAGES:
                    results[name, storage].latency_ms += latencies
            del trainee, per_policy, frames
            _bench.release_device_memory(device)
    return list(results.values())


# --- report ----------------------------------------------------------------------------------------


def print_table(results: list[Result]) -> None:
    header = (
        f"| {'device':<6} | {'policy':<12} | {'params M (trainable)':>20} | {'storage':<7} | {'batch':>5} "
        f"| {'train samples/s':>15} | {'data %':>6} | {'ms/step':>8} | {'select_action ms median / mean':>30} |"
    )
    _bench.print_table(header, (table_row(res) for res in results))


def table_row(res: Result) -> str:
    label = "act" if res.policy == ACT else f"bc {res.policy}"
    latency = f"{statistics.median(res.latency_ms):.2f} / {statistics.mean(res.latency_ms):.2f}"
    return (
        f"| {res.device:<6} | {label:<12} | {f'{res.params_m:.2f} ({res.trainable_m:.2f})':>20} "
        f"| {res.storage:<7} | {res.batch:>5} | {res.rate:>15.1f} | {100 * res.data_share:>5.1f}% "
        f"| {1000 * res.batch / res.rate:>8.1f} | {latency:>30} |"
    )


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="door-open", help="task of the benchmark datasets")
    parser.add_argument("--demos", type=int, default=10, help="demos per dataset (2 training environments)")
    parser.add_argument("--policies", default=",".join(POLICIES), help=f"comma-separated, from {', '.join(POLICIES)}")
    cuda = torch.cuda.is_available()
    parser.add_argument("--devices", default="cpu,cuda" if cuda else "cpu", help="comma-separated: cpu, cuda")
    parser.add_argument("--batch-size", type=int, default=8, help="training batch size (lerobot-train's default)")
    parser.add_argument("--num-workers", type=int, default=0, help="DataLoader workers (0: load in the main process)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds per (policy, storage), order alternating")
    parser.add_argument("--train-steps", type=int, default=0, help="timed training steps per block (0: per policy)")
    parser.add_argument(
        "--infer-calls", type=int, default=0, help="timed select_action calls per round (0: per policy)"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--data", default=None, help="folder for the two datasets (kept and reused; default: temp)")
    parser.add_argument("--quick", action="store_true", help="smoke run: 2 demos, conv, act, 1 round, batch 2, 1 step")
    args = parser.parse_args(argv)

    policies = _bench.parse_names(parser, args.policies, POLICIES, "policy(ies)")
    if args.quick:
        policies = list(QUICK["policies"])
        args.demos, args.rounds, args.batch_size = QUICK["demos"], QUICK["rounds"], QUICK["batch_size"]
    if "conv" not in policies or ACT not in policies:
        parser.error("--policies must include conv and act (the ratio compares them)")
    args.policy_list = policies
    args.device_list = _bench.parse_names(parser, args.devices, DEVICES, "device(s)")
    if not args.device_list:
        parser.error(f"no device given; valid: {', '.join(DEVICES)}")
    if "cuda" in args.device_list and not cuda:
        parser.error("--devices cuda requested but CUDA is not available")
    if (
        min(args.demos, args.batch_size, args.rounds) < 1
        or min(args.num_workers, args.train_steps, args.infer_calls) < 0
    ):
        parser.error("--demos, --batch-size and --rounds must be >= 1; --num-workers and step counts >= 0")
    _bench.check_tasks(parser, args.task)
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="bench_bc_"))
    data_dir = Path(args.data).resolve() if args.data else work / "data"
    print(
        f"bc encoders {', '.join(p for p in args.policy_list if p != ACT)} vs ACT on {', '.join(args.device_list)} "
        f"(torch {torch.__version__}, {torch.get_num_threads()} threads, {os.cpu_count()} CPUs); datasets: "
        f"{args.demos} demos of {args.task}, video and image storage, in {data_dir}",
        flush=True,
    )
    try:
        roots = collect_datasets(args, data_dir)
        datasets = {s: LeRobotDataset(f"local/bench_bc_{s}", root=roots[s]) for s in STORAGES}
        weights = write_weight_files(work) if set(args.policy_list) & {"clip_rn50", "r3m_rn50"} else {}
        load_start = os.getloadavg()
        results = [res for device in args.device_list for res in bench_device(device, args, datasets, weights)]
        load_end = os.getloadavg()
    finally:
        shutil.rmtree(work, ignore_errors=True)

    frames = datasets[RATIO_STORAGE].num_frames
    print()
    print(
        f"task {args.task}: {frames} frames per dataset | batch {args.batch_size} | {args.num_workers} dataloader "
        f"workers | {args.rounds} round(s) | seed {args.seed}"
    )
    print_table(results)
    print()
    for res in results:
        if res.storage == RATIO_STORAGE:
            steps, calls = workload(res.policy, args, res.device)
            per_round = ", ".join(f"{rate:.1f}" for rate in res.rates)
            print(
                f"{res.device} {res.policy}: samples/s per round [{per_round}] ({steps} timed steps each after "
                f"{WARMUP_STEPS} warm-up); select_action {len(res.latency_ms)} timed calls"
            )
    print(_bench.load_average_line(load_start, load_end))
    by_key = {(r.device, r.policy, r.storage): r for r in results}
    for device in args.device_list:
        for storage in STORAGES:
            ratio = by_key[device, "conv", storage].rate / by_key[device, ACT, storage].rate
            print(f"bc conv / ACT training samples/s, {storage} storage, {device}: {ratio:.2f}x")
    device = args.device_list[0]
    ratio = by_key[device, "conv", RATIO_STORAGE].rate / by_key[device, ACT, RATIO_STORAGE].rate
    print(f"headline ({RATIO_STORAGE} storage, {device}): {ratio:.2f}x ({_bench.target_verdict(ratio, TARGET_RATIO)})")
    print(_bench.ratio_line(ratio))
    return 0


if __name__ == "__main__":
    sys.exit(main())
