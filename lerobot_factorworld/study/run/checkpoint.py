"""Given checkpoints: a study method that names an existing LeRobot ``pretrained_model`` instead of policy
settings (``{name: my_policy, checkpoint: path/to/pretrained_model}``), which is all ``factorworld profile``
evaluates.

A checkpoint is a local folder or, only when the Hub can be reached, a Hub model id: it is fetched into the
Hugging Face cache before the study is planned (:func:`fetch_checkpoints`) and read from there afterwards.
Its evaluations' key holds the content hash of every file in the folder (:func:`keyed_checkpoint`), so a
changed checkpoint is never reused silently; an evaluation checks the hash again before it loads the policy
(:func:`checkpoint_folder`). Before any step runs, every checkpoint is checked (:func:`check_checkpoints`):
the folder exists, it is a LeRobot ``pretrained_model`` whose config LeRobot parses, and the observation and
action features it was made for are the ones the env it is evaluated in gives.
"""

from __future__ import annotations

import json
import logging
import os
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import huggingface_hub

from ...core.fingerprint import folder_fingerprint
from ...core.settings import one_line
from ...datasets.hub import HubUnreachableError, check_hub_reachable
from ...envs.lerobot_obs import FACTORWORLD_OBS, LEROBOT_METAWORLD_OBS
from ...protocol.sidecar import SIDECAR
from .eval_env import env_config
from .inputs import EnvInputs

CONFIG_FILE = "config.json"
TRAIN_CONFIG_FILE = "train_config.json"  # lerobot-train's settings, saved beside the weights
# What lerobot-train writes into <output_dir>/checkpoints/<step>/pretrained_model and lerobot-eval loads.
PRETRAINED_FILES = (CONFIG_FILE, "model.safetensors", "policy_preprocessor.json", "policy_postprocessor.json")
GIVEN_CHECKPOINT = "checkpoint"  # an evaluation's run entry: where its given checkpoint is (its key: the content)
MISSING = "missing:"  # a key's checkpoint entry while its folder is not here (a dry run plans it; a run refuses)
ENV_PROVIDED = ("VISUAL", "STATE", "ENV", "ACTION")  # feature types the env decides (processors add others)
IMAGES_PREFIX = "observation.images."  # Factor World's observation: one image feature per camera
_HUB_ID = re.compile(r"[\w.-]+/[\w.-]+")


def is_hub_id(value: str) -> bool:
    """``user/name`` that is not a path on this machine: a Hub model id."""
    return bool(_HUB_ID.fullmatch(value)) and not value.startswith(".") and not os.path.exists(value)


def checkpoint_setting(value: str) -> str:
    """A method's ``checkpoint`` as the config keeps it: a Hub id as given, a path made absolute (steps and
    reports run from elsewhere)."""
    value = str(value).strip()
    if not value:
        raise ValueError("checkpoint is empty: give a pretrained_model folder (or a Hub model id)")
    return value if is_hub_id(value) else os.path.abspath(os.path.expanduser(value))


def local_folder(value: str) -> Path | None:
    """The checkpoint's folder on this machine: the path itself, or a Hub model already in the local cache
    (nothing is downloaded); ``None`` when there is neither."""
    if not is_hub_id(value):
        return Path(value) if Path(value).is_dir() else None
    try:
        return Path(huggingface_hub.snapshot_download(value, local_files_only=True))
    except Exception:  # noqa: BLE001 - not in the cache (or not a model): there is no local folder
        return None


def keyed_checkpoint(value: str) -> str:
    """The checkpoint as an evaluation's key holds it: the content hash of its files, or ``missing:<value>``
    while it is not on this machine (a dry run still plans; a run refuses before any step)."""
    folder = local_folder(value)
    return folder_fingerprint(folder) if folder is not None else MISSING + value


def fetch_checkpoint(value: str) -> Path:
    """The checkpoint's local folder, a Hub model downloaded first, which only a Hub id that is not in the
    cache asks for (after checking, with a short timeout, that the Hub answers). One-line errors."""
    folder = local_folder(value)
    if folder is not None:
        return folder
    if not is_hub_id(value):
        raise FileNotFoundError(
            f"checkpoint {value} does not exist: give a LeRobot pretrained_model folder (lerobot-train writes one "
            "at <output_dir>/checkpoints/last/pretrained_model) or a Hub model id"
        )
    try:
        check_hub_reachable()
        return Path(huggingface_hub.snapshot_download(value))
    except HubUnreachableError as err:
        raise FileNotFoundError(f"checkpoint {value} is not a local folder, and {err}") from None
    except Exception as err:  # noqa: BLE001 - e.g. no such repo on the Hub: one line, what was looked for
        raise FileNotFoundError(
            f"checkpoint {value} is neither a local folder nor a model on the Hugging Face Hub "
            f"({type(err).__name__}: {one_line(str(err))[:200]})"
        ) from None


def checkpoint_folder(value: str, keyed: str) -> Path:
    """The folder of a planned evaluation's checkpoint, refused when its content is no longer what the
    evaluation's key holds (the checkpoint changed after the study was planned)."""
    folder = local_folder(value)
    found = folder_fingerprint(folder) if folder is not None else None
    if found != keyed:
        raise RuntimeError(
            f"checkpoint {value} changed after the study was planned (content {found or 'gone'}, planned {keyed}): "
            "run the command again to plan its evaluations anew"
        )
    return folder


def read_policy_config(folder: str | Path) -> dict[str, Any]:
    """A checkpoint's ``config.json`` as plain settings (``type`` and the rest; ``{}`` when unreadable)."""
    try:
        return json.loads((Path(folder) / CONFIG_FILE).read_text())
    except (OSError, ValueError):
        return {}


def training_dataset(folder: Path | None) -> str | None:
    """The Factor World dataset a checkpoint was trained on: the ``dataset.root`` its ``train_config.json``
    names, when that folder is here and holds Factor World's side-car; ``None`` otherwise (a checkpoint
    trained elsewhere, on the Hub, or on other data). A relative root is read from the current folder, as
    lerobot-train was most likely started there."""
    if folder is None:
        return None
    try:
        root = json.loads((folder / TRAIN_CONFIG_FILE).read_text()).get("dataset", {}).get("root")
    except (OSError, ValueError, AttributeError):
        return None
    return str(root) if root and (Path(root) / SIDECAR).is_file() else None


# --- checks before any work --------------------------------------------------------------------------------


def fetch_checkpoints(values: list[str]) -> None:
    """Make every given checkpoint local before planning (a Hub model is downloaded, only then): a missing
    folder, an unreachable Hub or an unknown Hub model stops the command in one line."""
    for value in dict.fromkeys(values):
        fetch_checkpoint(value)


def check_checkpoints(evaluations: list[tuple[str, str, EnvInputs]]) -> None:
    """Refuse, in one line before any work, a checkpoint that is not a LeRobot ``pretrained_model`` or whose
    features are not what the env it is evaluated in gives; ``evaluations``: (method name, checkpoint,
    environments) of every given checkpoint's evaluation."""
    problems = checkpoint_problems(evaluations)
    if problems:
        raise ValueError(problems[0] + (f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""))


def checkpoint_problems(evaluations: list[tuple[str, str, EnvInputs]]) -> list[str]:
    """What :func:`check_checkpoints` would refuse, one line per method and observation (``--dry-run`` lists
    them); a checkpoint that is not on this machine yet is named once, nothing downloaded."""
    out: list[str] = []
    seen: set[tuple] = set()
    for method, value, env in evaluations:
        view = (method, value, env.obs, env.cameras, env.image_size, env.task)
        if view in seen or (method, value) in seen:  # one line per method and observation, checked once
            continue
        seen.add(view)
        folder = local_folder(value)
        problem = _pretrained_problem(folder) if folder is not None else None
        if folder is None or problem:  # the checkpoint itself: named once, whatever it is evaluated in
            seen.add((method, value))
            out.append(f"method {method!r}: checkpoint {value} {problem or 'is not on this machine'}")
            continue
        problem = _feature_problem(folder, env)
        if problem:
            out.append(f"method {method!r}: checkpoint {folder} {problem}")
    return out


def _pretrained_problem(folder: Path) -> str | None:
    """Why ``folder`` is not a LeRobot ``pretrained_model`` LeRobot can load, or ``None``."""
    missing = [name for name in PRETRAINED_FILES if not (folder / name).is_file()]
    if missing:
        return (
            f"is not a LeRobot pretrained_model folder: no {', '.join(missing)} in it (lerobot-train writes one at "
            "<output_dir>/checkpoints/last/pretrained_model)"
        )
    try:
        _policy_config(folder)
    except Exception as err:  # noqa: BLE001 - LeRobot's parser says why (unknown type, bad field): one line
        while err.__cause__ is not None:
            err = err.__cause__
        return f"has a config.json LeRobot cannot read as a policy config ({type(err).__name__}: {one_line(str(err))})"
    return None


def _policy_config(folder: Path):
    """LeRobot's policy config of a checkpoint, parsed as an evaluation parses it (plugins registered)."""
    # Deliberately here: LeRobot's policy configs (seconds to import), only when a checkpoint is checked.
    import lerobot.policies  # noqa: F401, PLC0415 - registers LeRobot's own policy types (act, diffusion, ...)
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415
    from lerobot.utils.import_utils import register_third_party_plugins  # noqa: PLC0415

    register_third_party_plugins()  # as lerobot-eval does: Factor World's policy types and any other plugin
    quiet = logging.getLogger()
    level, quiet.level = quiet.level, logging.ERROR  # parsing a config logs device warnings
    try:
        return PreTrainedConfig.from_pretrained(folder)
    finally:
        quiet.level = level


def _feature_problem(folder: Path, env: EnvInputs) -> str | None:
    """Why the checkpoint cannot run on ``env``'s observation, naming what it expects and what the env gives."""
    config = _policy_config(folder)
    given = _env_features(env)
    expected = {
        key: (ft.type.name, tuple(ft.shape))
        for key, ft in [*config.input_features.items(), *config.output_features.items()]
        if ft.type.name in ENV_PROVIDED
    }
    if all(given.get(key) == value for key, value in expected.items()):
        return None
    return f"expects {_features_text(expected)}, but the env ({_view(env)}) gives {_features_text(given)}" + _hint(
        expected, env
    )


def _env_features(env: EnvInputs) -> dict[str, tuple[str, tuple[int, ...]]]:
    """Policy feature -> (type, shape) as ``env`` gives them to a policy (LeRobot's ``env_to_policy_features``)."""
    # Deliberately here: LeRobot's env utilities (seconds to import), only when a checkpoint is checked.
    from lerobot.envs.utils import env_to_policy_features  # noqa: PLC0415

    return {key: (ft.type.name, tuple(ft.shape)) for key, ft in env_to_policy_features(env_config(env)).items()}


def _features_text(features: dict[str, tuple[str, tuple[int, ...]]]) -> str:
    return ", ".join(f"{key} {shape}" for key, (_, shape) in sorted(features.items()))


def _view(env: EnvInputs) -> str:
    if env.obs == LEROBOT_METAWORLD_OBS:
        return f"obs={env.obs}"
    return f"obs={env.obs}, cameras={env.cameras}, image_size={env.image_size}"


def _hint(expected: dict[str, tuple[str, tuple[int, ...]]], env: EnvInputs) -> str:
    """The observation the checkpoint was made for, when its features say so (LeRobot's metaworld env, or
    Factor World's cameras at one image size)."""
    made_for = _env_features(replace(env, obs=LEROBOT_METAWORLD_OBS))
    if all(made_for.get(key) == value for key, value in expected.items()):
        return f": it was made for LeRobot's metaworld env (obs={LEROBOT_METAWORLD_OBS})"
    images = {key: shape for key, (kind, shape) in expected.items() if kind == "VISUAL"}
    cameras = [key.removeprefix(IMAGES_PREFIX) for key in images if key.startswith(IMAGES_PREFIX)]
    sizes = {shape[-1] for shape in images.values()}
    if cameras and len(cameras) == len(images) and len(sizes) == 1:
        return f": it was made for obs={FACTORWORLD_OBS}, cameras={','.join(cameras)}, image_size={sizes.pop()}"
    return ""
