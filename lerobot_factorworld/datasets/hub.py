"""Push a collected dataset with LeRobot's own mechanism (folder upload, card, tags, version tag)."""

from __future__ import annotations

import json
from pathlib import Path


class HubUnreachableError(RuntimeError):
    """The Hub could not be reached; the local dataset is untouched."""


def push_dataset(root: str | Path, repo_id: str, private: bool = False) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from .card import card_description, card_tags

    root = Path(root)
    settings = json.loads((root / "meta" / "factorworld.json").read_text())["settings"]
    dataset = LeRobotDataset(repo_id, root=root)
    try:
        dataset.push_to_hub(
            tags=card_tags(settings),
            private=private,
            license="apache-2.0",
            dataset_description=card_description(dataset.meta),
        )
    except Exception as err:  # requests/httpx/huggingface_hub errors all mean the same thing here
        if _is_network_error(err):
            raise HubUnreachableError(
                f"could not reach the Hugging Face Hub to push {repo_id} ({type(err).__name__}: {err}). "
                f"Nothing was lost: the dataset is complete at {root}. Push it later with "
                f"`factorworld push --root={root} --repo_id={repo_id}`."
            ) from err
        raise


def _is_network_error(err: BaseException) -> bool:
    names = {type(e).__name__ for e in _chain(err)}
    network = {
        "ConnectionError",
        "ConnectError",
        "OfflineModeIsEnabled",
        "Timeout",
        "ConnectTimeout",
        "ReadTimeout",
        "LocalEntryNotFoundError",
        "MaxRetryError",
        "NameResolutionError",
        "gaierror",
        "HfHubHTTPError",
        "OSError",
    }
    return bool(names & network)


def _chain(err: BaseException | None):
    while err is not None:
        yield err
        err = err.__cause__ or err.__context__
