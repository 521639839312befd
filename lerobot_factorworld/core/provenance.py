"""Which code made a result: the git commit of this package's checkout, whether the checkout differs from
that commit, and a SHA-256 of the package's own source.

A study step records :func:`current` in its ``result.json`` (never in its key: keys identify inputs), so a
study can tell steps made by other code from its own. Steps are compared by ``source_hash``; the commit
only names the code. What counts:

- ``source_hash``: every ``*.py`` and ``*.json`` file under ``lerobot_factorworld/`` (their relative paths,
  sorted, and contents), except :data:`UNHASHED`. Computed once per process.
- ``commit``: ``git rev-parse HEAD`` run in the package's folder, ``None`` when that folder is not a tracked
  part of a git checkout (an installed copy, no git, git refusing the folder). Never raises.
- ``clean``: ``True`` when the commit alone reproduces the hashed source: no tracked file under the package
  (other than :data:`UNHASHED`) differs from the commit, staged or not, and no untracked ``*.py`` or
  ``*.json`` file lies there. Untracked outputs and other folders (``outputs/``, ``docs/``, ``tests/``,
  ``configs/``, whose settings enter step keys anyway) never make it dirty. ``None`` without a commit.
"""

from __future__ import annotations

import functools
import hashlib
import subprocess
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

PACKAGE_DIR = Path(__file__).resolve().parents[1]  # lerobot_factorworld/
SOURCE_SUFFIXES = (".py", ".json")
# Relative to PACKAGE_DIR. The --dry-run cost model's constants, rewritten by `--fit_cost`: they change no
# result, and hashing them would mark every cached step stale after a refit.
UNHASHED = frozenset({"study/cost_model.json"})
GIT_TIMEOUT_S = 10
SHORT = 7  # characters of a commit in names (as `git log --oneline`)
SHORT_HASH = 12  # characters of a source hash in names and results.csv
UNKNOWN = "unknown"
DIRTY = "-dirty"


@dataclass(frozen=True)
class Provenance:
    """The code that made a result (see the module docstring for what each field covers)."""

    commit: str | None
    clean: bool | None
    source_hash: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Provenance:
        return cls(data.get("commit"), data.get("clean"), data["source_hash"])

    def revision(self, short: bool = False) -> str:
        """The commit (``short``: 7 characters) with ``-dirty`` when the tree differed from it (a dirty
        revision cannot be checked out, as it should not be); ``unknown`` without a commit."""
        if self.commit is None:
            return UNKNOWN
        return (self.commit[:SHORT] if short else self.commit) + (DIRTY if self.clean is False else "")

    @property
    def name(self) -> str:
        """A short name for messages: ``826fe54``; ``826fe54-dirty (source 1a2b3c4d5e6f)`` when the commit
        alone does not identify the code (a dirty tree, or no commit)."""
        name = self.revision(short=True)
        if self.clean is not True:
            name += f" (source {self.source_hash[:SHORT_HASH]})"
        return name


@functools.cache
def current() -> Provenance:
    """The provenance of the code this process runs (computed once: the source is read at the first call)."""
    commit, clean = git_state()
    return Provenance(commit, clean, source_hash())


@functools.cache
def source_hash(package_dir: Path = PACKAGE_DIR) -> str:
    """SHA-256 (hex) over the hashed source files of ``package_dir``: each file's relative path, size and content."""
    digest = hashlib.sha256()
    for rel, path in source_files(package_dir):
        data = path.read_bytes()
        digest.update(f"{rel}\0{len(data)}\0".encode())
        digest.update(data)
    return digest.hexdigest()


def source_files(package_dir: Path = PACKAGE_DIR) -> list[tuple[str, Path]]:
    """(relative POSIX path, path) of every hashed file under ``package_dir``, sorted by relative path."""
    files = [(p.relative_to(package_dir).as_posix(), p) for p in package_dir.rglob("*") if p.is_file()]
    return sorted((rel, p) for rel, p in files if is_hashed(rel))


def is_hashed(rel: str) -> bool:
    """A file (path relative to the package) that the source hash covers."""
    return rel.endswith(SOURCE_SUFFIXES) and rel not in UNHASHED and "__pycache__" not in rel.split("/")


def git_state(package_dir: Path = PACKAGE_DIR) -> tuple[str | None, bool | None]:
    """(commit, clean) of the checkout ``package_dir`` is tracked in; ``(None, None)`` when it is none."""
    head = _git(package_dir, "rev-parse", "HEAD")
    prefix = _git(package_dir, "rev-parse", "--show-prefix")  # the package's folder in the repository
    tracked = _git(package_dir, "ls-files", "--error-unmatch", "--", ".")  # some file of the package is in it
    if head is None or prefix is None or tracked is None:  # e.g. an installed copy inside another repository
        return None, None
    status = _git(package_dir, "status", "--porcelain", "-z", "--untracked-files=all", "--", ".")
    clean = None if status is None else not changed_paths(status, prefix.strip())
    return head.strip(), clean


def changed_paths(status: str, prefix: str) -> list[str]:
    """Paths (relative to the package) in ``git status --porcelain -z`` output that make the tree differ
    from its commit: tracked changes (except :data:`UNHASHED`) and untracked hashed files."""
    entries = status.split("\0")
    out = []
    i = 0
    while i < len(entries):
        entry = entries[i]
        i += 1
        if len(entry) < 4:
            continue
        code, path = entry[:2], entry[3:]
        if code[0] in "RC":  # a rename or copy: the next entry is its source path
            i += 1
        rel = path.removeprefix(prefix)
        untracked = code == "??"
        if (untracked and is_hashed(rel)) or (not untracked and rel not in UNHASHED):
            out.append(rel)
    return out


def _git(cwd: Path, *args: str) -> str | None:
    """``git args`` run in ``cwd``: its output, or ``None`` when git is missing, fails or hangs."""
    try:
        proc = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=GIT_TIMEOUT_S)
    except (OSError, subprocess.SubprocessError):
        return None
    return proc.stdout if proc.returncode == 0 else None
