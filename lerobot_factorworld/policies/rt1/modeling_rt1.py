"""``RT1Policy``: LeRobot shell (history, loss, token reuse) around the plain ``RT1`` network.

Shapes: B batch, T history steps (``n_obs_steps``), K cameras, N = K * num_tokens image tokens per
step, A action dimensions, V = action_bins.
"""

from __future__ import annotations

from collections import deque

import torch
import torch.nn.functional as F  # noqa: N812
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.utils.constants import ACTION
from torch import Tensor, nn

from ..common.augment import random_shift
from ..common.language import LANGUAGE_EMBEDDING_KEY
from ..common.speed import as_float32, compute_context, is_fast
from ..common.weights import RestoresBackboneFromCheckpoint
from .configuration_rt1 import RT1Config
from .film_efficientnet import FiLMEfficientNet
from .frozen_trunk import FrozenTrunkFiLMEncoder
from .tokenizers import ActionTokenizer, TokenLearner
from .transformer import RT1Transformer, TransformerSpec

BRIGHTNESS = 0.125
CONTRAST = (0.5, 1.5)
SATURATION = (0.5, 1.5)


class RT1(nn.Module):
    """Images (B, T, 3, H, W) per camera + instruction embedding (B, D) -> action logits (B, T, A, V)."""

    def __init__(
        self, config: RT1Config, camera_keys: list[str], action_dim: int, load_backbone_weights: bool = True
    ) -> None:
        super().__init__()
        self.config, self.camera_keys = config, camera_keys
        pretrained = bool(config.pretrained_backbone) and load_backbone_weights
        if config.frozen_backbone:
            self.encoder = FrozenTrunkFiLMEncoder(
                config.language_dim,
                config.token_dim,
                trunk_blocks=config.trunk_blocks,
                head_blocks=config.head_blocks,
                image_size=config.image_size,
                feature_shift=config.feature_shift,
                cache_size=config.feature_cache_size,
                pretrained=pretrained,
            )
        else:
            self.encoder = FiLMEfficientNet(
                config.backbone,
                config.language_dim,
                config.token_dim,
                pretrained=pretrained,
                weights_path=config.backbone_weights_path,
            )
        if is_fast(config.speed) and not config.frozen_backbone:
            self.encoder.keep_depthwise_float32()
        self.token_learner = TokenLearner(config.token_dim, config.num_tokens)
        self.transformer = RT1Transformer(TransformerSpec.from_config(config, len(camera_keys), action_dim))

    def frame_tokens(self, images: dict[str, Tensor], language: Tensor) -> Tensor:
        """Tokens of single frames: images[cam] (M, 3, H, W), language (M, D) -> (M, N, token_dim)."""
        tokens = []
        for key in self.camera_keys:
            # a frozen trunk takes the frames as rendered: they key its cache, and it resizes them itself
            x = images[key] if self.config.frozen_backbone else self.prepare(images[key])
            tokens.append(self.token_learner(self.encoder(x, language)))
        return torch.cat(tokens, dim=1)

    def forward(self, images: dict[str, Tensor], language: Tensor) -> Tensor:
        b, t = next(iter(images.values())).shape[:2]
        flat = {k: v.flatten(0, 1) for k, v in images.items()}  # (B*T, 3, H, W)
        tokens = self.frame_tokens(flat, language.repeat_interleave(t, dim=0))
        return self.transformer(tokens.view(b, t, *tokens.shape[1:]))

    # --- image preparation and augmentation (each frame independently, training only) ----------

    def prepare(self, x: Tensor) -> Tensor:
        cfg = self.config
        if self.training and cfg.crop == "shift":
            x = random_shift(x, cfg.crop_pad)
        elif cfg.crop == "random_resized":
            x = random_crop(x, cfg.crop_scale) if self.training else center_crop(x, cfg.crop_scale)
        if x.shape[-1] != cfg.image_size or x.shape[-2] != cfg.image_size:
            x = F.interpolate(x, size=(cfg.image_size, cfg.image_size), mode="bilinear", align_corners=False)
        if self.training and cfg.photometric:
            x = photometric(x)
        return x


def random_crop(x: Tensor, scale: float) -> Tensor:
    """A random ``scale`` x ``scale`` crop of each frame (resized back by the caller)."""
    n, _, h, w = x.shape
    ch, cw = max(1, round(h * scale)), max(1, round(w * scale))
    top = torch.randint(0, h - ch + 1, (n,)).tolist()
    left = torch.randint(0, w - cw + 1, (n,)).tolist()
    return torch.stack([x[i, :, t : t + ch, s : s + cw] for i, (t, s) in enumerate(zip(top, left, strict=True))])


def center_crop(x: Tensor, scale: float) -> Tensor:
    h, w = x.shape[-2:]
    ch, cw = max(1, round(h * scale)), max(1, round(w * scale))
    top, left = (h - ch) // 2, (w - cw) // 2
    return x[..., top : top + ch, left : left + cw]


def photometric(x: Tensor) -> Tensor:
    """RT-1's photometric distortion per image: brightness shift, then contrast, then saturation."""
    n = x.shape[0]
    rand = lambda low, high: torch.empty(n, 1, 1, 1, device=x.device).uniform_(low, high)  # noqa: E731
    x = x + rand(-BRIGHTNESS, BRIGHTNESS)
    mean = x.mean(dim=(1, 2, 3), keepdim=True)
    x = (x - mean) * rand(*CONTRAST) + mean
    gray = 0.299 * x[:, 0:1] + 0.587 * x[:, 1:2] + 0.114 * x[:, 2:3]
    x = gray + (x - gray) * rand(*SATURATION)
    return x.clamp(0.0, 1.0)


class RT1Policy(RestoresBackboneFromCheckpoint, PreTrainedPolicy):
    """RT-1 for LeRobot (``--policy.type=rt1``).

    ``from_pretrained`` takes the backbone from the checkpoint alone, loaded strictly: ``backbone_weights_path``
    (the ImageNet start) is not read again, and may be gone.
    """

    config_class = RT1Config
    name = "rt1"

    def __init__(
        self,
        config: RT1Config,
        dataset_stats=None,
        dataset_meta=None,
        *,
        load_backbone_weights: bool = True,
        **kwargs,
    ) -> None:
        """``load_backbone_weights=False`` skips reading the ImageNet weights (``from_pretrained`` restores them)."""
        super().__init__(config)
        config.validate_features()
        if config.backbone_weights_path and not config.pretrained_backbone:
            if load_backbone_weights:  # a fresh build would have to choose between the two settings
                raise ValueError(config.backbone_start_contradiction())
            # A checkpoint of older code, which saved the preset's False next to the file it started from.
            config.pretrained_backbone = True
        self.config = config
        self.camera_keys = sorted(config.image_features)
        self.action_dim = config.action_feature.shape[0]
        self.model = RT1(config, self.camera_keys, self.action_dim, load_backbone_weights)
        self.action_tokenizer = ActionTokenizer(config.action_bins)
        self.reset()

    def get_optim_params(self):
        return self.parameters()

    def reset(self) -> None:
        """Forget the history (each rollout starts with an empty window)."""
        self._tokens: deque[Tensor] = deque(maxlen=self.config.n_obs_steps)
        self._frames: deque[dict[str, Tensor]] = deque(maxlen=self.config.n_obs_steps)

    def forward(self, batch: dict[str, Tensor], reduction: str = "mean") -> tuple[Tensor, dict]:
        images = {key: batch[key] for key in self.camera_keys}  # (B, T, 3, H, W)
        with self._compute(batch):
            logits = as_float32(self.model(images, batch[LANGUAGE_EMBEDDING_KEY]), self.config.speed)  # (B, T, A, V)
        actions = batch[ACTION]  # (B, T, A), min-max normalised to [-1, 1]
        valid = ~batch["action_is_pad"] if "action_is_pad" in batch else None
        loss = self.action_tokenizer.loss(logits, actions, valid, per_sample=reduction == "none")
        with torch.no_grad():
            hits = (logits.argmax(-1) == self.action_tokenizer.tokenize(actions)).float()
            accuracy = (hits.mean(-1)[valid] if valid is not None else hits).mean().item()
        return loss, {"token_accuracy": accuracy}

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """(B, 1, A): the action for this frame after the history, leaving the history and the mode unchanged."""
        was_training = self.training
        self.eval()
        try:
            with self._compute(batch):
                window, _ = self._window(batch)
                return self._act(window).unsqueeze(1)
        finally:
            self.train(was_training)

    @torch.no_grad()
    def select_action(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """One new frame per call: (B, 3, H, W) per camera -> action (B, A); the frame joins the history."""
        self.eval()
        with self._compute(batch):
            window, history = self._window(batch)
            queue = self._tokens if self.config.token_reuse else self._frames
            queue.clear()
            queue.extend(history)
            return self._act(window)

    def _compute(self, batch: dict[str, Tensor]):
        """The forward's compute context under ``config.speed``: bf16 autocast for ``fast``, nothing for ``default``
        (``policies/common/speed.py``; the backbone's input is channels-last under either)."""
        return compute_context(self.config.speed, batch[self.camera_keys[0]].device)

    def _act(self, window: Tensor) -> Tensor:
        logits = self.model.transformer(window)[:, -1]  # (B, A, V)
        return self.action_tokenizer.detokenize(logits.argmax(-1))

    def _window(self, batch: dict[str, Tensor]) -> tuple[Tensor, list]:
        """Image tokens (B, T, N, token_dim) of the history plus this frame, and that new history.

        The stored history is not touched: ``select_action`` stores the new one, ``predict_action_chunk`` does not.
        """
        language = batch[LANGUAGE_EMBEDDING_KEY]
        frame = {key: batch[key] for key in self.camera_keys}
        if self.config.token_reuse:
            tokens = self.model.frame_tokens(frame, language)  # only the new frame goes through the CNN
            history = self._extended(self._tokens, tokens)
            return torch.stack(history, dim=1), history
        history = self._extended(self._frames, frame)
        stacked = {k: torch.stack([f[k] for f in history], dim=1) for k in self.camera_keys}
        b, t = stacked[self.camera_keys[0]].shape[:2]
        tokens = self.model.frame_tokens(
            {k: v.flatten(0, 1) for k, v in stacked.items()}, language.repeat_interleave(t, dim=0)
        )
        return tokens.view(b, t, *tokens.shape[1:]), history

    def _extended(self, queue: deque, item) -> list:
        """The window after ``item`` as a new list; like LeRobot's training padding, a first frame fills it."""
        items = list(queue) + [item] if queue else [item] * self.config.n_obs_steps
        return items[-self.config.n_obs_steps :]
