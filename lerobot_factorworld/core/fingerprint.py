"""Content hashes of files and folders: what a study step's key holds instead of a path, so that the same
content elsewhere gives the same key and new content at the same path gives a new one."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

PREFIX = "sha256:"


@functools.cache
def _sha256(path: str, size: int, mtime_ns: int) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def file_fingerprint(path: str | Path) -> str | None:
    """``sha256:<hex>`` of a file's content (cached per size and mtime), ``None`` when it is not a file."""
    path = Path(path)
    if not path.is_file():
        return None
    stat = path.stat()
    return PREFIX + _sha256(str(path.resolve()), stat.st_size, stat.st_mtime_ns)


def folder_fingerprint(folder: str | Path) -> str | None:
    """``sha256:<hex>`` over every file under ``folder`` (subfolders too, links followed): each relative path
    with its content hash, in sorted order, so a renamed, added, removed or changed file changes it; ``None``
    when ``folder`` is not a folder."""
    folder = Path(folder)
    if not folder.is_dir():
        return None
    digest = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        digest.update(f"{path.relative_to(folder).as_posix()}\0{file_fingerprint(path)}\n".encode())
    return PREFIX + digest.hexdigest()
