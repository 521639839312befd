"""How many pixels of a camera's image an object covers, counted by segmentation rendering of a compiled scene.

MuJoCo's segmentation rendering (``mujoco.Renderer.enable_segmentation_rendering``) draws, in every pixel,
the id and type of the front-most object there, so a count is of the pixels where the object is actually
seen: the arm, a distractor or the goal marker in front of it hide what they cover, as in the camera's
image. Segmentation draws the same geometry as the colour image (textures and lighting are off, not the
geoms), with one object per pixel at the quality ``fast`` renders (no multisampling).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from types import TracebackType

import mujoco
import numpy as np

from ..assets.scenes import VISIBLE_GROUPS
from .build import subtree_geoms


def visible_geoms(model: mujoco.MjModel, bodies: Sequence[str]) -> tuple[int, ...]:
    """The geoms drawn for ``bodies`` and every body below them: in a rendered group, with a visible colour.

    For a task's object (``TaskSpec.object_bodies``) these are the geoms the object-texture factor paints
    (:func:`lerobot_factorworld.scene.build.build_spec` uses the same rule)."""
    for name in bodies:
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) < 0:
            raise ValueError(f"no body {name!r} in the scene")
    return tuple(
        g for g in subtree_geoms(model, bodies) if model.geom_group[g] in VISIBLE_GROUPS and model.geom_rgba[g, 3] > 0
    )


class PixelCounter:
    """Segmentation renderers of one compiled model, one per (square) image size; close it when done
    (or use it as a context manager): each renderer holds a GL context."""

    def __init__(self, model: mujoco.MjModel, sizes: Iterable[int]) -> None:
        self.sizes = tuple(dict.fromkeys(int(s) for s in sizes))
        limit = min(int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
        bad = [s for s in self.sizes if not 1 <= s <= limit]
        if bad or not self.sizes:
            raise ValueError(
                f"image sizes must be in [1, {limit}] (the scene's offscreen buffer), got {list(self.sizes) or 'none'}"
            )
        self._renderers: dict[int, mujoco.Renderer] = {}
        try:
            for size in self.sizes:
                self._renderers[size] = mujoco.Renderer(model, height=size, width=size)
                self._renderers[size].enable_segmentation_rendering()
        except Exception:  # no GL context: release the ones made
            self.close()
            raise

    def masks(self, data: mujoco.MjData, camera: str, geoms: Collection[int]) -> dict[int, np.ndarray]:
        """Image size -> boolean (size, size) mask of ``camera``'s image: where one of ``geoms`` is the
        front-most object (rows top to bottom, as the colour image)."""
        wanted = np.fromiter(geoms, dtype=np.int64)
        out = {}
        for size, renderer in self._renderers.items():
            renderer.update_scene(data, camera=camera)
            seg = renderer.render()  # (h, w, 2): object id, object type; -1 where nothing is drawn
            out[size] = (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)) & np.isin(seg[..., 0], wanted)
        return out

    def count(self, data: mujoco.MjData, camera: str, geoms: Collection[int]) -> dict[int, int]:
        """Image size -> pixels of ``camera``'s image in which one of ``geoms`` is the front-most object."""
        return {size: int(np.count_nonzero(mask)) for size, mask in self.masks(data, camera, geoms).items()}

    def close(self) -> None:
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()

    def __enter__(self) -> PixelCounter:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()


def object_pixels(model: mujoco.MjModel, data: mujoco.MjData, bodies: Sequence[str], camera: str, size: int) -> int:
    """Pixels of ``camera``'s ``size`` x ``size`` image showing ``bodies`` (their visible geoms) in the scene's
    current state ``data``."""
    with PixelCounter(model, [size]) as counter:
        return counter.count(data, camera, visible_geoms(model, bodies))[size]
