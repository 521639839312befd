"""Image augmentation shared by rt1 (``crop="shift"``) and bc (``augmentation="shift"``)."""

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
