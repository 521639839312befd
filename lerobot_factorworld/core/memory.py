"""glibc's malloc, set for processes that train and evaluate: freed memory stays in the process.

A fresh glibc process hands freed memory back to the kernel as soon as 128 KiB lie free at the top of its
heap, and serves blocks above 128 KiB with their own ``mmap``, so every training step's tensors, freed at its
end, are page-faulted back in, zeroed by the kernel, at the next: 44-46 against 35 ms per CPU update of the
paper's CNN at batch 16, 82-86 against 64-65 ms at batch 32 (``scripts/bench_malloc.py``, 2-core machine).
glibc raises both thresholds by itself once the process frees a large ``mmap``-ed block (up to 32 MiB), so a
worker that collected before it trained is often fast already: this makes the speed independent of what the
process did before. Keeping freed memory (a 1 GiB trim threshold, a 64 MiB top pad, ``mmap`` only above
256 MiB) changes where blocks lie, never what is computed: torch aligns every CPU tensor to 64 bytes whatever
``malloc`` returns, and checkpoints, datasets and ``results.csv`` are byte-identical with and without it
(``scripts/bench_malloc.py``, ``scripts/bench_study.py``). The price is a resident size that stays at its
peak instead of shrinking between steps.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

# mallopt(3) parameters (malloc.h) and the values set: see the module docstring.
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
SETTINGS = {M_TRIM_THRESHOLD: 1 << 30, M_TOP_PAD: 64 << 20, M_MMAP_THRESHOLD: 256 << 20}


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
