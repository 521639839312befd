"""Scene cameras Factor World adds to every task, defined by position and look-at target.

They are world-fixed (the camera factor perturbs their pose; the table factor moves the table, not
them). Images are upright, unlike Meta-World's ``corner2`` which LeRobot has to flip.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from ..core.checks import split_list


@dataclass(frozen=True)
class CameraSpec:
    name: str
    pos: tuple[float, float, float]
    target: tuple[float, float, float]
    fovy: float = 45.0

    def quat(self) -> np.ndarray:
        """MuJoCo (w, x, y, z) orientation looking from ``pos`` at ``target`` with world z up."""
        return look_at_quat(np.asarray(self.pos, float), np.asarray(self.target, float))


def look_at_quat(pos: np.ndarray, target: np.ndarray) -> np.ndarray:
    forward = target - pos
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.array([0.0, 0.0, 1.0]))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    mat = np.stack([right, up, -forward], axis=1)  # camera axes as columns: x right, y up, looks along -z
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, mat.flatten())
    return quat


CAMERAS: dict[str, CameraSpec] = {
    cam.name: cam
    for cam in (
        # Over the robot's right shoulder: sees every fixture's handle side, the gripper and the table.
        CameraSpec("front", pos=(0.75, 0.2, 0.95), target=(-0.05, 0.7, 0.0), fovy=45.0),
        # Low from the right of the table.
        CameraSpec("side", pos=(1.05, 0.45, 0.55), target=(0.0, 0.7, 0.05), fovy=45.0),
        # Straight down on the workspace.
        CameraSpec("top", pos=(0.0, 0.5, 1.4), target=(0.0, 0.65, 0.0), fovy=45.0),
        # From the far side of the table facing the robot, like the public Factor World "movable" camera
        # (fixtures show their backs from here).
        CameraSpec("far", pos=(-0.55, 1.55, 0.85), target=(0.0, 0.55, 0.0), fovy=45.0),
    )
}
"""Factor World's scene cameras by name; ``front`` is the default observation camera."""

DEFAULT_CAMERAS = ("front",)
"""The default observation cameras: every default camera of the package derives from this one."""
DEFAULT_CAMERAS_SETTING = ",".join(DEFAULT_CAMERAS)  # its spelling in a config or on the command line
DEFAULT_IMAGE_SIZE = 84
"""The default square image side in pixels (the paper's): every default image size derives from this one."""


def check_camera_names(names: tuple[str, ...] | list[str], allow_none: bool = False) -> tuple[str, ...]:
    names = tuple(names)
    unknown = [n for n in names if n not in CAMERAS]
    if unknown or (not names and not allow_none) or len(set(names)) != len(names):
        raise ValueError(f"bad camera list {names!r}; valid cameras: {', '.join(CAMERAS)} (each at most once)")
    return names


def check_cameras(cameras: str | Sequence[str], setting: str = "cameras") -> tuple[str, ...]:
    """Camera names (comma-separated) -> tuple; at least one, each once, all known."""
    names = split_list(cameras)
    try:
        return check_camera_names(names)
    except ValueError:
        raise ValueError(
            f"bad {setting} {','.join(names) or '(none)'!s}; valid cameras: {', '.join(CAMERAS)} "
            "(at least one, each at most once, comma-separated)"
        ) from None
