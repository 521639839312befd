"""LeRobot's ``--env.type=metaworld`` observation on a Factor World scene (``obs="lerobot_metaworld"``).

LeRobot 0.6.1's Meta-World env (``lerobot.envs.metaworld.MetaworldEnv``) observes one 480 x 480 image from
Meta-World's ``corner2`` camera, moved to ``(0.75, 0.075, 0.7)`` (the position of Meta-World's ``corner4``)
and flipped on both axes, plus ``agent_pos`` = the first four numbers of Meta-World's state vector (hand
position and gripper opening, float64). Its episodes start where Meta-World's own seeded draw puts the
object and goal (``env.seed(seed)`` then a reset with ``seeded_rand_vec``). Reproducing all of that here
lets a checkpoint trained with LeRobot's env or data run on Factor World scenes unchanged; the factors
apply on top:

* ``corner2`` is Meta-World's own camera, in every compiled scene: the camera factor perturbs it as it
  perturbs Factor World's cameras (position plus quaternion offset) and the table factor moves it with the
  robot;
* ``agent_pos`` is in the robot's frame (:func:`lerobot_factorworld.scene.build.robot_frame_offset`), as
  Factor World's own proprioception: under a table shift the hand reads as if the table had moved;
* the object starts at Meta-World's seeded draw unless the configuration pins ``object_pos`` (then at
  Meta-World's nominal start plus the offset, as in Factor World); the arm factor moves the hand's start.

This module mirrors LeRobot's constants but does not import LeRobot (the simulation layer stays free of
it): the task descriptions are read from the JSON file LeRobot installs next to its Meta-World env.
"""

from __future__ import annotations

import importlib.util
import json
from functools import cache
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from ..core.checks import check_choice
from ..factors.values import FactorValues
from ..tasks import TaskSpec
from .metaworld import move_hand, reset_frozen_at, seeded_reset
from .runtime import CompiledScene

FACTORWORLD_OBS = "factorworld"
LEROBOT_METAWORLD_OBS = "lerobot_metaworld"
OBS_MODES = (FACTORWORLD_OBS, LEROBOT_METAWORLD_OBS)
"""Observation settings of ``FactorWorldEnv``: Factor World's own (cameras, 8-number state) or LeRobot's
Meta-World env's."""

CAMERA = "corner2"
IMAGE_SIZE = 480
CAMERA_POS = (0.75, 0.075, 0.7)  # LeRobot: ``env.model.cam_pos[2] = [0.75, 0.075, 0.7]`` (camera 2 is corner2)
STATE_DIM = 4  # hand x, y, z and gripper opening: Meta-World's state vector [:4]
STATE_BOUND = 1000.0  # LeRobot's agent_pos Box(-1000, 1000, (4,), float64)
_LEROBOT_CONFIG = ("envs", "metaworld_config.json")  # LeRobot's task descriptions, relative to its package


def check_obs_mode(obs: str) -> str:
    check_choice("obs", obs, OBS_MODES)
    return obs


def check_lerobot_task(task: TaskSpec) -> None:
    """Only a plain Meta-World task has a LeRobot Meta-World counterpart (a family's task has none)."""
    if task.family:
        raise ValueError(
            f"obs={LEROBOT_METAWORLD_OBS} needs a Meta-World task; {task.name!r} is a Factor World "
            f"{task.family!r}-family task with no counterpart in LeRobot's metaworld env"
        )


@cache
def lerobot_task_descriptions() -> dict[str, str]:
    """LeRobot's Meta-World task texts (what its env passes as ``task``), from the installed LeRobot's file."""
    spec = importlib.util.find_spec("lerobot")  # locates the package without importing it
    if spec is None or spec.origin is None:
        raise ValueError(f"obs={LEROBOT_METAWORLD_OBS} needs LeRobot installed (its Meta-World task texts)")
    path = Path(spec.origin).parent.joinpath(*_LEROBOT_CONFIG)
    return dict(json.loads(path.read_text())["TASK_DESCRIPTIONS"])


class LeRobotMetaworldObs:
    """What a ``FactorWorldEnv`` does differently under ``obs="lerobot_metaworld"``: the observation space,
    the camera, the episode start and the task text of LeRobot's Meta-World env.

    Attributes:
        task_description: LeRobot's text for the task (a language-conditioned checkpoint reads it).
        image_size: (height, width) of the image: LeRobot's 480 x 480.
        observation_space: LeRobot's: ``pixels`` uint8 (480, 480, 3), ``agent_pos`` float64 (4,).
    """

    def __init__(self, task: TaskSpec) -> None:
        check_lerobot_task(task)
        self.task_description = lerobot_task_descriptions()[task.metaworld_name]
        self.image_size = (IMAGE_SIZE, IMAGE_SIZE)
        self.observation_space = gym.spaces.Dict(
            {
                "pixels": gym.spaces.Box(0, 255, (IMAGE_SIZE, IMAGE_SIZE, 3), dtype=np.uint8),
                "agent_pos": gym.spaces.Box(-STATE_BOUND, STATE_BOUND, (STATE_DIM,), dtype=np.float64),
            }
        )

    def prepare_scene(self, scene: CompiledScene, factors: FactorValues) -> None:
        """Place ``corner2`` where LeRobot puts it (then the table and camera factors) and render it.

        The scene is compiled without Factor World's cameras: ``corner2`` comes with Meta-World's XML.
        """
        place_camera(scene.model, scene.robot_offset, factors.camera_pos)
        scene.cameras = (CAMERA,)

    def start_episode(self, scene: CompiledScene, seed: int, factors: FactorValues) -> tuple[float, float]:
        """Reset ``scene`` where LeRobot's env starts the episode of ``seed``; returns the object's offset from
        Meta-World's nominal start (what ``info["factors"]["object_pos"]`` reports)."""
        env = scene.env
        move_hand(env, factors.arm_pos or (0.0, 0.0, 0.0))
        obs, drawn = seeded_reset(env, seed)
        rand_vec = drawn.copy()
        if factors.object_pos is not None:
            rand_vec[:2] = env._factorworld_nominal[:2] + np.asarray(factors.object_pos, dtype=np.float64)
        if scene.task.object_is_free:
            rand_vec[2] += scene.rest_shift  # a resized object rests on the table as before
        if not np.array_equal(rand_vec, drawn):  # a factor moved the start: reset again, frozen at it
            obs = reset_frozen_at(env, rand_vec)
        scene.metaworld_obs = obs
        offset = rand_vec[:2] - env._factorworld_nominal[:2]
        return float(offset[0]), float(offset[1])

    def observe(self, scene: CompiledScene, mw_obs: np.ndarray) -> dict[str, Any]:
        """``pixels``: ``corner2`` flipped on both axes, as LeRobot flips it; ``agent_pos``: the hand and
        gripper in the robot's frame, float64 as Meta-World returns them."""
        frame = scene.render_all()[CAMERA]
        agent_pos = np.array(mw_obs[:STATE_DIM], dtype=np.float64)
        agent_pos[:3] += scene.robot_offset
        return {"pixels": np.flip(frame, (0, 1)).copy(), "agent_pos": agent_pos}


def place_camera(model: Any, robot_offset: np.ndarray, camera_pos: tuple[float, ...] | None) -> None:
    """Move ``corner2`` to LeRobot's position, carried with the robot side (table factor, ``-robot_offset``),
    and perturb it by the camera factor as ``scene.build`` perturbs Factor World's cameras."""
    cam = model.camera(CAMERA).id
    pos = np.asarray(CAMERA_POS, dtype=np.float64) - np.asarray(robot_offset, dtype=np.float64)
    quat = np.array(model.cam_quat[cam], dtype=np.float64)
    if camera_pos is not None:
        pos = pos + np.asarray(camera_pos[:3], dtype=np.float64)
        quat = quat + np.asarray(camera_pos[3:], dtype=np.float64)
        quat /= np.linalg.norm(quat)
    model.cam_pos[cam] = pos
    model.cam_quat[cam] = quat
