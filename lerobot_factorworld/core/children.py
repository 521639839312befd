"""Processes forked from a study's worker die with it.

A training run in a persistent worker (a Ray task's process, a grouped local worker) forks its data loaders
(``study/run/train_step.py``, ``loader_args``). A forked child holds copies of every file descriptor of its parent,
a Ray worker's connection to its raylet included. When the worker is killed (the OOM killer, kill -9) while a
loader child lives, the raylet can keep seeing an open connection, and so neither declare the worker lost nor retry
its task, until that child ends (a retry once came 7 minutes late in the test suite; that an orphaned loader held it
is the likely cause, not a reproduced one). Linux's ``PR_SET_PDEATHSIG`` has the kernel kill each child the moment
its parent dies instead.
"""

from __future__ import annotations

import ctypes
import functools
import os
import signal
import sys
from collections.abc import Callable

PR_SET_PDEATHSIG = 1  # prctl(2)
_parent = 0  # the pid of the process that is forking, set just before each fork


def _remember_parent() -> None:
    global _parent
    _parent = os.getpid()


def _die_with(prctl: Callable[..., int]) -> None:
    """In a just-forked child: ask for SIGKILL when the parent dies; if it died before the request, die now."""
    prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != _parent:
        os._exit(1)


@functools.cache
def forked_children_die_with_this_process() -> bool:
    """From now on, every process forked (``os.fork``, multiprocessing's ``fork``) from this process or from a
    thread of it is killed when this process's forking thread ends. ``False`` where the kernel has no such request
    (not Linux). Once per process; children started by ``subprocess`` are not concerned (they close inherited
    descriptors)."""
    if not sys.platform.startswith("linux"):
        return False
    prctl = ctypes.CDLL(None, use_errno=True).prctl  # looked up once, not in every child (a loader per epoch)
    os.register_at_fork(before=_remember_parent, after_in_child=functools.partial(_die_with, prctl))
    return True
