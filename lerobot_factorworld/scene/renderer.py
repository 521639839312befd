"""A ``mujoco.Renderer`` that shares one GL context per thread with every other one of its kind.

``mujoco.Renderer`` creates a GL context (EGL, OSMesa or GLFW) for each model it renders. On Mesa's
software rasteriser a new context also starts its shader compiler cold: creating one costs about 0.3 s and
its first frame a few times a later one, per compiled scene. A study builds a scene per environment per
condition, so an evaluation paid that for every environment it showed the policy. :class:`SharedContextRenderer`
keeps a new ``MjrContext`` per model (its meshes, textures and offscreen framebuffer, exactly what
``mujoco.Renderer`` uploads) in a context that lives as long as the thread, and selects its own
framebuffer before every frame (``mjr_render`` draws into whichever one is bound). Frames are bit-identical
to ``mujoco.Renderer``'s (``tests/test_renderer.py`` checks, interleaving several models).
"""

from __future__ import annotations

import atexit
import os
import sys
import threading
import weakref

import mujoco
from mujoco import gl_context

_local = threading.local()  # per thread: {(width, height): (pid, GLContext)}
_made: weakref.WeakSet = weakref.WeakSet()  # every shared context alive in this process, whichever thread made it


def shared_gl_context(width: int, height: int):
    """This thread's GL context for ``width`` x ``height`` frames (EGL ignores the size, OSMesa does not),
    created at the first call. A context inherited through ``fork`` belongs to the parent: a new one is made."""
    contexts = getattr(_local, "contexts", None)
    if contexts is None:
        contexts = _local.contexts = {}
    pid, context = contexts.get((width, height), (None, None))
    if pid != os.getpid():
        context = gl_context.GLContext(width, height)
        contexts[(width, height)] = (os.getpid(), context)
        _made.add(context)
    return context


@atexit.register
def _forget_contexts_at_exit() -> None:
    """Drop the handles of the shared contexts still alive when the interpreter exits, rather than destroy them
    later: MuJoCo's EGL backend terminates its display in an exit hook of its own, and a context destroyed after
    that raises in its ``__del__`` (printed as "Exception ignored in GLContext.__del__"). The process's contexts go
    with it."""
    for context in list(_made):
        context._context = None  # what every backend's GLContext.free() tests before destroying


class SharedContextRenderer(mujoco.Renderer):
    """``mujoco.Renderer(model, height, width)`` drawing in this thread's shared GL context (see the module
    docstring); ``render``, ``update_scene`` and the rest are ``mujoco.Renderer``'s. Use it from the thread
    that made it."""

    def __init__(self, model: mujoco.MjModel, height: int = 240, width: int = 320, max_geom: int = 10000) -> None:
        # What mujoco.Renderer.__init__ does, with the shared context instead of a new one.
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            mujoco.Renderer(model, height, width, max_geom)  # raises mujoco's own error, naming the fix
        self._width, self._height, self._model = width, height, model
        self._scene = mujoco.MjvScene(model=model, maxgeom=max_geom)
        self._scene_option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._gl_context = shared_gl_context(width, height)
        self._gl_context.make_current()
        self._mjr_context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr_context)
        self._mjr_context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._depth_rendering = False
        self._segmentation_rendering = False

    def render(self, *, out=None):
        if self._mjr_context is None:
            raise RuntimeError("render cannot be called after close.")
        self._gl_context.make_current()
        # Another model's MjrContext in this context may have bound its framebuffer since our last frame.
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr_context)
        return super().render(out=out)

    def close(self) -> None:
        """Free this model's GL resources; the shared context stays for the next renderer. At interpreter exit
        (an env never closed, its renderer collected by ``__del__``) there is nothing to free: the GL library's
        bindings may already be gone, and the process's contexts go with it."""
        if self._mjr_context is not None and not sys.is_finalizing():
            self._gl_context.make_current()
            self._mjr_context.free()
        self._mjr_context = None
