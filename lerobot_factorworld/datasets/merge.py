"""One LeRobotDataset made of several: a task's demos joined by other tasks' (out-of-domain data, the paper's
section 5.4), for a single ``lerobot-train`` run (LeRobot 0.6.1 trains on one dataset).

The sources are left untouched. The merge is written to a temporary folder next to ``root`` and renamed to
``root`` when complete, so an interrupted merge leaves no half dataset, and a finished one is reused.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from ..core.io import atomic_write_text

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
        write_stats_in_feature_order(tmp)
        tmp.rename(root)
    return int(LeRobotDatasetMetadata(repo_id, root=root).total_frames)


def write_stats_in_feature_order(root: Path) -> None:
    """Rewrite ``meta/stats.json`` with its features in ``info.json``'s order. LeRobot 0.6.1 aggregates the stats
    over a set of feature names, so their order in the file follows Python's per-process string hashing: two
    collections of the same demos would differ in that file's bytes (never in its numbers), and so would the
    dataset's content hash that a training's record of its runs compares (``study/run/train_step.py``). Every dataset
    this package aggregates (a collection's shards, a training's merged data) goes through it."""
    path = root / "meta" / "stats.json"
    stats = json.loads(path.read_text(encoding="utf-8"))
    features = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))["features"]
    order = [name for name in features if name in stats] + sorted(name for name in stats if name not in features)
    # LeRobot's own format (lerobot.utils.io_utils.write_json), so a reader sees no other change
    atomic_write_text(path, json.dumps({name: stats[name] for name in order}, indent=4, ensure_ascii=False))
