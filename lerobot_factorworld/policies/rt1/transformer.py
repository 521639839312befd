"""RT-1's decoder-only transformer over [image tokens, action slots] per step, block-causal in time."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn

if TYPE_CHECKING:
    from .configuration_rt1 import RT1Config


@dataclass(frozen=True)
class TransformerSpec:
    """Everything that shapes the transformer: the config's architecture fields plus the data's sizes.

    Attributes:
        token_dim: Size of each incoming image token.
        dim / layers / heads / head_dim / ffn / ffn_dim / dropout: as in ``RT1Config``.
        steps: History length (``n_obs_steps``).
        image_tokens: Image tokens per step (``num_tokens`` x cameras).
        action_dims: Action dimensions, one zero-input slot each per step.
        bins: Output vocabulary (``action_bins``).
    """

    token_dim: int
    dim: int
    layers: int
    heads: int
    head_dim: int
    ffn: str
    ffn_dim: int
    dropout: float
    steps: int
    image_tokens: int
    action_dims: int
    bins: int

    @classmethod
    def from_config(cls, config: RT1Config, cameras: int, action_dims: int) -> TransformerSpec:
        return cls(
            token_dim=config.token_dim,
            dim=config.dim,
            layers=config.layers,
            heads=config.heads,
            head_dim=config.head_dim,
            ffn=config.ffn,
            ffn_dim=config.ffn_dim,
            dropout=config.dropout,
            steps=config.n_obs_steps,
            image_tokens=config.num_tokens * cameras,
            action_dims=action_dims,
            bins=config.action_bins,
        )

    @property
    def sequence_length(self) -> int:
        return self.steps * (self.image_tokens + self.action_dims)


def block_causal_mask(steps: int, image_tokens: int, action_tokens: int) -> Tensor:
    """Boolean (L, L) mask, True = may attend. L = steps * (image_tokens + action_tokens).

    Image tokens of step t see the image tokens of steps <= t; action slots of step t see the image
    tokens of steps <= t and themselves, never another action slot (RT-1 predicts all action
    dimensions of a step in one pass; earlier steps' actions are not inputs).
    """
    per_step = image_tokens + action_tokens
    length = steps * per_step
    index = torch.arange(length)
    step = index // per_step
    is_image = (index % per_step) < image_tokens
    allowed = (step[None, :] <= step[:, None]) & is_image[None, :]
    return allowed | torch.eye(length, dtype=torch.bool)


class Attention(nn.Module):
    """Multi-head self-attention whose head size need not be dim / heads (RT-1: 8 heads x 128 on d512)."""

    def __init__(self, dim: int, heads: int, head_dim: int, dropout: float) -> None:
        super().__init__()
        self.heads, self.head_dim, self.dropout = heads, head_dim, dropout
        self.qkv = nn.Linear(dim, 3 * heads * head_dim)
        self.out = nn.Linear(heads * head_dim, dim)

    def forward(self, x: Tensor, allowed: Tensor) -> Tensor:  # x (B, L, D), allowed (L, L) bool
        b, length, _ = x.shape
        q, k, v = self.qkv(x).view(b, length, 3, self.heads, self.head_dim).permute(2, 0, 3, 1, 4)
        p = self.dropout if self.training else 0.0
        y = F.scaled_dot_product_attention(q, k, v, attn_mask=allowed, dropout_p=p)  # (B, H, L, hd)
        return self.out(y.transpose(1, 2).reshape(b, length, -1))


class Block(nn.Module):
    """Pre-LN block: attention then feed-forward, each with a residual.

    ``ffn="rt1"`` is the reference's single Dense layer without activation; ``"mlp"`` the usual
    two-layer GELU MLP.
    """

    def __init__(self, spec: TransformerSpec) -> None:
        super().__init__()
        dim = spec.dim
        self.norm1 = nn.LayerNorm(dim)
        self.attn = Attention(dim, spec.heads, spec.head_dim, spec.dropout)
        self.norm2 = nn.LayerNorm(dim)
        if spec.ffn == "rt1":
            self.ffn = nn.Sequential(nn.Linear(dim, dim), nn.Dropout(spec.dropout))
        elif spec.ffn == "mlp":
            self.ffn = nn.Sequential(
                nn.Linear(dim, spec.ffn_dim), nn.GELU(), nn.Linear(spec.ffn_dim, dim), nn.Dropout(spec.dropout)
            )
        else:
            raise ValueError(f"unknown ffn {spec.ffn!r}; valid: rt1, mlp")

    def forward(self, x: Tensor, allowed: Tensor) -> Tensor:
        x = x + self.attn(self.norm1(x), allowed)
        return x + self.ffn(self.norm2(x))


class RT1Transformer(nn.Module):
    """(B, T, N, D) image tokens -> (B, T, A, bins) action logits."""

    def __init__(self, spec: TransformerSpec) -> None:
        super().__init__()
        self.spec = spec
        self.input = nn.Linear(spec.token_dim, spec.dim)
        self.position = nn.Embedding(spec.sequence_length, spec.dim)  # learned absolute positions
        # The reference embeds positions with a Keras Dense layer on one-hot indices, i.e. a Glorot-uniform
        # (L, D) table; nn.Embedding's N(0, 1) default would drown the image tokens (~0.1) at the start.
        bound = math.sqrt(6.0 / (spec.sequence_length + spec.dim))
        nn.init.uniform_(self.position.weight, -bound, bound)
        self.blocks = nn.ModuleList(Block(spec) for _ in range(spec.layers))
        self.norm = nn.LayerNorm(spec.dim)
        self.head = nn.Linear(spec.dim, spec.bins)
        self.register_buffer(
            "allowed", block_causal_mask(spec.steps, spec.image_tokens, spec.action_dims), persistent=False
        )

    def forward(self, tokens: Tensor) -> Tensor:
        b, t, n, _ = tokens.shape
        spec = self.spec
        if t > spec.steps or n != spec.image_tokens:
            raise ValueError(
                f"expected at most {spec.steps} steps of {spec.image_tokens} tokens, got {tuple(tokens.shape)}"
            )
        x = self.input(tokens)  # (B, T, N, D)
        slots = x.new_zeros(b, t, spec.action_dims, x.shape[-1])  # action inputs are zero (as in RT-1)
        x = torch.cat([x, slots], dim=2).flatten(1, 2)  # (B, T*(N+A), D)
        length = x.shape[1]
        x = x + self.position.weight[:length]
        allowed = self.allowed[:length, :length]
        for block in self.blocks:
            x = block(x, allowed)
        x = self.norm(x).view(b, t, n + spec.action_dims, -1)[:, :, n:]  # (B, T, A, D)
        return self.head(x)
