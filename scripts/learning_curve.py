"""P_T against training epochs: how well the paper's CNN BC masters its own training environments.

One run: scripted demos of ``--task`` in ``--n`` training environments (``factorworld collect``, PNG frames),
one ``lerobot-train`` of ``bc`` that saves a checkpoint every ``--every`` epochs up to ``--epochs``, and a
``lerobot-eval`` of every checkpoint on those training environments (``--episodes`` episodes, episode ``i``
reset with seed ``--seed + i``). Writes ``curve.csv`` (epochs, steps, successes, episodes, success rate,
Wilson 95% interval, the training loss logged at the checkpoint), ``curve.md`` and ``curve.png``
in ``--out``, and prints the Markdown table.

Resumable: a finished dataset, training or evaluation (its ``eval_info.json``) is reused, so rerunning the
same command after an interruption redoes only what is missing (an interrupted training starts over). The
settings are kept in ``settings.json``; rerunning into the same ``--out`` with other settings is refused.
The loss column is the last training loss LeRobot logged at or before the checkpoint (LeRobot prints steps
rounded, e.g. ``step:2K``, so it is read from the log's order, one line per ``log_freq`` steps).

    MUJOCO_GL=egl .venv/bin/python scripts/learning_curve.py --task pick-place --demos 200 --epochs 40 --every 10

``--report`` runs nothing: it rewrites ``curve.md`` and ``curve.png`` from the ``curve.csv`` and ``settings.json``
in ``--out`` alone (a committed curve under ``docs/results/curves/`` regenerates the table docs/findings.md
quotes; ``tests/test_docs_results.py`` checks it).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import sys
import time
from pathlib import Path

from _bench import add_repo_to_path, check_tasks, run_logged, setup_headless_gl

setup_headless_gl()
add_repo_to_path()

from lerobot_factorworld.study.metrics import wilson_interval  # noqa: E402

BIN = Path(sys.executable).parent
COLUMNS = ("epochs", "steps", "successes", "episodes", "success_rate", "ci_low", "ci_high", "loss")


def collect(args: argparse.Namespace, data: Path, log: Path) -> int:
    """Collect the demos once; returns the dataset's frame count."""
    info = data / "meta" / "info.json"
    if not info.is_file():
        run_logged([str(BIN / "factorworld"), "collect", f"--task={args.task}", f"--n_envs={args.n}",
             f"--demos={args.demos}", f"--action_noise={args.action_noise}", "--use_videos=false",
             f"--root={data}", f"--repo_id=local/curve_{args.task}", "--mode=overwrite"], log)  # fmt: skip
    return int(json.loads(info.read_text())["total_frames"])


def log_freq(steps_per_save: int) -> int:
    return min(100, steps_per_save)


def train(args: argparse.Namespace, data: Path, out: Path, steps_per_save: int, total: int, log: Path) -> None:
    """Train once to ``total`` steps, a checkpoint every ``steps_per_save``."""
    if (out / "checkpoints" / f"{total:06d}" / "pretrained_model").is_dir():
        return
    if out.exists():  # an interrupted training: start over (lerobot-train refuses an existing folder)
        out.rename(out.with_name(f"{out.name}.interrupted-{int(time.time())}"))
    env = {**os.environ, "OMP_NUM_THREADS": str(args.threads)}
    run_logged([str(BIN / "lerobot-train"), "--policy.type=bc", f"--policy.augmentation={args.augmentation}",
         "--policy.device=cpu", "--policy.push_to_hub=false", f"--dataset.repo_id=local/curve_{args.task}",
         f"--dataset.root={data}", f"--steps={total}", f"--batch_size={args.batch_size}", "--num_workers=1",
         f"--save_freq={steps_per_save}", f"--log_freq={log_freq(steps_per_save)}", "--seed=0",
         f"--output_dir={out}", *args.train_arg], log, env, append=False)  # fmt: skip


def evaluate(args: argparse.Namespace, checkpoint: Path, out: Path, log: Path) -> list[bool]:
    """Successes of ``checkpoint`` on the training environments (cached in ``out/eval_info.json``)."""
    info = out / "eval_info.json"
    if not info.is_file():
        run_logged([str(BIN / "lerobot-eval"), f"--policy.path={checkpoint}", "--env.type=factorworld",
             f"--env.task={args.task}", f"--env.n_train_envs={args.n}", f"--eval.n_episodes={args.episodes}",
             f"--env.episode_length={args.max_episode_steps}", "--eval.batch_size=1", f"--seed={args.seed}",
             f"--output_dir={out}"], log)  # fmt: skip
    data = json.loads(info.read_text())
    return [bool(s) for task in data["per_task"] for s in task["metrics"]["successes"]]


def logged_losses(log: Path, log_freq: int) -> dict[int, float]:
    """``step -> loss`` from lerobot-train's log lines (``step:2K ... loss:0.031``): the n-th line is step
    ``n * log_freq`` (its printed step is rounded)."""
    losses = [float(m) for m in re.findall(r"step:\S+ smpl:.*?loss:([0-9.]+)", log.read_text())]
    return {(i + 1) * log_freq: loss for i, loss in enumerate(losses)}


def at_or_before(losses: dict[int, float], step: int) -> float:
    steps = [s for s in losses if s <= step]
    return losses[max(steps)] if steps else math.nan


def check_settings(args: argparse.Namespace, out: Path) -> None:
    """Refuse to mix a run's cached dataset, checkpoints or evaluations with other settings (one line)."""
    path, settings = out / "settings.json", {k: v for k, v in vars(args).items() if k not in ("out", "report")}
    if path.is_file():
        old = json.loads(path.read_text())
        diff = {k: (old.get(k), v) for k, v in settings.items() if old.get(k) != v}
        if diff:
            changes = ", ".join(f"{k}: {a} -> {b}" for k, (a, b) in diff.items())
            raise SystemExit(f"error: {out} holds a run with other settings ({changes}); choose another --out")
    path.write_text(json.dumps(settings, indent=1, sort_keys=True))


def curve_title(settings: dict) -> str:
    """The curve's settings in one line (from the command line, or a run's ``settings.json``)."""
    return (f"{settings['task']}, N = {settings['n']}, {settings['demos']} demos, batch {settings['batch_size']}, "
            f"{settings['augmentation']}, action noise {settings['action_noise']:g}")  # fmt: skip


def read_rows(path: Path) -> list[dict]:
    """``curve.csv``'s rows with their numbers parsed."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    ints = {"steps", "successes", "episodes"}
    return [{k: int(v) if k in ints else float(v) for k, v in row.items()} for row in rows]


def report(out: Path) -> str:
    """Rewrite ``curve.md`` and ``curve.png`` from ``out``'s ``curve.csv`` and ``settings.json``; the table."""
    for name in ("curve.csv", "settings.json"):
        if not (out / name).is_file():
            raise SystemExit(f"error: --report needs {out / name} (a finished run's folder)")
    return write_outputs(
        read_rows(out / "curve.csv"), out, curve_title(json.loads((out / "settings.json").read_text()))
    )


def write_outputs(rows: list[dict], out: Path, title: str) -> str:
    with open(out / "curve.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    lines = ["| epochs | steps | P_T [Wilson 95%] | successes | loss |", "|---|---|---|---|---|"]
    lines += [
        f"| {r['epochs']:g} | {r['steps']} | {r['success_rate']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}] "
        f"| {r['successes']}/{r['episodes']} | {r['loss']:.4f} |"
        for r in rows
    ]
    table = "\n".join(lines)
    (out / "curve.md").write_text(f"{title}\n\n{table}\n")
    import matplotlib  # noqa: PLC0415 - only for the figure, after every run is done

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(5, 3.2))
    x = [r["epochs"] for r in rows]
    ax.plot(x, [r["success_rate"] for r in rows], marker="o")
    ax.fill_between(x, [r["ci_low"] for r in rows], [r["ci_high"] for r in rows], alpha=0.25)
    ax.axhline(0.85, color="grey", linestyle="--", linewidth=0.8)
    ax.set(xlabel="epochs", ylabel="P_T (training environments)", ylim=(0, 1.02), title=title)
    fig.tight_layout()
    fig.savefig(out / "curve.png", dpi=120)
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", default="pick-place")
    parser.add_argument("--n", type=int, default=5, help="training environments")
    parser.add_argument("--demos", type=int, default=200)
    parser.add_argument("--action_noise", type=float, default=0.002)
    parser.add_argument("--epochs", type=float, default=40)
    parser.add_argument("--every", type=float, default=10, help="epochs between evaluated checkpoints")
    parser.add_argument("--batch_size", type=int, default=32)
    parser.add_argument("--augmentation", default="shift", choices=["none", "shift", "color", "shift+color"])
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--episodes", type=int, default=60)
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--max_episode_steps", type=int, default=200, help="evaluation step limit (the studies')")
    parser.add_argument("--train_arg", action="append", default=[], help="another lerobot-train flag")
    parser.add_argument("--out", default="")
    parser.add_argument("--report", action="store_true", help="run nothing: curve.md/png from --out's curve.csv")
    args = parser.parse_args()
    if args.report:
        print(report(Path(args.out or f"outputs/curves/{args.task}")))
        return
    check_tasks(parser, args.task)
    if not 0 < args.every <= args.epochs:
        raise SystemExit(f"error: --every must be in (0, --epochs={args.epochs:g}], got {args.every:g}")
    out = Path(args.out or f"outputs/curves/{args.task}")
    out.mkdir(parents=True, exist_ok=True)
    check_settings(args, out)
    log = out / "log.txt"
    start = time.perf_counter()
    frames = collect(args, out / "data", log)
    per_save = math.ceil(args.every * frames / args.batch_size)
    saves = math.ceil(args.epochs / args.every)
    train(args, out / "data", out / "train", per_save, per_save * saves, out / "train_log.txt")
    trained = time.perf_counter()
    losses = logged_losses(out / "train_log.txt", log_freq(per_save))
    rows = []
    for i in range(1, saves + 1):
        steps = per_save * i
        successes = evaluate(args, out / "train" / "checkpoints" / f"{steps:06d}" / "pretrained_model",
                             out / f"eval_{steps:06d}", log)  # fmt: skip
        k, n = sum(successes), len(successes)
        low, high = wilson_interval(k, n)
        epochs = round(steps * args.batch_size / frames, 2)
        rows.append({"epochs": epochs, "steps": steps, "successes": k, "episodes": n, "success_rate": k / n,
                     "ci_low": low, "ci_high": high, "loss": at_or_before(losses, steps)})  # fmt: skip
        print(f"{epochs:g} epochs: {k}/{n}", flush=True)
    print(write_outputs(rows, out, curve_title(vars(args))))
    print(f"wall time: {time.perf_counter() - start:.0f} s (training done at {trained - start:.0f} s)")


if __name__ == "__main__":
    main()
