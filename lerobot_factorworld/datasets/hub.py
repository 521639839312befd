"""Push to the Hugging Face Hub: a collected dataset with LeRobot's own mechanism (folder upload, card, tags,
version tag), or a few plain files (a study's per-episode results and their card) as a dataset repo.

Both say the same thing when the Hub cannot be reached (:class:`HubUnreachableError`): the local files are
complete, and how to push them later. A plain push asks the Hub once, with a short timeout, before it uploads
(:func:`check_hub_reachable`): ``huggingface_hub``'s own requests have no timeout, so a machine without a
network would otherwise wait on them.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

import huggingface_hub

from ..core.checks import check_repo_id
from .card import card_description, card_tags

LOCAL_NAMESPACE = "local"  # LeRobot's namespace for datasets that stay on disk (``local/<name>``)
PROBE_TIMEOUT_S = 10.0  # how long a push waits for the Hub to answer before saying it is unreachable
DATASET = "dataset"  # the Hub's repo type of what is pushed here


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
    check_not_local(repo_id, "repo_id")
    check_hub_token()


def check_not_local(repo_id: str, setting: str) -> None:
    """Refuse LeRobot's ``local/...`` namespace, which names data that stays on disk, as a push target."""
    if repo_id.split("/", 1)[0] == LOCAL_NAMESPACE:
        raise ValueError(
            f"push_to_hub=true needs a Hub {setting} ('user/name' with your user or organization), "
            f"not {repo_id!r} ({LOCAL_NAMESPACE}/... names a dataset that stays on disk)"
        )


def check_hub_repo_id(repo_id: str, setting: str) -> None:
    """A dataset repo a push can target: ``user/name`` as the Hub accepts it, outside the ``local`` namespace."""
    try:
        check_repo_id(repo_id)
    except ValueError as err:
        raise ValueError(f"{setting}: {err}") from None
    check_not_local(repo_id, setting)


def check_hub_token() -> None:
    """A push needs a token: refused in one line before any work, rather than after it."""
    try:
        token = huggingface_hub.get_token()
    except Exception as err:  # e.g. a failed OIDC exchange (HF_OIDC_RESOURCE): no usable token
        raise ValueError(f"push_to_hub=true, but no Hugging Face token could be read ({err})") from None
    if not token:
        raise ValueError(
            "push_to_hub=true needs a Hugging Face token with write access: run `hf auth login` or set HF_TOKEN "
            "(or run with --push_to_hub=false and push later)"
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


def check_hub_reachable(timeout: float = PROBE_TIMEOUT_S) -> None:
    """One request to the Hub that gives up after ``timeout`` seconds (offline mode, no route, no name
    resolution, a silent firewall: :class:`HubUnreachableError`); any answer, even an error status, means
    it is reachable."""
    try:
        huggingface_hub.get_session().head(huggingface_hub.constants.ENDPOINT, timeout=timeout)
    except Exception as err:
        if _is_network_error(err):
            raise HubUnreachableError(
                f"could not reach the Hugging Face Hub at {huggingface_hub.constants.ENDPOINT} "
                f"({type(err).__name__}: {err})"
            ) from err
        raise


def push_files(repo_id: str, files: Mapping[str, Path | bytes], message: str) -> str:
    """Upload ``files`` (path in the repo -> a local file or its bytes) to the dataset repo ``repo_id`` in one
    commit, creating the repo when it does not exist; returns the repo's URL. Nothing is downloaded and no
    local file is changed. An unreachable Hub raises :class:`HubUnreachableError` within about
    ``PROBE_TIMEOUT_S`` seconds; a refusal by the Hub (no write access, ...) raises its own error."""
    check_hub_reachable()
    api = huggingface_hub.HfApi()
    operations = [
        huggingface_hub.CommitOperationAdd(path_in_repo=name, path_or_fileobj=content)
        for name, content in files.items()
    ]
    try:
        url = api.create_repo(repo_id, repo_type=DATASET, exist_ok=True)
        api.create_commit(repo_id, operations, commit_message=message, repo_type=DATASET)
    except Exception as err:
        if _is_network_error(err) and not _refused(err):
            raise HubUnreachableError(
                f"lost the Hugging Face Hub while pushing {repo_id} ({type(err).__name__}: {err})"
            ) from err
        raise
    return str(url)


def _refused(err: BaseException) -> bool:
    """The Hub answered with an error status (no write access, a bad name): not a network failure."""
    return any(getattr(getattr(e, "response", None), "status_code", None) for e in _chain(err))


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
        "PoolTimeout",
        "WriteTimeout",
        "ProxyError",
        "RemoteProtocolError",
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
