"""RT-1's decoder-only transformer over [image tokens, action slots] per step, block-causal in time."""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn


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

    def __init__(self, dim: int, heads: int, head_dim: int, ffn: str, ffn_dim: int, dropout: float) -> None:
        super().__init__()
        self.norm1 = nn.LayerNorm(dim)
        self.attn = Attention(dim, heads, head_dim, dropout)
        self.norm2 = nn.LayerNorm(dim)
        if ffn == "rt1":
            self.ffn = nn.Sequential(nn.Linear(dim, dim), nn.Dropout(dropout))
        elif ffn == "mlp":
            self.ffn = nn.Sequential(nn.Linear(dim, ffn_dim), nn.GELU(), nn.Linear(ffn_dim, dim), nn.Dropout(dropout))
        else:
            raise ValueError(f"unknown ffn {ffn!r}; valid: rt1, mlp")

    def forward(self, x: Tensor, allowed: Tensor) -> Tensor:
        x = x + self.attn(self.norm1(x), allowed)
        return x + self.ffn(self.norm2(x))


class RT1Transformer(nn.Module):
    """(B, T, N, D) image tokens -> (B, T, A, bins) action logits."""

    def __init__(
        self,
        token_dim: int,
        dim: int,
        layers: int,
        heads: int,
        steps: int,
        image_tokens: int,
        action_dims: int,
        bins: int,
        ffn: str = "mlp",
        ffn_dim: int = 1024,
        dropout: float = 0.1,
        head_dim: int | None = None,
    ) -> None:
        super().__init__()
        self.steps, self.image_tokens, self.action_dims = steps, image_tokens, action_dims
        self.input = nn.Linear(token_dim, dim)
        self.position = nn.Embedding(steps * (image_tokens + action_dims), dim)  # learned absolute positions
        head_dim = head_dim or dim // heads
        self.blocks = nn.ModuleList(Block(dim, heads, head_dim, ffn, ffn_dim, dropout) for _ in range(layers))
        self.norm = nn.LayerNorm(dim)
        self.head = nn.Linear(dim, bins)
        self.register_buffer("allowed", block_causal_mask(steps, image_tokens, action_dims), persistent=False)

    def forward(self, tokens: Tensor) -> Tensor:
        b, t, n, _ = tokens.shape
        if t > self.steps or n != self.image_tokens:
            raise ValueError(
                f"expected at most {self.steps} steps of {self.image_tokens} tokens, got {tuple(tokens.shape)}"
            )
        x = self.input(tokens)  # (B, T, N, D)
        slots = x.new_zeros(b, t, self.action_dims, x.shape[-1])  # action inputs are zero (as in RT-1)
        x = torch.cat([x, slots], dim=2).flatten(1, 2)  # (B, T*(N+A), D)
        length = x.shape[1]
        x = x + self.position.weight[:length]
        allowed = self.allowed[:length, :length]
        for block in self.blocks:
            x = block(x, allowed)
        x = self.norm(x).view(b, t, n + self.action_dims, -1)[:, :, n:]  # (B, T, A, D)
        return self.head(x)
