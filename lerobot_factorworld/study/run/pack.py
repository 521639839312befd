"""A study's state carried to another machine: :func:`pack` copies what a rerun elsewhere needs to go on from
where this one is, :func:`unpack` puts it into that machine's study folder, and the same ``factorworld study``
command then continues there (a training from its newest saved pass, as after a kill).

Why not the whole folder: a study folder holds datasets and every save's optimizer state, hundreds of MB that a
rerun either makes again by itself or never reads. A pack leaves out:

- collection steps (their datasets): the rerun collects them again from the same seeds;
- the training state (optimizer, RNG) of every save but each training's newest, the one a rerun or a longer
  training that extends it continues from, and that one too once a finished longer training has continued it;
  every save's weights stay (an evaluation added later reads them);
- steps that have not finished, except trainings (an evaluation, a collection starts over anyway);
- steps linked from another study (``reuse_from``): pack that study, they are its steps;
- saves half written by a kill, the lock, the report (``factorworld report`` and the next run rewrite it).

A pack is a folder, ``pack.json`` (every file with its SHA-256, every link with its target) beside the copied
files, so that packs made again and again of one study (e.g. committed at the end of each session) share their
unchanged files in version control. Unpacking checks every file against ``pack.json`` and against what the study
folder already holds before it writes anything, and never replaces a file: a different file at a path is refused.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...core import machine, provenance
from ...core.io import atomic_write_json, temporary_path
from .step import STEPS_DIR
from .steps import RESULT_FILE, TRAIN_DIR
from .train_state import CHECKPOINTS_DIR, PARTIAL, STATE_DIR, saved_steps

MANIFEST = "pack.json"
PACK_FORMAT = 1
STUDY_FILES = ("config.json",)  # the study folder's own files a pack carries (the config the steps were made for)
LEFT_OUT_KINDS = ("collect",)  # made again by the rerun: a dataset is hundreds of MB, its collection minutes


@dataclass(frozen=True)
class Packed:
    """What :func:`pack` wrote: ``files`` and ``links`` carried, ``trainings`` in progress among them, and what it
    left out that a reader may look for (``linked``: steps of other studies; ``unfinished``: steps that start over)."""

    folder: Path
    files: int
    size: int
    trainings: tuple[str, ...]
    linked: tuple[str, ...]
    unfinished: tuple[str, ...]


def pack(study_dir: str | Path, out: str | Path) -> Packed:
    """Copy the part of ``study_dir`` a rerun elsewhere needs into the folder ``out`` (a new folder, or a pack of
    the same study, which is replaced whole once the new one is complete)."""
    study = Path(study_dir)
    out = Path(out)
    check_pack_target(study, out)
    partial = temporary_path(out)
    if partial.exists():
        shutil.rmtree(partial)
    files: dict[str, str] = {}
    links: dict[str, str] = {}
    trainings, linked, unfinished = [], [], []
    continued = _continued_trainings(study)
    for rel in STUDY_FILES:
        if (study / rel).is_file():
            files[rel] = _copy(study / rel, partial / rel)
    for step in _step_folders(study):
        rel = step.relative_to(study).as_posix()
        if step.is_symlink():
            linked.append(rel)
            continue
        done = (step / RESULT_FILE).is_file()
        is_training = (step / TRAIN_DIR).is_dir()
        if step.parent.name in LEFT_OUT_KINDS:
            continue
        if not done and not is_training:
            unfinished.append(rel)
            continue
        if not done:
            trainings.append(rel)
        step_files, step_links = _copy_step(step, study, partial, keep_state=step.name not in continued)
        files.update(step_files)
        links.update(step_links)
    manifest = {
        "format": PACK_FORMAT,
        "study": str(study),
        "made_by": provenance.current().to_dict(),
        "machine": machine.current(),
        "files": dict(sorted(files.items())),
        "links": dict(sorted(links.items())),
        "in_progress": sorted(trainings),
        "linked": sorted(linked),
        "unfinished": sorted(unfinished),
    }
    partial.mkdir(parents=True, exist_ok=True)
    atomic_write_json(partial / MANIFEST, manifest, indent=1)
    if out.exists():  # a pack of this study (checked): replaced whole, never mixed with the new one
        old = out.with_name(f"{PARTIAL}{out.name}")
        os.replace(out, old)
        os.replace(partial, out)
        shutil.rmtree(old)
    else:
        os.replace(partial, out)
    size = sum((out / name).stat().st_size for name in files)
    return Packed(out, len(files), size, tuple(sorted(trainings)), tuple(sorted(linked)), tuple(sorted(unfinished)))


def check_pack_target(study: Path, out: Path) -> None:
    """Refuse before any work: a study folder without steps, or a target that is neither new nor a pack."""
    if not (study / STEPS_DIR).is_dir():
        raise ValueError(f"study {study} is not a study folder (no {STEPS_DIR}/ in it): give a study's out_dir")
    if out.exists() and not (out / MANIFEST).is_file():
        raise ValueError(f"out {out} exists and is not a pack (no {MANIFEST} in it): give a new folder or a pack")
    if out.resolve() == study.resolve() or study.resolve() in out.resolve().parents:
        raise ValueError(f"out {out} is inside the study folder {study}: give a folder outside it")


def _step_folders(study: Path) -> Iterator[Path]:
    for kind in sorted((study / STEPS_DIR).iterdir()):
        if kind.is_dir():
            yield from sorted(kind.iterdir())


def _continued_trainings(study: Path) -> set[str]:
    """Keys of the trainings a finished longer training has continued (``extends`` in its result): their newest
    state has been read, and nothing goes on from it again."""
    keys = set()
    for result in (study / STEPS_DIR / "train").glob(f"*/{RESULT_FILE}"):
        if not result.parent.is_symlink():
            keys.add(json.loads(result.read_text()).get("extends"))
    return keys - {None}


def _copy_step(
    step: Path, study: Path, partial: Path, keep_state: bool, tries: int = 3
) -> tuple[dict[str, str], dict[str, str]]:
    """Copy one step folder's carried files into ``partial``: ``({name: sha256}, {name: link})``. A training that
    runs meanwhile may replace its newest save (the older is deleted once the newer is in place): then the step is
    copied again from a fresh listing."""
    for attempt in range(tries):
        files, links = {}, {}
        try:
            for path, link in _carried(step, study, keep_state):
                name = path.relative_to(study).as_posix()
                if link is not None:
                    links[name] = link
                    (partial / name).parent.mkdir(parents=True, exist_ok=True)
                    os.symlink(link, partial / name)
                else:
                    files[name] = _copy(path, partial / name)
            return files, links
        except FileNotFoundError:
            shutil.rmtree(partial / step.relative_to(study), ignore_errors=True)
            if attempt == tries - 1:
                raise
    raise AssertionError("unreachable")


def _link_target(path: Path, study: Path) -> str:
    """A link's target as the pack records it: relative, and inside the study folder (an absolute link into it, as
    older code wrote, is made relative; one that leads outside cannot be carried)."""
    target = os.readlink(path)
    resolved = (path.parent / target).resolve()
    if not resolved.is_relative_to(study.resolve()):
        raise ValueError(f"{path} links outside the study folder ({target}): a pack cannot carry it")
    return os.path.relpath(resolved, path.parent.resolve()) if os.path.isabs(target) else target


def _carried(step: Path, study: Path, keep_state: bool) -> list[tuple[Path, str | None]]:
    """``(path, link target or None)`` of what a pack carries of one step folder: everything but half-written saves
    and the training state of saves older than the training's newest (of every save, without ``keep_state``)."""
    checkpoints = step / TRAIN_DIR / CHECKPOINTS_DIR
    saves = saved_steps(step / TRAIN_DIR)
    newest = max(saves, default=None) if keep_state else None
    carried = []
    for path in sorted(step.rglob("*")):
        rel = path.relative_to(step).parts
        if path.is_symlink():
            carried.append((path, _link_target(path, study)))
            continue
        if not path.is_file() or any(part.startswith(PARTIAL) for part in rel):
            continue
        if path.is_relative_to(checkpoints) and len(rel) > 4 and rel[3] == STATE_DIR:
            if not rel[2].isdigit() or int(rel[2]) != newest:
                continue
        carried.append((path, None))
    return carried


def _copy(source: Path, target: Path) -> str:
    """Copy a file (written beside its name, then renamed) and return its SHA-256."""
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = temporary_path(target)
    shutil.copyfile(source, partial)
    os.replace(partial, target)
    return _sha256(target)


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


@dataclass(frozen=True)
class Unpacked:
    """What :func:`unpack` did: files written, files already there with the same content, links made."""

    written: int
    present: int
    links: int


def read_manifest(pack_dir: str | Path) -> dict[str, Any]:
    path = Path(pack_dir) / MANIFEST
    if not path.is_file():
        raise ValueError(f"pack {pack_dir} holds no {MANIFEST}: give a folder written by factorworld pack")
    manifest = json.loads(path.read_text())
    if manifest.get("format") != PACK_FORMAT:
        raise ValueError(f"pack {pack_dir} has format {manifest.get('format')!r}; this code reads {PACK_FORMAT}")
    return manifest


def unpack(pack_dir: str | Path, study_dir: str | Path) -> Unpacked:
    """Put a pack's files into ``study_dir`` (made if absent). Every file is checked first (its SHA-256 against the
    pack's record; a file already in the study folder must be the same), so a corrupt pack or a study folder that
    has moved on writes nothing."""
    source, study = Path(pack_dir), Path(study_dir)
    manifest = read_manifest(source)
    write, present = [], 0
    for name, digest in manifest["files"].items():
        have = source / name
        if not have.is_file() or _sha256(have) != digest:
            raise ValueError(
                f"pack {source}: {name} is missing or not the file packed (SHA-256 differs); nothing written"
            )
        target = study / name
        if target.is_symlink() or target.exists():
            if not target.is_file() or _sha256(target) != digest:
                raise ValueError(
                    f"study {study} already holds a different {name}; nothing written. "
                    "Unpack into a new folder, or remove that step's folder first"
                )
            present += 1
        else:
            write.append(name)
    links = []
    for name, link in manifest["links"].items():
        target = study / name
        if target.is_symlink() and os.readlink(target) == link:
            continue
        if target.is_symlink() or target.exists():
            raise ValueError(f"study {study} already holds {name}, not a link to {link}; nothing written")
        links.append((name, link))
    for name in write:
        _copy(source / name, study / name)
    for name, link in links:
        os.symlink(link, study / name)
    return Unpacked(len(write), present, len(links))
