"""One LeRobotDataset made of several: a task's demos joined by other tasks' (out-of-domain data, the paper's
section 5.4), for a single ``lerobot-train`` run (LeRobot 0.6.1 trains on one dataset).

The sources are left untouched. The merge is written to a temporary folder next to ``root`` and renamed to
``root`` when complete, so an interrupted merge leaves no half dataset, and a finished one is reused.
"""

from __future__ import annotations

import shutil
from pathlib import Path

TMP_SUFFIX = ".tmp"


def features_mismatch(first: dict, other: dict) -> str | None:
    """The first difference between two datasets' features (names, dtypes, shapes), or ``None``."""
    if set(first) != set(other):
        return f"features {sorted(set(first) ^ set(other))} are in one dataset only"
    for name in sorted(first):
        a, b = first[name], other[name]
        if (a["dtype"], list(a["shape"])) != (b["dtype"], list(b["shape"])):
            return f"feature {name!r} is {a['dtype']} {list(a['shape'])} in one and {b['dtype']} {list(b['shape'])} in the other"
    return None


def merge_datasets(sources: list[tuple[str, Path]], repo_id: str, root: Path) -> int:
    """Merge ``sources`` ((repo_id, root) pairs, in order) into ``repo_id`` at ``root``; its frame count.
    Datasets whose features differ are refused, naming the first difference, before anything is written."""
    # Deliberately here: LeRobot's dataset stack costs seconds to import; only a merging training needs it.
    from lerobot.datasets.aggregate import aggregate_datasets  # noqa: PLC0415
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

    if len(sources) < 2:
        raise ValueError(f"a merge needs at least two datasets, got {len(sources)}")
    if not (root / "meta" / "info.json").is_file():
        metas = [LeRobotDatasetMetadata(rid, root=src) for rid, src in sources]
        for (_, src), meta in zip(sources[1:], metas[1:], strict=True):
            problem = features_mismatch(metas[0].features, meta.features)
            if problem:
                raise ValueError(f"cannot merge {src} into {sources[0][1]}'s data: {problem}")
        tmp = root.with_name(root.name + TMP_SUFFIX)
        shutil.rmtree(tmp, ignore_errors=True)  # an interrupted merge
        aggregate_datasets([rid for rid, _ in sources], repo_id, roots=[src for _, src in sources], aggr_root=tmp)
        tmp.rename(root)
    return int(LeRobotDatasetMetadata(repo_id, root=root).total_frames)
