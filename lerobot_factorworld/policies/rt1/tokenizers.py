"""RT-1's token makers: TokenLearner (image map -> 8 tokens) and the 256-bin action tokenizer."""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import Tensor, nn


class TokenLearner(nn.Module):
    """TokenLearner v1.1: each output token is a learned softmax-weighted spatial pooling of the map.

    LayerNorm -> MLP (hidden 64, GELU) -> one attention map per token over the H*W positions.
    """

    def __init__(self, dim: int, num_tokens: int = 8, hidden: int = 64) -> None:
        super().__init__()
        self.norm = nn.LayerNorm(dim)
        self.mlp = nn.Sequential(nn.Linear(dim, hidden), nn.GELU(approximate="tanh"), nn.Linear(hidden, num_tokens))

    def forward(self, feature_map: Tensor) -> Tensor:  # (B, C, H, W) -> (B, num_tokens, C)
        x = feature_map.flatten(2).transpose(1, 2)  # (B, HW, C)
        weights = self.mlp(self.norm(x)).softmax(dim=1)  # (B, HW, S): softmax over positions
        return torch.einsum("bns,bnc->bsc", weights, x)


class ActionTokenizer:
    """Uniform bins over [-1, 1] (actions arrive min-max normalised with the dataset's statistics).

    Tokens are ``floor((a + 1) / 2 * bins)`` clipped to ``bins - 1``; decoding returns the bin centre,
    so a round trip is off by at most half a bin (the reference decodes to the bin's lower edge,
    which biases every action by half a bin).
    """

    def __init__(self, bins: int = 256, low: float = -1.0, high: float = 1.0) -> None:
        self.bins, self.low, self.high = bins, low, high
        self.width = (high - low) / bins

    def tokenize(self, actions: Tensor) -> Tensor:
        scaled = (actions.clamp(self.low, self.high) - self.low) / self.width
        return scaled.floor().long().clamp(0, self.bins - 1)

    def detokenize(self, tokens: Tensor) -> Tensor:
        return self.low + (tokens.float() + 0.5) * self.width

    def loss(self, logits: Tensor, actions: Tensor, mask: Tensor | None = None, per_sample: bool = False) -> Tensor:
        """Cross-entropy of logits (B, ..., A, bins) against the tokens of actions (B, ..., A).

        ``mask`` (B, ...) marks the steps that count (LeRobot pads windows at episode starts). Returns the
        mean over counted tokens, or with ``per_sample`` one mean per batch element (B,).
        """
        targets = self.tokenize(actions)
        loss = F.cross_entropy(logits.flatten(0, -2), targets.flatten(), reduction="none").view_as(targets)
        weight = torch.ones_like(loss) if mask is None else mask.unsqueeze(-1).expand_as(loss).float()
        if per_sample:
            dims = tuple(range(1, loss.ndim))
            return (loss * weight).sum(dims) / weight.sum(dims).clamp_min(1.0)
        return (loss * weight).sum() / weight.sum().clamp_min(1.0)
