"""Finished steps of other studies, used by this one (``reuse_from``) instead of being run again.

A step's key hashes everything that decides its result, so a finished step of another study with the same
key is this study's step, made already. Findings share them: F1, F3, F5 and F8 train the same recipe on the
same seed-0 datasets, and F3's and F5's single-factor evaluations are F1's. The other study's step folder
is linked (a symlink, never a copy: checkpoints and datasets are large) into this study's ``steps/``; its
``result.json`` keeps the provenance of the code that made it, so stale checks and ``results.csv`` name that
code. Only finished steps (with a ``result.json``) are linked, and only where this study has no folder of its
own for the key, so nothing here is replaced. Links are relative, so the two study folders may move together
(e.g. a runs folder copied to another machine); moved apart, the next run relinks from ``reuse_from``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from .result import is_done
from .step import Step


def check_reuse_from(folders: Sequence[str], out_dir: str) -> None:
    """Each folder must be another study's folder (one with a ``steps/`` folder), not this study's own."""
    for folder in folders:
        path = Path(folder)
        if not (path / "steps").is_dir():
            raise ValueError(f"reuse_from: {folder} is not a study folder (no steps/ in it)")
        if path.resolve() == Path(out_dir).resolve():
            raise ValueError(f"reuse_from: {folder} is this study's own folder (out_dir)")


def reusable_steps(steps: Sequence[Step], study_dir: str | Path, folders: Sequence[str]) -> dict[str, Path]:
    """``{key: folder}`` for the ``steps`` (a plan's) this study has no folder for and one of ``folders`` (in their
    order) has finished."""
    found: dict[str, Path] = {}
    for step in steps:
        if step.folder(study_dir).exists():
            continue
        for other in folders:
            if is_done(step, other):
                found[step.key] = step.folder(other)
                break
    return found


def link_reused_steps(steps: Sequence[Step], study_dir: str | Path, folders: Sequence[str]) -> int:
    """Link the :func:`reusable_steps` into ``study_dir`` and return how many. A link left dangling by a
    study folder that has moved is removed first (it holds nothing of this study's), so the step is linked
    again from ``folders`` or run here."""
    for step in steps:
        folder = step.folder(study_dir)
        if folder.is_symlink() and not folder.exists():
            folder.unlink()
    found = reusable_steps(steps, study_dir, folders)
    for step in steps:
        if step.key in found:
            target = step.folder(study_dir)
            target.parent.mkdir(parents=True, exist_ok=True)
            source = os.path.relpath(found[step.key].resolve(), target.parent.resolve())
            target.symlink_to(source, target_is_directory=True)
    return len(found)
