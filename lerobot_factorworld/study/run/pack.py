"""A study's state carried to another machine: :func:`pack` copies what a rerun elsewhere needs to go on from
where this one is, :func:`unpack` puts it into that machine's study folder, and the same ``factorworld study``
command then continues there (a training from its newest saved pass, as after a kill).

Why not the whole folder: a study folder holds datasets and every save's optimizer state, hundreds of MB that a
rerun either makes again by itself or never reads. A pack leaves out:

- datasets: the collection steps (the rerun collects them again from the same seeds) and a training's merged
  data (merged again from them);
- the training state (optimizer, RNG) of every save but the one a rerun, or a longer training that extends it,
  continues from (the newest at a pass's end; while the training runs, its newest save too), and that one as well
  once a finished longer training has continued it; every save's weights stay (an evaluation added later reads
  them);
- unfinished steps other than trainings, except the finished blocks of an ``episodes: auto`` evaluation (its
  group resumes from them); the others start over anyway;
- steps linked from another study (``reuse_from``): pack that study, they are its steps; the old folders of
  redone steps (``<key>.stale-<commit>``);
- saves half written by a kill, the lock, the report (``factorworld report`` and the next run rewrite it).

A pack is a folder, ``pack.json`` (every file with its SHA-256, every link with its target) beside the copied
files, so that packs made again and again of one study (e.g. committed at the end of each session) share their
unchanged files in version control. Unpacking checks every file against ``pack.json`` and against what the study
folder already holds before it writes anything, and never replaces a file: a different file at a path is refused.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from ...core import machine, provenance
from ...core.fingerprint import PREFIX as FINGERPRINT_PREFIX
from ...core.fingerprint import file_fingerprint
from ...core.io import atomic_write_json, temporary_path
from .blocks import BLOCKS_DIR
from .result import EXTENDS, INPUTS_FILE, MERGED_DATA_DIR, RESULT_FILE, TRAIN_DIR
from .step import RUN_CONFIG_FILE, STEPS_DIR, is_step_key
from .train_state import CHECKPOINTS_DIR, COMPLETE, PARTIAL, STATE_DIR, recorded_pass_steps, saved_steps

MANIFEST = "pack.json"
PACK_FORMAT = 1
COPY_TRIES = 3  # a training that saves while it is packed may delete a save being copied: the step is copied again


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
    study, out = Path(study_dir), Path(out)
    check_pack_target(study, out)
    _remove_leftovers(out)
    partial = temporary_path(out)
    files: dict[str, str] = {}
    links: dict[str, str] = {}
    trainings, linked, unfinished = [], [], []
    continued = _continued_trainings(study)
    if (study / RUN_CONFIG_FILE).is_file():
        files[RUN_CONFIG_FILE] = _copy(study / RUN_CONFIG_FILE, partial / RUN_CONFIG_FILE)
    for step in _step_folders(study):
        rel = step.relative_to(study).as_posix()
        if step.is_symlink():
            linked.append(rel)
            continue
        done, is_training = (step / RESULT_FILE).is_file(), (step / TRAIN_DIR).is_dir()
        if not done and not is_training:
            unfinished.append(rel)
            if not (step / BLOCKS_DIR).is_dir():
                continue
        elif not done:
            trainings.append(rel)
        step_files, step_links = _copy_step(step, study, partial, done, continued)
        files.update(step_files)
        links.update(step_links)
    manifest = {
        "format": PACK_FORMAT,
        "study": str(study),
        "name": _study_name(study),
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
        old = _set_aside(out)
        os.replace(out, old)
        os.replace(partial, out)
        shutil.rmtree(old)
    else:
        os.replace(partial, out)
    size = sum((out / name).stat().st_size for name in files)
    return Packed(out, len(files), size, tuple(sorted(trainings)), tuple(sorted(linked)), tuple(sorted(unfinished)))


def check_pack_target(study: Path, out: Path) -> None:
    """Refuse before any work: a study folder without steps, a target inside it, or one that is neither new nor a
    pack of this study (another study's pack may be the only copy of a machine that is gone)."""
    if not (study / STEPS_DIR).is_dir():
        raise ValueError(f"study {study} is not a study folder (no {STEPS_DIR}/ in it): give a study's out_dir")
    if out.resolve() == study.resolve() or study.resolve() in out.resolve().parents:
        raise ValueError(f"out {out} is inside the study folder {study}: give a folder outside it")
    if not out.exists():
        return
    if not (out / MANIFEST).is_file():
        raise ValueError(f"out {out} exists and is not a pack (no {MANIFEST} in it): give a new folder or a pack")
    theirs = read_manifest(out).get("name")
    if theirs != _study_name(study):
        raise ValueError(
            f"out {out} is a pack of study {theirs!r}, not of {_study_name(study)!r}: give a new folder or its own pack"
        )


def _study_name(study: Path) -> str | None:
    """The study's name, from the config its last run wrote (``None`` before any run)."""
    path = study / RUN_CONFIG_FILE
    return json.loads(path.read_text()).get("name") if path.is_file() else None


def _set_aside(out: Path) -> Path:
    return out.with_name(f"{PARTIAL}{out.name}")


def _remove_leftovers(out: Path) -> None:
    """What a pack killed before it ended left beside ``out``: its half-written copy, or the old pack it had set
    aside (put back when ``out`` is gone)."""
    if out.parent.is_dir():
        for leftover in out.parent.glob(f"{out.name}.tmp*"):
            shutil.rmtree(leftover)
    old = _set_aside(out)
    if old.exists():
        if out.exists():
            shutil.rmtree(old)
        else:
            os.replace(old, out)


def _step_folders(study: Path) -> Iterator[Path]:
    for kind in sorted((study / STEPS_DIR).iterdir()):
        if kind.is_dir() and kind.name != "collect":  # datasets: the rerun collects them again
            yield from sorted(step for step in kind.iterdir() if is_step_key(step.name))


def _continued_trainings(study: Path) -> set[str]:
    """Keys of the trainings a finished longer training has continued (``extends`` in its result): their state
    has been read, and nothing goes on from it again."""
    keys = set()
    for result in (study / STEPS_DIR / "train").glob(f"*/{RESULT_FILE}"):
        if not result.parent.is_symlink() and is_step_key(result.parent.name):
            keys.add(json.loads(result.read_text()).get(EXTENDS))
    return keys - {None}


def _kept_states(step: Path, done: bool, continued: set[str]) -> set[int]:
    """The saves whose training state a pack keeps: the newest at a pass's end (what a rerun or an extension
    continues from) and, while the training runs, its newest (``resume_point``'s choices); none once a finished
    longer training has continued it, or for a training older code made (no recorded pass: never resumed)."""
    train = step / TRAIN_DIR
    passes = recorded_pass_steps(train)
    if step.name in continued or passes is None:
        return set()
    saves = sorted(saved_steps(train))
    kept = {s for s in saves if s % passes == 0}
    kept = {max(kept)} if kept else set()
    if saves and not done:
        kept.add(saves[-1])
    return kept


def _copy_step(
    step: Path, study: Path, partial: Path, done: bool, continued: set[str]
) -> tuple[dict[str, str], dict[str, str]]:
    """Copy one step folder's carried files into ``partial``: ``({name: sha256}, {name: link})``. A training that
    runs meanwhile may delete a save as it makes the next: a file gone mid-copy, or a kept save not copied whole,
    and the step is copied again from a fresh listing."""
    for attempt in range(COPY_TRIES):
        kept = _kept_states(step, done, continued) if (step / TRAIN_DIR).is_dir() else set()
        files, links = {}, {}
        try:
            for path, link in _carried(step, study, kept, done):
                name = path.relative_to(study).as_posix()
                if link is not None:
                    links[name] = link
                    (partial / name).parent.mkdir(parents=True, exist_ok=True)
                    os.symlink(link, partial / name)
                else:
                    files[name] = _copy(path, partial / name)
            checkpoints = (step / TRAIN_DIR / CHECKPOINTS_DIR).relative_to(study).as_posix()
            missing = [s for s in kept if any(f"{checkpoints}/{s:06d}/{n}" not in files for n in COMPLETE)]
            if missing:
                raise FileNotFoundError(f"the save of step {missing[0]} was deleted while it was copied")
            return files, links
        except FileNotFoundError:
            shutil.rmtree(partial / step.relative_to(study), ignore_errors=True)
            if attempt == COPY_TRIES - 1:
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


def _carried(step: Path, study: Path, kept: set[int], done: bool) -> list[tuple[Path, str | None]]:
    """``(path, link target or None)`` of what a pack carries of one step folder: everything but half-written saves,
    merged data and the training state of saves not in ``kept``; of an unfinished evaluation, its finished blocks."""
    checkpoints = step / TRAIN_DIR / CHECKPOINTS_DIR
    blocks_only = not done and not (step / TRAIN_DIR).is_dir()  # an unfinished evaluation: its finished blocks
    carried = []
    for path in sorted(step.rglob("*")):
        rel = path.relative_to(step).parts
        if rel[0] == MERGED_DATA_DIR or rel[0].startswith(f"{MERGED_DATA_DIR}."):
            continue
        if blocks_only and rel[0] not in (BLOCKS_DIR, INPUTS_FILE):
            continue
        if path.is_symlink():
            carried.append((path, _link_target(path, study)))
            continue
        if not path.is_file() or any(part.startswith(PARTIAL) for part in rel):
            continue
        if path.is_relative_to(checkpoints) and len(rel) > 4 and rel[3] == STATE_DIR:
            if not rel[2].isdigit() or int(rel[2]) not in kept:
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
    """A file's SHA-256 in hex, as ``pack.json`` records it (the content hash every step key uses)."""
    return file_fingerprint(path).removeprefix(FINGERPRINT_PREFIX)


@dataclass(frozen=True)
class Unpacked:
    """What :func:`unpack` did: files written, files already there with the same content, links made, and the
    trainings that go on."""

    written: int
    present: int
    links: int
    in_progress: tuple[str, ...]  # the trainings in progress the pack carried: they go on from their newest save


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
    pack's record; a file already in the study folder must be the same; no name may lead outside the study folder
    or through a link in it), so a corrupt pack or a study folder that has moved on writes nothing."""
    source, study = Path(pack_dir), Path(study_dir)
    manifest = read_manifest(source)
    for name in [*manifest["files"], *manifest["links"]]:
        _check_name(name, study)
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
                    f"study {study} already holds a different {name}; nothing written. Unpack into a new folder, or "
                    "unpack only where that study has not gone on since the pack was made"
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
        (study / name).parent.mkdir(parents=True, exist_ok=True)
        os.symlink(link, study / name)
    return Unpacked(len(write), present, len(links), tuple(manifest["in_progress"]))


def _check_name(name: str, study: Path) -> None:
    """A pack's file name is a path inside the study folder, reached through no link (a step linked from another
    study by ``reuse_from`` would otherwise be written into)."""
    parts = PurePosixPath(name).parts
    if PurePosixPath(name).is_absolute() or ".." in parts or not parts:
        raise ValueError(f"pack names {name!r}, which is not a path inside the study folder; nothing written")
    for depth in range(1, len(parts)):
        if (study.joinpath(*parts[:depth])).is_symlink():
            raise ValueError(f"{study / name} lies under a link ({'/'.join(parts[:depth])}); nothing written")
