"""``BCPolicy``: LeRobot shell (loss, action clamp, checkpoint loading) around the plain ``BCNet``.

Shapes: B batch, K cameras, D embedding per camera, S state size, A action size. One step in, one
action out: ``observation.state`` already carries the previous step's end-effector position.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn

from ..common.language import LANGUAGE_EMBEDDING_KEY, MINILM_DIM
from ..common.speed import as_float32, compute_context, encoder_input
from ..common.weights import RestoresBackboneFromCheckpoint
from .augment import ImageAugmentation
from .backbones import build_backbone
from .configuration_bc import BCConfig
from .encoders import ConvEncoder, PretrainedEncoder


def mlp(in_dim: int, hidden: int, layers: int, out_dim: int) -> nn.Sequential:
    """``layers`` linear layers, ReLU between them; the last one outputs ``out_dim`` with no activation."""
    dims = [in_dim] + [hidden] * (layers - 1) + [out_dim]
    modules: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(dims[:-1], dims[1:], strict=True)):
        modules.append(nn.Linear(a, b))
        if i < layers - 1:
            modules.append(nn.ReLU(inplace=True))
    return nn.Sequential(*modules)


class BCNet(nn.Module):
    """Images (B, 3, H, W) per camera + state (B, S) [+ instruction embedding] -> action (B, A)."""

    def __init__(
        self, config: BCConfig, camera_keys: list[str], state_dim: int, action_dim: int, load_backbone_weights: bool
    ) -> None:
        super().__init__()
        self.config, self.camera_keys = config, camera_keys
        self.augment = ImageAugmentation(
            config.augmentation,
            config.shift_pad,
            config.color_jitter,
            config.color_prob,
            config.cutout_prob,
            config.cutout_size,
            config.noise_prob,
            config.noise_std,
        )
        image_shape = tuple(config.image_features[camera_keys[0]].shape)
        if config.trains_encoder:
            self.encoder: nn.Module = ConvEncoder(
                image_shape, config.conv_channels, config.conv_kernel, config.conv_stride, config.latent_dim
            )
        else:
            backbone = build_backbone(config.encoder, config.encoder_weights_path, load_backbone_weights)
            self.encoder = PretrainedEncoder(backbone, config.feature_cache_size)
        language_dim = MINILM_DIM if config.use_language else 0
        in_dim = self.encoder.out_dim * len(camera_keys) + state_dim + language_dim
        self.head = mlp(in_dim, config.hidden_dim, config.mlp_layers, action_dim)

    def encode(self, images: Tensor) -> Tensor:
        images = encoder_input(self.augment(images), self.config.speed)  # speed=fast: channels-last
        if isinstance(self.encoder, PretrainedEncoder):
            # cached features are valid for un-augmented training frames only
            return self.encoder(images, use_cache=self.training and not self.augment.active)
        return self.encoder(images)

    def forward(self, batch: dict[str, Tensor]) -> Tensor:
        # One encoder shared by every camera: the cameras go through it as one batch (K*B, 3, H, W).
        images = torch.cat([batch[key] for key in self.camera_keys])
        b = images.shape[0] // len(self.camera_keys)
        embeddings = self.encode(images).view(len(self.camera_keys), b, -1).transpose(0, 1).flatten(1)  # (B, K*D)
        parts = [embeddings]
        if self.config.robot_state_feature is not None:
            parts.append(batch[OBS_STATE])
        if self.config.use_language:
            parts.append(batch[LANGUAGE_EMBEDDING_KEY])
        return self.head(torch.cat(parts, dim=-1))


class BCPolicy(RestoresBackboneFromCheckpoint, PreTrainedPolicy):
    """Behaviour cloning (``--policy.type=bc``): mean-squared error on min-max normalised actions.

    ``from_pretrained`` takes the frozen encoder from the checkpoint, loaded strictly: its original weights
    file (``encoder_weights_path``) is not read again, and may be gone.
    """

    config_class = BCConfig
    name = "bc"

    def __init__(
        self,
        config: BCConfig,
        dataset_stats=None,
        dataset_meta=None,
        *,
        load_backbone_weights: bool = True,
        **kwargs,
    ) -> None:
        """``load_backbone_weights=False`` leaves a frozen encoder random (``from_pretrained`` fills it)."""
        super().__init__(config)
        config.validate_features()
        self.config = config
        self.camera_keys = sorted(config.image_features)
        state = config.robot_state_feature
        self.model = BCNet(
            config,
            self.camera_keys,
            state.shape[0] if state is not None else 0,
            config.action_feature.shape[0],
            load_backbone_weights,
        )

    def get_optim_params(self):
        return [p for p in self.parameters() if p.requires_grad]

    def reset(self) -> None:
        """Nothing to forget: the policy sees one step at a time."""

    def forward(self, batch: dict[str, Tensor], reduction: str = "mean") -> tuple[Tensor, dict]:
        predicted = self._predict(batch)  # (B, A), normalised action space
        per_sample = F.mse_loss(predicted, batch[ACTION], reduction="none").mean(dim=-1)  # (B,)
        loss = per_sample if reduction == "none" else per_sample.mean()
        with torch.no_grad():
            l1 = (predicted - batch[ACTION]).abs().mean().item()
        return loss, {"l1": l1}

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        return self.select_action(batch).unsqueeze(1)

    @torch.no_grad()
    def select_action(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """(B, A) action, clamped to [-1, 1]: the range of the dataset's actions after min-max normalisation."""
        self.eval()
        return self._predict(batch).clamp(-1.0, 1.0)

    def _predict(self, batch: dict[str, Tensor]) -> Tensor:
        """``BCNet``'s float32 output (B, A), computed under ``config.speed`` (``policies/common/speed.py``)."""
        speed = self.config.speed
        with compute_context(speed, batch[self.camera_keys[0]].device):
            return as_float32(self.model(batch), speed)
