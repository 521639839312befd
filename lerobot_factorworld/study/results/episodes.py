"""``episodes.parquet``: one row per evaluated episode, next to ``results.csv`` (one row per cell), and its push
to the Hugging Face Hub as a dataset repo with a card.

``results.csv`` says how often a policy failed under a shift; these rows say which episodes failed, in which
environment (its factor values), at which stage, made by which code, so that anyone can regroup them
(``datasets.load_dataset("parquet", data_files=...)`` or pandas) without the study's step folders. The
columns are :data:`EPISODE_COLUMNS`, the one place that names, types and explains them (the card's column
table is written from it); names follow LeRobot's ``eval_info`` where it has one (``episode_ix``,
``success``; the card's ``n_episodes``, ``n_success``, ``pc_success`` and ``pc_success_ci95``, the keys
LeRobot's evaluation reports after 0.6.1).

Rows come from finished evaluations, one at a time (:func:`evaluation_episodes`: labels, a step result and
the condition's environments), so a command that evaluates without a study (a profile of a given policy)
writes the same file. What is not here: episode lengths and rewards (LeRobot's rollout keeps only each
episode's success, rewards and seed, and a study's step records success, seed and stage), and the object
start of each episode (drawn from its reset seed, ``episode_seed``, by the environment).
"""

from __future__ import annotations

import functools
import itertools
import json
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ...core.io import temporary_path
from ...core.settings import one_line
from ...datasets.hub import HubUnreachableError, push_files
from ...envs.factor_env import env_index_for_seed
from ...factors.values import SceneConfig
from ...families import family_of
from ...protocol.conditions import TRAIN_SUITE, evaluation_suites, fingerprint, shifted_factors
from ...protocol.sampling import SamplingOptions
from ...protocol.sidecar import DatasetCondition, read_dataset_condition
from ...stats.proportions import wilson_interval
from ...tasks import get_task
from ..plan.config import StudyConfig
from ..run.inputs import EnvInputs, EvalInputs
from ..run.result import RESULT_FILE, read_result
from ..run.step import Step, step_folder
from .rows import RESULTS_FILE, Evaluation, commits_of, policy_of, provenance_columns

EPISODES_FILE = "episodes.parquet"
CARD_FILE = "README.md"  # the dataset card, in the pushed repo only


class Column(NamedTuple):
    """One column of ``episodes.parquet``: its name, Arrow type, whether it may be null, and what it means."""

    name: str
    type: pa.DataType
    nullable: bool
    meaning: str


EPISODE_COLUMNS = (
    Column("study", pa.string(), False, "study name"),
    Column("method", pa.string(), False, "method name from the study's config"),
    Column("policy", pa.string(), False, "LeRobot policy type of the method"),
    Column("task", pa.string(), False, "Meta-World task"),
    Column("n_train_envs", pa.int64(), False, "N, the training environments of the policy's dataset"),
    Column("seed", pa.int64(), False, "the study seed: sampled the environments and seeded training"),
    Column("widths", pa.string(), False, "sampling widths of the run: `default` or e.g. `camera_pos=medium`"),
    Column("condition", pa.string(), False, "`train`, a factor, or a pair `a+b`"),
    Column("n_factors", pa.int64(), False, "shifted factors: 0 (train), 1, 2"),
    Column("episode_ix", pa.int64(), False, "the episode's index in its evaluation (LeRobot's `episode_ix`)"),
    Column("episode_seed", pa.int64(), False, "its reset seed, `start_seed + episode_ix` (LeRobot's `seed`)"),
    Column("env_index", pa.int64(), False, "the condition's environment it ran in: `episode_seed % n_envs`"),
    Column("env_id", pa.string(), True, "that environment's id, e.g. `door-open/shift-light/001`"),
    Column("factors", pa.string(), True, "its factor values, JSON; a null value: the task's default"),
    Column("content", pa.string(), True, "what the episode asked for, JSON (pick: instruction, target, objects)"),
    Column("success", pa.bool_(), False, "the task's success test held (LeRobot's `success`)"),
    Column("stage", pa.string(), True, "the furthest stage reached (docs/study.md, Where episodes fail)"),
    Column("n_steps", pa.int64(), True, "the episode's length in environment steps (it ends at success)"),
    Column("step", pa.string(), False, "key of the evaluation step (`steps/eval/<key>/`)"),
    Column("commit", pa.string(), True, "git commit the evaluation ran at, `-dirty` when the package differed from it"),
    Column("source_hash", pa.string(), True, "first 12 hex digits of the SHA-256 of the package source it ran"),
)
EPISODE_COLUMN_NAMES = tuple(c.name for c in EPISODE_COLUMNS)
SCHEMA = pa.schema([pa.field(c.name, c.type, nullable=c.nullable) for c in EPISODE_COLUMNS])
CONDITION_CELL = ("method", "task", "n_train_envs", "widths", "condition")  # a card row: seeds pooled
CHUNK_ROWS = 65_536  # rows converted and written at a time (a row group of the file)


# --- rows ---------------------------------------------------------------------------------------


def evaluation_episodes(
    labels: Mapping[str, Any],
    result: Mapping[str, Any],
    configs: Sequence[SceneConfig] | None,
    *,
    study: str,
    policy: str,
    step: str,
) -> list[dict[str, Any]]:
    """The rows of one finished evaluation: ``labels`` name its cell (method, task, n_train_envs, seed,
    widths, condition), ``result`` holds what its step recorded (``successes``, ``seeds``, ``n_envs``, and
    ``stages``, the family's records and provenance when recorded) and ``configs`` are the condition's
    environments (``None`` when they cannot be rebuilt: environment ids and factor values are then null)."""
    n_envs = result["n_envs"]
    if configs is not None and len(configs) != n_envs:
        raise ValueError(f"{len(configs)} environments given for an evaluation of {n_envs}")
    stages = result.get("stages") or [None] * len(result["seeds"])
    lengths = result.get("lengths") or [None] * len(result["seeds"])
    key = family_of(labels["task"]).content_key
    contents = (result.get(key) if key else None) or [None] * len(result["seeds"])
    environments = [(c.env_id, _json(c.factors.to_dict())) for c in configs] if configs is not None else None
    cell = {
        "study": study,
        "method": labels["method"],
        "policy": policy,
        "task": labels["task"],
        "n_train_envs": int(labels["n_train_envs"]),
        "seed": int(labels["seed"]),
        "widths": labels["widths"],
        "condition": labels["condition"],
        "n_factors": len(shifted_factors(labels["condition"])),
        "step": step,
        **provenance_columns(result, empty=None),
    }
    episodes = zip(result["seeds"], result["successes"], stages, lengths, contents, strict=True)
    return [
        {**cell, **_episode(i, seed, success, stage, length, content, environments, n_envs)}
        for i, (seed, success, stage, length, content) in enumerate(episodes)
    ]


def _episode(
    index: int,
    seed: int,
    success: bool,
    stage: str | None,
    length: int | None,
    content: Any,
    environments: Sequence[tuple[str, str]] | None,
    n_envs: int,
) -> dict[str, Any]:
    env = env_index_for_seed(int(seed), n_envs)
    env_id, factors = environments[env] if environments is not None else (None, None)
    return {
        "episode_ix": index,
        "episode_seed": int(seed),
        "env_index": env,
        "env_id": env_id,
        "factors": factors,  # one string per environment, shared by its episodes
        "content": _json(content) if content is not None else None,
        "success": bool(success),
        "stage": stage,
        "n_steps": length,
    }


def _json(value: Any) -> str:
    return json.dumps(value, sort_keys=True)


def episode_rows(
    cfg: StudyConfig, evaluations: Sequence[Evaluation], study_dir: str | Path
) -> Iterator[dict[str, Any]]:
    """The rows of a study's finished ``evaluations`` (in their order), their environments rebuilt from each
    evaluation's dataset (:func:`condition_environments`); one evaluation at a time, so that a large study
    (the paper's grid: about a million episodes) is written without holding every row."""
    rebuild = environment_rebuilder(study_dir)
    for evaluation in evaluations:
        configs = condition_environments(evaluation.step, evaluation.result, rebuild)
        policy = policy_of(cfg, evaluation)
        yield from evaluation_episodes(
            evaluation.labels, evaluation.result, configs, study=cfg.name, policy=policy, step=evaluation.step.key
        )


Suite = tuple[list[SceneConfig], str | None]  # a condition's environments and the object-start width
Rebuild = Callable[[str, str, str, int | None], Suite | None]  # (collect key, task, condition, n_test_envs)


def environment_rebuilder(study_dir: str | Path) -> Rebuild:
    """The environments of a condition for the dataset of a collect step of ``study_dir``, each dataset read
    and each condition built once (for one writing of the records: a dataset remade later is read again)."""
    dataset_of = functools.cache(functools.partial(_dataset, Path(study_dir)))
    return functools.cache(functools.partial(_suite, dataset_of))


def condition_environments(step: Step, result: Mapping[str, Any], rebuild: Rebuild) -> list[SceneConfig] | None:
    """The environments an evaluation step ran in, rebuilt as it built them (from its dataset's side-car, or a
    given checkpoint's from its step's settings), or ``None`` when that is not possible or gives other
    environments than the ones it recorded (the fingerprint differs: sampling changed since, or the dataset
    was remade): factor values are never guessed."""
    inputs = EvalInputs.from_dict(step.inputs)
    suites = [rebuild(key, step.meta["task"], inputs.condition, inputs.n_test_envs) for key in step.deps]
    if inputs.environments is not None:
        suites.append(_given_suite(inputs.environments, inputs.condition, inputs.n_test_envs))
    for suite in suites:
        if suite is not None:
            configs, width = suite
            return configs if fingerprint(configs, width) == result.get("fingerprint") else None
    return None


def _given_suite(env: EnvInputs, condition: str, n_test_envs: int | None) -> Suite | None:
    """The environments of ``condition`` for a given checkpoint's evaluation, sampled from its settings."""
    sampling = env.sampling_options()
    return _condition_suite(env.task, condition, n_test_envs, env.n_envs, env.train_factors, env.seed, sampling)


def _dataset(study_dir: Path, collect_key: str) -> DatasetCondition | None:
    """What the dataset of collect step ``collect_key`` was collected in; ``None`` when that is no collect
    step or its dataset is gone (deleted to save space)."""
    folder = step_folder(study_dir, "collect", collect_key)
    if not (folder / RESULT_FILE).is_file():
        return None
    try:
        return read_dataset_condition(read_result(folder)["root"])
    except (OSError, ValueError, KeyError):
        return None


def _suite(
    dataset_of: Callable[[str], DatasetCondition | None],
    collect_key: str,
    task: str,
    condition: str,
    n_test_envs: int | None,
) -> Suite | None:
    """The environments of ``condition`` for the dataset of collect step ``collect_key``, as the evaluation's
    ``FactorWorldEnvConfig(dataset_root=...)`` builds them; ``None`` without that dataset."""
    dataset = dataset_of(collect_key)
    if dataset is None:
        return None
    try:
        train_configs = dataset.train_configs(get_task(task).name)
    except (OSError, ValueError, KeyError):  # not a dataset this code reads (another task)
        return None
    return _condition_suite(
        task, condition, n_test_envs, dataset.n_envs, dataset.factors, dataset.seed, dataset.sampling, train_configs
    )


def _condition_suite(
    task: str,
    condition: str,
    n_test_envs: int | None,
    n_envs: int,
    factors: Sequence[str],
    seed: int,
    sampling: SamplingOptions,
    train_configs: Sequence[SceneConfig] | None = None,
) -> Suite | None:
    """The environments of ``condition`` as an evaluation's env config builds them; ``None`` when this code
    cannot build them (other factors than it knows)."""
    try:
        name = get_task(task).name
        shifts = [] if condition == TRAIN_SUITE else [condition]
        suites = evaluation_suites(name, n_envs, factors, shifts, n_test_envs or n_envs, seed, sampling, train_configs)
    except (OSError, ValueError, KeyError):
        return None
    configs = suites[TRAIN_SUITE] if condition == TRAIN_SUITE else list(suites.values())[-1]
    return configs, sampling.widths.get("object_pos")


# --- the file -------------------------------------------------------------------------------------


def write_episodes(rows: Iterable[Mapping[str, Any]], path: str | Path) -> Path:
    """Write ``episodes.parquet`` atomically, its schema :data:`SCHEMA` whatever the rows (none too), a chunk
    of ``CHUNK_ROWS`` rows at a time (the same rows always give the same bytes)."""
    path = Path(path)
    tmp = temporary_path(path)
    try:
        with pq.ParquetWriter(tmp, SCHEMA) as writer:
            for chunk in itertools.batched(rows, CHUNK_ROWS):
                writer.write_table(episodes_table(chunk))
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def episodes_table(rows: Iterable[Mapping[str, Any]]) -> pa.Table:
    """Rows as an Arrow table of :data:`SCHEMA` (what :func:`dataset_card` reads)."""
    return pa.Table.from_pylist([{c: row[c] for c in EPISODE_COLUMN_NAMES} for row in rows], schema=SCHEMA)


def read_episodes_table(path: str | Path) -> pa.Table:
    """An ``episodes.parquet`` as an Arrow table; a file without its columns is refused in one line."""
    table = pq.read_table(path)
    missing = [c for c in EPISODE_COLUMN_NAMES if c not in table.column_names]
    if missing:
        raise ValueError(f"{path} is not an episodes file: no column(s) {', '.join(missing)}")
    return table.select(list(EPISODE_COLUMN_NAMES))


def read_episodes(path: str | Path) -> list[dict[str, Any]]:
    """The rows of an ``episodes.parquet`` (a small one: every row becomes a dict)."""
    return read_episodes_table(path).to_pylist()


# --- the card ---------------------------------------------------------------------------------------


def condition_summary(episodes: pa.Table) -> list[dict[str, Any]]:
    """Per method, task, N, widths and condition (seeds pooled, in row order): LeRobot's ``n_episodes``,
    ``n_success``, ``pc_success`` and ``pc_success_ci95`` (the Wilson 95% interval, in percent)."""
    cells = episodes.group_by(list(CONDITION_CELL), use_threads=False).aggregate(
        [("success", "count"), ("success", "sum")]
    )
    out = []
    for cell in cells.to_pylist():
        n, k = cell.pop("success_count"), cell.pop("success_sum")
        low, high = wilson_interval(k, n)
        out.append(
            {
                **{c: cell[c] for c in CONDITION_CELL},
                "n_episodes": n,
                "n_success": k,
                "pc_success": 100 * k / n,
                "pc_success_ci95": [100 * low, 100 * high],
            }
        )
    return out


def dataset_card(episodes: pa.Table, repo_id: str) -> str:
    """The dataset card (``README.md``) of pushed episodes (:func:`episodes_table` of the rows, or the file
    read back): metadata that makes ``episodes.parquet`` the default split, what the study covered, how to
    load it, the columns, and success per condition with intervals."""
    studies = _distinct(episodes, "study")
    conditions = _distinct(episodes, "condition")
    factors = list(dict.fromkeys(f for c in conditions for f in shifted_factors(c)))
    methods = [f"{m['method']} (`{m['policy']}`)" for m in _distinct_rows(episodes, "method", "policy")]
    tags = ["factorworld", "meta-world", "lerobot", "robotics", "generalization", *_distinct(episodes, "task")]
    lines = [
        "---",
        "license: apache-2.0",
        "task_categories:",
        "- robotics",
        "tags:",
        *[f"- {tag}" for tag in dict.fromkeys(tags)],
        "configs:",
        "- config_name: default",
        "  data_files:",
        "  - split: train",
        f"    path: {EPISODES_FILE}",
        "---",
        "",
        f"# {', '.join(studies)}: Factor World evaluation episodes",
        "",
        "Every evaluated episode of a Factor World generalization-gap study (Xie et al. 2023, *Decomposing the "
        "Generalization Gap in Imitation Learning for Visual Robotic Manipulation*), made with lerobot_factorworld: "
        f"one row per episode in `{EPISODES_FILE}`, one row per method x task x N x seed x condition in "
        f"`{RESULTS_FILE}` (its gaps and their paired intervals).",
        "",
        f"- **Tasks:** {', '.join(_distinct(episodes, 'task'))}",
        f"- **Factors shifted:** {', '.join(factors) or 'none'}",
        f"- **Conditions:** {', '.join(conditions)}",
        f"- **Methods (LeRobot policy type):** {', '.join(methods)}",
        f"- **N (training environments):** {', '.join(map(str, _distinct(episodes, 'n_train_envs')))}; "
        f"**seeds:** {', '.join(map(str, _distinct(episodes, 'seed')))}",
        f"- **Episodes:** {episodes.num_rows}, {pc.sum(episodes['success']).as_py() or 0} successful",
        f"- **Made at commit(s):** {', '.join(commits_of(_distinct_rows(episodes, 'commit', 'source_hash')))}",
        "",
        "```python",
        "from datasets import load_dataset",
        "",
        f'episodes = load_dataset("{repo_id}", split="train")',
        "```",
        "",
        "## Columns",
        "",
        "| column | meaning |",
        "|---|---|",
        *[f"| `{c.name}` | {c.meaning} |" for c in EPISODE_COLUMNS],
        "",
        "## Success per condition",
        "",
        "Seeds pooled; `pc_success_ci95` is the Wilson 95% score interval, in percent (the names are LeRobot's).",
        "",
        "| method | task | N | widths | condition | n_episodes | n_success | pc_success | pc_success_ci95 |",
        "|---|---|---|---|---|---|---|---|---|",
        *[_summary_line(s) for s in condition_summary(episodes)],
    ]
    return "\n".join(lines) + "\n"


def _distinct(episodes: pa.Table, column: str) -> list[Any]:
    """The values of a column, each once, in row order."""
    return pc.unique(episodes[column]).to_pylist()


def _distinct_rows(episodes: pa.Table, *columns: str) -> list[dict[str, Any]]:
    """The combinations of ``columns``' values, each once, in row order."""
    return episodes.select(list(columns)).group_by(list(columns), use_threads=False).aggregate([]).to_pylist()


def _summary_line(s: Mapping[str, Any]) -> str:
    low, high = s["pc_success_ci95"]
    return (
        f"| {s['method']} | {s['task']} | {s['n_train_envs']} | {s['widths']} | {s['condition']} | {s['n_episodes']} "
        f"| {s['n_success']} | {s['pc_success']:.1f} | [{low:.1f}, {high:.1f}] |"
    )


# --- the push ------------------------------------------------------------------------------------------

AGAIN = "run the same command again to push them (finished steps are not redone)"


def push_results(study_dir: str | Path, repo_id: str, again: str = AGAIN) -> tuple[bool, str]:
    """Push ``episodes.parquet``, ``results.csv`` and the card from ``study_dir`` to the dataset repo ``repo_id``;
    ``(pushed, one line to print)``. Nothing local changes: without a network (or when the Hub refuses the
    push) the line says so and how to push later (``again``), never a traceback."""
    study_dir = Path(study_dir)
    episodes = read_episodes_table(study_dir / EPISODES_FILE)
    if not episodes.num_rows:
        return False, f"warning: nothing pushed to {repo_id}: no evaluation has finished"
    files = {
        EPISODES_FILE: study_dir / EPISODES_FILE,
        RESULTS_FILE: study_dir / RESULTS_FILE,
        CARD_FILE: dataset_card(episodes, repo_id).encode(),
    }
    kept = f"nothing was lost: {EPISODES_FILE} and {RESULTS_FILE} are complete in {study_dir}; {again}"
    try:
        url = push_files(repo_id, files, f"Factor World episodes of {', '.join(_distinct(episodes, 'study'))}")
    except HubUnreachableError as err:
        return False, one_line(f"warning: not pushed to {repo_id}: {err}; {kept}")
    except Exception as err:  # noqa: BLE001 - e.g. the Hub refused it (no write access): one line, results kept
        return False, one_line(f"warning: the push to {repo_id} failed ({type(err).__name__}: {err}); {kept}")
    return True, f"pushed {EPISODES_FILE} ({episodes.num_rows} episodes), {RESULTS_FILE} and the card to {url}"
