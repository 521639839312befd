"""The ``collect`` step: scripted demonstrations of its task as a LeRobotDataset in ``<step>/data``
(``factorworld collect``'s code, ``datasets/collect.py``), resumed from its finished episodes after a kill."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .context import current
from .inputs import CollectInputs
from .result import DATA_DIR
from .step import Step


def collect_config(inputs: CollectInputs | dict[str, Any], root: Path, key: str, workers: int = 1):
    """The ``factorworld collect`` settings of a collect step."""
    # Deliberately here: the collection module imports LeRobot (about 2 s), which planning and reporting
    # never need.
    from ...datasets.collect import CollectConfig  # noqa: PLC0415

    if not isinstance(inputs, CollectInputs):
        inputs = CollectInputs.from_dict(inputs)
    sampling = inputs.sampling_options()
    return CollectConfig(
        task=inputs.task,
        factors=list(inputs.train_factors),
        n_envs=inputs.n_envs,
        demos=inputs.demos,
        seed=inputs.seed,
        cameras=inputs.cameras,
        image_size=inputs.image_size,
        action_noise=inputs.action_noise,
        max_episode_steps=inputs.max_episode_steps,
        use_videos=inputs.use_videos,
        root=str(root),
        repo_id=f"local/factorworld_{key}",
        workers=workers,
        mode="new",
        sampling=sampling,
        quality=inputs.render_quality,
    )


def run_collect(step: Step, folder: Path, deps: list[Path]) -> dict[str, Any]:
    """Collect ``step``'s dataset into ``folder`` (``worker.RUNNERS``); its result names the dataset."""
    timings, _ = current()
    with timings.span("imports"):
        # Deliberately here: LeRobot's dataset code (seconds to import), only in the process that collects.
        from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

        from ...datasets.collect import SIDECAR, collect  # noqa: PLC0415

    root = folder / DATA_DIR
    cfg = collect_config(step.inputs, root, step.key, step.run.get("workers", 1))
    if (root / SIDECAR).is_file():  # merged before an interruption: nothing left to do
        meta = LeRobotDatasetMetadata(cfg.repo_id, root=root)
        return {
            "root": str(root),
            "repo_id": cfg.repo_id,
            "episodes": meta.total_episodes,
            "frames": meta.total_frames,
            "failures": {},
        }
    report = collect(cfg)
    timings.update(report.timings)
    return {
        "root": str(root),
        "repo_id": cfg.repo_id,
        "episodes": report.episodes,
        "frames": report.frames,
        "failures": report.failures,
    }
