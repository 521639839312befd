"""Executors run the steps they are handed and nothing else: a local process pool (default) or Ray.

A task is a list of steps run one after another in one worker (one step, or the evaluations of one
checkpoint): both executors call :func:`~lerobot_factorworld.study.run.worker.run_steps` with the same
arguments and the steps fix their own thread counts, so a plan gives the same results on either. With Ray across several
machines the study folder must be on a filesystem they share (steps read their inputs' outputs).
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import subprocess
import sys
import threading
from collections.abc import Sequence
from multiprocessing import get_context
from typing import Any, Protocol

from ...core import provenance
from ...envs import runtime
from .device import device_problem
from .step import RUN, Step, evaluated
from .worker import run_steps, warm_up

# The module the forkserver imports (by name: importing it here would import everything in this process).
FORKSERVER_PRELOAD = f"{__package__}.forkserver_preload"


class Executor(Protocol):
    def submit(self, steps: Sequence[Step]) -> Any: ...

    def wait_any(self, handles: list[Any]) -> list[Any]: ...

    def result(self, handle: Any) -> dict[str, str | None]: ...  # step key -> None (done) or its error

    def shutdown(self) -> None: ...


class InlineExecutor:
    """Runs each task in this process, at once, as it is submitted: what a test or a debugger wants (the
    runners the process has, patched or not, are the ones used). Not a study setting."""

    def __init__(self, study_dir: str, execution: str = "per_step") -> None:
        self.study_dir, self.execution, self.results = study_dir, execution, []

    def submit(self, steps: Sequence[Step]) -> int:
        self.results.append(run_steps([s.to_dict() for s in steps], self.study_dir, self.execution))
        return len(self.results) - 1

    def wait_any(self, handles: list[int]) -> list[int]:
        return handles[:1]

    def result(self, handle: int) -> dict[str, str | None]:
        return self.results[handle]

    def shutdown(self) -> None:
        pass


class LocalExecutor:
    """``workers`` processes on this machine, kept for the whole study; each task runs in one of them.

    ``per_step`` (the earlier path): fresh (spawned) processes, each paying its imports in its first step.
    ``grouped``: this process imports what steps import (:func:`warm_up`, about 2 s on top of what the command
    line already imported) and then forks the workers, which start with everything imported: each of them
    had paid 15-20 s for it, on the study's critical path, when they were spawned and warmed side by side
    on 2 cores. Forking needs a process that can be forked safely (:func:`can_fork`); otherwise (a process
    with threads: a notebook's kernel, pytest's workers) the workers are forked from multiprocessing's
    forkserver, a fresh single-threaded process that imports once (:mod:`.forkserver_preload`) and lives as
    long as this process, so later studies in it start their workers at once too."""

    def __init__(self, study_dir: str, workers: int, execution: str = "per_step", steps: Sequence[Step] = ()) -> None:
        check_local_devices(steps)  # before any worker starts or step runs
        self.study_dir = study_dir
        self.execution = execution
        fork = execution == "grouped" and can_fork()
        if fork:
            warm_up()
        # A spawned worker hashes the package source as it starts, when it imports it: an edit made during the
        # study is then told apart from the code the worker runs (provenance is read once per process). A
        # forked worker inherits the provenance of the process it is forked from, read when that process
        # imported the code: this process's, before the study started, or the forkserver's, at its start.
        context = get_context("fork" if fork else "forkserver" if execution == "grouped" else "spawn")
        if context.get_start_method() == "forkserver":  # before its server starts (it then ignores the list)
            context.set_forkserver_preload([FORKSERVER_PRELOAD])
        self.pool = cf.ProcessPoolExecutor(workers, mp_context=context, initializer=provenance.current)
        if fork:  # fork every worker now, before this process starts any thread (progress bars' monitor)
            self.pool.submit(os.getpid).result()
        elif execution == "grouped":  # every worker starts now, not in its first step
            for _ in range(workers):
                self.pool.submit(warm_up)

    def submit(self, steps: Sequence[Step]) -> cf.Future:
        return self.pool.submit(run_steps, [s.to_dict() for s in steps], self.study_dir, self.execution)

    def wait_any(self, handles: list[cf.Future]) -> list[cf.Future]:
        done, _ = cf.wait(handles, return_when=cf.FIRST_COMPLETED)
        return list(done)

    def result(self, handle: cf.Future) -> dict[str, str | None]:
        return handle.result()

    def shutdown(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


# Times Ray runs a task again whose worker died (a node lost, a native crash, kill -9); never for a step's own
# error, which run_steps returns. Safe: every step goes on from what its dead attempt left (a training from its
# newest save, a collection from its finished episodes).
RAY_TASK_RETRIES = 2


class RayExecutor:
    """Ray tasks on the cluster at ``address`` (or a local Ray instance when ``None``), each asking for the
    CPUs (threads, collection workers) and GPU its step uses. A request the cluster can never grant would
    leave its task pending forever, so the steps are checked against the cluster before any is submitted."""

    def __init__(
        self,
        study_dir: str,
        workers: int,
        address: str | None = None,
        steps: Sequence[Step] = (),
        execution: str = "per_step",
    ) -> None:
        try:  # deliberately here: ray is an optional dependency, needed only by this executor
            import ray  # noqa: PLC0415
        except ImportError:
            raise ValueError("executor=ray needs Ray: pip install 'lerobot_env_factorworld[ray]'") from None
        self.ray = ray
        self.study_dir = study_dir
        self.execution = execution
        self._started = not ray.is_initialized()
        requests = [step_resources(s) for s in steps]
        if self._started:
            local = {"num_cpus": local_cpus(workers, requests), "include_dashboard": False} if address is None else {}
            ray.init(address=address, log_to_driver=False, runtime_env={"env_vars": {"MUJOCO_GL": "egl"}}, **local)
        try:
            check_feasible(requests, ray.cluster_resources())
        except ValueError:
            self.shutdown()
            raise
        self._run = ray.remote(num_cpus=1, max_retries=RAY_TASK_RETRIES)(run_steps)

    def submit(self, steps: Sequence[Step]):
        resources = step_resources(steps[0])  # a task's steps are of one kind and ask for the same
        return self._run.options(**resources).remote([s.to_dict() for s in steps], self.study_dir, self.execution)

    def wait_any(self, handles: list) -> list:
        done, _ = self.ray.wait(handles, num_returns=1)
        return done

    def result(self, handle) -> dict[str, str | None]:
        return self.ray.get(handle)

    def shutdown(self) -> None:
        if self._started:
            self.ray.shutdown()
            self._started = False


def can_fork() -> bool:
    """Whether this process can be forked into study workers safely: on Linux, one Python thread (a fork copies
    only the calling thread, and a lock another thread holds stays locked in the child), no GL context (the
    rasteriser's threads would be missing in the child) and no CUDA (it cannot be used again after a fork).
    Native threads that libraries start at import are not counted (importing torch starts one, pyarrow's
    jemalloc another; every forked study so far ran past them), which is why Python 3.12's warning about
    forking a multi-threaded process can show, under pytest for example."""
    torch = sys.modules.get("torch")
    cuda = torch is not None and torch.cuda.is_initialized()
    return sys.platform == "linux" and threading.active_count() == 1 and not runtime.gl_context_created() and not cuda


DEVICE_SETTINGS = {"train": "train.device", "eval": "eval.device"}  # a step kind's device, as the config names it
# What this machine offers, asked of a child Python: a process that asks CUDA itself cannot fork workers using it.
DEVICE_PROBE = f"from {__package__}.device import machine_devices; cuda, mps = machine_devices(); print(cuda, int(mps))"


def check_local_devices(steps: Sequence[Step]) -> None:
    """Refuse, in one line and before any step runs, a ``train.device`` or ``eval.device`` this machine lacks
    (each step checks again where it runs: :func:`.device.require_device`)."""
    wanted = {
        (DEVICE_SETTINGS[s.kind], str(s.inputs["device"]))
        for s in steps
        if s.kind in DEVICE_SETTINGS and s.inputs.get("device", "cpu") != "cpu"
    }
    if not wanted:
        return
    probe = subprocess.run([sys.executable, "-c", DEVICE_PROBE], capture_output=True, text=True, check=True)
    cuda_count, mps = (int(v) for v in probe.stdout.split())
    problems = [
        p for setting, device in sorted(wanted) if (p := device_problem(setting, device, cuda_count, bool(mps)))
    ]
    if problems:
        raise ValueError("; ".join(problems))


def step_resources(step: Step) -> dict[str, float]:
    """Ray resources of a step: its threads (training, evaluation) or collection workers as CPUs, and a GPU
    when it runs on CUDA (training with ``train.device``, evaluation with ``eval.device``)."""
    cpus = step.inputs.get("threads") or step.run.get("threads") or step.run.get("workers") or 1
    gpus = 1 if str(step.inputs.get("device", "")).startswith("cuda") else 0
    return {"num_cpus": cpus, "num_gpus": gpus}


def local_cpus(workers: int, requests: Sequence[dict[str, float]]) -> int:
    """CPUs of a local Ray instance: ``workers`` steps at a time, and at least the largest request."""
    return int(max([workers, *(r["num_cpus"] for r in requests)]))


def check_feasible(requests: Sequence[dict[str, float]], cluster: dict[str, float]) -> None:
    """Refuse requests beyond the whole cluster (Ray would keep such a task pending forever).

    ``cluster`` is ``ray.cluster_resources()`` (totals: a multi-machine cluster may still not fit a large
    request on one machine, which Ray then reports in its own log).
    """
    if not requests:
        return
    cpus, gpus = max(r["num_cpus"] for r in requests), max(r["num_gpus"] for r in requests)
    have_cpus, have_gpus = cluster.get("CPU", 0), cluster.get("GPU", 0)
    if cpus > have_cpus:
        raise ValueError(
            f"a step asks Ray for {cpus:g} CPUs (train.threads, eval.threads or collect.workers) but the cluster has "
            f"{have_cpus:g}; lower those settings or give the cluster more CPUs"
        )
    if gpus > have_gpus:
        raise ValueError(
            f"a step asks Ray for a GPU (train.device or eval.device is cuda) but the cluster has {have_gpus:g}; "
            "use --train.device=cpu --eval.device=cpu or a cluster with GPUs"
        )


def task_units(ready: list[Step], free: int, grouped: bool) -> list[list[Step]]:
    """The worker tasks for the ``ready`` steps, in their order: one step each, or (``grouped``) the ready
    evaluations of one checkpoint together (its policy loaded once), a checkpoint's group split in halves
    while fewer tasks than ``free`` workers would leave one idle."""
    if not grouped:
        return [[step] for step in ready]
    units: list[list[Step]] = []
    by_checkpoint: dict[str, list[Step]] = {}
    for step in ready:
        if step.kind != "eval":
            units.append([step])
        elif evaluated(step) in by_checkpoint:
            by_checkpoint[evaluated(step)].append(step)
        else:
            by_checkpoint[evaluated(step)] = [step]
            units.append(by_checkpoint[evaluated(step)])
    while len(units) < free:
        largest = max(range(len(units)), key=lambda i: len(units[i]), default=None)
        if largest is None or len(units[largest]) < 2:
            break
        unit = units[largest]
        half = (len(unit) + 1) // 2
        units[largest : largest + 1] = [unit[:half], unit[half:]]
    return lend_idle_workers(units, free)


def lend_idle_workers(units: list[list[Step]], free: int) -> list[list[Step]]:
    """``units`` with the workers they leave idle lent to their collections: a collection's jobs then run in
    that many more processes (``collect.workers`` never changes what is collected, so it is not in the key).
    The first collections get them first, one each in turn. With no collection to lend to, a training alone
    gets one as its data loader (``train_step.loader_args``: the same checkpoint, byte for byte), and so does the one
    training dispatched beside evaluations only: they end within minutes, the training keeps its loader for
    hours (a chain's next link starts beside the evaluation of the point before it)."""
    spare = free - len(units)
    collects = [i for i, unit in enumerate(units[:free]) if unit[0].kind == "collect"]
    trains = [i for i, unit in enumerate(units[:free]) if unit[0].kind == "train"]
    extra = dict.fromkeys(collects, 0)
    for n in range(max(0, spare) if collects else 0):
        extra[collects[n % len(collects)]] += 1
    out = list(units)
    for i, more in extra.items():
        if more:
            out[i] = [_with_run(units[i][0], workers=units[i][0].run.get("workers", 1) + more)]
    if not collects:
        kinds = [unit[0].kind for unit in units[:free]]
        beside_evaluations = kinds.count("train") == 1 and set(kinds) <= {"train", "eval"}
        for i in trains[: max(1 if beside_evaluations else 0, spare)]:
            out[i] = [_with_run(units[i][0], loader_workers=1)]
    return out


def _with_run(step: Step, **settings: Any) -> Step:
    """``step`` with run settings changed (how it runs, never its key or results)."""
    return Step(step.kind, step.inputs, step.deps, {**step.meta, RUN: {**step.run, **settings}})


def make_executor(
    kind: str,
    study_dir: str,
    workers: int,
    ray_address: str | None = None,
    steps: Sequence[Step] = (),
    execution: str = "per_step",
) -> Executor:
    """The executor for ``steps`` (Ray checks them against its cluster before any runs)."""
    if kind == "ray":
        return RayExecutor(study_dir, workers, ray_address, steps, execution)
    return LocalExecutor(study_dir, workers, execution, steps)
