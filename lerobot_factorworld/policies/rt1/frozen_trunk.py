"""RT-1's image tokenizer with a frozen ImageNet trunk computed once per frame (preset ``lite0_frozen``).

The departure from the reference, and why: RT-1 puts a FiLM layer after every MBConv block of a trainable
EfficientNet, so every frame of every window goes through the whole CNN at every epoch. Here the first
``trunk_blocks`` MBConv blocks of EfficientNet-Lite0 (ImageNet weights shipped offline) are frozen and in eval
mode, so their feature map is a fixed function of the frame's pixels: it is computed once per frame and cached
(``policies/common/feature_cache.py``). Language enters after the trunk: a trainable 1x1 projection, then
``head_blocks`` residual 1x1 blocks each followed by FiLM, then RT-1's final FiLM. TokenLearner, the
transformer and the 256-bin head train as in the other presets.

Augmentation cannot touch the pixels (every augmented frame would be new to the cache); ``feature_shift`` shifts
the cached feature map instead (DrQ's shift on the map: replicate-pad by that many cells, crop back at a random
offset), one draw per frame from torch's RNG.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn

from ..common.augment import random_shift
from ..common.efficientnet_lite import LITE0_STAGES, LiteNet, load_lite0_imagenet
from ..common.feature_cache import FeatureCache
from ..common.image_stats import LITE_MEAN, LITE_STD
from .film_efficientnet import FiLM

LITE0_BLOCKS = sum(stage.repeats for stage in LITE0_STAGES)  # 16 MBConv blocks


class FrozenLite0Trunk(nn.Module):
    """The first ``blocks`` MBConv blocks of ImageNet EfficientNet-Lite0: (N, 3, H, W) in [0, 1] -> (N, C, h, w).

    Never trains: no gradients, eval mode always (BatchNorm keeps ImageNet's statistics), so that a frame's
    feature map never changes and may be cached.
    """

    def __init__(self, blocks: int, image_size: int, pretrained: bool) -> None:
        super().__init__()
        if not 1 <= blocks <= LITE0_BLOCKS:
            raise ValueError(f"trunk_blocks={blocks}: EfficientNet-Lite0 has MBConv blocks 1..{LITE0_BLOCKS}")
        net = LiteNet(LITE0_STAGES)
        if pretrained:
            load_lite0_imagenet(net)
        self.stem_conv, self.stem_bn = net._conv_stem, net._bn0
        self.blocks = nn.ModuleList(net._blocks[:blocks])
        self.out_channels = net.block_channels()[blocks - 1]
        self.image_size = image_size
        self.register_buffer("mean", torch.tensor(LITE_MEAN).view(1, 3, 1, 1), persistent=False)
        self.register_buffer("std", torch.tensor(LITE_STD).view(1, 3, 1, 1), persistent=False)
        for p in self.parameters():
            p.requires_grad_(False)
        super().train(False)

    def train(self, mode: bool = True) -> FrozenLite0Trunk:
        return super().train(False)

    @torch.no_grad()
    def forward(self, images: Tensor) -> Tensor:
        if images.shape[-1] != self.image_size or images.shape[-2] != self.image_size:
            images = F.interpolate(
                images, size=(self.image_size, self.image_size), mode="bilinear", align_corners=False
            )
        x = ((images - self.mean) / self.std).contiguous(memory_format=torch.channels_last)
        x = F.relu6(self.stem_bn(self.stem_conv(x)))
        for block in self.blocks:
            x = block(x)
        return x.contiguous()


class FiLMBlock(nn.Module):
    """Residual ``x + FiLM(ReLU(LayerNorm(Linear(x))), language)`` at every cell of the map: a language-conditioned
    1x1 step. It has no spatial kernel, since the trunk's receptive field already spans the frame and TokenLearner
    pools over cells; the head runs on every frame of every window, where a 3x3 convolution's backward cost most
    of a training step on CPU (measured). The FiLM starts as the identity, as RT-1's do."""

    def __init__(self, channels: int, context_dim: int) -> None:
        super().__init__()
        self.linear = nn.Linear(channels, channels)
        self.norm = nn.LayerNorm(channels)
        self.film = FiLM(context_dim, channels)

    def forward(self, x: Tensor, context: Tensor) -> Tensor:  # x (N, h*w, C), context (N, D)
        y = F.relu(self.norm(self.linear(x)))
        return x + self.film(y.transpose(1, 2).unsqueeze(-1), context).squeeze(-1).transpose(1, 2)


class FrozenTrunkFiLMEncoder(nn.Module):
    """Image (B, 3, H, W) in [0, 1] + context (B, D) -> feature map (B, out_dim, h, w), like ``FiLMEfficientNet``.

    Frozen Lite0 trunk (cached per frame in training), optional shift of its map, then the trainable head: 1x1
    projection to ``out_dim``, ``head_blocks`` FiLM blocks (1x1), RT-1's final FiLM.
    """

    def __init__(
        self,
        context_dim: int,
        out_dim: int,
        *,
        trunk_blocks: int,
        head_blocks: int,
        image_size: int,
        feature_shift: int,
        cache_size: int,
        pretrained: bool,
    ) -> None:
        super().__init__()
        self.trunk = FrozenLite0Trunk(trunk_blocks, image_size, pretrained)
        self.project = nn.Linear(self.trunk.out_channels, out_dim)
        self.blocks = nn.ModuleList(FiLMBlock(out_dim, context_dim) for _ in range(head_blocks))
        self.final_film = FiLM(context_dim, out_dim)
        self.feature_shift = feature_shift
        self.cache = FeatureCache(cache_size) if cache_size > 0 else None
        # Weights loaded into the policy may change the trunk: forget every cached feature map.
        self.register_load_state_dict_pre_hook(self._forget)

    def _forget(self, *args, **kwargs) -> None:
        if self.cache is not None:
            self.cache.clear()

    def trunk_features(self, images: Tensor) -> Tensor:
        """The frozen trunk's map of each frame; in training from the cache (un-augmented pixels: a fixed function)."""
        if self.training and self.cache is not None:
            return self.cache(images, self.trunk)
        return self.trunk(images)

    def forward(self, images: Tensor, context: Tensor) -> Tensor:
        x = self.trunk_features(images)
        if self.training and self.feature_shift > 0:
            x = random_shift(x, self.feature_shift)
        n, _, h, w = x.shape
        x = self.project(x.flatten(2).transpose(1, 2))  # (N, h*w, out_dim): 1x1 convolutions as matrix products
        for block in self.blocks:
            x = block(x, context)
        return self.final_film(x.transpose(1, 2).reshape(n, -1, h, w), context)
