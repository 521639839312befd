"""``factorworld pack`` / ``unpack`` (``study/run/pack.py``) on a study folder laid out as the study writes one:
what a pack carries and leaves out, and that unpacking checks everything before it writes. That a killed training
goes on from a pack on another folder, to the uninterrupted run's checkpoint, is in test_train_resume.py."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from test_cli import assert_one_line, refusal

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.run import pack as pack_module
from lerobot_factorworld.study.run.pack import MANIFEST, pack, unpack
from lerobot_factorworld.study.run.train_state import COMPLETE

T1, T2, T3, T4 = (f"{i}" * 16 for i in "1234")  # step keys: 16 hex digits
E1, E2, E3, E4 = (f"e{i}" * 8 for i in "1234")


def _save(train: Path, step: int) -> None:
    for name in COMPLETE:
        path = train / "checkpoints" / f"{step:06d}" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"{name} at {step}")


def _training(study: Path, key: str, saves: list[int], result: str | None = None) -> Path:
    """A training's step folder with complete saves at ``saves`` (a pass: 7 steps), finished with ``result``."""
    train = study / "steps" / "train" / key / "train"
    for step in saves:
        _save(train, step)
    (train / "sampler.json").write_text('{"pass_steps": 7}')
    (train.parent / "step.json").write_text("{}")
    if result is not None:
        (train / "checkpoints" / "last").symlink_to(f"{saves[-1]:06d}")
        (train.parent / "result.json").write_text(result)
    return train


def _study(root: Path) -> Path:
    """A study folder as the study writes one (a pass is 7 steps):
    - a dataset (collect/c1) and a redone step's old folder;
    - t1: finished, saves at 7 and 14; t3, finished, continued it from 14;
    - t4: finished, its last step (16) not a pass's end: an extension would go on from 14;
    - t2: in progress, pass ends 21 and 28, then a curve checkpoint at 32, and a half-written save;
    - evaluations: e1 finished, e2 unfinished, e4 an unfinished episodes: auto group with a finished block, e3 a
      step linked from another study."""
    study = root / "study"
    (study / "steps").mkdir(parents=True)
    (study / "config.json").write_text('{"name": "toy"}')
    (study / "report.md").write_text("# report")
    dataset = study / "steps" / "collect" / "c1aaaaaaaaaaaaaa"
    (dataset / "data").mkdir(parents=True)
    (dataset / "data" / "frames.parquet").write_bytes(b"x" * 1000)
    (dataset / "result.json").write_text("{}")
    _training(study, T1, [7, 14], '{"checkpoint": "steps/train/t1/train/checkpoints/last/pretrained_model"}')
    _training(study, T3, [21], f'{{"extends": "{T1}"}}')
    _training(study, T4, [14, 16], "{}")
    (study / "steps" / "train" / f"{T4}.stale-abc123").mkdir()
    (study / "steps" / "train" / f"{T4}.stale-abc123" / "result.json").write_text("{}")
    running = _training(study, T2, [21, 28, 32])
    (running / "checkpoints" / ".partial-000035").mkdir()
    (running / "checkpoints" / ".partial-000035" / "half").write_text("half")
    (running.parent / "merged_data" / "meta").mkdir(parents=True)
    (running.parent / "merged_data" / "meta" / "info.json").write_text("{}")
    for key, finished in ((E1, True), (E2, False), (E4, False)):
        folder = study / "steps" / "eval" / key
        folder.mkdir(parents=True)
        (folder / "step.json").write_text("{}")
        (folder / "log.txt").write_text("log")
        if finished:
            (folder / "result.json").write_text('{"successes": 1}')
    (study / "steps" / "eval" / E4 / "blocks").mkdir()
    (study / "steps" / "eval" / E4 / "blocks" / "1.json").write_text("[1, 0]")
    other = root / "other" / "steps" / "eval" / E3
    other.mkdir(parents=True)
    (other / "result.json").write_text("{}")
    (study / "steps" / "eval" / E3).symlink_to(os.path.relpath(other, study / "steps" / "eval"))
    return study


def _files(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file() or p.is_symlink()}


def _checkpoint_files(key: str, step: int, whole: bool) -> set[str]:
    return {f"steps/train/{key}/train/checkpoints/{step:06d}/{n}" for n in COMPLETE if whole or "model/" in n}


def test_a_pack_carries_what_a_rerun_needs_and_leaves_out_what_it_makes_again(tmp_path):
    study = _study(tmp_path)
    packed = pack(study, tmp_path / "pack")
    carried = _files(tmp_path / "pack") - {MANIFEST}
    expected = {"config.json", *(f"steps/train/{key}/train/checkpoints/last" for key in (T1, T3, T4))}
    expected |= {
        f"steps/train/{key}/{name}" for key in (T1, T2, T3, T4) for name in ("step.json", "train/sampler.json")
    }
    expected |= {f"steps/train/{key}/result.json" for key in (T1, T3, T4)}
    expected |= {f"steps/eval/{E1}/{name}" for name in ("step.json", "log.txt", "result.json")}
    expected |= {f"steps/eval/{E4}/step.json", f"steps/eval/{E4}/blocks/1.json"}  # the group resumes from its blocks
    # whole: what a rerun or an extension continues from (T2: its newest pass end, 28, and its newest, the
    # curve's 32; T4: 14, its last pass end, not its last step; T3: its newest); weights only: the rest, and
    # T1's, which T3 has continued
    whole = {(T2, 28), (T2, 32), (T4, 14), (T3, 21)}
    for key, step in [(T1, 7), (T1, 14), (T2, 21), (T2, 28), (T2, 32), (T3, 21), (T4, 14), (T4, 16)]:
        expected |= _checkpoint_files(key, step, (key, step) in whole)
    assert carried == expected
    assert (packed.trainings, packed.linked, packed.unfinished) == (
        (f"steps/train/{T2}",),
        (f"steps/eval/{E3}",),
        (f"steps/eval/{E2}", f"steps/eval/{E4}"),
    )
    manifest = json.loads((tmp_path / "pack" / MANIFEST).read_text())
    assert manifest["links"][f"steps/train/{T1}/train/checkpoints/last"] == "000014"
    assert len(manifest["files"]) == packed.files and manifest["name"] == "toy"
    assert os.readlink(tmp_path / "pack" / f"steps/train/{T1}/train/checkpoints/last") == "000014"

    # packed again (the study went on): the pack is replaced whole, nothing of the old one is left in it
    _save(study / "steps" / "train" / T2 / "train", 35)
    pack(study, tmp_path / "pack")
    assert _checkpoint_files(T2, 35, True) <= _files(tmp_path / "pack")
    assert f"steps/train/{T2}/train/checkpoints/000028/training_state/training_step.json" not in _files(
        tmp_path / "pack"
    )
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(("pack.tmp", ".partial-pack"))]


def test_a_save_deleted_while_it_is_packed_is_packed_again_from_a_fresh_listing(tmp_path, monkeypatch):
    """The training saves 35 and deletes 28 (its older pass end) between the pack's listing and its copy: the pack
    copies the step again and carries 35 whole, never a pack without a state to resume from."""
    study = _study(tmp_path)
    train = study / "steps" / "train" / T2 / "train"
    real_copy, moved = pack_module._copy, []

    def copy_while_training(source: Path, target: Path) -> str:
        if not moved and "000028" in source.parts:
            _save(train, 35)
            shutil.rmtree(train / "checkpoints" / "000028")
            moved.append(source)
        return real_copy(source, target)

    monkeypatch.setattr(pack_module, "_copy", copy_while_training)
    pack(study, tmp_path / "pack")
    carried = _files(tmp_path / "pack")
    assert moved and _checkpoint_files(T2, 35, True) <= carried
    assert not any(f"{T2}/train/checkpoints/000028" in name for name in carried)


def test_a_pack_of_another_study_is_never_replaced(tmp_path):
    study = _study(tmp_path)
    pack(study, tmp_path / "pack")
    (study / "config.json").write_text('{"name": "other"}')
    with pytest.raises(ValueError, match="is a pack of study 'toy', not of 'other'"):
        pack(study, tmp_path / "pack")
    assert json.loads((tmp_path / "pack" / MANIFEST).read_text())["name"] == "toy"


def test_unpacking_checks_every_file_before_it_writes_and_never_replaces_one(tmp_path):
    pack(_study(tmp_path), tmp_path / "pack")
    moved = tmp_path / "elsewhere"
    done = unpack(tmp_path / "pack", moved)
    assert (done.written, done.present, done.links) == (len(_files(tmp_path / "pack")) - 4, 0, 3)
    last = moved / f"steps/train/{T1}/train/checkpoints/last/pretrained_model/model.safetensors"
    assert last.read_text() == "pretrained_model/model.safetensors at 14"
    again = unpack(tmp_path / "pack", moved)  # idempotent: the same files are there already
    assert (again.written, again.present, again.links) == (0, done.written, 0)

    changed = moved / f"steps/eval/{E1}/result.json"
    changed.write_text('{"successes": 0}')
    other = tmp_path / "third"
    with pytest.raises(ValueError, match=f"already holds a different steps/eval/{E1}/result.json; nothing written"):
        unpack(tmp_path / "pack", moved)
    assert changed.read_text() == '{"successes": 0}'

    (tmp_path / "pack" / f"steps/eval/{E1}/step.json").write_text("corrupt")
    with pytest.raises(ValueError, match=f"steps/eval/{E1}/step.json is missing or not the file packed"):
        unpack(tmp_path / "pack", other)
    assert not other.exists()


@pytest.mark.parametrize("name", ["../outside.txt", "/tmp/outside.txt", "steps/eval/linked/result.json"])
def test_unpacking_never_writes_outside_the_study_folder_or_through_a_link(tmp_path, name):
    """A pack's names come from a file anyone may edit (packs are committed and shared): one that leads outside the
    study folder, or into another study through a step linked by ``reuse_from``, is refused before anything."""
    pack_dir, study, elsewhere = tmp_path / "pack", tmp_path / "study", tmp_path / "elsewhere"
    (pack_dir / "a").mkdir(parents=True)
    (pack_dir / "a" / "ok.txt").write_text("ok")
    (elsewhere / "linked").mkdir(parents=True)
    (study / "steps" / "eval").mkdir(parents=True)
    (study / "steps" / "eval" / "linked").symlink_to(elsewhere / "linked")
    files = {"a/ok.txt": pack_module._sha256(pack_dir / "a" / "ok.txt"), name: "0" * 64}
    (pack_dir / MANIFEST).write_text(json.dumps({"format": 1, "files": files, "links": {}}))
    with pytest.raises(ValueError, match="nothing written"):
        unpack(pack_dir, study)
    assert not (study / "a").exists() and not list((elsewhere / "linked").iterdir())


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["pack", "--study={tmp}/study"], "factorworld pack needs --study=STUDY_DIR --out=PACK_DIR"),
        (["pack", "--study={tmp}", "--out={tmp}/p"], "study {tmp} is not a study folder (no steps/ in it)"),
        (["pack", "--study={tmp}/study", "--out={tmp}/study/p"], "is inside the study folder"),
        (["pack", "--study={tmp}/study", "--out={tmp}/study/config.json"], "config.json is a file, not a folder"),
        (["pack", "--study={tmp}/study", "--out={tmp}"], "exists and is not a pack (no pack.json in it)"),
        (["unpack", "--pack={tmp}/study"], "holds no pack.json: give a folder written by factorworld pack"),
        (["unpack", "--study={tmp}/x"], "factorworld unpack needs --pack=PACK_DIR"),
    ],
)
def test_pack_and_unpack_refuse_bad_settings_in_one_line(argv, expected, tmp_path, capsys):
    _study(tmp_path)
    status, err = refusal([a.format(tmp=tmp_path) for a in argv], capsys)
    assert status == 2
    assert_one_line(err, expected.format(tmp=tmp_path))
    assert not (tmp_path / "p").exists() and not (tmp_path / "study" / "p").exists()


def test_the_commands_say_what_was_carried_and_how_to_go_on(tmp_path, capsys):
    study = _study(tmp_path)
    main(["pack", f"--study={study}", f"--out={tmp_path / 'pack'}"])
    out = capsys.readouterr().out
    assert f"training in progress, carried with its newest save: steps/train/{T2}" in out
    assert f"left out, linked from another study (reuse_from; pack that study): steps/eval/{E3}" in out
    assert "left out 2 unfinished step(s)" in out
    main(["unpack", f"--pack={tmp_path / 'pack'}", f"--study={tmp_path / 'moved'}"])
    out = capsys.readouterr().out
    written = len(_files(tmp_path / "pack")) - 4  # not pack.json and the three links
    assert f"unpacked into {tmp_path / 'moved'}: {written} file(s) written, 0 already there, 3 link(s)" in out
