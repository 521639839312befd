"""Pure checks of user settings shared by every config (the ``factorworld`` commands and the LeRobot env
config), so that each rule and its message live in one place. Checks that need a fact of a higher layer
(task names, cameras, factors, asset folders) live next to that fact and use these.

Every check raises ``ValueError`` (``FileNotFoundError`` for a missing input) with one line that names
the valid choices. Configs call them from ``__post_init__``: a bad value is refused when it is parsed,
before any work starts (and before ``lerobot-eval`` builds a policy).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence
from pathlib import Path

from huggingface_hub.utils import validate_repo_id

MIN_IMAGE_SIZE = 8
# Within every GL's offscreen framebuffer limit; a 4096 x 4096 frame is already 48 MiB per camera and step.
MAX_IMAGE_SIZE = 4096


def split_list(value: str | Sequence[str] | None) -> list[str]:
    """``"a, b"`` or ``["a", "b"]`` -> ``["a", "b"]`` (empty items dropped)."""
    items = (value or "").split(",") if isinstance(value, str) or value is None else list(value)
    return [str(item).strip() for item in items if str(item).strip()]


def check_image_size(size: int | Sequence[int], setting: str = "image_size") -> None:
    sides = [size] if isinstance(size, numbers.Integral) else list(size)
    if not sides or any(
        not isinstance(s, numbers.Integral) or isinstance(s, bool) or not MIN_IMAGE_SIZE <= s <= MAX_IMAGE_SIZE
        for s in sides
    ):
        raise ValueError(
            f"{setting} must be at least {MIN_IMAGE_SIZE} pixels (and at most {MAX_IMAGE_SIZE}), got {size!r}"
        )


def check_choice(setting: str, value: object, choices: Iterable[object]) -> None:
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"unknown {setting} {value!r}; valid: {', '.join(map(str, choices))}")


def check_at_least(setting: str, value: int | float | None, minimum: int | float) -> None:
    if value is None or isinstance(value, bool) or not value >= minimum:
        raise ValueError(f"{setting} must be at least {minimum}, got {value!r}")


def check_seed(seed: int, setting: str = "seed") -> None:
    check_at_least(setting, seed, 0)  # numpy's SeedSequence only takes non-negative integers


def check_std(setting: str, value: float) -> None:
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{setting} must be a finite number >= 0, got {value!r}")


def check_folder_target(path: str | Path, setting: str) -> Path:
    """A folder we are about to create or fill: neither it nor a parent may be a plain file."""
    path = Path(path).expanduser()
    if not str(path).strip():
        raise ValueError(f"{setting} is empty; give a folder path")
    _check_parents(path, setting, include_self=True)
    return path


def check_output_file(path: str | Path, setting: str, suffixes: Sequence[str] = ()) -> Path:
    """A file we are about to write: not a folder, no parent that is a plain file, a known suffix."""
    path = Path(path).expanduser()
    if path.is_dir():
        raise ValueError(f"{setting} {path} is a folder; give a file path")
    _check_parents(path, setting, include_self=False)
    if suffixes and path.suffix.lower() not in suffixes:
        raise ValueError(f"{setting} {path} has an unsupported extension; valid: {', '.join(suffixes)}")
    return path


def _check_parents(path: Path, setting: str, include_self: bool) -> None:
    for candidate in (path, *path.parents) if include_self else path.parents:
        if candidate.exists() and not candidate.is_dir():
            what = f"{setting} {path}" if candidate == path else f"{setting} {path}: its parent {candidate}"
            raise ValueError(f"{what} is a file, not a folder; nothing was changed. Choose a folder path")


def check_input_file(path: str | Path, setting: str) -> Path:
    path = Path(path).expanduser()
    if not path.exists():
        raise FileNotFoundError(f"{setting} {path} does not exist")
    if not path.is_file():
        raise ValueError(f"{setting} {path} is not a file")
    return path


def check_repo_id(repo_id: str) -> None:
    """``user/name`` as the Hugging Face Hub accepts it (LeRobot keys datasets by it even offline)."""

    if repo_id.count("/") != 1:
        raise ValueError(f"repo_id must look like 'user/name', got {repo_id!r}")
    try:
        validate_repo_id(repo_id)
    except ValueError as err:
        raise ValueError(f"bad repo_id {repo_id!r}: {err}") from None
