"""``python -m lerobot_factorworld.study.run.train_process <lerobot-train flags>``: ``lerobot-train`` in a new
process (the ``per_step`` execution) that saves as the in-process training does (``train_state.saving``, its
``Saves`` given as JSON in ``FACTORWORLD_TRAIN_SAVES``); without it, ``lerobot-train`` as LeRobot runs it."""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys

from .train_state import SAVES_ENV, Saves, saving

PR_SET_PDEATHSIG = 1  # prctl(2): the signal this process gets when its parent dies


def die_with_parent() -> None:
    """Linux: be killed when the worker that started this training dies (kill -9, a lost Ray worker), so that no
    orphaned training goes on writing into the step folder a rerun resumes in."""
    if not sys.platform.startswith("linux"):
        return
    parent = os.getppid()
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:  # the parent died before the request took effect
        os._exit(1)


def main() -> None:
    die_with_parent()
    from lerobot.scripts import lerobot_train  # noqa: PLC0415 - LeRobot's training stack, once the process runs

    text = os.environ.get(SAVES_ENV)
    with saving(Saves.from_json(text)) if text else contextlib.nullcontext():
        lerobot_train.main()


if __name__ == "__main__":
    main()
