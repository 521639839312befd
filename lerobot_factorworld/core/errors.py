"""Telling a refusal from a bug, so that the command line answers each as it should.

A refusal is an error the code raises on purpose (``raise ValueError("... valid choices: ...")``) or one the
machine gives (a missing file, a full disk): the user can act on its message, so it is one ``error:`` line. A bug
is any other exception, and ``ValueError``s that no ``raise`` of ours wrote (``too many values to unpack``, a
shape that numpy refuses): its message means nothing to the user, so the command line says it is an internal
error and keeps the traceback in a log file for the report.
"""

from __future__ import annotations

import linecache
import os
import tempfile
import time
import traceback
from pathlib import Path
from types import TracebackType

DELIBERATE = (ValueError, RuntimeError)  # what our code raises to refuse or to report a failed step
# packages whose own ``raise`` of a DELIBERATE error is a refusal of the user's settings (ours, and the LeRobot
# config stack that validates the settings we pass on)
REFUSING_PACKAGES = ("lerobot_factorworld", "lerobot_env_factorworld", "lerobot", "draccus")
ERROR_LOG_DIR_ENV = "FACTORWORLD_ERROR_DIR"  # where internal errors' tracebacks go (default: the temp folder)


def is_refusal(err: BaseException) -> bool:
    """Whether ``err`` is a refusal (one line for the user) rather than a bug: an ``OSError``, or a ``ValueError`` /
    ``RuntimeError`` raised by a ``raise`` statement in one of :data:`REFUSING_PACKAGES`."""
    if isinstance(err, OSError):
        return True
    if not isinstance(err, DELIBERATE):
        return False
    frame = _innermost(err.__traceback__)
    if frame is None:
        return False
    filename, line = frame.tb_frame.f_code.co_filename, frame.tb_lineno
    package = Path(filename).parts
    in_package = any(name in package or f"{name}.py" in package for name in REFUSING_PACKAGES)
    return in_package and linecache.getline(filename, line).lstrip().startswith("raise")


def _innermost(tb: TracebackType | None) -> TracebackType | None:
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return tb


def write_traceback(err: BaseException, command: str) -> Path:
    """Write ``err``'s traceback to a new log file (:data:`ERROR_LOG_DIR_ENV`, else the temp folder) and return
    its path; a log that cannot be written is replaced by the temp folder's."""
    text = f"factorworld {command}\n\n" + "".join(traceback.format_exception(err))
    name = f"factorworld-internal-error-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.log"
    for folder in (os.environ.get(ERROR_LOG_DIR_ENV), tempfile.gettempdir()):
        if not folder:
            continue
        try:
            path = Path(folder) / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
            return path
        except OSError:
            continue
    raise err
