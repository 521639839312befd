"""glibc's malloc, set for processes that run a study's steps: freed memory stays in the process.

A fresh glibc process hands freed memory back to the kernel as soon as 128 KiB lie free at the top of its
heap, and serves every block above 128 KiB with its own ``mmap``, so each training step's tensors, freed at its
end, are page-faulted back in, zeroed by the kernel, at the next. glibc raises both thresholds by itself once
the process frees a large ``mmap``-ed block (up to 32 MiB), so how fast a CPU training runs depends on what its
process did before; with freed memory kept it does not. Where blocks lie changes, not what is computed (torch
aligns every CPU tensor to 64 bytes whatever ``malloc`` returns): checkpoints, datasets and ``results.csv`` are
byte-identical with and without it. The price is a resident size that stays at its peak. What it buys, measured
side by side (``scripts/bench_malloc.py``): docs/study.md, Throughput.
"""

from __future__ import annotations

import ctypes
import functools
import os

# mallopt(3) parameters (malloc.h).
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
# mmap only above 256 MiB (batches' tensors stay in the heap); glibc before 2.35 refuses more than 32 MiB here.
MMAP_THRESHOLDS = (256 << 20, 32 << 20)
SETTINGS = {M_TRIM_THRESHOLD: 1 << 30, M_TOP_PAD: 64 << 20}  # give back only above 1 GiB free; grow by 64 MiB


@functools.cache
def keep_freed_memory() -> bool:
    """Set the ``mmap`` threshold (the first of :data:`MMAP_THRESHOLDS` the C library takes), then
    :data:`SETTINGS`, with ``mallopt`` in this process (kept by processes it forks). ``False``, with nothing
    changed, where there is no ``mallopt`` (not glibc: macOS, musl, Windows) or it refuses every threshold.
    Once per process."""
    if os.name != "posix":
        return False
    mallopt = getattr(ctypes.CDLL(None), "mallopt", None)
    if mallopt is None:
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    if not any(mallopt(M_MMAP_THRESHOLD, threshold) == 1 for threshold in MMAP_THRESHOLDS):
        return False
    return all(mallopt(parameter, value) == 1 for parameter, value in SETTINGS.items())
