"""Which CPU made a result: its model, the instruction-set extensions that choose torch's CPU kernels, and a cap on
them set in the environment.

The same code and key make byte-identical steps on one machine, but a training on another CPU may differ in its
last bits: oneDNN picks its kernels by the instruction set (AVX-512, AVX2, SSE4.1 sum in different orders; bf16
kernels differ again with AVX512-BF16 and AMX), and ``ONEDNN_MAX_CPU_ISA`` caps that choice. A study step records
:func:`current` in its ``result.json`` beside the code that made it (never in a key), so two runs that differ can
be told apart by their machines (docs/study.md, "Across machines").
"""

from __future__ import annotations

import functools
import os
import platform
from pathlib import Path
from typing import Any

# The x86 extensions that change which oneDNN kernels run (fp32 and bf16), in the order of a description.
KERNEL_ISA = ("amx_bf16", "amx_tile", "avx512_bf16", "avx512f", "avx2", "fma")
ISA_CAP_ENV = "ONEDNN_MAX_CPU_ISA"  # oneDNN's cap on the instruction set its kernels use
CPUINFO = Path("/proc/cpuinfo")


def cpu_of(cpuinfo: str) -> tuple[str, list[str]]:
    """(model name, the :data:`KERNEL_ISA` extensions it lists) of a ``/proc/cpuinfo`` text's first CPU."""
    model, flags = "", set()
    for line in cpuinfo.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "model name" and not model:
            model = value.strip()
        elif key.strip() == "flags":
            flags = set(value.split())
            break
    return model, [name for name in KERNEL_ISA if name in flags]


def usable_cpus() -> int | None:
    """The logical CPUs this process may run on (its affinity where the OS has one, as a container's limit)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


@functools.cache
def current() -> dict[str, Any]:
    """This machine: ``cpu`` (model), ``isa`` (its :data:`KERNEL_ISA` extensions; empty where the OS does not list
    them), ``isa_cap`` (``ONEDNN_MAX_CPU_ISA``, or None) and ``cpus`` (:func:`usable_cpus`). Read once per process."""
    model, isa = cpu_of(CPUINFO.read_text()) if CPUINFO.is_file() else ("", [])
    return {
        "cpu": model or platform.processor() or platform.machine(),
        "isa": isa,
        "isa_cap": os.environ.get(ISA_CAP_ENV) or None,
        "cpus": usable_cpus(),
    }


def describe(machine: dict[str, Any]) -> str:
    """``Intel(R) Xeon(R) Processor; amx_bf16, ..., fma; 2 CPUs`` (and the cap where one was set)."""
    cap = f"; {ISA_CAP_ENV}={machine['isa_cap']}" if machine.get("isa_cap") else ""
    return f"{machine['cpu']}; {', '.join(machine['isa']) or 'no AVX2'}; {machine['cpus']} CPUs{cap}"


BF16_ISA = ("amx_bf16", "avx512_bf16")  # the extensions with native bf16 arithmetic (oneDNN's bf16 kernels)


EMULATED_BF16_COST = (
    "bf16 is emulated there: speed=fast measured 0.25x (rt1 small) and 0.08x (bc) the updates per second of "
    "speed=default on an AVX2-only CPU (docs/benchmarks/bench_policy_cpu_avx2_small.txt)"
)


def lacks_native_bf16(machine: dict[str, Any]) -> bool:
    """Whether ``machine`` is an x86 CPU whose bf16 oneDNN emulates (AVX2 but neither :data:`BF16_ISA`, or a cap
    below them; :data:`EMULATED_BF16_COST`). False where the OS lists no x86 extensions (another architecture)."""
    # oneDNN's cap names: SSE41, AVX2, ..., AVX512_CORE, AVX512_CORE_BF16, AVX512_CORE_AMX, AVX10_1_512, DEFAULT
    cap = str(machine.get("isa_cap") or "DEFAULT").upper()
    capped = cap != "DEFAULT" and not any(name in cap for name in ("BF16", "AMX", "AVX10"))
    return "avx2" in machine["isa"] and (capped or not set(BF16_ISA) & set(machine["isa"]))
