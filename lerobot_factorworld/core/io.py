"""Atomic file writes: a reader (or a crash) never sees half a file, and an existing file is replaced
only once its successor is complete. One home for the pattern every writer of results, configs and
side-cars uses."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any


def temporary_path(path: Path) -> Path:
    """A sibling of ``path`` for writing before the swap: unique per process, so concurrent writers
    (study workers) never share one."""
    return path.with_name(f"{path.name}.tmp{os.getpid()}")


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` (parents created) through a temporary sibling and one rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    try:
        tmp.write_text(text)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def atomic_write_json(path: str | Path, data: Any, **dumps: Any) -> Path:
    """``json.dumps(data, **dumps)`` written atomically (keyword arguments as ``json.dumps`` takes them)."""
    return atomic_write_text(path, json.dumps(data, **dumps))
