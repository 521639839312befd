"""Image augmentation shared by rt1 (``crop="shift"``) and bc (``augmentation="shift"``, and the cutout and
Gaussian noise of bc's photometric distortion). Every draw comes from torch's RNG on the images' device,
one per image, so a seeded run (``--seed``) augments the same way every time."""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor


def random_shift(x: Tensor, pad: int) -> Tensor:
    """DrQ-style shift: replicate-pad by ``pad`` and crop back at a random offset per image.

    (N, C, H, W) -> (N, C, H, W): a translation of at most ``pad`` px whose uncovered border repeats the edge pixels.
    """
    n, _, h, w = x.shape
    padded = F.pad(x, (pad, pad, pad, pad), mode="replicate")
    dx = torch.randint(0, 2 * pad + 1, (n,), device=x.device)
    dy = torch.randint(0, 2 * pad + 1, (n,), device=x.device)
    rows = (dy[:, None] + torch.arange(h, device=x.device)[None]).view(n, 1, h, 1).expand(n, x.shape[1], h, w + 2 * pad)
    out = padded.gather(2, rows)
    cols = (dx[:, None] + torch.arange(w, device=x.device)[None]).view(n, 1, 1, w).expand(n, x.shape[1], h, w)
    return out.gather(3, cols)


def cutout_sides(side: int, size: tuple[float, float]) -> tuple[int, int]:
    """Smallest and largest cutout side in pixels for an image side of ``side`` px: ``size`` is a fraction of
    the side (at least 1 px, at most the whole side)."""
    low = min(side, max(1, round(size[0] * side)))
    return low, min(side, max(low, round(size[1] * side)))


def random_cutout(x: Tensor, size: tuple[float, float], fill: float = 0.0) -> Tensor:
    """Cutout (DeVries & Taylor 2017; RAD's ``random_cutout``): in each image, one rectangle whose height
    and width are drawn independently and uniformly from ``size`` (fractions of the image's height and
    width) is set to ``fill``; it lies wholly inside the image, at a uniformly drawn position. Out of place."""
    n, _, h, w = x.shape
    (h_lo, h_hi), (w_lo, w_hi) = cutout_sides(h, size), cutout_sides(w, size)
    ch = torch.randint(h_lo, h_hi + 1, (n,), device=x.device)
    cw = torch.randint(w_lo, w_hi + 1, (n,), device=x.device)
    top = (torch.rand(n, device=x.device) * (h - ch + 1)).long()
    left = (torch.rand(n, device=x.device) * (w - cw + 1)).long()
    rows = torch.arange(h, device=x.device)[None]
    cols = torch.arange(w, device=x.device)[None]
    in_rows = (rows >= top[:, None]) & (rows < (top + ch)[:, None])  # (N, H)
    in_cols = (cols >= left[:, None]) & (cols < (left + cw)[:, None])  # (N, W)
    box = (in_rows[:, :, None] & in_cols[:, None, :])[:, None]  # (N, 1, H, W)
    return x.masked_fill(box, fill)


def gaussian_noise(x: Tensor, std: float) -> Tensor:
    """Independent zero-mean Gaussian noise of standard deviation ``std`` on every pixel and channel, then
    clipped to [0, 1] (torchvision's ``v2.GaussianNoise(mean=0, sigma=std, clip=True)``). Out of place."""
    return (x + torch.randn_like(x) * std).clamp(0.0, 1.0)
