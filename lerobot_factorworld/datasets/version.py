"""The version of what a collected dataset's data means, recorded with its settings.

Bump ``DATA_VERSION`` (and describe the new version) whenever a stored column or setting starts to mean
something else; ``factorworld collect`` never appends to, or resumes, data of another version. Kept free
of heavy imports: the check runs before any work starts.
"""

from __future__ import annotations

from typing import Any

DATA_VERSION = 3
DATA_VERSIONS = {
    1: "observation.state in the table's frame, Meta-World's pick-place goal, per-variant asset split",
    2: "observation.state in the robot's frame, the public Factor World pick-place goal on the table, "
    "asset_split recorded with the sampling settings",
    3: "observation.state in the robot's frame, the public Factor World pick-place goal on the table, "
    "textures a flat RGB colour with probability sampling.rgb_fraction (default 0.5, was 0), flat-colour "
    "object and distractor textures drawn in their colour (were white)",
}
DATA_VERSION_KEY = "data_version"  # in the settings of meta/factorworld.json and of a staged plan.json


def data_version(settings: dict[str, Any]) -> int:
    """The data version recorded in a collection's settings (version 1 recorded none)."""
    return int(settings.get(DATA_VERSION_KEY, 1))


def describe_data_version(version: int) -> str:
    return f"data version {version} ({DATA_VERSIONS.get(version, 'unknown to this version of lerobot_factorworld')})"
