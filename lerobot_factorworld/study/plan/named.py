"""Study configs by name: the quick study and every finding's config ship inside the package
(``lerobot_factorworld/studies/``, also ``configs/study/`` in a checkout), so ``factorworld study --config quick``
and ``--config findings/f1_ordering`` run after a ``pip install``, from any folder. A path to a YAML file still
works, and wins over a name."""

from __future__ import annotations

from pathlib import Path

STUDIES_DIR = Path(__file__).resolve().parents[2] / "studies"
SUFFIX = ".yaml"


def study_names() -> list[str]:
    """Every packaged study config's name (``quick``, ``findings/f1_ordering``, ...), sorted."""
    return sorted(path.relative_to(STUDIES_DIR).with_suffix("").as_posix() for path in STUDIES_DIR.rglob(f"*{SUFFIX}"))


def resolve_study_config(value: str) -> str:
    """The YAML file ``value`` names: an existing path as it is, else a packaged config's name (with or without
    ``.yaml``). An unknown one is refused in one line naming the valid names."""
    if Path(value).expanduser().is_file():
        return value
    name = value.removesuffix(SUFFIX)
    for prefix in ("configs/study/", "lerobot_factorworld/studies/"):  # a checkout's path, run elsewhere
        name = name.removeprefix(prefix)
    path = STUDIES_DIR / f"{name}{SUFFIX}"
    if path.is_file():
        return str(path)
    raise ValueError(
        f"--config {value}: no such file and no packaged study of that name; valid names: {', '.join(study_names())}"
    )
