"""Per-channel mean and std that pretrained image weights expect, for pixels in [0, 1].

``IMAGENET_*``: torchvision's ImageNet weights (EfficientNet-B3, R3M's ResNet-50). ``LITE_*``: the
EfficientNet-Lite weights, trained on ``(x - 127) / 128`` of 0..255 pixels.
"""

from __future__ import annotations

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
LITE_MEAN, LITE_STD = (127 / 255,) * 3, (128 / 255,) * 3
