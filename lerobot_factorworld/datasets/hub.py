"""Push a collected dataset with LeRobot's own mechanism (folder upload, card, tags, version tag)."""

from __future__ import annotations

import json
from pathlib import Path

import huggingface_hub

from .card import card_description, card_tags

LOCAL_NAMESPACE = "local"  # LeRobot's namespace for datasets that stay on disk (``local/<name>``)


class HubUnreachableError(RuntimeError):
    """The Hub could not be reached; the local dataset is untouched."""


def check_push_settings(repo_id: str, push_to_hub: bool, private: bool) -> None:
    """What a push needs, checked before collecting (so a bad setting never wastes a collection).

    A push needs a Hub repo id (``user/name`` outside LeRobot's ``local`` namespace) and a token; ``private``
    only means something for a push. Reachability is not checked here: an unreachable Hub after the
    collection keeps the data and says how to push it later (:class:`HubUnreachableError`).
    """
    if not push_to_hub:
        if private:
            raise ValueError("private=true only applies to a push: add --push_to_hub=true, or drop --private")
        return
    if repo_id.split("/", 1)[0] == LOCAL_NAMESPACE:
        raise ValueError(
            f"push_to_hub=true needs a Hub repo_id ('user/name' with your user or organization), "
            f"not {repo_id!r} ({LOCAL_NAMESPACE}/... names a dataset that stays on disk)"
        )
    try:
        token = huggingface_hub.get_token()
    except Exception as err:  # e.g. a failed OIDC exchange (HF_OIDC_RESOURCE): no usable token
        raise ValueError(f"push_to_hub=true, but no Hugging Face token could be read ({err})") from None
    if not token:
        raise ValueError(
            "push_to_hub=true needs a Hugging Face token with write access: run `hf auth login` or set HF_TOKEN "
            "(or collect with --push_to_hub=false and push later)"
        )


def push_dataset(root: str | Path, repo_id: str, private: bool = False) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: PLC0415  heavy (torch); only when pushing

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
            call = f"push_dataset('{root}', '{repo_id}'{', private=True' if private else ''})"
            raise HubUnreachableError(
                f"could not reach the Hugging Face Hub to push {repo_id} ({type(err).__name__}: {err}). "
                f"Nothing was lost: the dataset is complete at {root}. Push it later with "
                f'`python -c "from lerobot_factorworld.datasets.hub import push_dataset; {call}"`.'
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
