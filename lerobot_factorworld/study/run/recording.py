"""Episodes recorded where they are made: an evaluation step records the furthest stage and length of every
episode, and the frames of its first ``eval.record_episodes`` episodes, through the env's own observer hook
(``FactorWorldEnv.episode_observer``), never by simulating them again. The frames are the first camera's, as
the policy saw them, written as WebM (VP9, through PyAV, the video stack LeRobot's datasets use) into the
step's folder and reused with it (``episode_videos.py`` gathers them for a report).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...envs.stages import STAGE_KEY

VIDEOS_DIR = "episodes"  # in a step's folder, and next to a study's report
RECORDED_KEY = "recorded"  # an eval step's result: the episodes it recorded (absent when none was)
MEASURES_KEY = "measures"  # an eval step's result: each episode's family measures (absent for a family with none)
RECORD_SETTING = "record_episodes"  # how an eval step runs (never in its key): episodes to record per condition
CODEC = "libvpx-vp9"  # WebM: every browser plays it, Chromium's open builds included
PLAYBACK_FPS = 20  # a quarter of Meta-World's 80 Hz control: a 200-step episode plays in 10 s, slow enough to follow


@dataclass
class EpisodeRecorder:
    """An env's ``episode_observer`` for one evaluation: per reset seed, the furthest stage, the steps and the
    family's ``measure_keys`` of every seeded episode (an unseeded one, begun by an autoreset that the rollout
    discards, is not recorded), and the frames of the episodes reset with one of ``record_seeds``."""

    record_seeds: frozenset[int] = frozenset()
    measure_keys: tuple[str, ...] = ()  # info keys kept from each episode's last step (TaskFamily.episode_measures)
    stages: dict[int, str] = field(default_factory=dict)
    measures: dict[int, dict[str, float]] = field(default_factory=dict)
    lengths: dict[int, int] = field(default_factory=dict)
    frames: dict[int, list[np.ndarray]] = field(default_factory=dict)
    _seed: dict[int, int | None] = field(default_factory=dict)  # id(env) -> seed of its current episode
    _steps: dict[int, int] = field(default_factory=dict)

    def on_reset(self, env: Any, seed: int | None, obs: dict, info: dict) -> None:
        self._seed[id(env)], self._steps[id(env)] = seed, 0
        if seed in self.record_seeds and seed not in self.stages:
            self.frames[seed] = []
            self._keep_frame(env, seed)

    def on_step(self, env: Any, obs: dict, terminated: bool, truncated: bool, info: dict) -> None:
        self._steps[id(env)] = self._steps.get(id(env), 0) + 1
        seed = self._seed.get(id(env))
        if seed is None or seed in self.stages:
            return
        if seed in self.frames:
            self._keep_frame(env, seed)
        if terminated or truncated:
            self.stages[seed], self.lengths[seed] = info[STAGE_KEY], self._steps[id(env)]
            if self.measure_keys:
                self.measures[seed] = {key: round(float(info[key]), 6) for key in self.measure_keys}

    def _keep_frame(self, env: Any, seed: int) -> None:
        frame = env.render()  # the observation's frame, already rendered: no second render
        if frame is not None:
            self.frames[seed].append(frame)


def write_webm(frames: Sequence[np.ndarray], path: Path, fps: int) -> Path:
    """``frames`` (H x W x 3 uint8) as a VP9 WebM at ``fps`` (odd sides lose their last row or column)."""
    import av  # noqa: PLC0415 - deliberately here: only a step that records episodes encodes video

    h, w = (d - d % 2 for d in frames[0].shape[:2])
    tmp = path.with_name(path.name + ".tmp")
    with av.open(str(tmp), mode="w", format="webm") as container:
        stream = container.add_stream(CODEC, rate=fps)
        stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
        stream.options = {"crf": "32", "b": "0", "deadline": "good", "cpu-used": "4", "threads": "1"}
        for frame in frames:
            image = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame[:h, :w]), format="rgb24")
            for packet in stream.encode(image):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    os.replace(tmp, path)
    return path


def write_recorded(
    recorder: EpisodeRecorder, seeds: Sequence[int], folder: Path, fps: int = PLAYBACK_FPS
) -> list[dict[str, Any]]:
    """The recorded episodes' videos in ``folder / VIDEOS_DIR``, and what the step's result says of them."""
    out = []
    for index, seed in enumerate(seeds):
        frames = recorder.frames.get(seed)
        if not frames:
            continue
        (folder / VIDEOS_DIR).mkdir(exist_ok=True)
        video = write_webm(frames, folder / VIDEOS_DIR / f"episode_{index:03d}.webm", fps)
        out.append({"index": index, "seed": seed, "video": video.relative_to(folder).as_posix(), "frames": len(frames)})
    return out
