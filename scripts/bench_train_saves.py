"""What a study's training pays for the states a rerun resumes from (``study/run/train_state.py``): one training step
run twice in this process (as the ``grouped`` execution runs it), saving at the end of every pass of LeRobot's
sampler and saving only LeRobot's own checkpoints (the last), with the seconds of each, the saves made, the seconds
per save and the overhead; the two final weights files must be identical (saving changes nothing computed).

    MUJOCO_GL=egl python scripts/bench_train_saves.py                      # bc, 2 demos, 40 epochs
    MUJOCO_GL=egl python scripts/bench_train_saves.py --policy rt1 --epochs 8
"""

from __future__ import annotations

import argparse
import filecmp
import json
import sys
import tempfile
import time
from pathlib import Path

from lerobot_factorworld.core.settings import parse_config
from lerobot_factorworld.study.plan.command import StudyCommand
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.run.result import read_result
from lerobot_factorworld.study.run.step import RUN, Step
from lerobot_factorworld.study.run.worker import run_step

POLICIES = {"bc": "{type: bc}", "rt1": "{type: rt1, preset: small, speed: fast}"}
CONFIG = """
name: saves
out_dir: {out}
tasks: [handle-press]
n_train_envs: [1]
seeds: [0]
train_factors: [light]
factors: []
methods:
  - name: {policy}
    policy: {settings}
collect:
  demos: {demos}
  max_episode_steps: 60
  image_size: {image_size}
train:
  epochs: {epochs}
  batch_size: 8
eval:
  n_test_envs: 1
  episodes: 1
"""
NEVER = 10**9  # save_every_passes that never comes: only LeRobot's own checkpoints


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", choices=sorted(POLICIES), default="bc")
    parser.add_argument("--epochs", type=int, default=40)
    parser.add_argument("--demos", type=int, default=2)
    parser.add_argument("--image-size", type=int, default=48)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "saves.yaml"
        text = CONFIG.format(
            out=Path(tmp) / "study",
            policy=args.policy,
            settings=POLICIES[args.policy],
            demos=args.demos,
            image_size=args.image_size,
            epochs=args.epochs,
        )
        config.write_text(text)
        cfg = parse_config(StudyCommand, [f"--config_path={config}"], "study").grid()
        plan = make_plan(cfg)
        (collect,) = plan.of_kind("collect")
        (train,) = plan.of_kind("train")
        run_step(collect.to_dict(), cfg.out_dir, "grouped")

        def train_once(name: str, every: int) -> tuple[float, dict, Path]:
            """The training step in a study folder of its own (sharing the collection), saving every ``every`` passes."""
            study = Path(tmp) / name
            (study / "steps").mkdir(parents=True)
            (study / "steps" / "collect").symlink_to(Path(cfg.out_dir) / "steps" / "collect")
            step = Step(
                train.kind, train.inputs, train.deps, {**train.meta, RUN: {**train.run, "save_every_passes": every}}
            )
            start = time.perf_counter()
            result = run_step(step.to_dict(), str(study), "grouped")
            return time.perf_counter() - start, result, study

        train_once("warm_up", NEVER)  # the first training in a process pays its imports: not timed
        every_s, result, every_study = train_once("every_pass", 1)
        own_s, _, own_study = train_once("own_only", NEVER)
        steps = result["steps"]
        pass_steps = json.loads((Path(result["checkpoint"]).parents[2] / "sampler.json").read_text())["pass_steps"]
        saves = steps // pass_steps + (steps % pass_steps != 0)  # every pass's end and the last step
        weights = [Path(read_result(train, s)["checkpoint"]) / "model.safetensors" for s in (every_study, own_study)]
        identical = filecmp.cmp(*weights, shallow=False)
        print(
            f"policy {args.policy}, {args.demos} demos at {args.image_size} px, {args.epochs} epochs: {steps} steps, "
            f"a pass {pass_steps} steps"
        )
        print(f"{'saves':24s} {'seconds':>8s} {'saves made':>10s}")
        print(f"{'every pass':24s} {every_s:8.2f} {saves:10d}")
        print(f"{'LeRobot own only':24s} {own_s:8.2f} {1:10d}")
        per_save = (every_s - own_s) / max(1, saves - 1)
        print(f"seconds per save: {per_save:.3f}; overhead: {every_s / own_s - 1:+.1%} of the training")
        print(f"final weights {'identical' if identical else 'DIFFERENT'}")
        return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
