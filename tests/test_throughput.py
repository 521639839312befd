"""Study throughput (issue 21): per-step timings, the profile, the cost model's fit, grouped execution, and
``scripts/bench_study.py`` end to end at its smallest scale (both executions give identical results)."""

from __future__ import annotations

import json
import logging
import os
import platform
import re
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from lerobot_factorworld.core.timing import Timings
from lerobot_factorworld.study.plan.config import StudyConfig
from lerobot_factorworld.study.plan.grid import make_plan
from lerobot_factorworld.study.run.executors import can_fork, lend_idle_workers, task_units
from lerobot_factorworld.study.run.lerobot_process import as_lerobot_process
from lerobot_factorworld.study.run.options import RunOptions
from lerobot_factorworld.study.run.train_step import loader_args, stores_video

ROOT = Path(__file__).resolve().parents[1]


def _cfg(tmp_path: Path, **overrides) -> StudyConfig:
    settings = {
        "out_dir": str(tmp_path / "study"),
        "tasks": ["door-open"],
        "n_train_envs": [1, 2],
        "train_factors": ["light", "table_texture"],
        "factors": ["light", "table_texture"],
        "methods": [{"name": "bc", "policy": {"type": "bc"}}],
    }
    settings.update(overrides)
    return StudyConfig(**settings)


def test_timed_parts_are_exclusive_and_wrapping_restores_the_attribute():
    timings = Timings()

    class Thing:
        def work(self):
            time.sleep(0.02)
            return 7

    thing = Thing()
    with timings.span("outer"), timings.wrap(Thing, "work", "inner"):
        time.sleep(0.02)
        assert thing.work() == 7
    assert Thing.work.__name__ == "work" and "work" not in vars(thing)
    assert 0.015 < timings.seconds["inner"] < 0.1 and 0.015 < timings.seconds["outer"] < 0.1
    assert timings.calls == {"inner": 1, "outer": 1}
    with timings.wrap(thing, "work", "own"):
        thing.work()
    assert "work" not in vars(thing) and timings.calls["own"] == 1


def test_grouped_tasks_hold_one_checkpoints_evaluations_and_split_for_idle_workers(tmp_path):
    plan = make_plan(_cfg(tmp_path))
    evals = plan.of_kind("eval")  # 2 checkpoints x 3 conditions
    assert [len(u) for u in task_units(evals, 2, grouped=False)] == [1] * 6
    units = task_units(evals, 2, grouped=True)
    assert [len(u) for u in units] == [3, 3] and all(len({s.deps[0] for s in u}) == 1 for u in units)
    assert sorted(len(u) for u in task_units(evals[:3], 2, grouped=True)) == [1, 2]
    mixed = task_units([*evals[:3], *plan.of_kind("train")], 1, grouped=True)
    assert [len(u) for u in mixed] == [3, 1, 1]


def test_idle_workers_are_lent_to_a_collection_or_a_lone_training_without_changing_its_key(tmp_path):
    plan = make_plan(_cfg(tmp_path))
    collects, trains = plan.of_kind("collect"), plan.of_kind("train")
    (alone,) = task_units(collects[:1], 3, grouped=True)  # two workers idle: the collection gets them
    assert alone[0].key == collects[0].key and alone[0].run["workers"] == 1 + 2
    assert collects[0].run.get("workers", 1) == 1  # the plan's step is left as it was
    both = task_units(collects, 3, grouped=True)  # one idle worker: to the first collection
    assert [u[0].run["workers"] for u in both] == [2, 1]
    mixed = task_units([*trains[:1], *collects[:1]], 2, grouped=True)  # every worker busy: nothing to lend
    assert [u[0].run.get("workers", 1) for u in mixed] == [1, 1]
    ((train,),) = lend_idle_workers([[trains[0]]], 2)  # a training alone: the idle worker loads its data
    assert train.key == trains[0].key and train.run["loader_workers"] == 1 and "loader_workers" not in trains[0].run
    lent = lend_idle_workers([[trains[0]], [collects[0]]], 3)  # a collection first takes what is idle
    assert lent[0][0].run.get("loader_workers", 0) == 0 and lent[1][0].run["workers"] == 2
    assert lend_idle_workers([[trains[0]], [trains[1]]], 2) == [[trains[0]], [trains[1]]]  # nothing idle
    evals = plan.of_kind("eval")
    beside = lend_idle_workers([evals[:3], [trains[0]]], 2)  # a training beside evaluations only: its loader too
    assert beside[0] == evals[:3] and beside[1][0].run["loader_workers"] == 1
    two = lend_idle_workers([[trains[0]], [trains[1]], evals[:3]], 3)  # two trainings: none lent beyond the idle
    assert all(u[0].run.get("loader_workers", 0) == 0 for u in two)
    assert task_units(collects[:1], 3, grouped=False)[0][0].run.get("workers", 1) == 1  # per_step: as planned


def test_a_lent_loader_forks_fresh_workers_each_epoch_and_only_for_png_frames(tmp_path):
    """The flags that keep a lent loader's checkpoint byte-identical (persistent workers would draw torch's RNG
    differently), and no loader at all for video datasets, whose decoders LeRobot calls unsafe to fork."""
    assert loader_args(0) == ["--num_workers=0"]
    assert loader_args(1) == [
        "--num_workers=1",
        "--persistent_workers=false",
        "--dataloader_multiprocessing_context=fork",
    ]
    for dtype, video in (("image", False), ("video", True)):
        root = tmp_path / dtype
        (root / "meta").mkdir(parents=True)
        features = {"observation.images.front": {"dtype": dtype}, "action": {"dtype": "float32"}}
        (root / "meta" / "info.json").write_text(json.dumps({"features": features}))
        assert stores_video(root) is video


LOADER_CHILD = """
import multiprocessing, sys, time
from lerobot_factorworld.core.children import forked_children_die_with_this_process
if sys.argv[1] == "die_with_parent":
    assert forked_children_die_with_this_process()
child = multiprocessing.get_context("fork").Process(target=time.sleep, args=(120,))
child.start()
print(child.pid, flush=True)
time.sleep(120)
"""


def _running(pid: int) -> bool:
    """Whether ``pid`` runs (a killed orphan may stay a zombie where nothing reaps it)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
@pytest.mark.parametrize("mode", ["die_with_parent", "default"])
def test_a_loader_forked_by_a_killed_worker_dies_with_it(mode):
    """A worker killed with kill -9 (a lost Ray worker) takes the loader it forked with it, so no child keeps its
    raylet connection open (``core/children.py``); without the request the orphan lives on (what it prevents)."""
    worker = subprocess.Popen([sys.executable, "-c", LOADER_CHILD, mode], stdout=subprocess.PIPE, text=True)
    child = int(worker.stdout.readline())
    assert _running(child)
    worker.kill()
    worker.wait()
    deadline = time.time() + (10 if mode == "die_with_parent" else 0.3)
    while _running(child) and time.time() < deadline:
        time.sleep(0.02)
    try:
        assert _running(child) is (mode == "default")
    finally:
        if _running(child):
            os.kill(child, 9)


def test_a_process_with_another_thread_is_not_forked():
    import threading

    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert not can_fork()
    finally:
        stop.set()
        thread.join()


def test_profile_and_cost_fit_read_the_steps_timings(tmp_path, monkeypatch):
    from lerobot_factorworld.study.plan import cost, profile
    from lerobot_factorworld.study.run.result import RESULT_FILE

    cfg = _cfg(tmp_path)
    plan = make_plan(cfg)
    fake = {
        "collect": {"frames": 100, "timings": {"imports": 4.0, "render": 2.0, "expert_physics": 3.0, "total": 10.0}},
        "train": {"steps": 10, "timings": {"startup_save": 5.0, "data": 1.0, "update": 2.2, "total": 8.2}},
        "eval": {"env_steps": 50, "timings": {"policy_load": 1.0, "env_step": 1.5, "render": 1.0, "total": 4.0}},
    }
    for step in plan.steps:
        step.folder(cfg.out_dir).mkdir(parents=True)
        (step.folder(cfg.out_dir) / RESULT_FILE).write_text(json.dumps(fake[step.kind]))
    profile.record_run(cfg.out_dir, 40.0, 2, "grouped", {"collect": 2, "train": 2, "eval": 6})
    rows = {(r.kind, r.component): r for r in profile.component_rows(plan, cfg.out_dir)}
    assert rows["eval", "total"].count == 6 and rows["eval", "total"].seconds == 24.0
    assert abs(rows["eval", "other"].seconds - 6 * 0.5) < 1e-9 and abs(rows["collect", "other"].mean - 1.0) < 1e-9
    text = profile.profile_text(plan, cfg.out_dir)
    assert "40.0 s wall with 2 worker(s)" in text and "policy_load" in text
    assert profile.profile_markdown(plan, cfg.out_dir)[0] == "## Where the time went"

    model = cost.fit_constants(plan, cfg.out_dir)
    assert model["collect"]["frame_s"] == 0.05 and model["collect"]["fixed_s"] == 5.0
    assert model["train"]["sample_s"]["bc"] == round(3.2 / (10 * cfg.train.batch_size), 6)
    assert model["train"]["fixed_s"] == 5.0 and model["eval"]["sim_step_s"] == 0.05 and model["eval"]["fixed_s"] == 1.5
    assert model["study_s"] >= 0
    out = tmp_path / "cost_model.json"
    monkeypatch.setattr(cost, "COST_MODEL_FILE", cost.COST_MODEL_FILE)  # the package's file stays untouched
    text = cost.fit_cost_model(cfg, plan, cfg.out_dir, RunOptions(workers=2), path=out)
    written = json.loads(out.read_text())
    assert written["fitted_on"]["wall_s"] == 40.0 and "estimated" in text
    # the fitted constants are what the estimate uses (the fake results' frames are not the plan's demos)
    whole = cost.estimate(plan, list(plan.steps), "grouped", written)
    assert whole["one CPU machine (2 cores)"] * 3600 > written["study_s"]


KEPT_MEMORY_CHECK = textwrap.dedent(
    """
    import ctypes, os
    from lerobot_factorworld.core import memory

    class MallInfo2(ctypes.Structure):  # glibc's struct mallinfo2: arena (bytes from sbrk) first
        _fields_ = [(name, ctypes.c_size_t) for name in "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]

    libc = ctypes.CDLL(None)
    libc.mallinfo2.restype = MallInfo2

    def freed_memory_kept():  # 8 MiB in 64 KiB blocks (below the mmap threshold), then freed: does the heap shrink?
        before = libc.mallinfo2().arena
        blocks = [ctypes.create_string_buffer(64 << 10) for _ in range(128)]
        del blocks
        return libc.mallinfo2().arena - before >= 7 << 20

    print("default", freed_memory_kept())
    print("set", memory.keep_freed_memory())
    print("again", memory.keep_freed_memory())
    if (pid := os.fork()) == 0:
        print("forked child", freed_memory_kept(), flush=True)
        os._exit(0)
    os.waitpid(pid, 0)
    """
)


def _glibc_version() -> tuple[int, ...]:
    name, version = platform.libc_ver()
    return tuple(int(part) for part in version.split(".")) if name == "glibc" and version else ()


@pytest.mark.skipif(_glibc_version() < (2, 33), reason="mallopt's settings are glibc's; mallinfo2 needs 2.33")
def test_keeping_freed_memory_is_set_once_and_inherited_by_forked_workers():
    """glibc's malloc is left alone until a ``grouped`` worker runs its steps: freed memory goes back to the
    kernel; then ``mallopt`` takes every setting (once: the second call is cached), and a process forked from
    it keeps freed memory too."""
    proc = subprocess.run([sys.executable, "-c", KEPT_MEMORY_CHECK], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.splitlines() == ["default False", "set True", "again True", "forked child True"], proc.stdout


def test_bench_study_quick_grid_is_the_default_grid_smaller():
    """``--quick`` (what the test below runs) shrinks demos, steps and episodes only: the same tasks, N, seeds,
    factors and methods, so every code path the default grid reaches (its report's sections) is run."""
    import importlib.util  # noqa: PLC0415 - the script is not a module of the package

    spec = importlib.util.spec_from_file_location("bench_study", ROOT / "scripts" / "bench_study.py")
    bench = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        spec.loader.exec_module(bench)
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    assert set(bench.QUICK) <= {"collect", "train", "eval"}, sorted(bench.QUICK)
    assert len(bench.GRID["factors"]) > 1


@pytest.mark.slow
def test_bench_study_quick_runs_both_executions_with_identical_results():
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "bench_study.py"), "--quick"],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
        cwd=ROOT,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-4000:]}"
    lines = proc.stdout.strip().splitlines()
    assert any(line.startswith("identical results") for line in lines), proc.stdout
    assert re.fullmatch(r"ratio: \d+\.\d+", lines[-1]), proc.stdout


def test_a_lerobot_command_run_in_process_leaves_the_process_as_it_found_it(tmp_path, run_main):
    """The grouped execution's in-process ``lerobot-train`` (and the suite's, conftest.py) restores what it set
    for the run (command line, working directory, torch's threads, ``TOKENIZERS_PARALLELISM``) and logging's
    handlers, and reports a bad flag as the console script would: a non-zero exit naming the flag."""
    import torch  # noqa: PLC0415 - LeRobot's training stack (seconds): this test only
    from lerobot.scripts import lerobot_train  # noqa: PLC0415

    def state():
        root = logging.getLogger()
        tokenizers = os.environ.get("TOKENIZERS_PARALLELISM")
        return list(sys.argv), os.getcwd(), torch.get_num_threads(), tokenizers, list(root.handlers), root.level

    before = state()
    flags = ["--policy.type=bc", "--no_such_flag=1"]
    proc = run_main(
        ["lerobot-train", *flags],
        lerobot_train.main,
        as_lerobot_process("lerobot-train", flags, tmp_path, torch.get_num_threads() + 1),
    )
    assert proc.returncode != 0 and "no_such_flag" in proc.stderr, proc.stderr[-2000:]
    assert state() == before


def _worker_state() -> tuple[bool, bool, bool]:
    """In a study worker: were LeRobot's training stack and the simulation imported, and the provenance read,
    before this task ran?"""
    from lerobot_factorworld.core import provenance

    return (
        "lerobot.scripts.lerobot_train" in sys.modules,
        "lerobot_factorworld.envs.factor_env" in sys.modules,
        provenance.current.cache_info().currsize == 1,
    )


@pytest.mark.slow
def test_a_grouped_study_in_a_process_with_threads_forks_preloaded_workers(tmp_path):
    """Where this process cannot be forked (another thread), a grouped study's workers come from the forkserver,
    which imported what steps import and read the provenance once: each worker starts with both (a spawned
    worker would import for 8-20 s). The per_step execution keeps fresh spawned workers."""
    import threading

    from lerobot_factorworld.study.run.executors import LocalExecutor

    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert not can_fork()
        executor = LocalExecutor(str(tmp_path), 2, "grouped")
        try:
            assert executor.pool._mp_context.get_start_method() == "forkserver"
            assert executor.pool.submit(_worker_state).result() == (True, True, True)
        finally:
            executor.shutdown()
        per_step = LocalExecutor(str(tmp_path), 1, "per_step")
        try:
            assert per_step.pool._mp_context.get_start_method() == "spawn"
            trained, _, read = per_step.pool.submit(_worker_state).result()  # (this module imports the simulation)
            assert not trained and read  # read by the initializer
        finally:
            per_step.shutdown()
    finally:
        stop.set()
        thread.join()
