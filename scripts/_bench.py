"""What the benchmark scripts share: headless GL set-up, measurement processes, round order, the last line.

Two ways to run a measurement outside the reporting process:

* :class:`PipeWorker` + :func:`serve`: a persistent ``multiprocessing`` process that builds its state once,
  then answers timed requests over a pipe (``bench_env.py``: each env mode keeps its own GL context);
* :func:`run_child` + :func:`write_result`: a fresh interpreter per measurement that writes its result as
  JSON, its stdout routed to our stderr so that the report stays clean (``bench_collect.py``); plain
  commands (``bench_bc.py`` collecting its datasets) go through :func:`run_command` the same way.

The policy benchmarks (``bench_policy.py``, ``bench_bc.py``) time torch policies with :class:`Clock`,
:func:`optimizer_step` and :func:`select_action_latencies`. Reports print markdown tables with
:func:`print_table`; every script ends its report with :func:`ratio_line` (``ratio: <float>``, parsed by the
tests).
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

REPO_ROOT = Path(__file__).resolve().parents[1]


def setup_headless_gl() -> None:
    """EGL rendering unless the caller chose otherwise; call before anything imports MuJoCo (inherited by children)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    if os.environ["MUJOCO_GL"] == "egl":
        os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # as lerobot_factorworld does


def add_repo_to_path() -> None:
    """Make ``lerobot_factorworld`` importable from a checkout that is not installed."""
    if str(REPO_ROOT) not in sys.path:
        sys.path.insert(0, str(REPO_ROOT))


def round_order[T](items: Sequence[T], round_index: int) -> list[T]:
    """Alternate the order between rounds (A B, B A, A B, ...), so that drift on a noisy machine evens out."""
    return list(items) if round_index % 2 == 0 else list(items)[::-1]


def ratio_line(ratio: float) -> str:
    return f"ratio: {ratio:.4f}"


def target_verdict(ratio: float, target: float) -> str:
    """``meets the >= 5x target`` or ``BELOW the >= 5x target``."""
    return f"{'meets' if ratio >= target else 'BELOW'} the >= {target:g}x target"


def parse_names(parser: argparse.ArgumentParser, text: str, valid: Sequence[str], what: str) -> list[str]:
    """The comma-separated names in ``text``, in order and without repeats; ``parser.error`` lists unknown ones."""
    names = list(dict.fromkeys(name.strip() for name in text.split(",") if name.strip()))
    unknown = [name for name in names if name not in valid]
    if unknown:
        parser.error(f"unknown {what} {', '.join(unknown)}; valid: {', '.join(valid)}")
    return names


def check_tasks(parser: argparse.ArgumentParser, tasks: str | Sequence[str]) -> None:
    """``parser.error`` naming the valid tasks when any of ``tasks`` is not a Factor World task."""
    from lerobot_factorworld.tasks import TASKS  # after add_repo_to_path(): the package may not be importable before

    names = [tasks] if isinstance(tasks, str) else list(tasks)
    unknown = [task for task in names if task not in TASKS]
    if unknown:
        parser.error(f"unknown task(s) {', '.join(unknown)}; valid: {', '.join(TASKS)}")


def print_table(header: str, rows: Iterable[str]) -> None:
    """A markdown table: ``header`` (``| a | b |``), a rule as wide as each of its cells, then ``rows``."""
    print(header)
    print("|" + "|".join("-" * len(cell) for cell in header.split("|")[1:-1]) + "|")
    for row in rows:
        print(row)


def load_average_line(start: tuple[float, float, float], end: tuple[float, float, float]) -> str:
    fmt = lambda load: "/".join(f"{x:.2f}" for x in load)  # noqa: E731
    return (
        f"load average (1/5/15 min) at start {fmt(start)}, at end {fmt(end)} on {os.cpu_count()} CPUs "
        "(other work skews the numbers)"
    )


# --- a fresh interpreter per measurement ---------------------------------------------------------


def run_command(command: list[str], label: str) -> None:
    """Run ``command`` from the repository root, its stdout on our stderr; raise if it fails."""
    proc = subprocess.run(command, stdout=sys.stderr, cwd=REPO_ROOT, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{label} failed (exit code {proc.returncode}); see its output above")


def run_logged(command: list[str], log: Path, env: dict[str, str] | None = None, append: bool = True) -> None:
    """Run ``command`` from the repository root, its output appended to ``log`` (or replacing it); a failure
    stops the script with the log's tail (the long-run scripts: learning curves, the round trip)."""
    with open(log, "a" if append else "w") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        proc = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, cwd=REPO_ROOT, env=env)
    if proc.returncode != 0:
        raise SystemExit(
            f"failed (exit {proc.returncode}): {' '.join(command[:2])}; see {log}:\n" + log.read_text()[-2000:]
        )


def run_child(command: list[str], result_path: Path, label: str) -> dict:
    """Run ``command`` (which must call :func:`write_result`) and return its JSON result."""
    run_command(command, label)
    if not result_path.is_file():
        raise RuntimeError(f"{label} wrote no result to {result_path}")
    return json.loads(result_path.read_text())


def write_result(path: str | Path, result: dict) -> None:
    Path(path).write_text(json.dumps(result))


# --- a persistent worker process answering requests over a pipe ----------------------------------


def serve(
    conn,
    start: Callable[[], tuple[Any, Any]],
    handle: Callable[[Any, tuple, Callable[[int], None]], Any],
    stop: Callable[[Any], None],
) -> None:
    """Worker side of :class:`PipeWorker`.

    Protocol (worker -> parent): ``("ready", info)`` once ``start()`` returned ``(state, info)``; per request
    any number of ``("progress", n)`` and one ``("done", handle(state, request, progress))``; ``("closed",)``
    after ``("close",)``; ``("error", traceback)`` on any failure.
    """
    try:
        state, info = start()
        conn.send(("ready", info))
        while True:
            msg = conn.recv()
            if msg[0] == "close":
                stop(state)
                conn.send(("closed",))
                return
            conn.send(("done", handle(state, msg, lambda n: conn.send(("progress", n)))))
    except BaseException:
        conn.send(("error", traceback.format_exc()))


class PipeWorker:
    """Parent-side handle on a process running ``target(conn, *args)``, which calls :func:`serve`."""

    def __init__(self, ctx, label: str, target: Callable[..., None], args: tuple) -> None:
        self.label = label
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=target, args=(child, *args), daemon=True)
        self.process.start()
        child.close()

    def recv(self) -> tuple:
        msg = self.conn.recv()
        if msg[0] == "error":
            raise RuntimeError(f"{self.label} worker failed:\n{msg[1]}")
        return msg

    def ready(self) -> Any:
        """Wait for the worker's start-up; returns its ``info``."""
        return self.recv()[1]

    def request(self, msg: tuple, on_progress: Callable[[int], None] | None = None) -> Any:
        self.conn.send(msg)
        while True:
            reply = self.recv()
            if reply[0] == "progress":
                if on_progress is not None:
                    on_progress(reply[1])
            elif reply[0] == "done":
                return reply[1]

    def close(self) -> None:
        try:
            if self.process.is_alive():
                self.conn.send(("close",))
                self.conn.recv()
        except (EOFError, OSError):
            pass  # the worker already failed or exited; its error (if any) was raised by recv()
        finally:
            self.process.join(timeout=30)
            if self.process.is_alive():
                self.process.terminate()
                self.process.join(timeout=5)
            self.conn.close()


# --- torch policies (bench_policy.py, bench_bc.py) ---------------------------------------------------
# torch is imported inside these functions: bench_env.py's spawned workers and bench_collect.py's children
# import this module too, and never need torch.


def device_kind(device: str) -> str:
    """``cuda`` for any CUDA device (``cuda``, ``cuda:1``), else ``cpu``: the key of per-device workloads."""
    return "cuda" if device.startswith("cuda") else "cpu"


class Clock:
    """``time.perf_counter()`` read after the device's queued work is done (CUDA kernels run asynchronously)."""

    def __init__(self, device: str) -> None:
        self.device = device
        self._sync: Callable[[], None] = lambda: None
        if device_kind(device) == "cuda":
            import torch  # noqa: PLC0415  (see the section comment)

            self._sync = functools.partial(torch.cuda.synchronize, device)

    def __call__(self) -> float:
        self._sync()
        return time.perf_counter()


def release_device_memory(device: str) -> None:
    """Hand cached CUDA memory back once a policy is gone, so the next one starts from the same state."""
    if device_kind(device) == "cuda":
        import torch  # noqa: PLC0415  (see the section comment)

        torch.cuda.empty_cache()


def optimizer_step(policy, optimizer, batch: Mapping[str, Any], grad_clip_norm: float | None = None) -> None:
    """One update as lerobot-train makes it: forward, backward, gradient clipping (if a norm is given), step,
    ``zero_grad``. The policy's mode (``train()``) is the caller's to set."""
    import torch  # noqa: PLC0415  (see the section comment)

    loss, _ = policy.forward(batch)
    loss.backward()
    if grad_clip_norm is not None:
        torch.nn.utils.clip_grad_norm_(policy.parameters(), grad_clip_norm)
    optimizer.step()
    optimizer.zero_grad(set_to_none=True)


def select_action_latencies(
    policy,
    frames: Sequence[Mapping[str, Any]],
    warmup: int,
    calls: int,
    clock: Clock,
    on_call: Callable[[], None] = lambda: None,
) -> list[float]:
    """Milliseconds per ``policy.select_action`` call, one frame at a time (batch of 1), in eval mode.

    After ``policy.reset()``, ``warmup`` untimed calls then ``calls`` timed ones; call ``i`` gets a copy of
    ``frames[i % len(frames)]``, so consecutive calls see different frames. ``on_call`` runs after every call.
    """
    policy.eval()
    policy.reset()
    latencies = []
    for i in range(warmup + calls):
        batch = dict(frames[i % len(frames)])
        start = clock()
        action = policy.select_action(batch)
        elapsed_ms = (clock() - start) * 1000.0
        if i >= warmup:
            assert action.shape[0] == 1, action.shape
            latencies.append(elapsed_ms)
        on_call()
    return latencies
