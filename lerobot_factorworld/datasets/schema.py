"""The dataset's schema: frame features derived from the env, and typed per-episode factor columns.

Every episode row of ``meta/episodes`` carries ``factorworld/env_id``, ``factorworld/split``, the
episode's ``factorworld/instruction``, ``factorworld/target`` (the named object of a ``pick`` episode,
else empty) and ``factorworld/objects`` (a pick scene's objects and their poses as a JSON list, else
``[]``), and one ``factors/<name>`` column per factor (the values the scene really had). Column types are fixed per
factor so that every parquet file has one schema: vectors are lists of floats, scalars floats
(NaN when the factor does not apply to the task), assets strings ("" when not applicable) and
distractors a JSON list. :func:`decode_factors` turns a row back into typed values.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from typing import Any

from ..factors.registry import FACTORS
from ..factors.values import SceneObject
from ..families import family_of

FACTOR_PREFIX = "factors/"
META_PREFIX = "factorworld/"
ENV_ID_COLUMN = META_PREFIX + "env_id"
SPLIT_COLUMN = META_PREFIX + "split"
INSTRUCTION_COLUMN = META_PREFIX + "instruction"
TARGET_COLUMN = META_PREFIX + "target"
OBJECTS_COLUMN = META_PREFIX + "objects"
STATE_NAMES = ["x", "y", "z", "gripper", "prev_x", "prev_y", "prev_z", "prev_gripper"]
ACTION_NAMES = ["dx", "dy", "dz", "grip"]


def frame_features(cameras: tuple[str, ...], image_size: tuple[int, int], use_videos: bool = True) -> dict:
    """LeRobot features of a Factor World frame (keys match ``FactorWorldEnvConfig.features_map``)."""
    # LeRobot's names, imported here: the column names above are read by the dataset card and a study's report,
    # which load no LeRobot (importing it loads torch: seconds)
    from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE  # noqa: PLC0415

    h, w = image_size
    features = {
        f"{OBS_IMAGES}.{cam}": {
            "dtype": "video" if use_videos else "image",
            "shape": (h, w, 3),
            "names": ["height", "width", "channels"],
        }
        for cam in cameras
    }
    features[OBS_STATE] = {"dtype": "float32", "shape": (len(STATE_NAMES),), "names": STATE_NAMES}
    features[ACTION] = {"dtype": "float32", "shape": (len(ACTION_NAMES),), "names": ACTION_NAMES}
    return features


def encode_factors(factors: dict[str, Any]) -> dict[str, Any]:
    """Resolved factor values (``info["factors"]``) -> typed episode columns."""
    out = {}
    for name, spec in FACTORS.items():
        value = factors.get(name)
        if spec.kind == "vector":
            out[FACTOR_PREFIX + name] = [float(v) for v in value] if value is not None else []
        elif spec.kind == "scalar":
            out[FACTOR_PREFIX + name] = float(value) if value is not None else math.nan
        elif spec.kind == "asset":
            out[FACTOR_PREFIX + name] = str(value) if value is not None else ""
        else:
            out[FACTOR_PREFIX + name] = json.dumps([_object_dict(v) for v in value or ()], sort_keys=True)
    return out


def encode_episode(info: dict[str, Any], instruction: str, task: str) -> dict[str, Any]:
    """An episode's instruction and, for a task family with content (the pick family), its named object
    and objects (the episode record ``info`` holds under the family's content key) -> columns."""
    key = family_of(task).content_key
    record = (info.get(key) if key else None) or {}
    return {
        INSTRUCTION_COLUMN: instruction,
        TARGET_COLUMN: record.get("target", ""),
        OBJECTS_COLUMN: json.dumps(record.get("objects", []), sort_keys=True),
    }


def decode_episode(row: dict[str, Any]) -> dict[str, Any]:
    """``instruction``, ``target`` (``None`` outside the pick family) and ``objects`` (dicts with ``name``,
    ``x``, ``y``, ``yaw``) of an episode row; ``None``/``[]`` for datasets collected before these columns."""
    return {
        "instruction": row.get(INSTRUCTION_COLUMN),
        "target": row.get(TARGET_COLUMN) or None,
        "objects": json.loads(row.get(OBJECTS_COLUMN) or "[]"),
    }


def decode_factors(row: dict[str, Any]) -> dict[str, Any]:
    """An episode row -> factor values with their Python types (``None`` where not applicable)."""
    out: dict[str, Any] = {}
    for name, spec in FACTORS.items():
        value = row[FACTOR_PREFIX + name]
        if spec.kind == "vector":
            out[name] = tuple(float(v) for v in value) if len(value) else None
        elif spec.kind == "scalar":
            out[name] = None if value is None or math.isnan(value) else float(value)
        elif spec.kind == "asset":
            out[name] = value or None
        else:
            out[name] = tuple(SceneObject(**item) for item in json.loads(value))
    return out


def _object_dict(value: Any) -> dict:
    if isinstance(value, SceneObject):
        return asdict(value)
    return dict(value)
