"""Read factor values back from a dataset and select episodes by them."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..factors.registry import check_factor_names
from .schema import ENV_ID_COLUMN, SPLIT_COLUMN, decode_episode, decode_factors

EPISODE_FIELDS = ("instruction", "target")
"""Episode fields ``select_episodes`` matches besides factors (``target="red_mug"``)."""


def episode_records(repo_id: str, root: str | Path) -> list[dict[str, Any]]:
    """One record per episode: index, env_id, split, task, length, typed ``factors``, and the episode's
    ``instruction``, ``target`` and ``objects`` (a pick episode's named object and scene; see
    :func:`~lerobot_factorworld.datasets.schema.decode_episode`)."""
    # LeRobot is imported on use: importing it costs seconds (torch), and the package stays light without it.
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata  # noqa: PLC0415

    root = Path(root)
    if not (root / "meta" / "info.json").is_file():
        raise FileNotFoundError(f"no LeRobot dataset at {root} (meta/info.json is missing)")
    episodes = LeRobotDatasetMetadata(repo_id, root=root).episodes
    records = []
    for row in episodes:
        records.append(
            {
                "episode_index": int(row["episode_index"]),
                "env_id": row[ENV_ID_COLUMN],
                "split": row[SPLIT_COLUMN],
                "tasks": list(row["tasks"]),
                "length": int(row["length"]),
                "factors": decode_factors(row),
                **decode_episode(row),
            }
        )
    return records


def select_episodes(
    repo_id: str, root: str | Path, where: Callable[[dict], bool] | None = None, **equals: Any
) -> list[int]:
    """Episode indices whose factors match: ``select_episodes(id, root, table_texture="proc:wood-003")``
    or any predicate on the typed factor dict (``where=lambda f: f["light"][0] > 0.5``); ``target=`` and
    ``instruction=`` select pick episodes by their named object or instruction."""
    check_factor_names([k for k in equals if k not in EPISODE_FIELDS])
    out = []
    for record in episode_records(repo_id, root):
        factors = record["factors"]
        values = {**factors, **{k: record[k] for k in EPISODE_FIELDS}}
        if all(_same(values[k], v) for k, v in equals.items()) and (where is None or where(factors)):
            out.append(record["episode_index"])
    return out


def _same(actual: Any, wanted: Any) -> bool:
    if isinstance(actual, tuple) and isinstance(wanted, (list, tuple)):
        return len(actual) == len(wanted) and all(_same(a, w) for a, w in zip(actual, wanted, strict=True))
    if isinstance(actual, float) and isinstance(wanted, (int, float)):
        return abs(actual - wanted) < 1e-9
    return actual == wanted
