"""The dataset card: tasks, factors, N, splits and counts, in LeRobot's card template."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

from .schema import ENV_ID_COLUMN, SPLIT_COLUMN
from .version import data_version, describe_data_version


def card_tags(settings: dict) -> list[str]:
    tasks = [t.strip() for t in settings["task"].split(",") if t.strip()]
    return ["factorworld", "meta-world", *tasks, *settings["factors"]]


def card_description(meta) -> str:
    """Markdown summary of a collected dataset (``meta``: its ``LeRobotDatasetMetadata``)."""
    sidecar = json.loads((Path(meta.root) / "meta" / "factorworld.json").read_text())
    settings = sidecar["settings"]
    episodes = meta.episodes
    per_env = Counter(episodes[ENV_ID_COLUMN])
    splits = Counter(episodes[SPLIT_COLUMN])
    lines = [
        "Scripted Meta-World demonstrations in Factor World environments "
        "(Xie et al. 2023, *Decomposing the Generalization Gap in Imitation Learning for Visual Robotic Manipulation*), "
        "made with [lerobot_factorworld](https://github.com/).",
        "",
        f"- **Tasks:** {settings['task']}",
        f"- **Factors varied:** {', '.join(settings['factors']) or 'none'}",
        f"- **Environments (N):** {settings['n_envs']} per task, from the `{settings['split']}` asset split, seed {settings['seed']}",
        f"- **Episodes:** {meta.total_episodes} ({dict(splits)}), **frames:** {meta.total_frames}, fps {meta.fps}",
        f"- **Cameras:** {settings['cameras']} at {settings['image_size']}x{settings['image_size']}; action noise std {settings['action_noise']}",
        f"- **Failed attempts** (discarded): {sum(sidecar['failures'].values())}",
        f"- **Format:** {describe_data_version(data_version(settings))}",
        "",
        "Each episode row of `meta/episodes` holds `factorworld/env_id`, `factorworld/split` and one `factors/<name>` "
        "column per factor; `lerobot_factorworld.datasets.query` reads them back as typed values and selects episodes "
        "by factor. The environment configurations are in `meta/factorworld.json`.",
        "",
        "| environment | episodes |",
        "|---|---|",
        *[f"| {env} | {count} |" for env, count in sorted(per_env.items())],
    ]
    return "\n".join(lines)


def write_card(meta) -> Path:
    """Write ``README.md`` (the card) into the dataset folder; push_to_hub sends the same card."""
    from lerobot.datasets.utils import create_lerobot_dataset_card  # noqa: PLC0415  heavy; only once a dataset is written

    root = Path(meta.root)
    sidecar = json.loads((root / "meta" / "factorworld.json").read_text())
    card = create_lerobot_dataset_card(
        tags=card_tags(sidecar["settings"]),
        dataset_info=meta.info,
        license="apache-2.0",
        repo_id=meta.repo_id,
        dataset_description=card_description(meta),
    )
    path = root / "README.md"
    path.write_text(str(card))
    return path
