"""Config pieces ``BCConfig`` and ``RT1Config`` share: the normalisation defaults and the feature checks."""

from __future__ import annotations

from lerobot.configs import NormalizationMode, PreTrainedConfig


def default_normalization_mapping() -> dict[str, NormalizationMode]:
    """Images stay in [0, 1] (each encoder normalises them its own way), state is standardised, and actions are
    min-max normalised to [-1, 1]: the range bc clamps its output to and RT-1's bins span."""
    return {
        "VISUAL": NormalizationMode.IDENTITY,
        "STATE": NormalizationMode.MEAN_STD,
        "ACTION": NormalizationMode.MIN_MAX,
    }


def require_images_and_action(config: PreTrainedConfig, policy: str) -> None:
    """Refuse a config without an image input or without an action output (``policy`` names it in the error)."""
    if not config.image_features:
        raise ValueError(f"{policy} needs at least one image feature (observation.image or observation.images.*)")
    if config.action_feature is None:
        raise ValueError(f"{policy} needs an 'action' output feature")
