"""Checks that several settings groups share: a per-task override, a device, a number.

Each raises one line naming the setting and the valid choices, as every study setting does.
"""

from __future__ import annotations

import math
import re
from typing import Any

from ...tasks import get_task

DEVICE_PATTERN = re.compile(r"cpu|mps|cuda(:\d+)?")


def per_task_setting(setting: str, values: dict[str, Any]) -> dict[str, Any]:
    """A per-task override (``{task: value}``) keyed by task names, the Meta-World ``-v3`` spelling folded.
    A task the study leaves out is fine (``--tasks`` may narrow a config); an unknown one is refused,
    naming the valid tasks, before any work starts."""
    out = {}
    for task, value in values.items():
        try:
            out[get_task(str(task)).name] = value
        except ValueError as err:  # "unknown task 'x'; valid tasks: ..."
            raise ValueError(f"{setting}: {err}") from None
    return out


def check_device(setting: str, device: str) -> None:
    """``device`` is one torch can name (training and evaluation run elsewhere: refused before any work)."""
    if not DEVICE_PATTERN.fullmatch(str(device)):
        raise ValueError(f"unknown {setting} {device!r}; valid: cpu, cuda, cuda:<index>, mps")


def is_number(value: Any) -> bool:
    """An int or float, not a bool (YAML's ``true`` is not a budget)."""
    return not isinstance(value, bool) and isinstance(value, int | float)


def positive_number(value: Any) -> bool:
    """A finite number above 0."""
    return is_number(value) and math.isfinite(value) and value > 0
