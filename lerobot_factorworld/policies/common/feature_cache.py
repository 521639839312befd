"""Per-frame cache of frozen-encoder features, so that a pretrained network runs once per frame, not once per epoch
(bc's frozen encoders, RT-1's frozen trunk).

Keyed by a 128-bit BLAKE2b digest of the frame's pixels exactly as the encoder receives them (float32,
(3, H, W), before the encoder's own resizing), so a key never depends on dataset indices or file names
and the same pixels always hit. Valid because a frozen backbone in eval mode is a fixed function of its
input. The cache lives in memory with the policy (never saved); it is least-recently-used bounded by
``feature_cache_size`` frames, consulted by its owner only for training frames whose pixels are not augmented
(augmented pixels are new every time: bc with augmentation ``none``; RT-1's frozen trunk, which augments the
cached feature map instead), and cleared whenever weights are loaded into the policy.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable

import torch
from torch import Tensor


class FeatureCache:
    """frame pixels -> feature vector, least-recently-used with at most ``capacity`` entries."""

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self._store: OrderedDict[bytes, Tensor] = OrderedDict()
        self.hits = 0
        self.misses = 0

    def __len__(self) -> int:
        return len(self._store)

    def clear(self) -> None:
        self._store.clear()

    @staticmethod
    def keys(images: Tensor) -> list[bytes]:
        flat = images.detach().to("cpu", torch.float32).contiguous().numpy()
        return [hashlib.blake2b(frame.tobytes(), digest_size=16).digest() for frame in flat]

    def __call__(self, images: Tensor, compute: Callable[[Tensor], Tensor]) -> Tensor:
        """Features of ``images`` (N, 3, H, W): cached rows reused, the others computed in one call."""
        keys = self.keys(images)
        rows: list[Tensor | None] = [None] * len(keys)
        for i, key in enumerate(keys):  # read the hits first: inserting the misses may evict entries
            if key in self._store:
                self._store.move_to_end(key)
                rows[i] = self._store[key].to(images.device)
        missing = [i for i, row in enumerate(rows) if row is None]
        self.hits += len(keys) - len(missing)
        self.misses += len(missing)
        if missing:
            features = compute(images[missing])
            for i, row in zip(missing, features, strict=True):
                rows[i] = row
                self._store[keys[i]] = row.detach().to("cpu")
                self._store.move_to_end(keys[i])
            while len(self._store) > self.capacity:
                self._store.popitem(last=False)
        return torch.stack(rows)
