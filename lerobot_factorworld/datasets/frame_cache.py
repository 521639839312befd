"""A training's PNG frames decoded once: LeRobot's dataset rows served from memory, value for value.

LeRobot reads every sample through Hugging Face ``datasets``: each row is formatted and its PNG decoded again for
every sample whose window holds it (RT-1's six-frame history decodes each frame six times per epoch). On 2 cores
the loader process then spends a whole core feeding one single-threaded training. :func:`cached_frames` makes
every dataset a training opens keep its rows in memory, images as ``uint8`` (a quarter of ``float32``), and give
them back as LeRobot's own transform does (``to_tensor``: ``uint8`` to ``float32``, divided by 255), so every
sample, and so every checkpoint, is what the uncached dataset gives. Rows spread over the dataset are checked
against the dataset's own once the cache is built; a dataset whose rows it cannot rebuild exactly (video, depth,
other image modes, a selected view), or whose frames would not fit in :data:`MAX_BYTES`, is read as before.
"""

from __future__ import annotations

import contextlib
import io
import time
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np
import torch
from PIL import Image

MAX_BYTES = 4 * 2**30  # the frames of one dataset kept in memory at most (uint8); larger datasets are read as before
BATCH = 512  # rows formatted at once while the cache is built
CHECKED_ROWS = 64  # rows compared with the dataset's own once the cache is built
CACHE_LOG = "frames decoded once"  # how a training's log says what the cache holds


class _Column:
    """``rows[key]``: a column whose ``[indices]`` are its values at those rows (as ``Dataset[key][indices]``)."""

    def __init__(self, rows: CachedRows, key: str) -> None:
        self._rows, self._key = rows, key

    def __getitem__(self, indices: int | Sequence[int]) -> Any:
        if isinstance(indices, int):
            return self._rows.value(self._key, indices)
        return [self._rows.value(self._key, int(i)) for i in indices]


class CachedRows:
    """A Hugging Face dataset's rows as its torch transform gives them, kept in memory; ``[i]``, ``[key][indices]``
    and ``[indices]`` read from memory, everything else is the dataset's."""

    def __init__(self, dataset: Any, images: dict[str, torch.Tensor], other: dict[str, list[Any]]) -> None:
        self._dataset, self._images, self._other = dataset, images, other
        self._keys = tuple(dataset.column_names)

    def value(self, key: str, i: int) -> Any:
        if key in self._images:
            return self._images[key][i].to(torch.get_default_dtype()).div(255)  # to_tensor's own conversion
        value = self._other[key][i]
        return value.clone() if isinstance(value, torch.Tensor) else value  # a fresh tensor, as the dataset gives

    def __getitem__(self, key: Any) -> Any:
        if isinstance(key, int):
            return {name: self.value(name, key) for name in self._keys}
        if isinstance(key, str):
            return _Column(self, key)
        if isinstance(key, (list, tuple)):
            return {name: [self.value(name, int(i)) for i in key] for name in self._keys}
        return self._dataset[key]

    def __len__(self) -> int:
        return len(self._dataset)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._dataset, name)


def cache_rows(dataset: Any, image_keys: Sequence[str], max_bytes: int = MAX_BYTES) -> CachedRows | None:
    """``dataset``'s rows in memory, or ``None`` where they cannot be rebuilt exactly or would not fit.

    The PNG frames are decoded straight from the arrow table (PIL, as ``datasets``' ``Image`` feature does; 20x
    faster than formatting rows), the other columns formatted a batch at a time; :data:`CHECKED_ROWS` rows spread
    over the dataset, its first and last among them, are compared with the dataset's own, value for value."""
    n = len(dataset)
    if n == 0 or not image_keys or getattr(dataset, "_indices", None) is not None:  # a selected view: rows differ
        return None
    first = dataset[0]
    if any(not isinstance(first.get(k), torch.Tensor) or first[k].dtype != torch.float32 for k in image_keys):
        return None
    if any(getattr(dataset.features[k], "mode", None) for k in image_keys):  # converted on decoding: not rebuilt here
        return None
    if sum(first[k].numel() for k in image_keys) * n > max_bytes:
        return None
    images = {k: _decoded(dataset.data.column(k), first[k].shape) for k in image_keys}
    others = [k for k in dataset.column_names if k not in images]
    other: dict[str, list[Any]] = {k: [] for k in others}
    columns = dataset.select_columns(others)
    for begin in range(0, n, BATCH):  # a slice is formatted as one batch: many times faster than row by row
        for key, values in columns[begin : begin + BATCH].items():
            other[key].extend(values)
    cached = CachedRows(dataset, images, other)
    step = max(1, n // CHECKED_ROWS)
    for i in sorted({*range(0, n, step), n - 1}):
        mine, theirs = cached[i], dataset[i]
        if list(mine) != list(theirs) or not all(_same(mine[k], theirs[k]) for k in theirs):
            return None
    return cached


def _decoded(column: Any, shape: torch.Size) -> torch.Tensor:
    """A PNG column's frames as one ``uint8`` tensor of ``shape`` (C, H, W) frames."""
    frames = torch.empty((len(column), *shape), dtype=torch.uint8)
    for i, cell in enumerate(column.to_pylist()):
        with Image.open(io.BytesIO(cell["bytes"])) as image:
            frames[i] = torch.from_numpy(np.array(image)).permute(2, 0, 1)
    return frames


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, torch.Tensor) or isinstance(b, torch.Tensor):
        return isinstance(a, torch.Tensor) and isinstance(b, torch.Tensor) and a.dtype == b.dtype and torch.equal(a, b)
    return a == b


@contextlib.contextmanager
def cached_frames() -> Iterator[None]:
    """Every LeRobot dataset opened inside keeps its PNG frames' rows in memory (:func:`cache_rows`)."""
    from lerobot.datasets.dataset_reader import DatasetReader  # noqa: PLC0415 - LeRobot's stack, for a training only

    load = DatasetReader._load_hf_dataset

    def load_cached(reader: DatasetReader) -> Any:
        dataset = load(reader)
        meta = reader._meta
        if meta.video_keys or meta.depth_keys:
            return dataset
        start = time.perf_counter()
        cached = cache_rows(dataset, list(meta.image_keys))
        if cached is None:
            print(f"{CACHE_LOG}: not used for {reader.root} (its rows are read as before)", flush=True)
            return dataset
        size = sum(frames.numel() for frames in cached._images.values()) / 2**20
        print(
            f"{CACHE_LOG}: {len(cached)} rows, {size:.0f} MiB of frames, in {time.perf_counter() - start:.1f} s",
            flush=True,
        )
        return cached

    DatasetReader._load_hf_dataset = load_cached
    try:
        yield
    finally:
        DatasetReader._load_hf_dataset = load
