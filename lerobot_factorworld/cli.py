"""``factorworld`` command line: ``factorworld <command> [--key=value ...]`` (draccus-parsed configs).

Commands:
    tasks           list the tasks and their instructions
    factors         the factors, their ranges, and the task x factor support matrix
    cameras         the scene cameras
    sample          sample N environment configurations and save them as JSON
    contact-sheet   render a task under every factor (PNG)
    collect         scripted demos -> LeRobotDataset with per-episode factor values (resumable)
    rt1-presets     the RT-1 presets and their parameter counts
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import draccus


@dataclass
class SampleConfig:
    """``factorworld sample``: N training (or eval) environments of a task.

    Attributes:
        task: Task name.
        n: Number of environments.
        seed: Sampling seed.
        split: ``train`` or ``eval`` asset split.
        factors: Factors to vary (default: the paper's seven).
        out: JSON file to write (nothing is written when empty).
    """

    task: str = "pick-place"
    n: int = 5
    seed: int = 0
    split: str = "train"
    factors: list[str] = field(default_factory=list)
    out: str = ""


def cmd_tasks(_: list[str]) -> None:
    from .tasks import TASKS

    for task in TASKS.values():
        print(f"{task.name:28s} {task.gym_id:40s} {task.instruction}")


def cmd_factors(_: list[str]) -> None:
    from .factors.registry import FACTORS, support_matrix_markdown

    print("| factor | paper name | kind | visual | ranges |\n|---|---|---|---|---|")
    for spec in FACTORS.values():
        ranges = "; ".join(f"{w}: {list(lo)} .. {list(hi)}" for w, (lo, hi) in spec.ranges.items()) or spec.asset_kind
        print(f"| {spec.name} | {spec.title} | {spec.kind} | {'yes' if spec.visual else 'no'} | {ranges} |")
    print("\nSupport matrix (— = the factor cannot apply to the task; requesting it raises an error):\n")
    print(support_matrix_markdown())
    print("\nPer-task limits (where the task's scripted expert stays >= 90% successful; ranges are clipped to them):\n")
    from .tasks import TASKS

    for task in TASKS.values():
        for name, (low, high) in task.limits:
            print(f"- {task.name}: {name} in {list(low)} .. {list(high)}")


def cmd_cameras(_: list[str]) -> None:
    from .scene.cameras import CAMERAS

    for cam in CAMERAS.values():
        print(f"{cam.name:8s} pos={cam.pos} target={cam.target} fovy={cam.fovy}")


def cmd_sample(args: list[str]) -> None:
    from .factors.registry import PAPER_STUDY_FACTORS
    from .factors.sampling import sample_configs
    from .factors.values import save_configs

    cfg = draccus.parse(SampleConfig, args=args)
    configs = sample_configs(cfg.task, cfg.n, cfg.seed, cfg.split, cfg.factors or PAPER_STUDY_FACTORS)
    for config in configs:
        print(config)
    if cfg.out:
        print(f"wrote {save_configs(configs, cfg.out)}")


def cmd_contact_sheet(args: list[str]) -> None:
    from .contact_sheet import ContactSheetConfig, render_contact_sheet

    cfg = draccus.parse(ContactSheetConfig, args=args)
    print(f"wrote {render_contact_sheet(cfg)}")


def cmd_collect(args: list[str]) -> None:
    from .datasets.collect import CollectConfig, collect

    cfg = draccus.parse(CollectConfig, args=args)
    report = collect(cfg)
    print(f"wrote {report.episodes} episodes ({report.frames} frames) to {report.root} in {report.seconds:.1f} s")
    for env, count in report.failures.items():
        print(f"  {env}: {count} failed attempt(s) discarded")


def cmd_rt1_presets(_: list[str]) -> None:
    from .policies.rt1.presets import preset_table

    print(preset_table())


COMMANDS: dict[str, Callable[[list[str]], None]] = {
    "tasks": cmd_tasks,
    "factors": cmd_factors,
    "cameras": cmd_cameras,
    "sample": cmd_sample,
    "contact-sheet": cmd_contact_sheet,
    "collect": cmd_collect,
    "rt1-presets": cmd_rt1_presets,
}


def main(argv: list[str] | None = None) -> None:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return
    command, args = argv[0], argv[1:]
    if command not in COMMANDS:
        raise SystemExit(f"unknown command {command!r}; valid commands: {', '.join(COMMANDS)}")
    try:
        COMMANDS[command](args)
    except (ValueError, FileNotFoundError, FileExistsError) as err:
        raise SystemExit(f"error: {err}") from None


if __name__ == "__main__":
    main()
