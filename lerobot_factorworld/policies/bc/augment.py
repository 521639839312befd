"""The paper's two training-time image augmentations, each drawn independently per image.

``shift`` is DrQ's random shift (Yarats et al. 2021): replicate-pad by 4 px and crop back to the
original size at a random offset, i.e. a translation of at most 4 px whose uncovered border repeats
the edge pixels. ``color`` is the paper's photometric distortion (section 5.2: brightness, saturation,
hue and contrast, then random cutout and random Gaussian noise), applied to each image with
probability 0.3 (the appendix's probability for its colour jitter):

1. torchvision's ColorJitter (brightness, contrast, saturation, hue 0.2; the appendix's values).
   torchvision draws one set of jitter factors per call, so it is called once per selected image,
   never once per batch;
2. with probability ``cutout_prob`` (0.5), one black rectangle, each side drawn from ``cutout_size``
   (0.12-0.35 of the image side: 10-29 px at 84 px, RAD's cutout), placed wholly inside the image;
3. with probability ``noise_prob`` (0.5), Gaussian noise of standard deviation ``noise_std`` (0.1, on
   pixels in [0, 1]) on every pixel, clipped to [0, 1].

The paper gives no values for cutout and noise; these are stated in ``docs/bc.md``. Every draw comes
from torch's RNG. Nothing happens in eval mode.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn
from torchvision.transforms import ColorJitter

from ..common.augment import gaussian_noise, random_cutout, random_shift
from .configuration_bc import AUGMENTATIONS


class ImageAugmentation(nn.Module):
    """(N, 3, H, W) images in [0, 1] -> the same, augmented in training mode only."""

    def __init__(
        self,
        mode: str,
        shift_pad: int = 4,
        jitter: float = 0.2,
        prob: float = 0.3,
        cutout_prob: float = 0.5,
        cutout_size: tuple[float, float] = (0.12, 0.35),
        noise_prob: float = 0.5,
        noise_std: float = 0.1,
    ) -> None:
        super().__init__()
        if mode not in AUGMENTATIONS:
            raise ValueError(f"unknown augmentation {mode!r}; valid: {', '.join(AUGMENTATIONS)}")
        self.mode = mode
        self.shift = mode in ("shift", "shift+color")
        self.color = mode in ("color", "shift+color")
        self.shift_pad = shift_pad
        self.prob = prob
        self.jitter = ColorJitter(brightness=jitter, contrast=jitter, saturation=jitter, hue=jitter)
        self.cutout_prob, self.cutout_size = cutout_prob, tuple(cutout_size)
        self.noise_prob, self.noise_std = noise_prob, noise_std

    @property
    def active(self) -> bool:
        return self.training and (self.shift or self.color)

    def forward(self, images: Tensor) -> Tensor:
        if not self.training:
            return images
        if self.shift and self.shift_pad > 0:
            images = random_shift(images, self.shift_pad)
        if self.color:
            images = self.photometric(images)
        return images

    def photometric(self, images: Tensor) -> Tensor:
        """Jitter, then cutout, then noise, on the images drawn with probability ``prob`` (each independently)."""
        device = images.device
        chosen = (torch.rand(images.shape[0], device=device) < self.prob).nonzero().flatten()
        if not len(chosen):
            return images
        images = images.clone()
        for i in chosen.tolist():
            images[i] = self.jitter(images[i])
        # no draw for a step whose probability is 0: with both at 0 this is exactly the jitter-only stream
        if self.cutout_prob > 0:
            cut = chosen[torch.rand(len(chosen), device=device) < self.cutout_prob]
            if len(cut):
                images[cut] = random_cutout(images[cut], self.cutout_size)
        if self.noise_prob > 0 and self.noise_std > 0:
            noisy = chosen[torch.rand(len(chosen), device=device) < self.noise_prob]
            if len(noisy):
                images[noisy] = gaussian_noise(images[noisy], self.noise_std)
        return images
