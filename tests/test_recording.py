"""Episodes recorded where they are made (study/run/recording.py): the env's observer hook gives every seeded
episode's furthest stage and length, and the first episodes' frames as the policy saw them; they are written as
WebM videos that decode to the same number of frames."""

import av
import numpy as np

from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.protocol.sampling import sample_configs, shift_configs
from lerobot_factorworld.study.run.recording import EpisodeRecorder, write_recorded


def _run(env: FactorWorldEnv, seed: int, steps: int) -> list[np.ndarray]:
    """An episode of ``steps`` random actions; the observations' frames."""
    obs, _ = env.reset(seed=seed)
    frames = [obs["pixels"]["front"]]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 4).astype(np.float32))
        frames.append(obs["pixels"]["front"])
        if terminated or truncated:
            break
    return frames


def test_the_observer_records_stages_lengths_and_the_first_episodes_frames(tmp_path):
    train = sample_configs("door-open", n=2, seed=0)
    env = FactorWorldEnv("door-open", train, image_size=32, max_episode_steps=6)
    recorder = EpisodeRecorder(frozenset({1000}))
    env.episode_observer = recorder
    seen = {seed: _run(env, seed, 10) for seed in (1000, 1001)}
    env.reset()  # an unseeded reset (an autoreset) records nothing
    env.step(np.zeros(4, dtype=np.float32))
    assert recorder.lengths == {1000: 6, 1001: 6}
    assert set(recorder.stages) == {1000, 1001}
    assert set(recorder.frames) == {1000}  # only the seeds asked for
    assert len(recorder.frames[1000]) == 7  # the reset's frame and one per step
    assert all(np.array_equal(a, b) for a, b in zip(recorder.frames[1000], seen[1000]))  # what the policy saw

    written = write_recorded(recorder, [1000, 1001], tmp_path, fps=80)
    assert written == [{"index": 0, "seed": 1000, "video": "episodes/episode_000.webm", "frames": 7}]
    with av.open(str(tmp_path / written[0]["video"])) as video:
        frames = [f.to_ndarray(format="rgb24") for f in video.decode(video=0)]
    assert len(frames) == 7 and frames[0].shape == (32, 32, 3)
    assert np.abs(frames[3].astype(int) - seen[1000][3].astype(int)).mean() < 12  # lossy, but the same picture
    env.close()


def test_paired_episodes_start_alike_under_a_shift():
    """Episode i of train and of a shifted condition start the object at the same place: the viewer's pairs."""
    train = sample_configs("pick-place", n=2, seed=0)
    shifted = shift_configs(train, "camera_pos", n=2, seed=1)
    starts = []
    for configs in (train, shifted):
        env = FactorWorldEnv("pick-place", configs, image_size=16)
        _, info = env.reset(seed=1003)
        starts.append(info["factors"]["object_pos"])
        env.close()
    assert starts[0] == starts[1]


def test_nothing_is_recorded_when_no_episode_is_asked_for(tmp_path):
    recorder = EpisodeRecorder()
    env = FactorWorldEnv("door-open", sample_configs("door-open", n=1, seed=0), image_size=16, max_episode_steps=2)
    env.episode_observer = recorder
    _run(env, 1000, 3)
    env.close()
    assert recorder.frames == {} and recorder.lengths == {1000: 2}
    assert write_recorded(recorder, [1000], tmp_path, fps=80) == []
    assert not (tmp_path / "episodes").exists()
