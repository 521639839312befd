"""Procedural mesh families: object-like shapes a robot could find on a table.

Factor World swapped objects for Google Scanned Objects; offline, we generate closed, outward-facing
triangle meshes from a handful of constructions (revolution, extrusion, voxels, convex hulls, sweeps).
Each family draws all parameters from the generator it is given, so a name always yields the same
vertices. Every family stays under ~1000 faces to keep MuJoCo compilation fast.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .mesh import Mesh, convex_hull, is_watertight, normalize_mesh, signed_volume

Array = np.ndarray
Raw = tuple[Array, Array]
ShapeFn = Callable[[np.random.Generator], Raw]

# ----------------------------------------------------------------------------------------------------------
# construction helpers


def _oriented(v: Array, f: Array) -> Raw:
    """Flip a closed component inside out if needed, so that faces point outwards."""
    return (v, f[:, ::-1].copy()) if signed_volume(v, f) < 0 else (v, f)


def _combine(parts: Sequence[Raw]) -> Raw:
    """Concatenate closed components (they may interpenetrate, like a mug and its handle)."""
    vs, fs, off = [], [], 0
    for v, f in parts:
        vs.append(v)
        fs.append(f + off)
        off += len(v)
    return np.concatenate(vs), np.concatenate(fs)


def _surface(rings: Sequence[Array], first: Array | None, last: Array | None, closed: bool = False) -> Raw:
    """Stitch rings of equal vertex count into a tube; ``first``/``last`` are pole vertices closing the
    ends with fans, ``closed`` joins the last ring back to the first (torus topology)."""
    r = len(rings)
    n = len(rings[0])
    verts = [np.asarray(ring, dtype=np.float64) for ring in rings]
    j = np.arange(n)
    jn = (j + 1) % n
    faces = []
    for i in range(r - 1 + int(closed)):
        a, b = i * n, ((i + 1) % r) * n
        faces.append(np.stack([a + j, a + jn, b + jn], 1))
        faces.append(np.stack([a + j, b + jn, b + j], 1))
    count = r * n
    if first is not None:
        faces.append(np.stack([np.full(n, count), jn, j], 1))
        verts.append(np.asarray(first, dtype=np.float64)[None])
        count += 1
    if last is not None:
        base = (r - 1) * n
        faces.append(np.stack([np.full(n, count), base + j, base + jn], 1))
        verts.append(np.asarray(last, dtype=np.float64)[None])
    return _oriented(np.concatenate(verts), np.concatenate(faces))


def _revolve(profile: Array, n: int) -> Raw:
    """Surface of revolution about z of a (r, z) polyline; end points with r == 0 become poles, a profile
    that never touches the axis is treated as a closed loop (ring/torus)."""
    profile = np.asarray(profile, dtype=np.float64)
    ang = 2 * np.pi * np.arange(n) / n
    cs, sn = np.cos(ang), np.sin(ang)
    first = profile[0] if profile[0, 0] <= 1e-12 else None
    last = profile[-1] if profile[-1, 0] <= 1e-12 else None
    body = profile[int(first is not None) : len(profile) - int(last is not None)]
    rings = [np.stack([r * cs, r * sn, np.full(n, z)], 1) for r, z in body]
    poles = [None if p is None else np.array([0.0, 0.0, p[1]]) for p in (first, last)]
    return _surface(rings, poles[0], poles[1], closed=first is None and last is None)


def _triangulate(poly: Array) -> Array:
    """Ear-clipping triangulation of a simple counter-clockwise polygon without collinear vertices."""
    idx = list(range(len(poly)))
    tris = []

    def cross(o: Array, a: Array, b: Array) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    while len(idx) > 3:
        for k in range(len(idx)):
            a, b, c = idx[k - 1], idx[k], idx[(k + 1) % len(idx)]
            pa, pb, pc = poly[a], poly[b], poly[c]
            if cross(pa, pb, pc) <= 1e-12:
                continue
            blocked = any(
                cross(pa, pb, poly[m]) >= 0 and cross(pb, pc, poly[m]) >= 0 and cross(pc, pa, poly[m]) >= 0
                for m in idx
                if m not in (a, b, c)
            )
            if not blocked:
                tris.append((a, b, c))
                del idx[k]
                break
        else:
            raise ValueError("polygon is not simple")
    tris.append(tuple(idx))
    return np.array(tris, dtype=np.int64)


def _polygon_area(poly: Array) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _extrude(poly: Array, height: float, z0: float = 0.0) -> Raw:
    """Prism over a simple 2-D polygon (any orientation), from ``z0`` to ``z0 + height``."""
    poly = np.asarray(poly, dtype=np.float64)
    if _polygon_area(poly) < 0:
        poly = poly[::-1]
    k = len(poly)
    tri = _triangulate(poly)
    bottom = np.column_stack([poly, np.full(k, z0)])
    top = np.column_stack([poly, np.full(k, z0 + height)])
    i = np.arange(k)
    i1 = (i + 1) % k
    sides = np.concatenate([np.stack([i, i1, k + i1], 1), np.stack([i, k + i1, k + i], 1)])
    faces = np.concatenate([tri[:, ::-1], tri + k, sides])
    return _oriented(np.concatenate([bottom, top]), faces)


def _rot_x90(v: Array) -> Array:
    """Rotate +90 degrees about x: a profile drawn in the xy plane stands up in xz (extruded along -y)."""
    return np.column_stack([v[:, 0], -v[:, 2], v[:, 1]])


def _lay_down(v: Array) -> Array:
    """Rotate +90 degrees about y so a standing shape lies on its side (x becomes the long axis)."""
    return np.column_stack([v[:, 2], v[:, 1], -v[:, 0]])


def _rotation_to(a: Array, b: Array) -> Array:
    """Rotation matrix turning unit vector ``a`` onto unit vector ``b`` (Rodrigues)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1 + 1e-9:  # opposite: rotate pi about any axis perpendicular to a
        axis = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + k + k @ k / (1 + c)


def _hull_resting(rng: np.random.Generator, points: Array) -> Raw:
    """Convex hull of ``points``, rotated so that one random hull face lies flat (a stable resting pose)."""
    f = convex_hull(points)
    v = points
    t = f[rng.integers(len(f))]
    n = np.cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]])
    v = v @ _rotation_to(n, np.array([0.0, 0.0, -1.0])).T
    return v, f


def _catmull_rom(y: Array, samples: int) -> Array:
    """Smooth interpolation through equally spaced knots ``y`` (used for lathe profiles)."""
    k = len(y)
    t = np.linspace(0, k - 1, samples)
    i = np.minimum(t.astype(np.int64), k - 2)
    u = t - i
    p0, p1 = y[np.maximum(i - 1, 0)], y[i]
    p2, p3 = y[i + 1], y[np.minimum(i + 2, k - 1)]
    return 0.5 * (2 * p1 + (p2 - p0) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u**2 + (3 * p1 - p0 - 3 * p2 + p3) * u**3)


# ----------------------------------------------------------------------------------------------------------
# families


def _box(rng: np.random.Generator) -> Raw:
    sx, sy, sz = 1.0, rng.uniform(0.15, 1.0), rng.uniform(0.08, 1.0)  # books, bricks, slabs, cubes
    return _extrude(np.array([[0, 0], [sx, 0], [sx, sy], [0, sy]]), sz)


def _cylinder(rng: np.random.Generator) -> Raw:
    n = int(rng.choice([12, 16, 20, 24, 32]))
    r, h = rng.uniform(0.1, 0.6), rng.uniform(0.15, 1.4)
    v, f = _revolve(np.array([[0, 0], [r, 0], [r, h], [0, h]]), n)
    return (_lay_down(v), f) if rng.random() < 0.3 else (v, f)


def _cone(rng: np.random.Generator) -> Raw:
    n = int(rng.choice([12, 16, 20, 24, 32]))
    rb, h = rng.uniform(0.25, 0.6), rng.uniform(0.3, 1.2)
    rt = 0.0 if rng.random() < 0.35 else rb * rng.uniform(0.15, 0.75)
    if rt > 0 and rng.random() < 0.3:  # upside-down frustum (flower-pot / cup-like)
        rb, rt = rt, rb
    prof = [[0, 0], [rb, 0], [0, h]] if rt == 0 else [[0, 0], [rb, 0], [rt, h], [0, h]]
    return _revolve(np.array(prof, dtype=np.float64), n)


def _ellipsoid(rng: np.random.Generator) -> Raw:
    lat, n = int(rng.integers(9, 14)), int(rng.choice([16, 20, 24]))
    th = np.linspace(-np.pi / 2, np.pi / 2, lat + 1)
    prof = np.stack([np.cos(th), 1 + np.sin(th)], 1)
    prof[0, 0] = prof[-1, 0] = 0.0
    v, f = _revolve(prof, n)
    radii = rng.uniform(0.3, 1.0, 3) if rng.random() < 0.75 else np.ones(3)
    return v * radii, f


def _capsule(rng: np.random.Generator) -> Raw:
    n, k = int(rng.choice([16, 20, 24])), int(rng.integers(4, 7))
    r, length = rng.uniform(0.15, 0.4), rng.uniform(0.2, 1.0)
    th = np.linspace(-np.pi / 2, 0, k + 1)
    lower = np.stack([r * np.cos(th), r + r * np.sin(th)], 1)
    upper = np.stack([r * np.cos(-th[::-1]), r + length + r * np.sin(-th[::-1])], 1)
    prof = np.concatenate([lower, upper])
    prof[0, 0] = prof[-1, 0] = 0.0
    v, f = _revolve(prof, n)
    return (_lay_down(v), f) if rng.random() < 0.5 else (v, f)


def _prism(rng: np.random.Generator) -> Raw:
    k = int(rng.integers(3, 9))
    ang = 2 * np.pi * np.arange(k) / k + rng.uniform(0, np.pi)
    poly = np.stack([np.cos(ang) * rng.uniform(0.6, 1.0), np.sin(ang)], 1)
    v, f = _extrude(poly, rng.uniform(0.2, 1.6))
    return (_lay_down(v), f) if rng.random() < 0.25 else (v, f)


def _star(rng: np.random.Generator) -> Raw:
    k = int(rng.integers(4, 9))
    inner = rng.uniform(0.35, 0.7)
    ang = np.pi * np.arange(2 * k) / k
    rad = np.where(np.arange(2 * k) % 2 == 0, 1.0, inner)
    poly = np.stack([rad * np.cos(ang), rad * np.sin(ang)], 1)
    return _extrude(poly, rng.uniform(0.12, 0.8))


def _pyramid(rng: np.random.Generator) -> Raw:
    k = int(rng.integers(3, 7))
    ang = 2 * np.pi * np.arange(k) / k
    base = np.stack([np.cos(ang) * rng.uniform(0.6, 1.0), np.sin(ang), np.zeros(k)], 1)
    apex = np.array([[*rng.uniform(-0.2, 0.2, 2), rng.uniform(0.4, 1.6)]])
    pts = np.concatenate([base, apex])
    return pts, convex_hull(pts)


def _superellipsoid(rng: np.random.Generator) -> Raw:
    e1, e2 = rng.uniform(0.15, 2.2, 2)
    lat, n = 14, 24
    v = np.linspace(-np.pi / 2, np.pi / 2, lat + 1)[1:-1]
    u = 2 * np.pi * np.arange(n) / n

    def sp(w: Array, e: float, fn: Callable[[Array], Array]) -> Array:
        x = fn(w)
        return np.sign(x) * np.abs(x) ** e

    radii = rng.uniform(0.35, 1.0, 3)
    rings = [
        np.stack(
            [
                sp(vv, e1, np.cos) * sp(u, e2, np.cos),
                sp(vv, e1, np.cos) * sp(u, e2, np.sin),
                np.full(n, sp(vv, e1, np.sin)),
            ],
            1,
        )
        * radii
        for vv in v
    ]
    return _surface(rings, np.array([0, 0, -radii[2]]), np.array([0, 0, radii[2]]))


def _hull(rng: np.random.Generator) -> Raw:
    k = int(rng.integers(8, 36))
    kind = rng.integers(3)
    if kind == 0:
        pts = rng.normal(size=(k, 3)) * rng.uniform(0.3, 1.0, 3)
    elif kind == 1:
        pts = rng.uniform(-1, 1, (k, 3)) * rng.uniform(0.3, 1.0, 3)
    else:
        d = rng.normal(size=(k, 3))
        pts = d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(0.4, 1.0, 3)
    return _hull_resting(rng, pts)


_PHI = (1 + 5**0.5) / 2


def _cyclic(points: Sequence[Sequence[float]]) -> Array:
    """All sign changes and cyclic permutations of the given coordinate triples (deduplicated)."""
    out = set()
    for p in points:
        for sx in (1, -1):
            for sy in (1, -1):
                for sz in (1, -1):
                    q = (sx * p[0], sy * p[1], sz * p[2])
                    for r in range(3):
                        out.add(tuple(float(c) + 0.0 for c in q[r:] + q[:r]))
    return np.array(sorted(out))


_POLYHEDRA = {
    "tetrahedron": np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64),
    "octahedron": _cyclic([(1, 0, 0)]),
    "icosahedron": _cyclic([(0, 1, _PHI)]),
    "dodecahedron": _cyclic([(1, 1, 1), (0, 1 / _PHI, _PHI)]),
    "cuboctahedron": _cyclic([(1, 1, 0)]),
    "rhombic_dodecahedron": _cyclic([(1, 1, 1), (2, 0, 0)]),
    "truncated_octahedron": np.concatenate([_cyclic([(0, 1, 2)]), _cyclic([(0, 2, 1)])]),
    "hexagonal_bipyramid": np.concatenate(
        [
            np.stack([np.cos(np.arange(6) * np.pi / 3), np.sin(np.arange(6) * np.pi / 3), np.zeros(6)], 1),
            [[0, 0, 1.2], [0, 0, -1.2]],
        ]
    ),
}


def _polyhedron(rng: np.random.Generator) -> Raw:
    name = sorted(_POLYHEDRA)[rng.integers(len(_POLYHEDRA))]
    return _hull_resting(rng, _POLYHEDRA[name] * rng.uniform(0.6, 1.4, 3))


def _vase(rng: np.random.Generator) -> Raw:
    knots = int(rng.integers(4, 8))
    h = rng.uniform(0.8, 2.0)
    radii = rng.uniform(0.2, 0.55, knots)
    radii[0] = max(radii[0], 0.3)  # a base wide enough to stand on
    r = np.maximum(_catmull_rom(radii, 14), 0.12)
    z = np.linspace(0, h, 14)
    prof = np.concatenate([[[0, 0]], np.stack([r, z], 1), [[0, h]]])
    return _revolve(prof, int(rng.choice([16, 20, 24])))


def _container_profile(rng: np.random.Generator, kind: int) -> tuple[Array, float]:
    """(r, z) polyline of an open vessel with wall thickness: outside up, over the rim, inside down."""
    if kind == 0:  # bowl
        rim, h, rb, p = (
            rng.uniform(0.8, 1.0),
            rng.uniform(0.35, 0.6),
            rng.uniform(0.3, 0.5),
            rng.uniform(0.4, 0.7),
        )
    elif kind == 1:  # cup / pot
        rim, h, rb, p = rng.uniform(0.5, 0.8), rng.uniform(0.7, 1.3), rng.uniform(0.4, 0.75), 1.0
    else:  # plate / tray
        rim, h, rb, p = 1.0, rng.uniform(0.1, 0.2), rng.uniform(0.6, 0.85), rng.uniform(0.5, 1.0)
    rb = min(rb, rim)
    t = rng.uniform(0.04, 0.08)
    s = np.linspace(0, 1, 8)
    outer = np.stack([rb + (rim - rb) * s**p, h * s], 1)
    zi = t + (h - t) * s[::-1]
    inner = np.stack([rb + (rim - rb) * ((zi / h) ** p) - t, zi], 1)
    inner[:, 0] = np.maximum(inner[:, 0], 0.05)
    return np.concatenate([[[0, 0]], outer, inner, [[0, t]]]), t


def _bowl(rng: np.random.Generator) -> Raw:
    prof, _ = _container_profile(rng, int(rng.integers(3)))
    return _revolve(prof, int(rng.choice([20, 24, 28])))


def _torus(rng: np.random.Generator) -> Raw:
    n = int(rng.choice([20, 24, 28]))
    if rng.random() < 0.6:  # donut / ring with a round or elliptic section
        m, small = int(rng.choice([8, 10, 12])), rng.uniform(0.15, 0.55)
        psi = 2 * np.pi * np.arange(m) / m
        prof = np.stack([1.0 + small * np.cos(psi), small * np.sin(psi) * rng.uniform(0.6, 1.5)], 1)
    else:  # washer, tape roll or pipe section: rectangular section
        inner, h = rng.uniform(0.45, 0.85), rng.uniform(0.1, 1.5)
        prof = np.array([[1.0, 0], [1.0, h], [inner, h], [inner, 0]])
    return _revolve(prof, n)


def _voxels(occ: Array, scale: Array) -> Raw:
    """Closed surface of a boolean voxel grid (only faces between filled and empty cells)."""
    occ = np.pad(occ, 1)
    index: dict[tuple[int, int, int], int] = {}
    faces = []
    corners = ((0, 0), (1, 0), (1, 1), (0, 1))
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        step = np.zeros(3, dtype=np.int64)
        step[a] = 1
        for cell in np.argwhere(occ):
            for sign in (1, -1):
                nb = cell + sign * step
                if occ[tuple(nb)]:
                    continue
                quad = []
                for cb, cc in corners if sign > 0 else corners[::-1]:
                    p = cell.copy()
                    p[a] += 1 if sign > 0 else 0
                    p[b] += cb
                    p[c] += cc
                    quad.append(index.setdefault(tuple(int(x) for x in p), len(index)))
                faces += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    v = np.array(sorted(index, key=index.get), dtype=np.float64) * scale
    return _oriented(v, np.array(faces, dtype=np.int64))


def _blocks(rng: np.random.Generator) -> Raw:
    scale = rng.uniform(0.6, 1.4, 3)
    for _ in range(50):
        k = int(rng.integers(3, 7))
        cells = {(0, 0)}
        while len(cells) < k:
            x, y = sorted(cells)[rng.integers(len(cells))]
            dx, dy = ((1, 0), (-1, 0), (0, 1), (0, -1))[rng.integers(4)]
            cells.add((x + dx, y + dy))
        xs, ys = zip(*cells, strict=True)
        occ = np.zeros((max(xs) - min(xs) + 1, max(ys) - min(ys) + 1, 3), dtype=bool)
        flat = rng.random() < 0.5
        for x, y in cells:
            occ[x - min(xs), y - min(ys), : 1 if flat else int(rng.integers(1, 4))] = True
        v, f = _voxels(occ, scale)
        if is_watertight(f):
            return v, f
    raise RuntimeError("could not build a manifold voxel shape")  # pragma: no cover - 50 tries never all fail


def _gear(rng: np.random.Generator) -> Raw:
    teeth = int(rng.integers(6, 17))
    root, depth = 1.0, rng.uniform(0.12, 0.3)
    pitch = 2 * np.pi / teeth
    frac = np.array([0.0, 0.15, 0.4, 0.55])
    rad = np.array([root, root + depth, root + depth, root])
    ang = (np.arange(teeth)[:, None] * pitch + frac[None] * pitch).ravel()
    rr = np.tile(rad, teeth)
    thick = rng.uniform(0.15, 0.5)
    parts = [_extrude(np.stack([rr * np.cos(ang), rr * np.sin(ang)], 1), thick)]
    if rng.random() < 0.5:  # hub on top
        hub_r, hub_h = rng.uniform(0.25, 0.5), rng.uniform(0.1, 0.4)
        prof = np.array([[0, thick * 0.5], [hub_r, thick * 0.5], [hub_r, thick + hub_h], [0, thick + hub_h]])
        parts.append(_revolve(prof, 20))
    return _combine(parts)


def _wedge(rng: np.random.Generator) -> Raw:
    length, height = rng.uniform(0.6, 1.0), rng.uniform(0.25, 0.8)
    kind = rng.integers(4)
    if kind == 0:  # door stop
        poly = [[0, 0], [length, 0], [0, height]]
    elif kind == 1:  # ramp block
        poly = [[0, 0], [length, 0], [length, height * rng.uniform(0.2, 0.6)], [0, height]]
    elif kind == 2:  # house / roof prism
        wall = height * rng.uniform(0.3, 0.7)
        poly = [[0, 0], [length, 0], [length, wall], [length / 2, height], [0, wall]]
    else:  # symmetric trapezoid
        inset = length * rng.uniform(0.1, 0.35)
        poly = [[0, 0], [length, 0], [length - inset, height], [inset, height]]
    v, f = _extrude(np.array(poly, dtype=np.float64), rng.uniform(0.2, 1.0))
    return _rot_x90(v), f


def _arch(rng: np.random.Generator) -> Raw:
    width, height = 1.0, rng.uniform(0.4, 1.0)
    a = width / 2 * rng.uniform(0.35, 0.75)
    b = min(a * rng.uniform(0.6, 1.4), height * 0.6)
    hs = rng.uniform(0.0, height - b - 0.12) if height - b > 0.2 else 0.0
    k = 10
    th = np.pi - np.pi * np.arange(1, k + 1) / (k + 1)
    arc = np.stack([a * np.cos(th), hs + b * np.sin(th)], 1)
    pts = [[-width / 2, 0], [-a, 0]] + ([[-a, hs]] if hs > 1e-3 else [])
    pts += (
        arc.tolist()
        + ([[a, hs]] if hs > 1e-3 else [])
        + [[a, 0], [width / 2, 0], [width / 2, height], [-width / 2, height]]
    )
    v, f = _extrude(np.array(pts, dtype=np.float64), rng.uniform(0.15, 0.6))
    return _rot_x90(v), f


def _mug(rng: np.random.Generator) -> Raw:
    rim, h, t = rng.uniform(0.35, 0.5), rng.uniform(0.6, 1.1), rng.uniform(0.04, 0.07)
    s = np.linspace(0, 1, 6)
    taper = rng.uniform(0.88, 1.0)  # little taper, so the straight handle ends stay inside the wall
    rb = rim * taper
    outer = np.stack([rb + (rim - rb) * s, h * s], 1)
    zi = t + (h - t) * s[::-1]
    inner = np.stack([rb + (rim - rb) * zi / h - t, zi], 1)
    cup = _revolve(np.concatenate([[[0, 0]], outer, inner, [[0, t]]]), 20)
    # handle: a tube along an arc in the xz plane whose capped ends are buried in the wall
    rh, rt = h * rng.uniform(0.22, 0.35), rng.uniform(0.035, 0.06)
    alpha = np.radians(95)
    cz = h * rng.uniform(0.45, 0.55)
    wall_x = rb + (rim - rb) * cz / h - t / 2
    cx = wall_x + rh * abs(np.cos(alpha))
    phi = np.linspace(-alpha, alpha, 11)
    psi = 2 * np.pi * np.arange(8) / 8
    rings = []
    for p in phi:
        centre = np.array([cx + rh * np.cos(p), 0.0, cz + rh * np.sin(p)])
        normal = np.array([np.cos(p), 0.0, np.sin(p)])
        rings.append(centre + rt * (np.cos(psi)[:, None] * normal + np.sin(psi)[:, None] * np.array([0, 1.0, 0])))
    ends = [np.array([cx + rh * np.cos(p), 0.0, cz + rh * np.sin(p)]) for p in (phi[0], phi[-1])]
    handle = _surface(rings, ends[0], ends[1])
    return _combine([cup, handle])


SHAPE_FAMILY_FUNCS: dict[str, ShapeFn] = {
    "box": _box,
    "cylinder": _cylinder,
    "cone": _cone,
    "ellipsoid": _ellipsoid,
    "capsule": _capsule,
    "prism": _prism,
    "star": _star,
    "pyramid": _pyramid,
    "superellipsoid": _superellipsoid,
    "hull": _hull,
    "polyhedron": _polyhedron,
    "vase": _vase,
    "bowl": _bowl,
    "torus": _torus,
    "blocks": _blocks,
    "gear": _gear,
    "wedge": _wedge,
    "arch": _arch,
    "mug": _mug,
}
SHAPE_FAMILIES: tuple[str, ...] = tuple(SHAPE_FAMILY_FUNCS)


def generate_shape(family: str, seed: int) -> Mesh:
    """Build variant ``seed`` of ``family`` and normalise it (see :func:`normalize_mesh`)."""
    if family not in SHAPE_FAMILY_FUNCS:
        raise ValueError(f"unknown shape family {family!r}; valid families: {', '.join(SHAPE_FAMILIES)}")
    v, f = SHAPE_FAMILY_FUNCS[family](np.random.default_rng(seed))
    return normalize_mesh(v, f)
