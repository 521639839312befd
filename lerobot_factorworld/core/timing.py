"""Where a piece of work spends its time: named wall-clock totals (seconds), for the study's per-step
``timings`` (``study/plan/profile.py`` summarises them). Measuring never changes what is computed: a timed
call returns what the untimed one returns.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Iterator, Mapping
from typing import Any


class Timings:
    """Named totals of wall-clock seconds, with call counts; ``as_dict()`` gives ``{name: seconds}``.

    Timed parts are exclusive: time spent in a timed part nested inside another (rendering inside an
    environment step inside a rollout) counts for the inner one only, so the totals of one piece of work
    add up to at most its wall time and never overlap."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._nested: list[float] = []  # per open timed part: the time of the parts timed inside it

    @contextlib.contextmanager
    def _timed(self, name: str) -> Iterator[None]:
        start = time.perf_counter()
        self._nested.append(0.0)
        try:
            yield
        finally:
            elapsed = time.perf_counter() - start
            inner = self._nested.pop()
            self.add(name, elapsed - inner)
            if self._nested:
                self._nested[-1] += elapsed

    def add(self, name: str, seconds: float, calls: int = 1) -> None:
        self.seconds[name] = self.seconds.get(name, 0.0) + float(seconds)
        self.calls[name] = self.calls.get(name, 0) + calls

    def update(self, other: Mapping[str, float]) -> None:
        """Add every total of ``other`` (e.g. a worker's timings, read back from its result)."""
        for name, seconds in other.items():
            self.add(name, seconds)

    def span(self, name: str) -> contextlib.AbstractContextManager[None]:
        """Time the block under ``name`` (less the parts timed inside it)."""
        return self._timed(name)

    @contextlib.contextmanager
    def wrap(self, owner: Any, attribute: str, name: str) -> Iterator[None]:
        """Time every call of ``owner.attribute`` (a class's method or an object's) under ``name`` while
        inside the block; the attribute is restored afterwards."""
        original = getattr(owner, attribute)
        had_own = attribute in vars(owner) if hasattr(owner, "__dict__") else False

        @functools.wraps(original)
        def timed(*args, **kwargs):
            with self._timed(name):
                return original(*args, **kwargs)

        setattr(owner, attribute, timed)
        try:
            yield
        finally:
            if had_own:
                setattr(owner, attribute, original)
            else:
                delattr(owner, attribute)

    def as_dict(self, digits: int = 3) -> dict[str, float]:
        return {name: round(seconds, digits) for name, seconds in self.seconds.items()}
