"""``factorworld pack`` / ``unpack`` (``study/run/pack.py``) on a study folder laid out as the study writes one:
what a pack carries and leaves out, and that unpacking checks everything before it writes. That a killed training
goes on from a pack on another folder, to the uninterrupted run's checkpoint, is in test_train_resume.py."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from test_cli import assert_one_line, refusal

from lerobot_factorworld.cli import main
from lerobot_factorworld.study.run.pack import MANIFEST, pack, unpack
from lerobot_factorworld.study.run.train_state import COMPLETE


def _save(train: Path, step: int) -> None:
    for name in COMPLETE:
        path = train / "checkpoints" / f"{step:06d}" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"{name} at {step}")


def _study(root: Path) -> Path:
    """A study folder: a dataset, a finished training (a curve point and its last save) and a finished one that
    continued it, one in progress (two pass-end saves, a half-written third), a finished and an unfinished evaluation, a step linked from elsewhere."""
    study = root / "study"
    (study / "config.json").parent.mkdir(parents=True)
    (study / "config.json").write_text("{}")
    (study / "report.md").write_text("# report")
    dataset = study / "steps" / "collect" / "c1"
    (dataset / "data").mkdir(parents=True)
    (dataset / "data" / "frames.parquet").write_bytes(b"x" * 1000)
    (dataset / "result.json").write_text("{}")
    done = study / "steps" / "train" / "t1" / "train"
    _save(done, 7)
    _save(done, 14)
    (done / "checkpoints" / "last").symlink_to("000014")
    (done.parent / "result.json").write_text('{"checkpoint": "steps/train/t1/train/checkpoints/last/pretrained_model"}')
    longer = study / "steps" / "train" / "t3" / "train"  # finished, continued from t1's last save
    _save(longer, 21)
    (longer.parent / "result.json").write_text('{"extends": "t1"}')
    running = study / "steps" / "train" / "t2" / "train"
    _save(running, 21)
    _save(running, 28)
    (running / "checkpoints" / ".partial-000035").mkdir()
    (running / "checkpoints" / ".partial-000035" / "half").write_text("half")
    (running / "sampler.json").write_text('{"pass_steps": 7}')
    (running.parent / "step.json").write_text("{}")
    for key, finished in (("e1", True), ("e2", False)):
        folder = study / "steps" / "eval" / key
        folder.mkdir(parents=True)
        (folder / "step.json").write_text("{}")
        if finished:
            (folder / "result.json").write_text('{"successes": 1}')
    other = root / "other" / "steps" / "eval" / "e3"
    other.mkdir(parents=True)
    (other / "result.json").write_text("{}")
    (study / "steps" / "eval" / "e3").symlink_to(os.path.relpath(other, study / "steps" / "eval"))
    return study


def _files(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file() or p.is_symlink()}


def test_a_pack_carries_what_a_rerun_needs_and_leaves_out_what_it_makes_again(tmp_path):
    study = _study(tmp_path)
    packed = pack(study, tmp_path / "pack")
    carried = _files(tmp_path / "pack") - {MANIFEST}
    t1, t2, t3 = (f"steps/train/{key}/train/checkpoints" for key in ("t1", "t2", "t3"))
    expected = {"config.json", "steps/train/t1/result.json", f"{t1}/last", "steps/train/t2/step.json"}
    expected |= {"steps/train/t2/train/sampler.json", "steps/eval/e1/step.json", "steps/eval/e1/result.json"}
    expected.add("steps/train/t3/result.json")
    expected |= {f"{t}/{step:06d}/{name}" for t, step in ((t2, 28), (t3, 21)) for name in COMPLETE}  # newest: whole
    weights = ((t1, 7), (t1, 14), (t2, 21))  # older saves, and t1's newest, which t3 has continued: weights only
    expected |= {f"{t}/{step:06d}/{name}" for t, step in weights for name in COMPLETE if "model/" in name}
    assert carried == expected
    assert (packed.trainings, packed.linked, packed.unfinished) == (
        ("steps/train/t2",),
        ("steps/eval/e3",),
        ("steps/eval/e2",),
    )
    manifest = json.loads((tmp_path / "pack" / MANIFEST).read_text())
    assert manifest["links"] == {f"{t1}/last": "000014"} and len(manifest["files"]) == packed.files
    assert os.readlink(tmp_path / "pack" / t1 / "last") == "000014"

    # packed again (the study went on): the pack is replaced whole, nothing of the old one is left in it
    _save(study / "steps" / "train" / "t2" / "train", 35)
    pack(study, tmp_path / "pack")
    assert f"{t2}/000035/training_state/optimizer_state.safetensors" in _files(tmp_path / "pack")
    assert f"{t2}/000028/training_state/optimizer_state.safetensors" not in _files(tmp_path / "pack")
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(("pack.tmp", ".partial-pack"))]


def test_unpacking_checks_every_file_before_it_writes_and_never_replaces_one(tmp_path):
    pack(_study(tmp_path), tmp_path / "pack")
    moved = tmp_path / "elsewhere"
    done = unpack(tmp_path / "pack", moved)
    assert (done.written, done.present, done.links) == (len(_files(tmp_path / "pack")) - 2, 0, 1)
    assert (moved / "steps/train/t1/train/checkpoints/last/pretrained_model/model.safetensors").read_text() == (
        "pretrained_model/model.safetensors at 14"
    )
    again = unpack(tmp_path / "pack", moved)  # idempotent: the same files are there already
    assert (again.written, again.present, again.links) == (0, done.written, 0)

    changed = moved / "steps/eval/e1/result.json"
    changed.write_text('{"successes": 0}')
    other = tmp_path / "third"
    with pytest.raises(ValueError, match="already holds a different steps/eval/e1/result.json; nothing written"):
        unpack(tmp_path / "pack", moved)
    assert changed.read_text() == '{"successes": 0}'

    (tmp_path / "pack" / "steps/eval/e1/step.json").write_text("corrupt")
    with pytest.raises(ValueError, match="steps/eval/e1/step.json is missing or not the file packed"):
        unpack(tmp_path / "pack", other)
    assert not other.exists()


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
    assert "training in progress, carried with its newest save: steps/train/t2" in out
    assert "left out 1 step(s) linked from other studies" in out and "left out 1 unfinished step(s)" in out
    main(["unpack", f"--pack={tmp_path / 'pack'}", f"--study={tmp_path / 'moved'}"])
    out = capsys.readouterr().out
    assert f"unpacked into {tmp_path / 'moved'}: 23 file(s) written, 0 already there, 1 link(s)" in out
