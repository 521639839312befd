"""Whether a study's training, killed and rerun, ends with the checkpoint of one never interrupted, on this machine
and at the scale you train at (``tests/test_train_resume.py`` checks it on a toy study of one instruction).

The study's config is run twice side by side, each into its own folder under ``--out``: once uninterrupted, once
killed (kill -9 of its process group) as soon as its training has saved a state at or after ``--kill_after`` steps,
then run again. Every file of the two final checkpoints is compared (``train_config.json`` with each folder's own
path in it). Give a config of one training (one method, task, N and seed) and a small evaluation; ``--reuse_from``
links a collected dataset instead of collecting it twice. Prints one line per file, then ``identical`` or
``DIFFERENT``; exits 1 when they differ.

    MUJOCO_GL=egl python scripts/check_resume.py --config my_study.yaml --kill_after 1064 --out /tmp/resume \\
        --reuse_from outputs/study/learning/rt1_curve_pick_160
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml

from lerobot_factorworld.study.run.train_state import saved_steps


def saves(study: Path) -> dict[int, Path]:
    """The study's complete training saves (its one training's), by step: a save still being written is not one."""
    return {step: folder for train in study.glob("steps/train/*/train") for step, folder in saved_steps(train).items()}


def final_checkpoint(study: Path) -> Path:
    found = saves(study)
    return found[max(found)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", type=Path, required=True, help="a study YAML of one training")
    parser.add_argument("--kill_after", type=int, required=True, help="kill at the first save at or after this step")
    parser.add_argument("--out", type=Path, required=True, help="a new folder for the two studies")
    parser.add_argument("--reuse_from", default=None, help="a study folder whose collected dataset both link")
    args = parser.parse_args()
    if not args.config.is_file():
        raise SystemExit(f"error: no config at {args.config}")
    if args.out.exists():
        raise SystemExit(f"error: {args.out} exists; give a new folder")
    config = yaml.safe_load(args.config.read_text())
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    studies, commands = {}, {}
    for run in ("uninterrupted", "killed"):
        studies[run] = args.out / run
        path = args.out / f"{run}.yaml"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(yaml.safe_dump({**config, "out_dir": str(studies[run])}))
        commands[run] = [sys.executable, "-m", "lerobot_factorworld.cli", "study", f"--config_path={path}"]
        if args.reuse_from:
            commands[run].append(f"--reuse_from=[{Path(args.reuse_from).resolve()}]")

    def start(run: str) -> subprocess.Popen:
        log = (args.out / f"{run}.log").open("a")
        return subprocess.Popen(commands[run], env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)

    whole, killed = start("uninterrupted"), start("killed")
    try:
        while killed.poll() is None and not any(s >= args.kill_after for s in saves(studies["killed"])):
            time.sleep(0.01)
        if killed.poll() is not None:
            raise SystemExit(f"error: the study ended before saving step {args.kill_after}; see {args.out}/killed.log")
        os.killpg(killed.pid, signal.SIGKILL)
        killed.wait()
        print(f"killed with saves {sorted(saves(studies['killed']))}", flush=True)
        rerun = start("killed")
        for proc, run in ((rerun, "killed"), (whole, "uninterrupted")):
            if proc.wait() != 0:
                raise SystemExit(f"error: the {run} study failed; see {args.out}/{run}.log")
    finally:  # never leave the uninterrupted study running behind an error
        if whole.poll() is None:
            os.killpg(whole.pid, signal.SIGKILL)
    a, b = final_checkpoint(studies["uninterrupted"]), final_checkpoint(studies["killed"])
    same = True
    for name in sorted({p.relative_to(c) for c in (a, b) for p in c.rglob("*") if p.is_file()}):
        if not (a / name).is_file() or not (b / name).is_file():
            same = False
            print(f"DIFFERS {name} (only in {'the killed run' if (b / name).is_file() else 'the uninterrupted run'})")
            continue
        mine, theirs = (b / name).read_bytes(), (a / name).read_bytes()
        if name.name == "train_config.json":
            theirs = theirs.replace(str(studies["uninterrupted"]).encode(), str(studies["killed"]).encode())
        same &= mine == theirs
        print(f"{'same' if mine == theirs else 'DIFFERS'} {name}")
    print("identical" if same else "DIFFERENT")
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
