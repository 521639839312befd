"""Image encoders of the bc policy: images (N, 3, H, W) in [0, 1] -> embeddings (N, D).

- ``ConvEncoder``: the paper's CNN (Sekar et al. 2020's encoder, as in KitchenShift): four 4x4
  convolutions with 32/64/128/128 filters, stride 2, ReLU; flatten; linear to 128; LayerNorm; tanh.
- ``PretrainedEncoder``: a frozen backbone (``backbones.py``) followed by a trainable BatchNorm, as the
  paper does for R3M and CLIP; its features may come from a per-frame cache (``policies/common/feature_cache.py``).
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from ..common.feature_cache import FeatureCache
from .backbones import FrozenBackbone


class ConvEncoder(nn.Module):
    """The paper's CNN. At 84x84: 32x41x41 -> 64x19x19 -> 128x8x8 -> 128x3x3 -> 1152 -> 128."""

    def __init__(
        self,
        image_shape: tuple[int, int, int],
        channels: tuple[int, ...] = (32, 64, 128, 128),
        kernel: int = 4,
        stride: int = 2,
        latent_dim: int = 128,
    ) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        cin = image_shape[0]
        for cout in channels:
            layers += [nn.Conv2d(cin, cout, kernel, stride), nn.ReLU(inplace=True)]
            cin = cout
        self.convs = nn.Sequential(*layers)
        with torch.no_grad():
            flat = self.convs(torch.zeros(1, *image_shape)).numel()
        self.project = nn.Sequential(nn.Linear(flat, latent_dim), nn.LayerNorm(latent_dim), nn.Tanh())
        self.out_dim = latent_dim

    def forward(self, images: Tensor) -> Tensor:
        x = self.convs(images - 0.5)  # centred pixels, as DrQ's encoder (x / 255 - 0.5)
        return self.project(x.flatten(1))


class PretrainedEncoder(nn.Module):
    """Frozen backbone -> BatchNorm (trainable). Features of training frames come from ``cache`` when enabled."""

    def __init__(self, backbone: FrozenBackbone, cache_size: int = 0) -> None:
        super().__init__()
        self.backbone = backbone
        self.norm = nn.BatchNorm1d(backbone.out_dim)
        self.out_dim = backbone.out_dim
        self.cache = FeatureCache(cache_size) if cache_size > 0 else None
        # Any weights loaded into the policy may change the backbone: forget every cached feature.
        self.register_load_state_dict_pre_hook(self._forget)

    def _forget(self, *args, **kwargs) -> None:
        if self.cache is not None:
            self.cache.clear()

    def features(self, images: Tensor, use_cache: bool) -> Tensor:
        if use_cache and self.cache is not None:
            return self.cache(images, self.backbone)
        return self.backbone(images)

    def forward(self, images: Tensor, use_cache: bool = False) -> Tensor:
        return self.norm(self.features(images, use_cache))
