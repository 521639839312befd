"""The normalised triangle mesh every shape source (procedural, Meta-World, user file) is turned into.

Normalising in one place means a scene builder can scale any asset by a single number: every mesh sits on
z = 0, is centred in x and y, and its largest bounding-box extent is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

Array = np.ndarray

MAX_FACES = 5000
"""Meshes with more faces are simplified on load (vertex clustering): MuJoCo rebuilds scenes often."""


@dataclass(frozen=True)
class Mesh:
    """A normalised triangle mesh ready for ``MjSpec.add_mesh(uservert=..., userface=...)``.

    ``vertices`` is (N, 3) float32 and ``faces`` (M, 3) int32 with counter-clockwise (outward) winding.
    Both arrays are read-only because loaded meshes are cached and shared.
    """

    vertices: Array
    faces: Array

    @property
    def extents(self) -> Array:
        """Bounding-box size along x, y, z (the largest is 1.0)."""
        return self.vertices.max(axis=0) - self.vertices.min(axis=0)


def face_areas(vertices: Array, faces: Array) -> Array:
    """Area of every triangle."""
    v = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)


def signed_volume(vertices: Array, faces: Array) -> float:
    """Enclosed volume; positive when faces wind counter-clockwise seen from outside."""
    v = np.asarray(vertices, dtype=np.float64)[faces]
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


def is_watertight(faces: Array) -> bool:
    """Every directed edge appears once and its reverse once: closed, manifold, consistently oriented."""
    f = np.asarray(faces, dtype=np.int64)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    n = int(f.max()) + 1
    fwd = edges[:, 0] * n + edges[:, 1]
    rev = edges[:, 1] * n + edges[:, 0]
    if len(np.unique(fwd)) != len(fwd):
        return False
    return bool(np.array_equal(np.sort(fwd), np.sort(rev)))


def weld(vertices: Array, faces: Array) -> tuple[Array, Array]:
    """Merge bit-identical vertices (STL stores three per triangle) and re-index the faces."""
    uniq, inverse = np.unique(vertices, axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)[faces]


def _clean(vertices: Array, faces: Array) -> tuple[Array, Array]:
    """Drop repeated-index, zero-area and duplicate faces, then unreferenced vertices."""
    f = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
    if len(f):
        scale = float(np.ptp(vertices, axis=0).max()) or 1.0
        f = f[face_areas(vertices, f) > 1e-12 * scale * scale]
    if len(f):
        _, keep = np.unique(np.sort(f, axis=1), axis=0, return_index=True)
        f = f[np.sort(keep)]
    used, f = np.unique(f, return_inverse=True)
    return vertices[used], f.reshape(-1, 3)


def decimate(vertices: Array, faces: Array, max_faces: int = MAX_FACES) -> tuple[Array, Array]:
    """Vertex-clustering simplification: snap to an ever coarser grid until at most ``max_faces`` remain.

    Crude but deterministic and dependency-free; MuJoCo collides with the convex hull anyway, so only the
    rendered detail is affected.
    """
    lo = vertices.min(axis=0)
    scale = float(np.ptp(vertices, axis=0).max()) or 1.0
    res = 256
    while True:
        cells = np.floor((vertices - lo) / scale * res).astype(np.int64)
        _, inverse = np.unique(cells, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        sums = np.zeros((inverse.max() + 1, 3))
        np.add.at(sums, inverse, vertices)
        counts = np.bincount(inverse)[:, None]
        v, f = _clean(sums / counts, inverse[faces])
        if len(f) <= max_faces or res <= 4:
            return v, f
        # face count scales with the square of the grid resolution: jump close to the target at once
        res = max(4, min(int(res * 0.9), int(res * 0.95 * (max_faces / len(f)) ** 0.5)))


def normalize_mesh(vertices: Array, faces: Array, max_faces: int = MAX_FACES) -> Mesh:
    """Clean, orient and normalise raw arrays into a :class:`Mesh`.

    Raises ``ValueError`` when nothing three-dimensional is left (MuJoCo needs >= 4 non-coplanar vertices).
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"expected (N, 3) vertices and (M, 3) faces, got {v.shape} and {f.shape}")
    if len(f) == 0 or f.min() < 0 or f.max() >= len(v):
        raise ValueError("faces are empty or index vertices that do not exist")
    if not np.isfinite(v).all():
        raise ValueError("vertices contain NaN or infinity")
    v, f = weld(v, f)
    v, f = _clean(v, f)
    if len(f) > max_faces:
        v, f = decimate(v, f, max_faces)
    if len(v) < 4:
        raise ValueError(f"mesh has {len(v)} usable vertices; MuJoCo needs at least 4 non-coplanar ones")
    sv = np.linalg.svd(v - v.mean(axis=0), compute_uv=False)
    if sv[2] <= 1e-6 * sv[0]:
        raise ValueError("mesh is flat (all vertices coplanar); MuJoCo cannot build a volume from it")
    if signed_volume(v, f) < 0:
        f = f[:, ::-1]
    lo, hi = v.min(axis=0), v.max(axis=0)
    ext = float((hi - lo).max())
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    v32 = ((v - centre) / ext).astype(np.float32)
    f32 = np.ascontiguousarray(f, dtype=np.int32)
    v32.flags.writeable = False
    f32.flags.writeable = False
    return Mesh(vertices=v32, faces=f32)


def convex_hull(points: Array) -> Array:
    """Triangles (outward, indices into ``points``) of the convex hull; incremental, O(n^2) for small n.

    Points inside or on the hull are skipped. Used by the ``hull`` and ``polyhedron`` shape families, so
    that no SciPy/Qhull dependency is needed.
    """
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    scale = float(np.ptp(p, axis=0).max())
    eps = 1e-9 * max(scale, 1e-12)
    # initial tetrahedron: two extreme points, the farthest from their line, the farthest from that plane
    i0 = int(np.argmin(p[:, 0]))
    i1 = int(np.argmax(np.linalg.norm(p - p[i0], axis=1)))
    d_line = np.linalg.norm(np.cross(p - p[i0], p[i1] - p[i0]), axis=1)
    i2 = int(np.argmax(d_line))
    normal = np.cross(p[i1] - p[i0], p[i2] - p[i0])
    d_plane = (p - p[i0]) @ normal
    i3 = int(np.argmax(np.abs(d_plane)))
    if d_line[i2] <= eps or abs(d_plane[i3]) <= eps * scale:
        raise ValueError("points are degenerate (collinear or coplanar); no 3-D hull")
    if d_plane[i3] > 0:
        i1, i2 = i2, i1
    faces = [(i0, i1, i2), (i0, i3, i1), (i1, i3, i2), (i2, i3, i0)]
    for k in range(n):
        if k in (i0, i1, i2, i3):
            continue
        tri = np.array(faces)
        a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
        nrm = np.cross(b - a, c - a)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        visible = np.einsum("ij,ij->i", nrm, p[k] - a) > eps
        if not visible.any():
            continue
        vis_edges = {(int(e0), int(e1)) for t in tri[visible] for e0, e1 in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
        horizon = [(e0, e1) for e0, e1 in vis_edges if (e1, e0) not in vis_edges]
        faces = [tuple(int(i) for i in t) for t in tri[~visible]]
        faces.extend((e0, e1, k) for e0, e1 in sorted(horizon))
    return np.array(faces, dtype=np.int64)
