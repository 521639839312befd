"""Pretrained starting weights of an image encoder: the one switch that skips them, and strict local files.

A policy built fresh starts its encoder from pretrained weights, read now: a file that ships with a package
(EfficientNet-Lite0) or a local file named in the config (never downloaded). A policy restored by
``from_pretrained`` already holds the trained encoder in its checkpoint, so it reads no weights file (the
file may be gone) and loads the checkpoint strictly (nothing else fills the encoder). Both policies take
that switch as ``load_backbone_weights`` (``__init__``), set by :class:`RestoresBackboneFromCheckpoint`.

Weights files are checked key by key (:func:`compare_keys`); a refusal lists the keys that do not fit.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch
from torch import Tensor

SHOWN_KEYS = 12  # keys listed per category in a refusal


class WeightsError(ValueError):
    """A weights file that does not fit the network (unreadable, or missing, unexpected or wrongly shaped keys)."""


class RestoresBackboneFromCheckpoint:
    """``from_pretrained`` for a ``PreTrainedPolicy`` whose ``__init__`` takes ``load_backbone_weights``.

    Mix in before ``PreTrainedPolicy``. The policy is built with ``load_backbone_weights=False`` (the
    checkpoint holds the trained backbone, so its original weights file is neither needed nor read) and
    the checkpoint loads with ``strict=True`` (missing keys must fail, not leave layers random).
    """

    @classmethod
    def from_pretrained(cls, pretrained_name_or_path, **kwargs):
        kwargs.setdefault("strict", True)
        return super().from_pretrained(pretrained_name_or_path, load_backbone_weights=False, **kwargs)


def local_weights_file(path: str | Path | None, owner: str, needs: str) -> Path:
    """The existing local file ``path``: ValueError "<owner> needs <needs>" without one, FileNotFoundError if absent."""
    if not path:
        raise ValueError(f"{owner} needs {needs}")
    file = Path(path).expanduser()
    if not file.is_file():
        raise FileNotFoundError(f"{owner}: weights file not found: {file}")
    return file


def read_torch_file(path: Path, what: str) -> Any:
    """``torch.load`` of ``path`` (tensors only, on CPU); any unreadable file is a :class:`WeightsError`."""
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # noqa: BLE001  (pickle errors come in many types: one clear message)
        raise WeightsError(f"{path} could not be read as {what}: {err}") from err


def listed(keys: list[str], limit: int = SHOWN_KEYS) -> str:
    """The first ``limit`` keys, comma-separated, and how many more there are."""
    return ", ".join(keys[:limit]) + (f", ... ({len(keys) - limit} more)" if len(keys) > limit else "")


def listing(title: str, keys: list[str]) -> str:
    return f"{title} ({len(keys)}): {listed(keys)}"


@dataclass(frozen=True)
class KeyReport:
    """How a state dict's keys differ from the ones a network expects (each list sorted; empty: they fit)."""

    missing: list[str]
    unexpected: list[str]
    wrong_shape: list[str]  # "key (found shape) (expected (shape))"

    def __bool__(self) -> bool:
        return bool(self.missing or self.unexpected or self.wrong_shape)

    def __str__(self) -> str:
        categories = (
            ("missing keys", self.missing),
            ("unexpected keys", self.unexpected),
            ("wrong shapes", self.wrong_shape),
        )
        return "; ".join(listing(title, keys) for title, keys in categories if keys)


def compare_keys(
    expected: Mapping[str, Tensor | torch.Size],
    state: Mapping[Any, Any],
    may_be_missing: Callable[[str], bool] = lambda key: False,
) -> KeyReport:
    """Compare ``state`` with ``expected`` (a network's state dict, or its keys' shapes); a value that is no
    tensor has the wrong shape. Expected keys for which ``may_be_missing`` is true may be absent."""
    shapes = {k: tuple(v.shape) if isinstance(v, Tensor) else tuple(v) for k, v in expected.items()}
    found = {str(k): v for k, v in state.items()}

    def shape(value: Any) -> str:
        return str(tuple(value.shape)) if isinstance(value, Tensor) else type(value).__name__

    return KeyReport(
        missing=sorted(k for k in shapes if k not in found and not may_be_missing(k)),
        unexpected=sorted(k for k in found if k not in shapes),
        wrong_shape=sorted(
            f"{k} {shape(v)} (expected {shapes[k]})"
            for k, v in found.items()
            if k in shapes and (not isinstance(v, Tensor) or tuple(v.shape) != shapes[k])
        ),
    )
