"""LeRobot's console scripts run by a study's training: ``lerobot-train`` in a new Python process (the ``per_step``
execution, through ``train_process.py``) or in this worker process (``grouped``), which then must look to LeRobot
as a new process would (:func:`as_lerobot_process`). Both save as the training's ``Saves`` say, and both leave a
byte-identical checkpoint."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from ...core.children import forked_children_die_with_this_process
from ...core.timing import Timings
from ...datasets.frame_cache import cached_frames
from .result import LOG_FILE
from .train_state import SAVES_ENV, Saves, saving


def train_subprocess(cmd: list[str], folder: Path, threads: int, saves: Saves) -> None:
    """``lerobot-train`` in a new Python process (the ``per_step`` execution), saving as ``saves`` say."""
    n = str(threads)
    env = {**os.environ, "OMP_NUM_THREADS": n, "MKL_NUM_THREADS": n, "TOKENIZERS_PARALLELISM": "false"}
    env[SAVES_ENV] = saves.to_json()
    with open(folder / LOG_FILE, "a") as log:
        log.write(" ".join(cmd) + "\n")
        log.flush()
        proc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=folder)
    if proc.returncode != 0:
        tail = (folder / LOG_FILE).read_text()[-2000:]
        raise RuntimeError(f"lerobot-train failed (exit {proc.returncode}); log {folder / LOG_FILE}:\n{tail}")


def train_in_process(args: list[str], folder: Path, threads: int, timings: Timings, saves: Saves) -> None:
    """``lerobot-train`` with ``args`` in this (persistent worker) process, saving as ``saves`` say: no interpreter
    start and no imports per run, PNG frames decoded once (``datasets/frame_cache.py``: the loader then needs a
    fraction of a core), and a checkpoint byte-identical to the subprocess's (``scripts/bench_study.py`` checks)."""
    with timings.span("imports"):
        from lerobot.scripts import lerobot_train  # noqa: PLC0415 - LeRobot's training stack (seconds, once)

    print("lerobot-train (in process) " + " ".join(args), flush=True)
    forked_children_die_with_this_process()  # a killed worker's loaders must not keep its Ray connection open
    try:
        with (
            as_lerobot_process("lerobot-train", args, folder, threads),
            saving(saves),
            cached_frames(),
            warnings.catch_warnings(),
        ):
            # A lent loader (loader_args) forks this worker, whose renderer and arrow threads sit idle meanwhile:
            # its children only read PNG frames from parquet, so Python's warning about forking with threads is
            # noise here.
            warnings.filterwarnings("ignore", r"This process .* is multi-threaded, use of fork\(\)", DeprecationWarning)
            lerobot_train.main()
    except SystemExit as err:  # draccus exits on a bad flag
        raise RuntimeError(f"lerobot-train failed (exit {err.code}); log {folder / LOG_FILE}") from None


@contextlib.contextmanager
def as_lerobot_process(command: str, args: list[str], cwd: Path, threads: int) -> Iterator[None]:
    """Run a LeRobot console script's ``main()`` (``lerobot-train``, ``lerobot-eval``) in this process as a new
    process would run it: everything such a process fixes at its start is fixed here (the command line
    LeRobot parses, the working directory, torch's threads, ``TOKENIZERS_PARALLELISM``; the scripts seed every
    RNG themselves), restored afterwards, and accelerate's process-wide state forgotten."""
    import torch  # noqa: PLC0415 - deliberately here: only a training (or evaluating) worker needs torch

    saved = (list(sys.argv), os.getcwd(), torch.get_num_threads(), os.environ.get("TOKENIZERS_PARALLELISM"))
    sys.argv = [command, *args]
    os.environ["TOKENIZERS_PARALLELISM"] = "false"
    torch.set_num_threads(threads)
    os.chdir(cwd)
    try:
        yield
    finally:
        sys.argv, previous_cwd, n, tokenizers = saved
        os.chdir(previous_cwd)
        torch.set_num_threads(n)
        if tokenizers is None:
            os.environ.pop("TOKENIZERS_PARALLELISM", None)
        else:
            os.environ["TOKENIZERS_PARALLELISM"] = tokenizers
        _reset_accelerate()


def _reset_accelerate() -> None:
    """Forget accelerate's process-wide state, so that the next in-process run starts as a new process would."""
    from accelerate.state import AcceleratorState, GradientState, PartialState  # noqa: PLC0415 - with lerobot-train only

    for state in (AcceleratorState, GradientState, PartialState):
        state._reset_state()
