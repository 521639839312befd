"""The step this process runs now: how it runs (its execution) and the timings its kind's code records into.

Its own module so that the step kinds (``collect_step.py``, ``train_step.py``, ``eval_step.py``) read it without
importing the worker that dispatches to them (``worker.py``).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator

from ...core.timing import Timings

# How steps run (never what they compute: the same step keys, results, checkpoints and datasets either way):
# ``per_step`` runs every step on its own (``lerobot-train`` as a subprocess, each evaluation loading its
# policy); ``grouped`` trains in the worker process and evaluates all conditions of a checkpoint in one task.
EXECUTIONS = ("grouped", "per_step")

# (timings, execution) of the step this process runs now: what the runners record into, and how they run
_CURRENT: contextvars.ContextVar[tuple[Timings, str]] = contextvars.ContextVar("study_step")


def current() -> tuple[Timings, str]:
    """The running step's timings and execution (fresh ones when a runner is called on its own)."""
    return _CURRENT.get((Timings(), "per_step"))


@contextlib.contextmanager
def running(timings: Timings, execution: str) -> Iterator[None]:
    """Within it, :func:`current` is ``(timings, execution)``: the step the worker runs now."""
    token = _CURRENT.set((timings, execution))
    try:
        yield
    finally:
        _CURRENT.reset(token)
