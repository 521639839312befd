"""The paper's two training-time image augmentations, each drawn independently per image.

``shift`` is DrQ's random shift (Yarats et al. 2021): replicate-pad by 4 px and crop back to the
original size at a random offset, i.e. a translation of at most 4 px whose uncovered border repeats
the edge pixels. ``color`` is torchvision's ColorJitter (brightness, contrast, saturation, hue 0.2),
applied to each image with probability 0.3. torchvision draws one set of jitter factors per call, so
it is called once per selected image, never once per batch. Nothing happens in eval mode.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn
from torchvision.transforms import ColorJitter

from ..common.augment import random_shift
from .configuration_bc import AUGMENTATIONS


class ImageAugmentation(nn.Module):
    """(N, 3, H, W) images in [0, 1] -> the same, augmented in training mode only."""

    def __init__(self, mode: str, shift_pad: int = 4, jitter: float = 0.2, prob: float = 0.3) -> None:
        super().__init__()
        if mode not in AUGMENTATIONS:
            raise ValueError(f"unknown augmentation {mode!r}; valid: {', '.join(AUGMENTATIONS)}")
        self.mode = mode
        self.shift = mode in ("shift", "shift+color")
        self.color = mode in ("color", "shift+color")
        self.shift_pad = shift_pad
        self.prob = prob
        self.jitter = ColorJitter(brightness=jitter, contrast=jitter, saturation=jitter, hue=jitter)

    @property
    def active(self) -> bool:
        return self.training and (self.shift or self.color)

    def forward(self, images: Tensor) -> Tensor:
        if not self.training:
            return images
        if self.shift and self.shift_pad > 0:
            images = random_shift(images, self.shift_pad)
        if self.color:
            chosen = (torch.rand(images.shape[0], device=images.device) < self.prob).nonzero().flatten().tolist()
            if chosen:
                images = images.clone()
                for i in chosen:
                    images[i] = self.jitter(images[i])
        return images
