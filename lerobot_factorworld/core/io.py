"""Atomic file writes: a reader (or a crash) never sees half a file, and an existing file is replaced
only once its successor is complete. One home for the pattern every writer of results, configs and
side-cars uses; and :func:`read_table`, the typed reader of the CSV files they write."""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Sequence
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


def read_table(
    path: str | Path,
    columns: Sequence[str],
    integers: Sequence[str] = (),
    floats: Sequence[str] = (),
    optional_floats: Sequence[str] = (),
) -> list[dict[str, Any]]:
    """The rows of a CSV file that must have ``columns`` (more are kept as text); ``integers`` and ``floats``
    converted (an empty float: NaN, an empty optional float: ``None``). Errors name the file and line."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []
            missing = [c for c in columns if c not in header]
            if missing:
                shown = ",".join(header) or "none"
                raise ValueError(
                    f"{path} is not the expected CSV file: it lacks the column(s) {', '.join(missing)} "
                    f"(its header: {shown[:120] + '...' if len(shown) > 120 else shown})"
                )
            return [_typed(row, integers, floats, optional_floats, f"{path} line {reader.line_num}") for row in reader]
    except (csv.Error, UnicodeDecodeError) as err:
        raise ValueError(f"{path} is not a readable CSV file: {err}") from None


def _typed(
    row: dict[str, Any], integers: Sequence[str], floats: Sequence[str], optional_floats: Sequence[str], where: str
) -> dict[str, Any]:
    if None in row or any(v is None for v in row.values()):
        raise ValueError(f"{where}: the row has another number of fields than the header")
    out = dict(row)
    try:
        for c in integers:
            out[c] = int(row[c])
        for c in floats:
            out[c] = float(row[c]) if row[c] != "" else math.nan
        for c in optional_floats:
            out[c] = float(row[c]) if row[c] != "" else None
    except ValueError:
        raise ValueError(f"{where}: column {c} holds {row[c]!r}, not a number") from None
    return out
