"""Results where the Hub shows them: ``.eval_results/factorworld.yaml`` for a model repo (one entry per task and
condition, success in percent) and the benchmark card ``eval.yaml`` that declares those task ids, written next
to ``report.md`` from ``results.csv`` rows; and a pull request that adds the YAML and the per-episode Parquet to
a model repo (``open_model_pr``).

Why: a model page on the Hub shows the entries of its ``.eval_results/*.yaml`` (the Hub's "Evaluation Results",
a work in progress there), and a benchmark dataset with an ``eval.yaml`` aggregates them; our own Parquet and
card reach no model page. Fields written (the Hub's documented ones): ``dataset.id``, ``dataset.task_id``
(``<task>/<condition>``), ``value`` and ``notes``; no ``date`` (the Hub takes the commit's time, and the file stays
a function of the results). Both files are checked against the Hub's documented fields before they are written
(:func:`entry_problems`, :func:`card_problems`: the specification of hub-docs' ``eval_results.yaml`` and
``docs/hub/eval-results.md``). The benchmark is the study's ``hub_benchmark``; the Hub's own validation at push
time (beta, allow-listed, and ``evaluation_framework`` an enumerable the Hub maintains, where
:data:`EVALUATION_FRAMEWORK` is not listed yet) is untested here.
"""

from __future__ import annotations

import math
import re
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
EVAL_RESULTS_STEM = "factorworld"  # our files in .eval_results/: factorworld.yaml and its variants factorworld_*.yaml
EVAL_RESULTS_FILE = f"{EVAL_RESULTS_STEM}.yaml"
BENCHMARK_CARD = "eval.yaml"
EVALUATION_FRAMEWORK = "lerobot-factorworld"  # eval.yaml's framework key (the Hub's list must add it: module doc)
EPISODES_IN_REPO = "factorworld/episodes.parquet"  # where a pull request puts the per-episode Parquet
ENTRY_FIELDS = ("dataset", "value", "notes")  # what every entry we write has (``dataset``: ``id`` and ``task_id``)

# The Hub's documented fields (hub-docs: eval_results.yaml; docs/hub/eval-results.md, "Eval.yaml specification")
HUB_ENTRY = {"required": ("dataset", "value"), "optional": ("verifyToken", "date", "source", "notes")}
HUB_ENTRY_DATASET = {"required": ("id", "task_id"), "optional": ("revision",)}
HUB_ENTRY_SOURCE = {"required": ("url",), "optional": ("name", "user", "org")}
HUB_CARD = {"required": ("name", "description", "evaluation_framework", "tasks"), "optional": ()}
HUB_CARD_TASK = {"required": ("id",), "optional": ("config", "split")}
INSPECT_TASK_FIELDS = ("field_spec", "solvers", "scorers")  # a task's further fields with ``inspect-ai`` only


def task_id(task: str, condition: str) -> str:
    """``pick-place/camera_pos``: the benchmark's task of one condition of one Meta-World task."""
    return f"{task}/{condition}"


def eval_entries(cfg: StudyConfig, rows: Sequence[dict]) -> list[dict]:
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
                "dataset": {"id": cfg.hub_benchmark, "task_id": task_id(r["task"], r["condition"])},
                "value": round(100 * r["success_rate"], 2),
                "notes": "; ".join(notes),
            }
        )
    return out


def benchmark_card(cfg: StudyConfig, named: Sequence[str] = ()) -> dict:
    """The ``eval.yaml`` of a Factor World benchmark dataset: the task ids of the study's grid, then any other the
    entries name (``named``)."""
    conditions = [TRAIN_SUITE, *cfg.conditions()]
    ids = dict.fromkeys([*(task_id(task, condition) for task in cfg.tasks for condition in conditions), *named])
    return {
        "name": f"Factor World ({cfg.hub_benchmark})",
        "description": "Meta-World manipulation under factor shifts (lighting, textures, camera pose, table "
        "position, distractors, ...). Each task is one Meta-World task under one condition, <task>/<condition>, "
        "with train the training environments; its value is the success rate in percent over paired episode "
        "seeds, evaluated by lerobot_factorworld's `factorworld profile`.",
        "evaluation_framework": EVALUATION_FRAMEWORK,
        "tasks": [{"id": i} for i in ids],
    }


def _field_problems(item: object, spec: dict, where: str) -> list[str]:
    if not isinstance(item, dict):
        return [f"{where} is not a mapping"]
    missing = [f"{where} lacks {name}" for name in spec["required"] if name not in item]
    unknown = [
        f"{where} has {name}, not a documented field"
        for name in item
        if name not in (*spec["required"], *spec["optional"])
    ]
    return missing + unknown


def entry_problems(entries: object, task_ids: Sequence[str] | None = None) -> list[str]:
    """What in an ``.eval_results`` file departs from the Hub's documented fields (empty: nothing); with
    ``task_ids`` (the benchmark's ``eval.yaml`` tasks), entries naming another task too."""
    if not isinstance(entries, list) or not entries:
        return ["an .eval_results file is a non-empty list of entries"]
    problems: list[str] = []
    named: set[str] = set()
    for i, entry in enumerate(entries):
        where = f"entry {i}"
        problems += _field_problems(entry, HUB_ENTRY, where)
        if not isinstance(entry, dict):
            continue
        if "dataset" in entry:
            problems += _field_problems(entry["dataset"], HUB_ENTRY_DATASET, f"{where}'s dataset")
            task = entry["dataset"].get("task_id") if isinstance(entry["dataset"], dict) else None
            if task_ids is not None and task is not None and task not in task_ids:
                problems.append(f"{where} names task {task!r}, which the benchmark's eval.yaml does not declare")
            if task is not None and task in named:
                problems.append(
                    f"{where} names task {task!r} again: a variant of a benchmark goes in a file of its own"
                )
            named.add(task)
        value = entry.get("value")
        if "value" in entry and (
            isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value)
        ):
            problems.append(f"{where}'s value is not a finite number")
        if "source" in entry:
            problems += _field_problems(entry["source"], HUB_ENTRY_SOURCE, f"{where}'s source")
        for name in ("date", "notes", "verifyToken"):
            if name in entry and not isinstance(entry[name], str):
                problems.append(f"{where}'s {name} is not a string")
    return problems


def card_problems(card: object) -> list[str]:
    """What in a benchmark's ``eval.yaml`` departs from the Hub's documented specification (empty: nothing)."""
    problems = _field_problems(card, HUB_CARD, "eval.yaml")
    if not isinstance(card, dict):
        return problems
    tasks = card.get("tasks")
    if not isinstance(tasks, list) or not tasks:
        return [*problems, "eval.yaml's tasks is not a non-empty list"]
    inspect = card.get("evaluation_framework") == "inspect-ai"
    spec = {**HUB_CARD_TASK, "optional": (*HUB_CARD_TASK["optional"], *(INSPECT_TASK_FIELDS if inspect else ()))}
    for i, task in enumerate(tasks):
        problems += _field_problems(task, spec, f"eval.yaml's task {i}")
        if inspect and isinstance(task, dict):
            problems += [
                f"eval.yaml's task {i} lacks {name} (inspect-ai)" for name in INSPECT_TASK_FIELDS if name not in task
            ]
    ids = [t.get("id") for t in tasks if isinstance(t, dict)]
    problems += [f"eval.yaml declares task {i!r} more than once" for i in sorted({i for i in ids if ids.count(i) > 1})]
    return problems


def eval_files(cfg: StudyConfig, rows: Sequence[dict]) -> dict[str, list[dict]]:
    """The ``.eval_results`` files (path under the study folder: entries), one per method and set-up: the Hub
    puts variants of one benchmark in separate files, and a model repo holds its own model's only. One method
    (a profile): ``.eval_results/factorworld.yaml``, other set-ups beside it (``factorworld_n10.yaml`` for one
    of several N, ``factorworld_camera_pos-wide.yaml`` for a radius sweep's width); several methods: the same
    under ``.eval_results/<method>/``."""
    several = len({r["method"] for r in rows}) > 1
    n_values = {m: {int(r["n_train_envs"]) for r in rows if r["method"] == m} for m in {r["method"] for r in rows}}
    files: dict[str, list[dict]] = {}
    for row, entry in zip(rows, eval_entries(cfg, rows), strict=True):
        folder = f"{EVAL_RESULTS_DIR}/{_safe_name(row['method'])}" if several else EVAL_RESULTS_DIR
        variant = [f"n{row['n_train_envs']}"] if len(n_values[row["method"]]) > 1 else []
        if row["widths"] != "default":
            variant.append(row["widths"].replace("=", "-").replace(",", "_"))
        name = "_".join([EVAL_RESULTS_STEM, *variant])
        files.setdefault(f"{folder}/{name}.yaml", []).append(entry)
    return files


def _safe_name(name: str) -> str:
    """``name`` as one folder name: characters other than letters, digits, ``_ . -`` become ``_``, no leading dot."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name).lstrip(".") or "_"


def write_eval_results(cfg: StudyConfig, rows: Sequence[dict], out_dir: Path) -> list[Path]:
    """The :func:`eval_files` and ``<out_dir>/eval.yaml`` (declaring every task they name), checked against the
    Hub's documented fields first (a departure is a bug here, never the user's); their paths, the card last.
    Files of an earlier run that these results no longer hold are removed: the folder is these results."""
    files = eval_files(cfg, rows)
    card = benchmark_card(cfg, [e["dataset"]["task_id"] for entries in files.values() for e in entries])
    problems = card_problems(card)
    for name, entries in files.items():
        problems += [f"{name}: {p}" for p in entry_problems(entries, [t["id"] for t in card["tasks"]])]
    if problems:
        raise RuntimeError(f"the Hub files would depart from the Hub's format: {'; '.join(problems)}")
    out_dir = Path(out_dir)
    dump = {"sort_keys": False, "allow_unicode": True, "width": 1000}
    written = []
    for name, entries in files.items():
        (out_dir / name).parent.mkdir(parents=True, exist_ok=True)
        written.append(atomic_write_text(out_dir / name, yaml.safe_dump(entries, **dump)))
    for old in (out_dir / EVAL_RESULTS_DIR).rglob(f"{EVAL_RESULTS_STEM}*.yaml"):  # ours only: a user's own files stay
        if old not in written:
            old.unlink()
            if old.parent != out_dir / EVAL_RESULTS_DIR and not any(old.parent.iterdir()):
                old.parent.rmdir()
    return [*written, atomic_write_text(out_dir / BENCHMARK_CARD, yaml.safe_dump(card, **dump))]


def open_model_pr(study_dir: str | Path, model_repo_id: str) -> tuple[bool, str]:
    """A pull request on the model repo ``model_repo_id`` adding the ``.eval_results/*.yaml`` files of the study's
    one method and the per-episode Parquet; ``(opened, one line to print)``. Offline or refused: one line,
    nothing local changes."""
    import huggingface_hub  # noqa: PLC0415 - the Hub client, for a push only

    study_dir = Path(study_dir)
    results = sorted((study_dir / EVAL_RESULTS_DIR).glob(f"{EVAL_RESULTS_STEM}*.yaml"))  # ours only
    files = {f"{EVAL_RESULTS_DIR}/{p.name}": p for p in results}
    files[EPISODES_IN_REPO] = study_dir / "episodes.parquet"
    kept = f"nothing was lost: {', '.join(str(p) for p in files.values())} are complete; rerun with --push_to_hub"
    if not results:  # several methods (one folder each) or none written: no one model's results to add
        return False, one_line(
            f"warning: no pull request opened on {model_repo_id}: {study_dir / EVAL_RESULTS_DIR} holds no one "
            "model's results (a study of one given checkpoint writes them, such as factorworld profile's)"
        )
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
