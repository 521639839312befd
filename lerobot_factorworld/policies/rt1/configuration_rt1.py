"""``RT1Config`` (``--policy.type=rt1``): RT-1's architecture with named presets.

Presets fill every architecture field left unset (``None``); anything given explicitly wins, and the
saved ``config.json`` holds the resolved values, so a checkpoint reloads exactly.

==========  ==================================================  =========================================
preset      backbone / transformer                              for
==========  ==================================================  =========================================
``rt1``     FiLM-EfficientNet-B3 @300 px, 8 layers x d512 x 8    faithful RT-1 (~35M params), GPU
            heads, RT-1's linear feed-forward
``lite0``   FiLM-EfficientNet-Lite0 @128 px with packaged        a pretrained backbone that works offline
            ImageNet weights, 4 layers x d256
``small``   tiny FiLM-MBConv net @84 px, 2 layers x d128         2 CPU cores: tests and the embedded demo
``lite0_    frozen ImageNet Lite0 trunk @128 px computed once     2 CPU cores: a pretrained trunk within a
frozen``    per frame, FiLM after it; 2 layers x d128            CPU budget (``frozen_trunk.py``)
==========  ==================================================  =========================================

``factorworld rt1-presets`` prints each preset's parameter count.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

from lerobot.configs import FeatureType, NormalizationMode, PreTrainedConfig
from lerobot.optim import AdamWConfig

from ...scene.cameras import DEFAULT_IMAGE_SIZE
from ..common.config import default_normalization_mapping, require_images_and_action
from ..common.language import MINILM_DIM
from ..common.speed import check_speed
from .film_efficientnet import BACKBONES
from .frozen_trunk import LITE0_BLOCKS

PRESETS: dict[str, dict] = {
    "rt1": dict(
        backbone="efficientnet_b3",
        pretrained_backbone=False,
        image_size=300,
        token_dim=512,
        dim=512,
        layers=8,
        heads=8,
        head_dim=128,
        ffn="rt1",
        ffn_dim=512,
        crop="random_resized",
        optimizer_lr=1e-4,
    ),
    "lite0": dict(
        backbone="efficientnet_lite0",
        pretrained_backbone=True,
        image_size=128,
        token_dim=256,
        dim=256,
        layers=4,
        heads=4,
        head_dim=64,
        ffn="mlp",
        ffn_dim=1024,
        crop="shift",
        optimizer_lr=3e-4,
    ),
    "small": dict(
        backbone="tiny",
        pretrained_backbone=False,
        image_size=DEFAULT_IMAGE_SIZE,  # the env's default: frames are not resized
        token_dim=128,
        dim=128,
        layers=2,
        heads=4,
        head_dim=32,
        ffn="mlp",
        ffn_dim=256,
        crop="shift",
        optimizer_lr=3e-4,
    ),
    "lite0_frozen": dict(
        backbone="efficientnet_lite0",
        pretrained_backbone=True,
        frozen_backbone=True,
        trunk_blocks=11,  # through Lite0's 112-channel stage: stride 16, an 8 x 8 map at 128 px
        head_blocks=1,
        image_size=128,
        token_dim=128,
        dim=128,
        layers=2,
        heads=4,
        head_dim=32,
        ffn="mlp",
        ffn_dim=256,
        crop="none",  # pixels stay as rendered (the cache's key); the map is shifted instead (feature_shift)
        photometric=False,
        feature_shift=1,
        optimizer_lr=3e-4,
    ),
}
# What the faithful presets (FiLM inside a trainable backbone) leave as they always were.
PRESET_DEFAULTS: dict = dict(frozen_backbone=False, trunk_blocks=0, head_blocks=0, feature_shift=0, photometric=True)
CROPS = ("shift", "random_resized", "none")


@PreTrainedConfig.register_subclass("rt1")
@dataclass
class RT1Config(PreTrainedConfig):
    """RT-1 policy configuration.

    Attributes:
        preset: Named architecture (``rt1``, ``lite0``, ``small``, ``lite0_frozen``) filling the fields left ``None``.
        n_obs_steps: History length (RT-1: 6 frames); actions are predicted for every step.
        action_bins: Uniform bins per action dimension (RT-1: 256), over the min-max normalised range.
        num_tokens: TokenLearner tokens per frame and camera (RT-1: 8).
        backbone: ``efficientnet_b3``, ``efficientnet_lite0`` or ``tiny``.
        pretrained_backbone: Start from ImageNet weights (lite0: shipped; b3: from ``backbone_weights_path``).
        backbone_weights_path: Local torchvision EfficientNet-B3 state dict (never downloaded; implies
            ``pretrained_backbone``, and an explicit ``pretrained_backbone=false`` next to it is refused), loaded
            strictly when a policy is built fresh. ``from_pretrained`` does not read it: the checkpoint holds
            the trained backbone.
        frozen_backbone: Freeze the pretrained trunk (``efficientnet_lite0`` only) and compute its feature map once
            per frame: language then enters by FiLM after the trunk, not inside it (``frozen_trunk.py``). False for
            the faithful presets.
        trunk_blocks: Frozen trunk only: how many of Lite0's 16 MBConv blocks it keeps (11: through the stride-16
            stage).
        head_blocks: Frozen trunk only: trainable residual 1x1 blocks after it, each followed by FiLM.
        feature_shift: Frozen trunk only: training shift of the cached feature map, in cells (0: none).
        feature_cache_size: Frozen trunk only: trunk feature maps of up to this many training frames kept in
            memory, keyed by the frame's pixels (0 disables; ``policies/common/feature_cache.py``).
        image_size: Side the frames are resized to before the backbone.
        token_dim: Channels of the FiLM-EfficientNet output (1x1 conv) and of each image token.
        dim / layers / heads / head_dim / ffn / ffn_dim / dropout: the transformer (RT-1: 8 heads of 128 on
            d512; ``ffn="rt1"``: the reference's single linear feed-forward layer).
        crop: Training crop augmentation of the pixels (``none`` with a frozen trunk): ``shift`` (pad ``crop_pad`` px and crop back, for small images),
            ``random_resized`` (random ``crop_scale`` crop of the full frame, resized; center crop at eval)
            or ``none``.
        photometric: Brightness shift in [-0.125, 0.125], contrast and saturation factors in [0.5, 1.5] (off with a
            frozen trunk). ``None`` takes the preset's (on, except ``lite0_frozen``).
        token_reuse: At inference, tokenize only the new frame and reuse the window's earlier tokens.
        language_dim: Size of the instruction embedding the FiLM layers take; must be 384 (``MINILM_DIM``),
            what RT-1's language step (MiniLM-L6, the only encoder shipped offline) gives.
        normalization_mapping: ACTION must stay MIN_MAX (the bins span [-1, 1]); other modes are refused.
        speed: ``default`` (float32: every existing result; the backbone's input is channels-last under either
            value, as it always was) or ``fast`` (bfloat16 autocast over the forward, in training and in action
            selection, tokens reused across steps included). One setting shared with bc, documented in
            ``policies/common/speed.py``.
    """

    preset: str = "small"
    n_obs_steps: int = 6
    action_bins: int = 256
    num_tokens: int = 8
    backbone: str | None = None
    pretrained_backbone: bool | None = None
    backbone_weights_path: str | None = None
    frozen_backbone: bool | None = None
    trunk_blocks: int | None = None
    head_blocks: int | None = None
    feature_shift: int | None = None
    feature_cache_size: int = 100_000
    image_size: int | None = None
    token_dim: int | None = None
    dim: int | None = None
    layers: int | None = None
    heads: int | None = None
    head_dim: int | None = None
    ffn: str | None = None
    ffn_dim: int | None = None
    dropout: float = 0.1
    crop: str | None = None
    crop_pad: int = 4
    crop_scale: float = 0.9
    photometric: bool | None = None
    token_reuse: bool = True
    language_dim: int = MINILM_DIM
    speed: str = "default"
    optimizer_lr: float | None = None
    optimizer_weight_decay: float = 0.0
    normalization_mapping: dict[str, NormalizationMode] = field(default_factory=default_normalization_mapping)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_speed(self.speed)
        if self.preset not in PRESETS:
            raise ValueError(f"unknown RT-1 preset {self.preset!r}; valid presets: {', '.join(PRESETS)}")
        self._resolve_backbone_start()
        names = {f.name for f in fields(self)}
        for key, value in {**PRESET_DEFAULTS, **PRESETS[self.preset]}.items():
            assert key in names, key
            if getattr(self, key) is None:
                setattr(self, key, value)
        if self.crop not in CROPS:
            raise ValueError(f"unknown crop {self.crop!r}; valid: {', '.join(CROPS)}")
        if self.n_obs_steps < 1 or self.action_bins < 2:
            raise ValueError("n_obs_steps must be >= 1 and action_bins >= 2")
        self._check_backbone_weights()
        self._check_frozen_trunk()
        self._check_action_normalization()
        self._check_language_dim()

    def _resolve_backbone_start(self) -> None:
        """A weights file means "start from it": it sets ``pretrained_backbone`` (before the preset's ``False``
        could), and an explicit ``false`` next to it is a contradiction, refused while the config is new.

        Older code saved the preset's ``false`` next to a path it did load. A config that already holds its
        features comes from a saved checkpoint (``lerobot-train`` fills them in only after parsing): it keeps
        its values here, and ``RT1Policy`` refuses the contradiction when building fresh but reloads it
        (``from_pretrained`` reads no weights file and records ``pretrained_backbone=true``)."""
        if not self.backbone_weights_path:
            return
        if self.pretrained_backbone is None:
            self.pretrained_backbone = True
        elif not self.pretrained_backbone and not (self.input_features or self.output_features):
            raise ValueError(self.backbone_start_contradiction())

    def backbone_start_contradiction(self) -> str:
        return (
            f"pretrained_backbone=false contradicts backbone_weights_path={self.backbone_weights_path} (the file "
            "is read only to start from its ImageNet weights): drop backbone_weights_path to start the backbone "
            "from random weights, or drop pretrained_backbone=false to start from the file"
        )

    def _check_backbone_weights(self) -> None:
        """Where the ImageNet weights come from, checked before anything is built (the file is read at build)."""
        if self.backbone not in BACKBONES:
            raise ValueError(f"unknown backbone {self.backbone!r}; valid backbones: {', '.join(BACKBONES)}")
        if self.backbone_weights_path and self.backbone != "efficientnet_b3":
            raise ValueError(
                f"backbone_weights_path is only read by backbone=efficientnet_b3, not {self.backbone!r} "
                "(efficientnet_lite0's ImageNet weights come with its package)"
            )
        if self.pretrained_backbone and self.backbone == "tiny":
            raise ValueError(
                "no pretrained weights for backbone 'tiny'; pretrained: efficientnet_lite0, efficientnet_b3"
            )
        if self.pretrained_backbone and self.backbone == "efficientnet_b3" and not self.backbone_weights_path:
            raise ValueError(
                "efficientnet_b3 ImageNet weights are not shipped: pass backbone_weights_path=<local torchvision "
                "efficientnet_b3 state dict>, or use backbone=efficientnet_lite0 for offline pretrained weights"
            )

    def _check_frozen_trunk(self) -> None:
        """A frozen trunk is a pretrained Lite0 whose input pixels are never augmented (they key its cache)."""
        if self.frozen_backbone:
            if self.backbone != "efficientnet_lite0" or not self.pretrained_backbone:
                raise ValueError(
                    "frozen_backbone=true needs backbone=efficientnet_lite0 with pretrained_backbone=true (a frozen "
                    f"random trunk learns nothing); got backbone={self.backbone!r}, "
                    f"pretrained_backbone={self.pretrained_backbone}"
                )
            if self.crop != "none" or self.photometric:
                raise ValueError(
                    f"frozen_backbone=true computes each frame's trunk features once, so pixels are not augmented: "
                    f"crop={self.crop!r} and photometric={self.photometric} must be 'none' and false "
                    "(feature_shift shifts the cached feature map instead)"
                )
            if not 1 <= self.trunk_blocks <= LITE0_BLOCKS or self.head_blocks < 0 or self.feature_shift < 0:
                raise ValueError(
                    f"trunk_blocks must be in 1..{LITE0_BLOCKS}, head_blocks and feature_shift >= 0; got "
                    f"{self.trunk_blocks}, {self.head_blocks}, {self.feature_shift}"
                )
        if self.feature_cache_size < 0:
            raise ValueError(f"feature_cache_size must be >= 0; got {self.feature_cache_size}")

    def _check_action_normalization(self) -> None:
        """The bins span [-1, 1], which is where MIN_MAX puts the dataset's min..max; other modes do not."""
        mode = self.normalization_mapping.get(FeatureType.ACTION)  # str enum: also finds the key "ACTION"
        if mode != NormalizationMode.MIN_MAX:
            raise ValueError(
                f"RT-1 needs ACTION normalization MIN_MAX (its {self.action_bins} bins span the min-max normalised "
                f"range [-1, 1]); got {getattr(mode, 'value', mode)!r}. Valid: MIN_MAX"
            )

    def _check_language_dim(self) -> None:
        """The FiLM layers are built for ``language_dim``; the language step can only give MiniLM's size."""
        if self.language_dim != MINILM_DIM:
            raise ValueError(
                f"language_dim={self.language_dim}, but RT-1's instruction encoder (MiniLM-L6, the only one shipped "
                f"offline) gives {MINILM_DIM}-d embeddings; valid: {MINILM_DIM}"
            )

    def validate_features(self) -> None:
        require_images_and_action(self, "RT-1")
        for key, feature in self.image_features.items():
            if feature.type is not FeatureType.VISUAL:
                raise ValueError(f"{key} is not a visual feature")

    @property
    def observation_delta_indices(self) -> list[int]:
        return list(range(1 - self.n_obs_steps, 1))

    @property
    def action_delta_indices(self) -> list[int]:
        return list(range(1 - self.n_obs_steps, 1))  # RT-1 predicts the action of every step in the window

    @property
    def reward_delta_indices(self) -> None:
        return None

    def get_optimizer_preset(self) -> AdamWConfig:
        return AdamWConfig(lr=self.optimizer_lr, weight_decay=self.optimizer_weight_decay)

    def get_scheduler_preset(self) -> None:
        return None
