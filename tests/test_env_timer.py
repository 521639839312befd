"""An env's timing hook (``FactorWorldEnv.timer``): an evaluation times scene compilation and rendering on the env
instances it runs, not by patching ``CompiledScene`` for every env in the process."""

import contextlib

import numpy as np

from lerobot_factorworld.core.timing import Timings
from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.envs.runtime import CompiledScene
from lerobot_factorworld.protocol.sampling import sample_configs


def test_the_timer_sees_each_compilation_and_render_of_its_env_only():
    configs = sample_configs("door-open", n=2, seed=0)
    timed, plain = (FactorWorldEnv("door-open", configs, image_size=32, max_episode_steps=5) for _ in range(2))
    calls: list[str] = []

    @contextlib.contextmanager
    def record(name: str):
        calls.append(name)
        yield

    timed.timer = record
    render, init = CompiledScene.render_all, CompiledScene.__init__
    for seed in (1000, 1001, 1002):  # environments 0, 1, 0: the third reset reuses a compiled scene
        timed.reset(seed=seed)
        timed.step(np.zeros(4, dtype=np.float32))
        plain.reset(seed=seed)
        plain.step(np.zeros(4, dtype=np.float32))
    assert calls == ["scene_compile", "render", "render", "scene_compile", "render", "render", "render", "render"]
    assert (CompiledScene.render_all, CompiledScene.__init__) == (render, init)  # the class is untouched


def test_a_study_step_s_timings_hold_the_env_s_spans():
    timings = Timings()
    env = FactorWorldEnv("door-open", sample_configs("door-open", n=1, seed=0), image_size=32, max_episode_steps=3)
    env.timer = timings.span
    env.reset(seed=0)
    for _ in range(2):
        env.step(np.zeros(4, dtype=np.float32))
    assert timings.calls == {"scene_compile": 1, "render": 3}
    assert all(seconds > 0 for seconds in timings.seconds.values())
