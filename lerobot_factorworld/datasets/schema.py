"""The dataset's schema: frame features derived from the env, and typed per-episode factor columns.

Every episode row of ``meta/episodes`` carries ``factorworld/env_id``, ``factorworld/split`` and one
``factors/<name>`` column per factor (the values the scene really had). Column types are fixed per
factor so that every parquet file has one schema: vectors are lists of floats, scalars floats
(NaN when the factor does not apply to the task), assets strings ("" when not applicable) and
distractors a JSON list. :func:`decode_factors` turns a row back into typed values.
"""

from __future__ import annotations

import json
import math
from typing import Any

from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE

from ..factors.registry import FACTORS
from ..factors.values import SceneObject

FACTOR_PREFIX = "factors/"
META_PREFIX = "factorworld/"
ENV_ID_COLUMN = META_PREFIX + "env_id"
SPLIT_COLUMN = META_PREFIX + "split"
STATE_NAMES = ["x", "y", "z", "gripper", "prev_x", "prev_y", "prev_z", "prev_gripper"]
ACTION_NAMES = ["dx", "dy", "dz", "grip"]


def frame_features(cameras: tuple[str, ...], image_size: tuple[int, int], use_videos: bool = True) -> dict:
    """LeRobot features of a Factor World frame (keys match ``FactorWorldEnvConfig.features_map``)."""
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
        from dataclasses import asdict

        return asdict(value)
    return dict(value)
