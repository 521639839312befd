"""``python -m lerobot_factorworld.study.run.train_process <lerobot-train flags>``: ``lerobot-train`` in a new
process (the ``per_step`` execution) that saves as the in-process training does (``train_state.saving``, its
``Saves`` given as JSON in ``FACTORWORLD_TRAIN_SAVES``); without it, ``lerobot-train`` as LeRobot runs it."""

from __future__ import annotations

import contextlib
import os

from .train_state import SAVES_ENV, Saves, saving


def main() -> None:
    from lerobot.scripts import lerobot_train  # noqa: PLC0415 - LeRobot's training stack, once the process runs

    text = os.environ.get(SAVES_ENV)
    with saving(Saves.from_json(text)) if text else contextlib.nullcontext():
        lerobot_train.main()


if __name__ == "__main__":
    main()
