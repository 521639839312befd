"""Scenes share one GL context per thread (``scene/renderer.py``): the frames are mujoco.Renderer's, bit for bit,
with several models' renderers alive at once, drawn in turn, closed and replaced."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import mujoco
import numpy as np
import pytest

from lerobot_factorworld.protocol.sampling import sample_configs
from lerobot_factorworld.scene.build import build_model
from lerobot_factorworld.scene.renderer import SharedContextRenderer, shared_gl_context

SIZE = 64


def _scenes() -> list[tuple[mujoco.MjModel, mujoco.MjData]]:
    """Three door-open scenes that differ in every drawn thing a renderer uploads (textures, lights, camera)."""
    configs = sample_configs("door-open", 3, 0, "train", ["camera_pos", "table_texture", "light"])
    scenes = []
    for config in configs:
        model = build_model("door-open", config.factors)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        scenes.append((model, data))
    return scenes


def _frames(make, scenes, cameras=("front", "corner")) -> list[np.ndarray]:
    """Every scene through every camera, twice, all renderers alive and drawn in turn; then one closed and a
    new one made in its place."""
    renderers = [make(model) for model, _ in scenes]
    frames = []
    for _ in range(2):
        for renderer, (_, data) in zip(renderers, scenes, strict=True):
            for camera in cameras:
                renderer.update_scene(data, camera=camera)
                frames.append(renderer.render().copy())
    renderers[0].close()
    renderers[0] = make(scenes[0][0])
    renderers[0].update_scene(scenes[0][1], camera=cameras[0])
    frames.append(renderers[0].render().copy())
    for renderer in renderers:
        renderer.close()
    return frames


def test_shared_context_frames_are_mujoco_renderers_frames_bit_for_bit():
    scenes = _scenes()
    reference = _frames(lambda model: mujoco.Renderer(model, SIZE, SIZE), scenes)
    shared = _frames(lambda model: SharedContextRenderer(model, SIZE, SIZE), scenes)
    assert len(shared) == len(reference) == 13
    assert len({frame.tobytes() for frame in reference}) == 6  # 3 scenes x 2 cameras, all different
    for i, (got, want) in enumerate(zip(shared, reference, strict=True)):
        np.testing.assert_array_equal(got, want, err_msg=f"frame {i}")


def test_one_context_per_thread_and_a_closed_renderer_refuses_to_draw():
    here = shared_gl_context(SIZE, SIZE)
    assert shared_gl_context(SIZE, SIZE) is here
    other = []
    thread = threading.Thread(target=lambda: other.append(shared_gl_context(SIZE, SIZE)))
    thread.start()
    thread.join()
    assert other[0] is not here
    model, data = _scenes()[0]
    renderer = SharedContextRenderer(model, SIZE, SIZE)
    renderer.update_scene(data, camera="front")
    assert renderer.render().shape == (SIZE, SIZE, 3)
    renderer.close()
    renderer.close()  # twice is harmless
    try:
        renderer.render()
    except RuntimeError as err:
        assert "after close" in str(err)
    else:
        raise AssertionError("a closed renderer drew a frame")


@pytest.mark.slow
def test_an_env_left_open_at_exit_prints_nothing():
    """A script that never closes its env exits quietly: the renderer's ``__del__`` at interpreter exit does not
    try to free GL resources through bindings already torn down (it used to print an ignored TypeError)."""
    script = (  # LeRobot's metaworld module first: with it, the GL bindings are torn down before the renderer
        "import lerobot.envs.metaworld\n"
        "from lerobot_factorworld.envs.factor_env import FactorWorldEnv\n"
        "env = FactorWorldEnv('door-open')\n"
        "env.reset(seed=0)\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "Exception ignored" not in proc.stderr and "Traceback" not in proc.stderr, proc.stderr[-2000:]


@pytest.mark.slow
def test_an_env_left_open_releases_its_renderers_when_collected_and_at_exit():
    """Not only close(): a collected env frees its scenes' GL resources, and a script that never closes its env
    ends without GL tracebacks (its renderers are released at exit, while GL is still loaded)."""
    script = """
import gc
from lerobot_factorworld.envs.factor_env import FactorWorldEnv
from lerobot_factorworld.protocol.sampling import sample_configs
configs = sample_configs("door-open", n=1, seed=0)
env = FactorWorldEnv("door-open", configs, image_size=16)
env.reset(seed=0)
scene = next(iter(env._scenes.values()))
del env
gc.collect()
assert scene._renderer is None, "a collected env kept its renderer"
env = FactorWorldEnv("door-open", configs, image_size=16)
env.reset(seed=0)
env.close()
env.reset(seed=1)  # a reset after close builds scenes again; left open at exit
print("ok")
"""
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env={**os.environ, "MUJOCO_GL": "egl"}
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert "Traceback" not in out.stderr and "Exception ignored" not in out.stderr, out.stderr


def test_shared_contexts_left_alive_are_dropped_at_exit_not_destroyed_after_egl_is_gone():
    """MuJoCo's EGL backend terminates its display in an exit hook; a shared context destroyed after that raised in
    ``GLContext.__del__`` ("Exception ignored", once per context, at every xdist worker's exit). The package's own
    exit hook drops their handles, so nothing is destroyed once the display is gone: here the contexts, one made
    in another thread, are deleted after the display is terminated, with and without that hook having run."""
    script = """
import sys, threading
from mujoco import egl
from lerobot_factorworld.scene import renderer
made = [renderer.shared_gl_context(32, 32)]
worker = threading.Thread(target=lambda: made.append(renderer.shared_gl_context(64, 64)))
worker.start(); worker.join()
if sys.argv[1] == "hook":
    renderer._forget_contexts_at_exit()
egl.EGL.eglTerminate(egl.EGL_DISPLAY)  # what MuJoCo's own exit hook does
renderer._local.contexts.clear()
del made
print("deleted")
"""
    if os.environ.get("MUJOCO_GL") != "egl":
        pytest.skip("the EGL backend's exit order")
    runs = {
        mode: subprocess.run([sys.executable, "-c", script, mode], capture_output=True, text=True, timeout=120)
        for mode in ("hook", "none")
    }
    assert runs["hook"].returncode == 0 and runs["hook"].stdout.strip() == "deleted", runs["hook"].stderr[-2000:]
    assert "Exception ignored" not in runs["hook"].stderr, runs["hook"].stderr[-2000:]
    assert "Exception ignored" in runs["none"].stderr  # without it, the noise this removes
