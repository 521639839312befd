"""Procedural texture families.

Factor World used scraped photos for table/floor/object textures; we cannot download them, so each
family below turns a seeded generator into an RGB image. Every family:

* draws all its parameters (colours, frequencies, angles, noise lattices) before touching pixels, so a
  variant looks the same at any resolution;
* uses integer frequencies on the unit square (periodic noise lattices, wrap-around cell search), so the
  image tiles without visible seams when MuJoCo repeats it over a table top.
"""

from __future__ import annotations

import colorsys
from collections.abc import Callable

import numpy as np

Array = np.ndarray
TextureFn = Callable[[np.random.Generator, int], Array]

# ----------------------------------------------------------------------------------------------------------
# colour helpers


def _hsv(h: float, s: float, v: float) -> Array:
    return np.array(colorsys.hsv_to_rgb(h % 1.0, float(np.clip(s, 0, 1)), float(np.clip(v, 0, 1))))


def _palette(rng: np.random.Generator, n: int) -> Array:
    """``n`` RGB colours in [0, 1]; colour 0 and colour 1 always differ strongly in lightness.

    A colour scheme (analogous, complementary, triadic, monochrome or random) keeps palettes pleasant
    while still covering the whole hue circle across variants.
    """
    h0 = rng.random()
    scheme = rng.integers(5)
    if scheme == 0:  # analogous
        hues = h0 + rng.uniform(-0.09, 0.09, n)
    elif scheme == 1:  # complementary
        hues = h0 + 0.5 * (np.arange(n) % 2) + rng.uniform(-0.03, 0.03, n)
    elif scheme == 2:  # triadic
        hues = h0 + np.arange(n) / 3.0 + rng.uniform(-0.03, 0.03, n)
    elif scheme == 3:  # monochrome
        hues = np.full(n, h0)
    else:
        hues = rng.random(n)
    s_hi = rng.choice([0.3, 0.6, 0.95])
    sats = rng.uniform(0.1, s_hi, n)
    lo, hi = rng.uniform(0.08, 0.4), rng.uniform(0.7, 0.98)
    vals = np.linspace(lo, hi, n) if n > 1 else np.array([rng.uniform(lo, hi)])
    order = np.concatenate([[0, n - 1], np.arange(1, n - 1)]) if n > 1 else np.array([0])
    if rng.random() < 0.5:  # background dark or light
        order = np.concatenate([[order[1], order[0]], order[2:]]) if n > 1 else order
    return np.stack([_hsv(h, s, v) for h, s, v in zip(hues, sats, vals[order], strict=True)])


def _ramp(t: Array, colors: Array) -> Array:
    """Piecewise-linear colour map of ``t`` in [0, 1] through ``colors`` (k, 3)."""
    k = len(colors)
    x = np.clip(t, 0.0, 1.0) * (k - 1)
    i = np.minimum(x.astype(np.int64), k - 2)
    f = (x - i)[..., None]
    return colors[i] * (1 - f) + colors[i + 1] * f


def _mix(a: Array, b: Array, m: Array) -> Array:
    """Blend colours/images ``a`` and ``b`` with mask ``m`` (HxW) in [0, 1]."""
    m = m[..., None]
    return a * (1 - m) + b * m


def _normalise(v: Array) -> Array:
    lo, hi = float(v.min()), float(v.max())
    return (v - lo) / (hi - lo) if hi > lo else np.zeros_like(v)


# ----------------------------------------------------------------------------------------------------------
# geometry helpers (all periodic on the unit square)


def _coords(size: int) -> tuple[Array, Array]:
    c = (np.arange(size) + 0.5) / size
    return np.meshgrid(c, c, indexing="xy")


def _band(phase: Array, duty: float, period: float, size: int) -> Array:
    """Anti-aliased periodic band, 1 where ``frac(phase) < duty``; ``period``: one cycle in texture units."""
    f = phase - np.floor(phase)
    inside = np.minimum(f, duty - f)
    outside = -np.minimum(f - duty, 1.0 - f)
    d = np.where(f < duty, inside, outside) * period * size
    return np.clip(d + 0.5, 0.0, 1.0)


def _interp_index(freq: int, size: int) -> tuple[Array, Array, Array]:
    """Lattice neighbours (wrapped) and smoothstep weight for each pixel centre along one axis."""
    c = (np.arange(size) + 0.5) / size * freq
    i0 = np.floor(c).astype(np.int64)
    t = c - i0
    return i0 % freq, (i0 + 1) % freq, t * t * (3 - 2 * t)


class _Fbm:
    """Tileable fractal value noise: octaves of random values on periodic lattices, drawn at construction."""

    def __init__(
        self, rng: np.random.Generator, fx: int, fy: int | None = None, octaves: int = 4, gain: float = 0.5
    ) -> None:
        fy = fx if fy is None else fy
        self.layers = [(rng.random((fy * 2**o, fx * 2**o)), gain**o) for o in range(octaves)]

    def grid(self, size: int) -> Array:
        """Noise on the pixel grid in [0, 1]. Interpolation is separable (rows, then columns), which avoids
        BLAS calls whose thread start-up made small textures slow and erratic on busy machines."""
        total = np.zeros((size, size))
        for lat, amp in self.layers:
            y0, y1, ty = _interp_index(lat.shape[0], size)
            x0, x1, tx = _interp_index(lat.shape[1], size)
            rows = lat[y0] * (1 - ty)[:, None] + lat[y1] * ty[:, None]
            total += (rows[:, x0] * (1 - tx) + rows[:, x1] * tx) * amp
        return _normalise(total)


def _worley(size: int, offsets: Array) -> tuple[Array, Array, Array, Array]:
    """Periodic cell search on the pixel grid: one feature point per cell at ``offsets[iy, ix]`` (cell units).

    Returns the wrapped cell indices (ix, iy) of the nearest point and the nearest / second-nearest
    distances in texture units. Only the 3x3 neighbourhood is searched, which is exact for offsets in
    [0, 1). Row and column terms are separable, which keeps this at ~2 ms for 128 x 128.
    """
    gy, gx = offsets.shape[:2]
    c = (np.arange(size) + 0.5) / size
    px, py = c * gx, c * gy
    cx, cy = np.floor(px).astype(np.int64), np.floor(py).astype(np.int64)
    ox, oy = offsets[..., 0] / gx, offsets[..., 1] / gy
    d1 = np.full((size, size), np.inf)
    d2 = d1.copy()
    best = np.zeros((size, size), np.int64)
    for dy in (-1, 0, 1):
        wy = (cy + dy) % gy
        ry = (py - cy - dy) / gy
        for dx in (-1, 0, 1):
            wx = (cx + dx) % gx
            rx = (px - cx - dx) / gx
            ix = np.ix_(wy, wx)
            d = (rx[None, :] - ox[ix]) ** 2 + (ry[:, None] - oy[ix]) ** 2
            closer = d < d1
            np.minimum(d2, np.where(closer, d1, d), out=d2)
            np.minimum(d1, d, out=d1)
            best[closer] = (wy[:, None] * gx + wx[None, :])[closer]
    return best % gx, best // gx, np.sqrt(d1), np.sqrt(d2)


def _grain(rng: np.random.Generator, size: int, amount: float) -> Array:
    """Fine per-pixel luminance noise so flat areas do not look synthetic."""
    return rng.normal(0.0, amount, (size, size, 1))


# ----------------------------------------------------------------------------------------------------------
# families


def _checker(rng: np.random.Generator, size: int) -> Array:
    n = int(rng.choice([2, 4, 6, 8, 10, 12, 16]))
    diamond = rng.random() < 0.3
    c = _palette(rng, 2)
    jitter = rng.uniform(0.0, 0.12)
    cell_noise = rng.normal(0.0, jitter, (n, n))
    x, y = _coords(size)
    u, v = (x + y, x - y) if diamond else (x, y)
    per = 1.0 / n if not diamond else 1.0 / (n * np.sqrt(2))
    m = _band(u * n / 2, 0.5, 2 * per, size)
    m2 = _band(v * n / 2, 0.5, 2 * per, size)
    mask = m * (1 - m2) + (1 - m) * m2  # xor, anti-aliased
    img = _mix(np.broadcast_to(c[0], (size, size, 3)), np.broadcast_to(c[1], (size, size, 3)), mask)
    ix = (np.floor(u * n).astype(np.int64)) % n
    iy = (np.floor(v * n).astype(np.int64)) % n
    return img * (1 + cell_noise[iy, ix][..., None]) + _grain(rng, size, 0.015)


_DIRECTIONS = [(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 2), (2, -1), (1, -2), (3, 1), (1, 3), (3, -1)]


def _stripes(rng: np.random.Generator, size: int) -> Array:
    a, b = _DIRECTIONS[rng.integers(len(_DIRECTIONS))]
    k = int(rng.integers(2, 11))
    nb = int(rng.integers(2, 5))
    c = _palette(rng, nb)
    widths = rng.uniform(0.3, 1.0, nb)
    edges = np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])
    x, y = _coords(size)
    t = k * (a * x + b * y)
    f = t - np.floor(t)
    idx = np.searchsorted(edges[1:-1], f, side="right")
    img = c[idx]
    return img + _grain(rng, size, 0.015)


def _noise(rng: np.random.Generator, size: int) -> Array:
    f = int(rng.integers(2, 9))
    octaves = int(rng.integers(3, 7))
    gain = rng.uniform(0.35, 0.7)
    c = _palette(rng, int(rng.integers(2, 4)))
    fbm = _Fbm(rng, f, octaves=octaves, gain=gain)
    x, y = _coords(size)
    t = fbm.grid(size)
    contrast = rng.uniform(1.0, 2.0)
    t = np.clip((t - 0.5) * contrast + 0.5, 0, 1)
    return _ramp(t, c)


def _gradient(rng: np.random.Generator, size: int) -> Array:
    a, b = _DIRECTIONS[rng.integers(len(_DIRECTIONS))]
    c = _palette(rng, int(rng.integers(2, 4)))
    phase = rng.random()
    fbm = _Fbm(rng, 4, octaves=3)
    wobble = rng.uniform(0.0, 0.25)
    x, y = _coords(size)
    t = 0.5 - 0.5 * np.cos(2 * np.pi * (a * x + b * y + phase + wobble * fbm.grid(size)))
    return _ramp(t, c) + _grain(rng, size, 0.01)


def _dots(rng: np.random.Generator, size: int) -> Array:
    n = int(rng.choice([3, 4, 5, 6, 8, 10]))
    hexa = rng.random() < 0.5
    rows = 2 * max(1, round(n / np.sqrt(3))) if hexa else n  # regular hexagonal packing, even for tiling
    radius = rng.uniform(0.18, 0.42) / n
    c = _palette(rng, 3)
    two_tone = rng.random() < 0.4
    offsets = np.full((rows, n, 2), 0.5)
    if hexa:
        offsets[1::2, :, 0] = 0.0  # odd rows shifted by half a cell
        offsets[..., 0] += 0.25
        offsets[..., 0] %= 1.0
    x, y = _coords(size)
    ix, iy, d1, _ = _worley(size, offsets)
    inside = np.clip((radius - d1) * size + 0.5, 0, 1)
    dot_col = np.where(((ix + iy) % 2 == 0)[..., None] & two_tone, c[2], c[1])
    return _mix(np.broadcast_to(c[0], (size, size, 3)), dot_col, inside) + _grain(rng, size, 0.015)


def _grid(rng: np.random.Generator, size: int) -> Array:
    n = int(rng.choice([3, 4, 5, 6, 8, 10, 12]))
    thick = rng.uniform(0.04, 0.25)
    c = _palette(rng, 3)
    minor = int(rng.choice([1, 1, 2, 4]))
    tiles = rng.random() < 0.5  # per-tile colour jitter, like bathroom tiles
    jit = rng.normal(0, 0.08, (n, n)) if tiles else np.zeros((n, n))
    x, y = _coords(size)
    per = 1.0 / n
    lx = _band(x * n + thick / 2, thick, per, size)
    ly = _band(y * n + thick / 2, thick, per, size)
    line = np.maximum(lx, ly)
    img = (
        np.broadcast_to(c[0], (size, size, 3)) * (1 + jit[(y * n).astype(int) % n, (x * n).astype(int) % n])[..., None]
    )
    if minor > 1:
        m = n * minor
        mx = _band(x * m + thick / 4, thick / 2, 1.0 / m, size)
        my = _band(y * m + thick / 4, thick / 2, 1.0 / m, size)
        img = _mix(img, np.broadcast_to(c[2], (size, size, 3)), 0.6 * np.maximum(mx, my))
    return _mix(img, np.broadcast_to(c[1], (size, size, 3)), line) + _grain(rng, size, 0.012)


def _marble(rng: np.random.Generator, size: int) -> Array:
    a, b = _DIRECTIONS[rng.integers(len(_DIRECTIONS))]
    k = int(rng.integers(1, 4))
    turb = rng.uniform(0.8, 2.5)
    sharp = rng.uniform(2.0, 8.0)
    c = _palette(rng, 3)
    fbm = _Fbm(rng, int(rng.integers(2, 5)), octaves=5, gain=0.55)
    cloud = _Fbm(rng, 3, octaves=3)
    x, y = _coords(size)
    n = fbm.grid(size)
    v = np.abs(np.sin(np.pi * (k * (a * x + b * y) + turb * n)))
    veins = (1 - v) ** sharp
    base = _ramp(0.35 + 0.3 * cloud.grid(size), np.stack([c[1], c[1] * 0.92 + c[2] * 0.08]))
    return _mix(base, c[0], np.clip(veins * 1.3, 0, 1)) + _grain(rng, size, 0.01)


def _wood(rng: np.random.Generator, size: int) -> Array:
    hue = rng.uniform(0.03, 0.11) if rng.random() < 0.8 else rng.random()
    sat = rng.uniform(0.35, 0.8)
    light = _hsv(hue, sat * 0.8, rng.uniform(0.65, 0.92))
    dark = _hsv(hue + rng.uniform(-0.02, 0.02), min(1.0, sat * 1.2), rng.uniform(0.25, 0.5))
    rings = int(rng.integers(4, 14))
    planks = int(rng.choice([1, 2, 3, 4, 5, 6]))
    warp = rng.uniform(0.05, 0.3)
    vertical = rng.random() < 0.5
    grain_n = _Fbm(rng, 1, 8, octaves=3)
    fine = _Fbm(rng, 4, 96, octaves=1)
    plank_shift = rng.random(planks)
    plank_tint = rng.normal(0, 0.07, planks)
    _, y = _coords(size)  # computed un-rotated; a vertical variant is transposed at the end
    p = np.floor(y * planks).astype(np.int64) % planks
    t = rings * (y + warp * grain_n.grid(size)) + plank_shift[p] * 7
    f = t - np.floor(t)
    ring = f**3 * 0.8 + 0.2 * fine.grid(size)
    img = _mix(np.broadcast_to(light, (size, size, 3)), np.broadcast_to(dark, (size, size, 3)), ring)
    img = img * (1 + plank_tint[p])[..., None]
    if planks > 1:
        seam = _band(y * planks + 0.006 * planks, 0.012 * planks, 1.0 / planks, size)
        img = img * (1 - 0.55 * seam)[..., None]
    if vertical:
        img = img.transpose(1, 0, 2)
    return img + _grain(rng, size, 0.01)


def _voronoi(rng: np.random.Generator, size: int) -> Array:
    g = int(rng.integers(3, 9))
    offsets = rng.uniform(0.05, 0.95, (g, g, 2))
    c = _palette(rng, int(rng.integers(3, 6)))
    cell_col = rng.integers(1, len(c), (g, g))
    border = rng.choice([0.0, 0.004, 0.012, 0.03])
    shade = rng.random() < 0.5
    x, y = _coords(size)
    ix, iy, d1, d2 = _worley(size, offsets)
    img = c[cell_col[iy, ix]]
    if shade:
        img = img * (1.05 - 0.5 * np.clip(d1 * g, 0, 1))[..., None]
    if border > 0:
        edge = np.clip((border - (d2 - d1)) * size + 0.5, 0, 1)
        img = _mix(img, c[0], edge)
    return img + _grain(rng, size, 0.012)


def _bricks(rng: np.random.Generator, size: int) -> Array:
    rows = int(rng.choice([4, 6, 8, 10, 12]))
    cols = int(rng.integers(2, 7))
    mortar = rng.uniform(0.008, 0.025)
    base_h = rng.uniform(0.0, 0.1) if rng.random() < 0.6 else rng.random()
    brick = _hsv(base_h, rng.uniform(0.3, 0.8), rng.uniform(0.35, 0.75))
    mortar_c = _hsv(rng.random(), rng.uniform(0, 0.15), rng.uniform(0.2, 0.9))
    tint = rng.normal(0, 0.1, (rows, cols))
    fbm = _Fbm(rng, 8, octaves=3)
    x, y = _coords(size)
    r = np.floor(y * rows).astype(np.int64) % rows
    xs = x + 0.5 / cols * (r % 2)
    col = np.floor(xs * cols).astype(np.int64) % cols
    bx = _band(xs * cols + mortar * cols / 2, mortar * cols, 1.0 / cols, size)
    by = _band(y * rows + mortar * rows / 2, mortar * rows, 1.0 / rows, size)
    line = np.maximum(bx, by)
    img = brick * (1 + tint[r, col] + 0.25 * (fbm.grid(size) - 0.5))[..., None]
    return _mix(img, np.broadcast_to(mortar_c, (size, size, 3)), line) + _grain(rng, size, 0.02)


def _hexagons(rng: np.random.Generator, size: int) -> Array:
    n = int(rng.choice([3, 4, 6, 6, 8, 9, 12]))
    rows = 2 * max(1, round(n * 2 / np.sqrt(3) / 2))
    offsets = np.full((rows, n, 2), 0.5)
    offsets[1::2, :, 0] = 0.0
    offsets[..., 0] = (offsets[..., 0] + 0.25) % 1.0
    c = _palette(rng, int(rng.integers(3, 5)))
    three = rng.random() < 0.5  # classic 3-colouring vs random cells
    cells = rng.integers(1, len(c), (rows, n))
    border = rng.uniform(0.003, 0.03)
    x, y = _coords(size)
    ix, iy, d1, d2 = _worley(size, offsets)
    if three and n % 3 == 0 and len(c) >= 4:
        q = ix - (iy + (iy & 1)) // 2  # axial coordinates of the "even rows shifted" layout
        img = c[1 + (q - iy) % 3]
    else:
        img = c[cells[iy, ix]]
    edge = np.clip((border - (d2 - d1)) * size + 0.5, 0, 1)
    return _mix(img, c[0], edge) + _grain(rng, size, 0.012)


def _waves(rng: np.random.Generator, size: int) -> Array:
    k = int(rng.integers(2, 5))
    vecs = rng.integers(-4, 5, (k, 2))
    vecs[np.all(vecs == 0, axis=1)] = (1, 2)
    phases = rng.random(k)
    cos_pal = rng.random() < 0.5
    pa, pb, pc, pd = (
        rng.uniform(0.35, 0.65, 3),
        rng.uniform(0.25, 0.5, 3),
        rng.uniform(0.5, 1.5, 3),
        rng.random(3),
    )
    c = _palette(rng, 3)
    bands = int(rng.choice([0, 0, 4, 6]))
    x, y = _coords(size)
    v = sum(np.sin(2 * np.pi * (a * x + b * y + p)) for (a, b), p in zip(vecs, phases, strict=True))
    t = _normalise(v)
    if bands:
        t = np.floor(t * bands) / (bands - 1)
    if cos_pal:
        return pa + pb * np.cos(2 * np.pi * (pc * t[..., None] + pd))
    return _ramp(t, c)


def _plaid(rng: np.random.Generator, size: int) -> Array:
    reps = int(rng.choice([1, 2, 3, 4]))
    nb = int(rng.integers(3, 7))
    c = _palette(rng, 4)
    widths = rng.uniform(0.2, 1.0, nb)
    edges = np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])
    band_col = rng.integers(0, len(c), nb)
    twill = rng.uniform(0.0, 0.15)
    x, y = _coords(size)
    fx, fy = (x * reps) % 1.0, (y * reps) % 1.0
    cx = c[band_col[np.searchsorted(edges[1:-1], fx, side="right")]]
    cy = c[band_col[np.searchsorted(edges[1:-1], fy, side="right")]]
    i = np.arange(size)
    diag = ((i[None, :] + i[:, None]) // 2 % 2).astype(float)
    m = 0.5 + twill * (2 * diag - 1)
    return _mix(cx, cy, m) + _grain(rng, size, 0.01)


def _weave(rng: np.random.Generator, size: int) -> Array:
    n = int(rng.choice([2, 4, 6, 8]))
    strands = int(rng.integers(2, 5))
    c = _palette(rng, 3)
    gap = rng.uniform(0.05, 0.25)
    x, y = _coords(size)
    ix, iy = np.floor(x * n).astype(np.int64), np.floor(y * n).astype(np.int64)
    horiz = (ix + iy) % 2 == 0
    across = np.where(horiz, y, x) * n * strands
    along = np.where(horiz, x, y) * n
    f = across - np.floor(across)
    profile = np.clip(np.sin(np.pi * f) * (1 + gap) - gap, 0, 1) ** 0.5
    col = np.where(horiz[..., None], c[1], c[2])
    bend = 0.85 + 0.15 * np.sin(np.pi * (along - np.floor(along)))
    img = _mix(np.broadcast_to(c[0], (size, size, 3)), col * bend[..., None], profile)
    return img + _grain(rng, size, 0.015)


def _terrazzo(rng: np.random.Generator, size: int) -> Array:
    g = int(rng.integers(6, 16))
    c = _palette(rng, int(rng.integers(3, 6)))
    offsets = rng.uniform(0.0, 1.0, (g, g, 2))
    radius = rng.uniform(0.12, 0.45, (g, g)) / g
    chip_col = rng.integers(1, len(c), (g, g))
    present = rng.random((g, g)) < rng.uniform(0.5, 1.0)
    wobble = _Fbm(rng, 16, octaves=2)
    x, y = _coords(size)
    ix, iy, d1, _ = _worley(size, offsets)
    d = d1 * (0.8 + 0.4 * wobble.grid(size))
    inside = np.clip((radius[iy, ix] - d) * size + 0.5, 0, 1) * present[iy, ix]
    img = _mix(np.broadcast_to(c[0], (size, size, 3)), c[chip_col[iy, ix]], inside)
    return img + _grain(rng, size, 0.03)


def _camo(rng: np.random.Generator, size: int) -> Array:
    k = int(rng.integers(3, 5))
    if rng.random() < 0.5:  # military-ish greens/browns
        c = np.stack([_hsv(rng.uniform(0.05, 0.3), rng.uniform(0.2, 0.6), rng.uniform(0.15, 0.7)) for _ in range(k)])
    else:
        c = _palette(rng, k)
    f = int(rng.integers(2, 6))
    fields = [_Fbm(rng, f, octaves=4, gain=0.55) for _ in range(k - 1)]
    thresholds = rng.uniform(0.45, 0.6, k - 1)
    x, y = _coords(size)
    img = np.broadcast_to(c[0], (size, size, 3)).copy()
    for i, (fb, th) in enumerate(zip(fields, thresholds, strict=True)):
        m = np.clip((fb.grid(size) - th) * 40, 0, 1)
        img = _mix(img, c[i + 1], m)
    return img + _grain(rng, size, 0.015)


def _rings(rng: np.random.Generator, size: int) -> Array:
    g = int(rng.choice([1, 2, 3, 4]))
    jitter = rng.random() < 0.5
    offsets = rng.uniform(0.2, 0.8, (g, g, 2)) if jitter else np.full((g, g, 2), 0.5)
    freq = rng.uniform(3, 10) * g
    c = _palette(rng, 3)
    duty = rng.uniform(0.3, 0.7)
    x, y = _coords(size)
    ix, iy, d1, _ = _worley(size, offsets)
    m = _band(d1 * freq, duty, 1.0 / freq, size)
    img = _mix(np.broadcast_to(c[0], (size, size, 3)), c[1], m)
    centre = np.clip((0.25 / freq - d1) * size + 0.5, 0, 1)
    return _mix(img, c[2], centre) + _grain(rng, size, 0.012)


def _zigzag(rng: np.random.Generator, size: int) -> Array:
    k = int(rng.integers(2, 8))
    m = int(rng.integers(2, 7))
    amp = rng.uniform(0.3, 1.2) / (2 * m)  # zigzag slope between 0.3 and 1.2
    nb = int(rng.integers(2, 5))
    c = _palette(rng, nb)
    smooth = rng.random() < 0.3
    vertical = rng.random() < 0.5
    x, y = _coords(size)
    if vertical:
        x, y = y, x
    s = m * x - np.floor(m * x)
    tri = np.sin(2 * np.pi * s) * 0.5 + 0.5 if smooth else 1 - 2 * np.abs(s - 0.5)
    t = k * (y + amp * tri)
    f = t - np.floor(t)
    return c[np.minimum((f * nb).astype(np.int64), nb - 1)] + _grain(rng, size, 0.015)


TEXTURE_FAMILY_FUNCS: dict[str, TextureFn] = {
    "checker": _checker,
    "stripes": _stripes,
    "noise": _noise,
    "gradient": _gradient,
    "dots": _dots,
    "grid": _grid,
    "marble": _marble,
    "wood": _wood,
    "voronoi": _voronoi,
    "bricks": _bricks,
    "hexagons": _hexagons,
    "waves": _waves,
    "plaid": _plaid,
    "weave": _weave,
    "terrazzo": _terrazzo,
    "camo": _camo,
    "rings": _rings,
    "zigzag": _zigzag,
}
TEXTURE_FAMILIES: tuple[str, ...] = tuple(TEXTURE_FAMILY_FUNCS)


def generate_texture(family: str, seed: int, size: int = 128) -> Array:
    """Render variant ``seed`` of ``family`` as a ``size`` x ``size`` x 3 uint8 image."""
    if family not in TEXTURE_FAMILY_FUNCS:
        raise ValueError(f"unknown texture family {family!r}; valid families: {', '.join(TEXTURE_FAMILIES)}")
    if size < 1:
        raise ValueError(f"texture size must be positive, got {size}")
    img = TEXTURE_FAMILY_FUNCS[family](np.random.default_rng(seed), size)
    return np.clip(np.rint(np.asarray(img, dtype=np.float64) * 255.0), 0, 255).astype(np.uint8)
