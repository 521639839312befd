"""Shared fixtures and the suite's scheduling. Rendering is headless (the package defaults MUJOCO_GL to egl
before MuJoCo loads).

Under ``pytest -n auto`` (``make test``; pyproject.toml adds ``--dist loadgroup --no-loadscope-reorder``):

* the expensive inputs (collected datasets, weight files) are built once per run by whichever worker asks first
  and reused by every worker (:func:`shared`);
* tests that change one shared folder in turn (the toy study) carry ``pytest.mark.xdist_group`` and run on
  one worker;
* the longest tests are started first (:data:`EXPECTED_SECONDS`), so the workers finish together;
* ``-n auto`` starts one worker more than there are CPUs (:func:`pytest_xdist_auto_num_workers`).
"""

import contextlib
import functools
import io
import logging
import os
import pickle
import shutil
import subprocess
import sys
import traceback
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest  # noqa: E402
from filelock import FileLock  # noqa: E402

from lerobot_factorworld.core.memory import keep_freed_memory  # noqa: E402
from lerobot_factorworld.envs.factor_env import FactorWorldEnv  # noqa: E402
from lerobot_factorworld.study.run.lerobot_process import as_lerobot_process  # noqa: E402

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "LP_NUM_THREADS")  # torch/oneDNN, MKL, Mesa's llvmpipe


def pytest_configure(config):
    """Under ``pytest -n N`` give each worker, and every process it starts (``lerobot-train``, ``lerobot-eval``,
    the scripts: they inherit the environment), its share of the CPUs for torch's and llvmpipe's thread pools.

    Left at their default (one thread per CPU), 2 workers on 2 cores run 4 or more busy threads: an OpenMP
    region then waits, spinning, for a thread the other worker has descheduled, and a 40-step RT-1
    ``lerobot-train`` took 100 s and 240 CPU-s instead of 21 s. xdist tells a worker its count only here
    (``workerinput``), after this file is imported and before the test modules import torch. A value already in
    the environment is kept."""
    workerinput = getattr(config, "workerinput", None)
    if workerinput is None:
        return
    threads = str(max(1, (os.cpu_count() or 1) // max(1, int(workerinput["workercount"]))))
    for variable in THREAD_VARIABLES:
        os.environ.setdefault(variable, threads)
    if "torch" in sys.modules:  # imported already (by a plugin): its pool is sized at first use, so resize it
        sys.modules["torch"].set_num_threads(int(os.environ["OMP_NUM_THREADS"]))
    keep_freed_memory()  # as a study's grouped workers: faster in-process trainings, the same results


def pytest_xdist_auto_num_workers(config) -> int:
    """``-n auto`` starts one worker more than there are CPUs: with one per CPU about an eighth of the CPUs' time
    in this suite went unused (processes starting, Ray, a killed study restarting), which a third worker on 2
    cores partly fills (each worker capped at one thread, above). A fresh clone's suite on 2 idle cores of an AMD
    EPYC: 594 s with 3 workers (2026-12-07), 609 s with 2 the day before (not side by side)."""
    return len(os.sched_getaffinity(0)) + 1


@pytest.fixture
def make_env():
    """Build FactorWorldEnvs that are closed after the test."""
    envs = []

    def _make(*args, **kwargs):
        env = FactorWorldEnv(*args, **kwargs)
        envs.append(env)
        return env

    yield _make
    for env in envs:
        env.close()


def _run_main(argv: list[str], main: Callable[[], object], *contexts) -> subprocess.CompletedProcess:
    """``main()`` of a command line program run in this process with ``sys.argv = argv`` (inside ``contexts``),
    reported as a process would be: the exit status (``SystemExit``'s code; 1 and the traceback on stderr for
    an exception), stdout and stderr; logging's root handlers are restored afterwards (LeRobot's
    ``init_logging`` replaces them)."""
    root = logging.getLogger()
    saved = list(sys.argv), list(root.handlers), root.level
    stdout, stderr, code = io.StringIO(), io.StringIO(), 0
    sys.argv = list(argv)
    try:
        with contextlib.ExitStack() as stack:
            stack.enter_context(contextlib.redirect_stdout(stdout))
            stack.enter_context(contextlib.redirect_stderr(stderr))
            for context in contexts:
                stack.enter_context(context)
            main()
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 1
    except Exception:  # noqa: BLE001 - reported as a failed process would report it
        code = 1
        stderr.write(traceback.format_exc())
    finally:
        sys.argv, root.handlers[:] = saved[0], saved[1]
        root.setLevel(saved[2])
    return subprocess.CompletedProcess(argv, code, stdout.getvalue(), stderr.getvalue())


@pytest.fixture
def run_main():
    """Run a command line program's ``main()`` in this process (:func:`_run_main`)."""
    return _run_main


def _run_lerobot(command: str, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    """``lerobot-train`` or ``lerobot-eval`` with ``args``: their console script's ``main()`` run in this worker
    process as a study's grouped execution trains (``study/run/lerobot_process.py: as_lerobot_process``); with ``check``,
    asserts it succeeded. The same code as the console script without the ~7 s of imports a new process pays;
    the console scripts themselves, found on the PATH with the ``factorworld`` env discovered as a plugin by a
    fresh process, run as processes in the LeRobot round trip (tests/test_lerobot_metaworld_obs.py: both)."""
    # LeRobot's training and evaluation stacks (seconds): imported by the slow tests only.
    import torch  # noqa: PLC0415
    from lerobot.scripts import lerobot_eval, lerobot_train  # noqa: PLC0415

    main = {"lerobot-train": lerobot_train.main, "lerobot-eval": lerobot_eval.main}[command]
    process = as_lerobot_process(command, list(args), Path.cwd(), torch.get_num_threads())
    proc = _run_main([command, *args], main, process)
    assert proc.returncode == 0 or not check, proc.stderr[-3000:]
    return proc


def _eval_one_light_episode(checkpoint: Path, out: Path) -> None:
    """``lerobot-eval`` of ``checkpoint`` (made for the ``factorworld`` env's default observation) for one short
    episode in one training environment under the light factor, writing ``out/eval_info.json``."""
    _run_lerobot(
        "lerobot-eval",
        f"--policy.path={checkpoint}",
        "--env.type=factorworld",
        "--env.n_train_envs=1",
        "--env.train_factors=[light]",
        "--env.episode_length=10",
        "--eval.n_episodes=1",
        "--eval.batch_size=1",
        f"--output_dir={out}",
    )
    assert (out / "eval_info.json").is_file()


@pytest.fixture
def eval_one_light_episode():
    """Evaluate a checkpoint for one short episode in process (:func:`_eval_one_light_episode`)."""
    return _eval_one_light_episode


@pytest.fixture
def run_lerobot():
    """Run ``lerobot-train`` or ``lerobot-eval`` in this process (:func:`_run_lerobot`)."""
    return _run_lerobot


# --- expensive inputs, built once per run and shared by every xdist worker ---------------------------


def shared(tmp_path_factory: pytest.TempPathFactory, name: str, build: Callable[[Path], object]):
    """``build(folder)`` once per test run, by whichever (xdist) worker asks first; the others wait and reuse it.

    ``folder`` is an empty folder that lives until the run ends; returns ``build``'s return value (pickled, so
    every worker gets an equal copy). Use it only for inputs that the tests read and never change.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's folder, above every worker's own
    folder = base / "shared" / name
    folder.parent.mkdir(parents=True, exist_ok=True)
    result = folder.parent / f"{name}.pickle"
    with FileLock(f"{folder}.lock"):
        if not result.exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            value = build(folder)
            partial = result.with_suffix(".partial")
            partial.write_bytes(pickle.dumps(value))
            partial.replace(result)
        return pickle.loads(result.read_bytes())


def _collect_pick_place_light(folder: Path) -> Path:
    from lerobot_factorworld.datasets.collect import CollectConfig, collect  # LeRobot's dataset stack: slow tests only

    root = folder / "pp"
    collect(
        CollectConfig(
            task="pick-place",
            n_envs=1,
            demos_per_env=3,
            factors=["light"],
            root=str(root),
            repo_id="local/pp",
            workers=1,
            use_videos=False,
        )
    )
    return root


@pytest.fixture(scope="session")
def build_once(tmp_path_factory) -> Callable[[str, Callable[[Path], object]], object]:
    """``build_once(name, build)``: :func:`shared` for this run."""
    return functools.partial(shared, tmp_path_factory)


@pytest.fixture(scope="session")
def tiny_dataset(build_once) -> Path:
    """3 pick-place demos in one environment under the light factor, image storage (repo id ``local/pp``):
    what the policies' ``lerobot-train`` runs train on (bc, RT-1)."""
    return build_once("pick_place_light", _collect_pick_place_light)


def _train_bc(dataset: Path, folder: Path) -> Path:
    """``lerobot-train`` of bc for 2 steps on ``dataset`` (``tiny_dataset``): its ``pretrained_model`` folder."""
    out = folder / "train"
    _run_lerobot(
        "lerobot-train",
        "--policy.type=bc",
        "--policy.device=cpu",
        "--policy.push_to_hub=false",
        "--dataset.repo_id=local/pp",
        f"--dataset.root={dataset}",
        "--steps=2",
        "--batch_size=4",
        "--num_workers=0",
        "--save_freq=2",
        "--seed=0",
        "--wandb.enable=false",
        f"--output_dir={out}",
    )
    return out / "checkpoints" / "last" / "pretrained_model"


@pytest.fixture(scope="session")
def bc_checkpoint(build_once, tiny_dataset) -> Path:
    """A real LeRobot ``pretrained_model``: bc trained 2 steps on ``tiny_dataset`` (pick-place, the front camera at
    84 px, 8-number state), for the tests that evaluate a given checkpoint. Read it, never change it."""
    return build_once("bc_checkpoint", functools.partial(_train_bc, tiny_dataset))


def _untrained_checkpoint(config, env_cfg, folder: Path) -> Path:
    """A LeRobot ``pretrained_model`` folder (config, weights, processors) of an untrained policy made for
    ``env_cfg``'s features, as ``lerobot-train`` would save one trained there."""
    from lerobot.policies.factory import make_policy, make_pre_post_processors  # LeRobot's policy stack (seconds)

    policy = make_policy(config, env_cfg=env_cfg)
    for part in (policy, *make_pre_post_processors(config)):
        part.save_pretrained(folder)
    return folder


def _lerobot_metaworld_act(folder: Path) -> Path:
    # LeRobot's policy and env configs (seconds to import): only the tests that use this checkpoint pay for them
    from lerobot.envs.configs import MetaworldEnv as LeRobotMetaworldConfig
    from lerobot.policies.act.configuration_act import ACTConfig

    config = ACTConfig(
        pretrained_backbone_weights=None,
        device="cpu",
        dim_model=32,
        dim_feedforward=64,
        n_encoder_layers=1,
        n_decoder_layers=1,
        chunk_size=4,
        n_action_steps=4,
    )
    # the features of LeRobot's metaworld env are the same for every task
    return _untrained_checkpoint(config, LeRobotMetaworldConfig(task="button-press-v3"), folder / "checkpoint")


@pytest.fixture(scope="session")
def lerobot_metaworld_checkpoint(build_once) -> Path:
    """A (tiny, untrained) ACT ``pretrained_model`` built against LeRobot's own ``metaworld`` env config
    (``observation.image`` 480 x 480, 4-number ``observation.state``), as a checkpoint trained there would be."""
    return build_once("lerobot_metaworld_act", _lerobot_metaworld_act)


def _factorworld_bc(folder: Path) -> Path:
    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig  # LeRobot's env config (seconds)
    from lerobot_factorworld.policies.bc.configuration_bc import BCConfig

    return _untrained_checkpoint(BCConfig(device="cpu"), FactorWorldEnvConfig(), folder / "checkpoint")


@pytest.fixture(scope="session")
def factorworld_checkpoint(build_once) -> Path:
    """An untrained bc ``pretrained_model`` made for the ``factorworld`` env's default observation (the front
    camera at 84 px, 8-number state): what the checks of a given checkpoint read, without a training run."""
    return build_once("factorworld_bc", _factorworld_bc)


# --- scheduling --------------------------------------------------------------------------------------

# Seconds a test (or an xdist group, summed) took in a full run (`pytest -n 2 --durations=100`, 2026-12-07, on the
# idle 2 cores of an AMD EPYC; each worker and its processes capped to one thread by pytest_configure; the first
# in-process `lerobot-train` / `lerobot-eval` of a worker pays its imports, the others about none); a test not listed
# counts as SLOW_DEFAULT when marked slow, else 0 (kept in file order after the listed ones). Only the order depends
# on these numbers: update them when a test becomes one of the longest.
EXPECTED_SECONDS = {
    "train_resume": 145.0,  # tests/test_train_resume.py: a killed study, a lost Ray worker (one Ray start), a pack
    "toy_study": 90.0,  # the xdist group of tests/test_study.py's toy study (local, rerun, reuse, a part on Ray)
    "tests/test_lerobot_metaworld_obs.py::test_round_trip_from_lerobots_own_metaworld_data": 85.0,
    "tests/test_throughput.py::test_bench_study_quick_runs_both_executions_with_identical_results": 60.0,
    "tests/test_bench_scripts.py::test_bench_script_prints_consistent_rows_and_the_ratio_last[collect]": 51.0,
    "tests/test_docs_results.py::test_every_committed_report_and_fenced_docs_table_is_what_its_results_csv_regenerates": 37.0,
    "tests/test_named_studies.py::test_a_wheel_in_a_fresh_environment_runs_a_study_by_name_and_lerobot_finds_the_env": 32.0,
    "tests/test_bench_scripts.py::test_bench_script_prints_consistent_rows_and_the_ratio_last[bc]": 26.0,
    "tests/test_datasets.py::test_killed_collection_resumes_without_duplicates": 25.0,
    "tests/test_learning_curve.py::test_a_study_with_a_curve_evaluates_each_checkpoint_and_reports_it": 24.0,
    "tests/test_train_extend.py::test_ten_epochs_continued_to_twenty_give_the_checkpoint_files_of_twenty_from_scratch": 22.0,
    "tests/test_bench_scripts.py::test_bench_script_prints_consistent_rows_and_the_ratio_last[malloc]": 21.0,
    "tests/test_rerun.py::test_the_cpu_fingerprint_hashes_each_layer_and_a_oneDNN_cap_leaves_pixels_and_physics_alone": 21.0,
    "tests/test_pick.py::test_expert_succeeds_in_default_scenes_and_under_physical_shifts": 21.0,
    "tests/test_profile.py::test_profile_writes_a_studys_outputs_without_collecting_or_training": 20.0,
    "tests/test_stopping_benchmarks.py::test_a_committed_output_is_what_its_commands_print[stopping_power.txt]": 18.0,
    "tests/test_pick.py::test_held_out_objects_and_phrasings_never_appear_in_training_environments": 16.0,
    "tests/test_profile.py::test_profile_of_a_lerobot_metaworld_checkpoint": 15.0,
    "tests/test_pick.py::test_rt1_trains_across_instructions_and_lerobot_eval_reports_every_condition": 15.0,
    "tests/test_experts.py::test_expert_solves_default_and_each_physical_shift[pick-place]": 13.0,
    "tests/test_bench_scripts.py::test_bench_frame_cache_reads_the_same_samples_faster_and_prints_the_ratio": 13.0,
    "tests/test_bc.py::test_checkpoint_reloads_after_its_weights_file_is_deleted[clip_rn50]": 12.0,
    "tests/test_lerobot_metaworld_obs.py::test_the_docs_comparison_script_finds_lerobots_frames_and_states": 12.0,
    "tests/test_experts.py::test_expert_solves_default_and_each_physical_shift[basketball]": 11.0,
    "tests/test_compare_gaps.py::test_the_command_prints_the_differences_findings_quotes_and_refuses_in_one_line": 11.0,
    "tests/test_experts.py::test_expert_solves_default_and_each_physical_shift[bin-picking]": 9.0,
    "tests/test_datasets.py::test_offline_push_fails_clearly_and_loses_nothing": 9.0,
    "tests/test_renderer.py::test_an_env_left_open_at_exit_prints_nothing": 9.0,
    "tests/test_bench_scripts.py::test_bench_script_prints_consistent_rows_and_the_ratio_last[policy]": 9.0,
    "tests/test_named_studies.py::test_factorworld_configs_lists_every_name_with_its_cost": 8.0,
    "tests/test_docs_results.py::test_report_command_regenerates_report_and_plots_from_a_results_csv_alone": 8.0,
    "tests/test_rt1.py::test_lerobot_train_lowers_the_loss_and_lerobot_eval_runs_the_checkpoint": 8.0,
    "tests/test_html_report.py::test_report_html_in_headless_chromium": 8.0,
    "tests/test_datasets.py::test_several_tasks_in_one_video_dataset_and_append": 8.0,
    "tests/test_datasets.py::test_full_disk_keeps_finished_shards_and_a_rerun_completes": 7.0,
    "tests/test_experts.py::test_expert_solves_default_and_each_physical_shift[window-close]": 7.0,
    "tests/test_experts.py::test_expert_solves_default_and_each_physical_shift[window-open]": 7.0,
}
SLOW_DEFAULT = 10.0


def _group(item: pytest.Item) -> str | None:
    mark = item.get_closest_marker("xdist_group")
    return None if mark is None else (mark.args[0] if mark.args else mark.kwargs["name"])


def _expected_seconds(item: pytest.Item) -> float:
    group = _group(item)
    if group is not None:
        return EXPECTED_SECONDS.get(group, SLOW_DEFAULT)
    nodeid = item.nodeid
    seconds = EXPECTED_SECONDS.get(nodeid, EXPECTED_SECONDS.get(nodeid.split("[")[0]))
    if seconds is None:
        return SLOW_DEFAULT if item.get_closest_marker("slow") else 0.0
    return seconds


def pytest_collection_modifyitems(config, items):
    """Longest first (an xdist group's tests together, at the group's place): with the workers handed one test
    (or group) at a time, the long ones run side by side at the start and short ones fill in at the end.
    Expensive fixtures are session-scoped (:func:`shared`), so this order builds none of them twice."""
    units: dict[str, tuple[int, float]] = {}
    keys = {}
    for index, item in enumerate(items):
        group = _group(item)
        unit = f"group:{group}" if group is not None else item.nodeid
        first, seconds = units.setdefault(unit, (index, _expected_seconds(item)))
        keys[item.nodeid] = (-seconds, first)
    items.sort(key=lambda item: keys[item.nodeid])
    if config.getoption("loadgroup", False):  # an xdist worker under --dist loadgroup
        for item in items:
            group = _group(item)
            if group is not None and "@" not in item.nodeid and hasattr(item, "_id"):
                # pytest-xdist (3.8) tags a grouped test by appending "@group" to ``item._nodeid``, which pytest 9
                # no longer reads: without this, tests of one group would be spread over workers.
                item._id = type(item._id).parse(f"{item.nodeid}@{group}")
