"""Results where the Hub shows them: ``.eval_results/factorworld.yaml`` for a model repo (one entry per task and
condition, success in percent) and the benchmark card ``eval.yaml`` that declares those task ids, written next
to ``report.md`` from ``results.csv`` rows; and a pull request that adds the YAML and the per-episode Parquet to
a model repo (``open_model_pr``).

Why: a model page on the Hub shows the entries of its ``.eval_results/*.yaml`` (the Hub's "Evaluation Results",
a work in progress there), and a benchmark dataset with an ``eval.yaml`` aggregates them; our own Parquet and
card reach no model page. Fields written (the Hub's documented ones): ``dataset.id``, ``dataset.task_id``
(``<task>/<condition>``), ``value`` and ``notes``; no ``date`` (the Hub takes the commit's time, and the file stays
a function of the results). The benchmark id is :data:`BENCHMARK_ID` unless given: no Factor World benchmark repo
exists on the Hub yet, and the Hub's validation of ``eval.yaml`` (beta, allow-listed) is untested here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import yaml

from ... import __version__
from ...core.io import atomic_write_text
from ...core.settings import one_line
from ...datasets.hub import HubUnreachableError, check_hub_reachable
from ...protocol.conditions import TRAIN_SUITE
from ..plan.config import StudyConfig
from ..sequential import INTERVAL_LABEL
from .stopping import stop_rows

EVAL_RESULTS_DIR = ".eval_results"
EVAL_RESULTS_FILE = "factorworld.yaml"
BENCHMARK_CARD = "eval.yaml"
BENCHMARK_ID = "lerobot-factorworld/factor-world"  # the benchmark dataset the entries name (not on the Hub yet)
EPISODES_IN_REPO = "factorworld/episodes.parquet"  # where a pull request puts the per-episode Parquet
ENTRY_FIELDS = ("dataset", "value", "notes")  # what every entry has (``dataset``: ``id`` and ``task_id``)


def task_id(task: str, condition: str) -> str:
    """``pick-place/camera_pos``: the benchmark's task of one condition of one Meta-World task."""
    return f"{task}/{condition}"


def eval_entries(cfg: StudyConfig, rows: Sequence[dict], benchmark: str = BENCHMARK_ID) -> list[dict]:
    """One entry per row (task and condition; a study of several methods or cells writes each, its notes say
    which), success in percent, notes with the episodes, the interval, the gap and the package version."""
    reasons = {(r.method, r.task, r.n_train_envs, r.widths, r.condition): r.reason for r in stop_rows(cfg, rows)} if (
        cfg.eval.auto
    ) else {}  # fmt: skip
    label = f"{INTERVAL_LABEL} {cfg.eval.confidence:.0%}" if cfg.eval.auto else "Wilson 95%"
    gap_label = f"{INTERVAL_LABEL} {cfg.eval.confidence:.0%}" if cfg.eval.auto else "Newcombe paired 95%"
    out = []
    for r in rows:
        key = (r["method"], r["task"], int(r["n_train_envs"]), r["widths"], r["condition"])
        notes = [
            f"method {r['method']} ({r['policy']}), N {r['n_train_envs']}, seed {r['seed']}, widths {r['widths']}",
            f"{r['episodes']} episodes, {r['successes']} successes, {label} interval "
            f"[{100 * r['ci_low']:.1f}, {100 * r['ci_high']:.1f}] %",
        ]
        if r["condition"] != TRAIN_SUITE and not math.isnan(r["gap"]):
            gap = f"gap to train {r['gap']:+.3f}"
            if not math.isnan(r["gap_ci_low"]):
                gap += f" ({gap_label} [{r['gap_ci_low']:+.3f}, {r['gap_ci_high']:+.3f}])"
            notes.append(gap)
        if key in reasons:
            notes.append(f"eval.episodes=auto, stopped: {reasons[key]}")
        notes.append(f"lerobot_factorworld {__version__}, study {r['study']}")
        out.append(
            {
                "dataset": {"id": benchmark, "task_id": task_id(r["task"], r["condition"])},
                "value": round(100 * r["success_rate"], 2),
                "notes": "; ".join(notes),
            }
        )
    return out


def benchmark_card(cfg: StudyConfig, benchmark: str = BENCHMARK_ID) -> dict:
    """The ``eval.yaml`` of a Factor World benchmark dataset: the task ids the entries name."""
    conditions = [TRAIN_SUITE, *cfg.conditions()]
    return {
        "name": benchmark,
        "description": "Factor World (Meta-World under factor shifts): success rate in percent per task and "
        "condition, evaluated on paired episode seeds by lerobot_factorworld's `factorworld profile`.",
        "tasks": [
            {"id": task_id(task, condition), "name": f"{task} under {condition}", "metric": "success rate (%)"}
            for task in cfg.tasks
            for condition in conditions
        ],
    }


def write_eval_results(cfg: StudyConfig, rows: Sequence[dict], out_dir: Path) -> tuple[Path, Path]:
    """``<out_dir>/.eval_results/factorworld.yaml`` and ``<out_dir>/eval.yaml``; their paths."""
    folder = Path(out_dir) / EVAL_RESULTS_DIR
    folder.mkdir(parents=True, exist_ok=True)
    dump = {"sort_keys": False, "allow_unicode": True, "width": 1000}
    results = atomic_write_text(folder / EVAL_RESULTS_FILE, yaml.safe_dump(eval_entries(cfg, rows), **dump))
    card = atomic_write_text(Path(out_dir) / BENCHMARK_CARD, yaml.safe_dump(benchmark_card(cfg), **dump))
    return results, card


def open_model_pr(study_dir: str | Path, model_repo_id: str) -> tuple[bool, str]:
    """A pull request on the model repo ``model_repo_id`` adding ``.eval_results/factorworld.yaml`` and the
    per-episode Parquet; ``(opened, one line to print)``. Offline or refused: one line, nothing local changes."""
    import huggingface_hub  # noqa: PLC0415 - the Hub client, for a push only

    study_dir = Path(study_dir)
    files = {
        f"{EVAL_RESULTS_DIR}/{EVAL_RESULTS_FILE}": study_dir / EVAL_RESULTS_DIR / EVAL_RESULTS_FILE,
        EPISODES_IN_REPO: study_dir / "episodes.parquet",
    }
    kept = f"nothing was lost: {', '.join(str(p) for p in files.values())} are complete; rerun with --push_to_hub"
    try:
        check_hub_reachable()
        operations = [huggingface_hub.CommitOperationAdd(path_in_repo=k, path_or_fileobj=v) for k, v in files.items()]
        commit = huggingface_hub.HfApi().create_commit(
            model_repo_id, operations, commit_message="Add Factor World evaluation results", create_pr=True
        )
    except HubUnreachableError as err:
        return False, one_line(f"warning: no pull request opened on {model_repo_id}: {err}; {kept}")
    except Exception as err:  # noqa: BLE001 - e.g. the Hub refused it (no such repo, no access): one line
        return False, one_line(
            f"warning: the pull request on {model_repo_id} failed ({type(err).__name__}: {err}); {kept}"
        )
    return True, f"opened a pull request on {model_repo_id} with {', '.join(files)}: {commit.pr_url}"
