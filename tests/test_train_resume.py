"""A study's training survives a kill: killed with kill -9 at a random point, it resumes from its last saved state
(the study's process group: when the same ``factorworld study`` command runs again; the Ray worker that trains: at
once, in Ray's retry of its task), and its final checkpoint's files are those of an uninterrupted run, byte for
byte (``study/run/train_state.py``)."""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from toy_study import write_toy_study

from lerobot_factorworld.study.run.pack import pack as pack_study

# Both tests read one uninterrupted run (a module fixture): one xdist worker runs them, one after the other.
pytestmark = pytest.mark.xdist_group("train_resume")
PASS_STEPS = 7  # ceil(51 frames / 8): the toy's two demos hold 51 frames
STEPS = 255  # ceil(40 epochs * 51 / 8)


def _config(folder: Path, executor: str = "local") -> Path:
    return write_toy_study(folder / "resume.yaml", folder / "study", train={"epochs": 40}, executor=executor)


def _study(config: Path) -> list[str]:
    return [sys.executable, "-m", "lerobot_factorworld.cli", "study", f"--config_path={config}"]


def _train_folder(study: Path) -> Path:
    (folder,) = (study / "steps" / "train").iterdir()
    return folder


def _saved(study: Path) -> list[int]:
    checkpoints = study / "steps" / "train"
    return sorted(int(d.name) for d in checkpoints.glob("*/train/checkpoints/*") if d.name.isdigit())


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> Path:
    """The toy study run once without interruption: its study folder (the reference every resumed run must equal)."""
    config = _config(tmp_path_factory.mktemp("uninterrupted"))
    subprocess.run(_study(config), check=True, capture_output=True, timeout=600)
    return config.parent / "study"


def _copy_collection(reference: Path, study: Path) -> None:
    """The reference's collected dataset into ``study`` (the same step key): only the training is run again."""
    shutil.copytree(reference / "steps" / "collect", study / "steps" / "collect", symlinks=True)


def _kill_at_random_save(
    start: Callable[[], subprocess.Popen],
    study: Path,
    kill: Callable[[subprocess.Popen], None],
    study_goes_on: bool = False,
):
    """Start the study and kill it (``kill``) once the training has saved past a random pass's end (the save after
    it may be half written); returns what was killed when, for the failure messages, and the study's exit status
    (once it has ended: at the kill, or when ``study_goes_on``, once it has finished)."""
    seed = random.randrange(10**6)
    target = random.Random(seed).randrange(2, STEPS // PASS_STEPS - 2) * PASS_STEPS
    proc = start()
    deadline = time.time() + 300
    while time.time() < deadline and not any(step >= target for step in _saved(study)) and proc.poll() is None:
        time.sleep(0.005)
    kill(proc)
    status = proc.wait(timeout=600)
    if not study_goes_on:
        assert not (_train_folder(study) / "result.json").exists(), f"the kill (seed {seed}) should land mid-training"
    return f"killed after step {target} (seed {seed}), saves {_saved(study)}", status


def _same_checkpoints(study: Path, reference: Path, why: str) -> None:
    """The final checkpoint's files (weights, processors, optimizer, RNG, step) equal the reference's byte for byte;
    ``train_config.json`` names the study folder, so it is compared with the reference's folder in its place."""
    mine = _train_folder(study) / "train" / "checkpoints" / f"{STEPS:06d}"
    theirs = _train_folder(reference) / "train" / "checkpoints" / f"{STEPS:06d}"
    files = sorted(p.relative_to(theirs) for p in theirs.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(mine) for p in mine.rglob("*") if p.is_file()), why
    assert len(files) >= 8, files
    for name in files:
        a, b = (theirs / name).read_bytes(), (mine / name).read_bytes()
        if name.name == "train_config.json":
            a = a.replace(str(reference).encode(), str(study).encode())
        assert a == b, f"{name} differs; {why}"


def _kill_group(proc: subprocess.Popen) -> None:
    os.killpg(proc.pid, signal.SIGKILL)


@pytest.mark.slow
def test_a_study_killed_mid_training_resumes_and_ends_with_the_uninterrupted_checkpoint(uninterrupted, tmp_path):
    config = _config(tmp_path)
    study = config.parent / "study"
    _copy_collection(uninterrupted, study)

    def start() -> subprocess.Popen:
        return subprocess.Popen(
            _study(config), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
        )

    why, status = _kill_at_random_save(start, study, _kill_group)
    assert status == -signal.SIGKILL
    subprocess.run(_study(config), check=True, capture_output=True, timeout=600)
    result = json.loads((_train_folder(study) / "result.json").read_text())
    assert result["resumed_from"] > 0 and result["resumed_from"] % PASS_STEPS == 0, why
    log = (_train_folder(study) / "log.txt").read_text()
    assert "Resuming data order at epoch" in log and "frames decoded once: 51 rows" in log  # the frame cache served it
    _same_checkpoints(study, uninterrupted, why)
    # the saves only a rerun needed are gone: the curve-less training keeps its last and the newest pass's end
    assert _saved(study) == [STEPS // PASS_STEPS * PASS_STEPS, STEPS], why


@pytest.mark.slow
def test_a_training_packed_on_a_machine_that_goes_away_goes_on_elsewhere_to_the_uninterrupted_checkpoint(
    uninterrupted, tmp_path
):
    """Packed while it trains (``factorworld pack``), the study's machine then lost (kill -9, its folder deleted),
    unpacked into another folder: the rerun there collects the dataset again and ends with the same checkpoint."""
    config = _config(tmp_path / "first")
    study = config.parent / "study"
    _copy_collection(uninterrupted, study)
    pack = tmp_path / "pack"

    def start() -> subprocess.Popen:
        return subprocess.Popen(
            _study(config), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
        )

    def pack_then_lose_the_machine(proc: subprocess.Popen) -> None:
        pack_study(study, pack)  # in this process: the command's 3 s of imports would outlast the toy's training
        _kill_group(proc)

    why, _ = _kill_at_random_save(start, study, pack_then_lose_the_machine)
    shutil.rmtree(study)
    assert not (pack / "steps" / "collect").exists()  # the dataset is not carried: it is collected again
    elsewhere = _config(tmp_path / "second")
    moved = elsewhere.parent / "study"
    factorworld("unpack", f"--pack={pack}", f"--study={moved}")
    subprocess.run(_study(elsewhere), check=True, capture_output=True, timeout=600)
    result = json.loads((_train_folder(moved) / "result.json").read_text())
    assert result["resumed_from"] > 0 and result["resumed_from"] % PASS_STEPS == 0, why
    runs = result["trained_on"]  # both runs recorded, on this machine, on datasets of the same content
    assert [run["from_step"] for run in runs] == [0, result["resumed_from"]], why
    assert runs[0]["dataset"] == runs[1]["dataset"] and runs[0]["dataset"].startswith("sha256:"), runs
    _same_checkpoints(moved, uninterrupted, why)


def factorworld(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "lerobot_factorworld.cli", *args], check=True, capture_output=True)


def _ray_training_workers() -> list[int]:
    """Processes running a Ray task of the study (Ray names them after the task's function)."""
    found = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit():
            try:
                if (proc / "cmdline").read_bytes().startswith(b"ray::run_steps"):
                    found.append(int(proc.name))
            except OSError:
                continue
    return found


@pytest.mark.slow
def test_a_ray_worker_lost_mid_training_is_retried_and_resumes_to_the_uninterrupted_checkpoint(uninterrupted, tmp_path):
    pytest.importorskip("ray")
    config = _config(tmp_path, executor="ray")
    study = config.parent / "study"
    _copy_collection(uninterrupted, study)
    log = tmp_path / "first_run.txt"

    def start() -> subprocess.Popen:
        return subprocess.Popen(_study(config), stdout=log.open("w"), stderr=subprocess.STDOUT, start_new_session=True)

    def lose_the_worker(proc: subprocess.Popen) -> None:
        workers = _ray_training_workers()
        assert workers, "no Ray worker is training"
        for pid in workers:
            os.kill(pid, signal.SIGKILL)

    why, status = _kill_at_random_save(start, study, lose_the_worker, study_goes_on=True)
    assert status == 0, log.read_text()[-2000:]  # Ray ran the task again: the study itself finished
    result = json.loads((_train_folder(study) / "result.json").read_text())
    assert result["resumed_from"] > 0 and result["resumed_from"] % PASS_STEPS == 0, why  # the retry went on
    _same_checkpoints(study, uninterrupted, why)


def test_a_worker_killed_by_a_native_fault_prints_the_python_stack_first():
    """What a Ray worker's ``.err`` log holds when MuJoCo or Mesa crashes it: the stack, not just a lost worker."""
    crash = (
        "import ctypes, lerobot_factorworld.study.run.worker as worker\n"
        "worker.run_steps([], '.')  # a Ray worker runs its task\n"
        "def render_the_scene():\n"
        "    ctypes.string_at(0)\n"
        "render_the_scene()\n"
    )
    run = subprocess.run([sys.executable, "-c", crash], capture_output=True, text=True, timeout=120)
    assert run.returncode == -signal.SIGSEGV, run.stderr[-2000:]
    assert "Segmentation fault" in run.stderr and "render_the_scene" in run.stderr, run.stderr[-2000:]
