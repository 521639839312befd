"""Machine-independent seeding: every procedural asset is a pure function of its name."""

from __future__ import annotations

import hashlib

import numpy as np


def stable_seed(*parts: str | int) -> int:
    """Return a 64-bit seed from sha256 of ``parts``.

    Python's ``hash()`` is salted per process, so it would give different assets on every run; sha256
    gives the same seed on every machine and interpreter.
    """
    text = "\x1f".join(str(p) for p in parts)
    return int.from_bytes(hashlib.sha256(text.encode("utf-8")).digest()[:8], "little")


def rng_for(*parts: str | int) -> np.random.Generator:
    """A fresh generator seeded from ``parts`` (see :func:`stable_seed`)."""
    return np.random.default_rng(stable_seed(*parts))
