"""The two splits every seeded draw is keyed by: ``train`` (what a policy is trained on) and ``eval``
(held-out assets, objects and phrasings). One home for the names and their check."""

from __future__ import annotations

from typing import Literal, get_args

Split = Literal["train", "eval"]
SPLITS: tuple[str, ...] = get_args(Split)


def check_split(split: str, setting: str = "split") -> str:
    """``split`` if it is a known split, else a ``ValueError`` naming the valid ones."""
    if split not in SPLITS:
        raise ValueError(f"unknown {setting} {split!r}; valid splits: {', '.join(SPLITS)}")
    return split
