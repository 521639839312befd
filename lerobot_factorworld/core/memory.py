"""glibc's malloc, set for processes that train and evaluate: freed memory stays in the process.

By default glibc hands freed memory back to the kernel as soon as 128 KiB lie free at the top of the heap
(and serves large blocks with their own ``mmap``), so every training step's tensors, freed at its end, are
page-faulted back in, zeroed by the kernel, at the next: 4-5 ms of a 43 ms CPU update of the paper's CNN at
batch 16 on the 2-core machine (``scripts/bench_malloc.py``). Keeping freed memory (a high trim threshold,
a 64 MiB top pad, ``mmap`` only above 32 MiB) changes where blocks lie, never what is computed: torch aligns
every CPU tensor to 64 bytes whatever ``malloc`` returns, and checkpoints, datasets and ``results.csv`` are
byte-identical with and without it (``scripts/bench_study.py``). The price is a resident size that stays at
its peak instead of shrinking between steps.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

# mallopt(3) parameters (malloc.h) and the values set: see the module docstring.
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
SETTINGS = {M_TRIM_THRESHOLD: 1 << 30, M_TOP_PAD: 64 << 20, M_MMAP_THRESHOLD: 32 << 20}


@functools.cache
def keep_freed_memory() -> bool:
    """Set :data:`SETTINGS` with ``mallopt`` in this process (inherited by processes it forks); ``False``
    where the C library has no ``mallopt`` (not glibc: macOS, musl) or refuses a value, and nothing is
    changed there. Once per process."""
    libc = ctypes.CDLL(ctypes.util.find_library("c") or None)
    mallopt = getattr(libc, "mallopt", None)
    if mallopt is None:
        return False
    return all(mallopt(parameter, value) == 1 for parameter, value in SETTINGS.items())
