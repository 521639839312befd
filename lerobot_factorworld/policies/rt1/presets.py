"""Describe the RT-1 presets: architecture and measured parameter counts (built, not estimated)."""

from __future__ import annotations

import torch
from lerobot.configs import FeatureType, PolicyFeature

from ...scene.cameras import DEFAULT_IMAGE_SIZE
from .configuration_rt1 import PRESETS, RT1Config
from .modeling_rt1 import RT1Policy


def parameter_counts(preset: str, cameras: int = 1, action_dim: int = 4) -> dict[str, int]:
    """Parameters of the whole policy and of its parts, for ``cameras`` cameras and ``action_dim`` actions."""
    torch.manual_seed(0)
    features = {
        f"observation.images.cam{i}": PolicyFeature(FeatureType.VISUAL, (3, DEFAULT_IMAGE_SIZE, DEFAULT_IMAGE_SIZE))
        for i in range(cameras)
    }
    config = RT1Config(
        preset=preset,
        device="cpu",
        input_features=features,
        output_features={"action": PolicyFeature(FeatureType.ACTION, (action_dim,))},
    )
    model = RT1Policy(config).model
    count = lambda module: sum(p.numel() for p in module.parameters())  # noqa: E731
    return {
        "total": count(model),
        "image tokenizer": count(model.encoder) + count(model.token_learner),
        "transformer": count(model.transformer),
    }


def preset_table() -> str:
    lines = [
        "| preset | backbone | image | transformer | params (total / tokenizer / transformer) |",
        "|---|---|---|---|---|",
    ]
    for name, preset in PRESETS.items():
        counts = parameter_counts(name)
        pretrained = " (ImageNet, packaged)" if preset["pretrained_backbone"] else ""
        if preset.get("frozen_backbone"):
            pretrained = (
                f" (ImageNet, packaged; first {preset['trunk_blocks']} blocks frozen and cached,"
                f" then {preset['head_blocks']} FiLM block{'' if preset['head_blocks'] == 1 else 's'})"
            )
        lines.append(
            f"| {name} | {preset['backbone']}{pretrained} | {preset['image_size']} px | {preset['layers']} x d{preset['dim']},"
            f" {preset['heads']} heads x {preset['head_dim']}, ffn {preset['ffn']} | "
            + " / ".join(f"{v / 1e6:.2f}M" for v in counts.values())
            + " |"
        )
    return "\n".join(lines)
