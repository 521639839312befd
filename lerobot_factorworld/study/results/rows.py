"""``results.csv``: one row per method x task x N x widths x condition x seed, built from the finished
evaluation steps. Everything else the report shows (tables, plots) is derived from these rows, so a rerun
or a resumed study rewrites the same file (no duplicated rows). Each row names the code that made its
evaluation (``commit``, ``source_hash``, from the step's recorded provenance): the same at one commit, so
two runs of the same code still write the same file."""

from __future__ import annotations

import csv
import io
import math
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...core.io import atomic_write_text, read_table
from ...core.provenance import DIRTY, SHORT, SHORT_HASH, UNKNOWN
from ...envs.stages import as_tracked, stage_names, tracked_before
from ...protocol.conditions import TRAIN_SUITE, shifted_factors
from ...stats.proportions import paired_gap, wilson_interval
from ..plan.config import RADIUS_FACTORS, StudyConfig
from ..plan.grid import Plan, radius_of
from ..run.blocks import SEQUENTIAL
from ..run.result import is_done, provenance_of, read_result
from ..run.step import Step, evaluated

RESULTS_FILE = "results.csv"
STAGE_SEPARATOR = ";"  # between the stage:count items of the stages column
RESULT_COLUMNS = (
    "study",  # study name
    "method",  # method name from the config
    "policy",  # LeRobot policy type
    "task",
    "n_train_envs",  # N
    "seed",  # environment-sampling and training seed
    "widths",  # sampling widths of the run: "default" or e.g. "camera_pos=medium" (radius sweep)
    "condition",  # "train", a factor, or a pair "a+b"
    "n_factors",  # shifted factors: 0 (train), 1, 2
    "radius_m",  # radius of camera_pos / table_pos in this run (single-factor rows of those factors)
    "n_envs",  # environments of the condition (N for train, n_test_envs otherwise)
    "episodes",
    "successes",
    "success_rate",
    "ci_low",  # Wilson 95% interval of success_rate (eval.episodes=auto: its anytime-valid interval)
    "ci_high",
    "train_success_rate",  # P_T of the same checkpoint on the same episode seeds
    "gap",  # P_T - P_F (0 for train)
    "gap_ci_low",  # Newcombe paired 95% interval of gap (eval.episodes=auto: its anytime-valid interval)
    "gap_ci_high",
    "envs_visited",  # environments the episodes visited (all, equally, unless flagged in report.md)
    "fingerprint",  # hash of the condition's environments (configurations and object-start width)
    "stages",  # episodes per furthest stage, the task's stages in order: "none:3;reached:2;...;succeeded:5"
    "step",  # key of the eval step (steps/eval/<key>/)
    "commit",  # git commit the evaluation ran at, "-dirty" when the tree differed from it; empty: not recorded
    "source_hash",  # first 12 hex digits of the SHA-256 of the package's source it ran (core/provenance.py)
)


OPTIONAL_COLUMNS = ("stages", "commit", "source_hash")  # added later: older results.csv files lack them
INTEGER_COLUMNS = ("n_train_envs", "seed", "n_factors", "n_envs", "episodes", "successes", "envs_visited")
FLOAT_COLUMNS = (  # empty: NaN (undefined)
    "success_rate",
    "ci_low",
    "ci_high",
    "train_success_rate",
    "gap",
    "gap_ci_low",
    "gap_ci_high",
)
OPTIONAL_FLOAT_COLUMNS = ("radius_m",)  # empty: None (not a radius-sweep row)


@dataclass(frozen=True)
class Evaluation:
    """A finished evaluation step and its result (episode outcomes, seeds, and any family records)."""

    step: Step
    result: dict[str, Any]

    @property
    def labels(self) -> dict[str, Any]:
        """method, task, n_train_envs, seed, widths and condition of the evaluation."""
        return self.step.meta


def finished_evaluations(plan: Plan, study_dir: str | Path) -> list[Evaluation]:
    """Every finished evaluation of ``plan``, in plan order."""
    return [Evaluation(s, read_result(s, study_dir)) for s in plan.evaluations() if is_done(s, study_dir)]


def result_rows(cfg: StudyConfig, evaluations: Sequence[Evaluation]) -> list[dict]:
    """``results.csv`` rows of ``evaluations`` (in their order)."""
    train_outcomes = {evaluated(e.step): e.result for e in evaluations if e.labels["condition"] == TRAIN_SUITE}
    return [_row(cfg.name, policy_of(cfg, e), e, train_outcomes.get(evaluated(e.step))) for e in evaluations]


def policy_of(cfg: StudyConfig, evaluation: Evaluation) -> str:
    """The LeRobot policy type of an evaluation: its method's ``policy.type``, or what a given checkpoint's
    evaluation read from the checkpoint (``""`` for one made before that was recorded)."""
    types = {m.name: m.policy.get("type") for m in cfg.methods}
    return types.get(evaluation.labels["method"]) or evaluation.result.get("policy_type", "")


def _row(study: str, policy: str, evaluation: Evaluation, train: dict | None) -> dict:
    res, meta = evaluation.result, evaluation.labels
    k, n = sum(res["successes"]), len(res["successes"])
    low, high = wilson_interval(k, n)
    gap = gap_low = gap_high = p_train = math.nan
    condition = meta["condition"]
    stop = res.get(SEQUENTIAL)
    if stop is not None:  # eval.episodes=auto: the anytime-valid intervals at the stop, on train's first n seeds
        low, high = stop["success_low"], stop["success_high"]
        if train is not None and train["seeds"][:n] == res["seeds"]:
            p_train = sum(train["successes"][:n]) / n
            gap, gap_low, gap_high = (0.0, math.nan, math.nan) if stop["gap"] is None else _gap_of(stop)
    elif train is not None and train["seeds"] == res["seeds"]:
        p_train = sum(train["successes"]) / len(train["successes"])
        if condition == TRAIN_SUITE:
            gap = 0.0  # by construction: no interval
        else:
            gap, gap_low, gap_high = paired_gap(train["successes"], res["successes"])
    factors = shifted_factors(condition)
    radius = radius_of(meta["widths"], factors[0]) if len(factors) == 1 and factors[0] in RADIUS_FACTORS else None
    return {
        "study": study,
        "method": meta["method"],
        "policy": policy,
        "task": meta["task"],
        "n_train_envs": meta["n_train_envs"],
        "seed": meta["seed"],
        "widths": meta["widths"],
        "condition": condition,
        "n_factors": len(factors),
        "radius_m": radius,
        "n_envs": res["n_envs"],
        "episodes": n,
        "successes": k,
        "success_rate": k / n if n else math.nan,
        "ci_low": low,
        "ci_high": high,
        "train_success_rate": p_train,
        "gap": gap,
        "gap_ci_low": gap_low,
        "gap_ci_high": gap_high,
        "envs_visited": res["envs_visited"],
        "fingerprint": res["fingerprint"],
        "stages": stage_counts_text(meta["task"], res.get("stages"), res.get("stage_names")),
        "step": evaluation.step.key,
        **provenance_columns(res),
    }


def _gap_of(stop: Mapping[str, Any]) -> tuple[float, float, float]:
    return stop["gap"], stop["gap_low"], stop["gap_high"]


def stage_counts_text(task: str, stages: Sequence[str] | None, tracked: Sequence[str] | None = None) -> str:
    """The ``stages`` column: how many episodes ended at each stage, every stage of ``task`` the evaluation tracked
    in order (zeros too, so the column reads alone), e.g. ``none:3;reached:2;moved:0;succeeded:5``; a stage the task
    no longer defines comes last. ``tracked``: the result's ``stage_names`` (``None``, an evaluation that did not
    record them: the stages before any added later, :func:`~lerobot_factorworld.envs.stages.tracked_before`, so
    no stage it could not see reads 0). Empty for an evaluation made before stages were recorded."""
    if stages is None:
        return ""
    names = tuple(tracked) if tracked is not None else tracked_before(task)
    counts = Counter(as_tracked(task, list(stages), names))
    return STAGE_SEPARATOR.join(f"{name}:{counts[name]}" for name in in_stage_order(task, [*names, *counts], names))


def in_stage_order(task: str, names: Iterable[str], tracked: Sequence[str] | None = None) -> list[str]:
    """Every stage of ``task`` (of those in ``tracked``, where given) in its order, then any other of ``names``
    (a stage the task no longer defines)."""
    own = [n for n in stage_names(task) if tracked is None or n in tracked]
    return list(dict.fromkeys([*own, *names]))


def parse_stage_counts(text: str) -> dict[str, int]:
    """``none:3;reached:2`` -> ``{"none": 3, "reached": 2}`` in the column's order; ``{}`` for an empty cell."""
    if not text:
        return {}
    pairs = [item.rpartition(":") for item in text.split(STAGE_SEPARATOR)]
    try:
        return {name: int(count) for name, _, count in pairs}
    except ValueError:
        raise ValueError(f"stages column {text!r} is not 'stage:count;...'") from None


def provenance_columns(result: Mapping[str, Any], empty: str | None = "") -> dict[str, str | None]:
    """``commit`` and ``source_hash`` of a step result; ``empty`` for one made before they were recorded
    (``""`` in ``results.csv``, ``None`` in ``episodes.parquet``)."""
    made_by = provenance_of(dict(result))
    if made_by is None:
        return {"commit": empty, "source_hash": empty}
    commit = empty if made_by.commit is None else made_by.revision()
    return {"commit": commit, "source_hash": made_by.source_hash[:SHORT_HASH]}


def commits_of(rows: Sequence[dict], short: bool = True) -> list[str]:
    """The commit(s) behind ``rows`` (``results.csv`` rows), each once, in row order: ``826fe54``, or
    ``826fe54-dirty`` for code with uncommitted changes, ``unknown`` for rows that name no commit (made
    before commits were recorded, or outside a git checkout). ``short``: 7 characters, as ``git log --oneline``.
    A dirty revision names its source hash too (``826fe54-dirty (source 1a2b3c4d5e6f)``): two different sets
    of uncommitted changes on one commit are different code."""
    return list(dict.fromkeys(commit_name(row, short) for row in rows))


def commit_name(row: dict, short: bool = True) -> str:
    """The code behind one row, as :func:`commits_of` names it."""
    revision = _short(row.get("commit") or UNKNOWN, short)
    dirty = revision.endswith(DIRTY) or revision == UNKNOWN
    return f"{revision} (source {row['source_hash']})" if dirty and row.get("source_hash") else revision


def _short(revision: str, short: bool) -> str:
    if not short or revision == UNKNOWN:
        return revision
    commit = revision.removesuffix(DIRTY)
    return commit[:SHORT] + revision[len(commit) :]


def csv_text(rows: Sequence[dict], columns: Sequence[str]) -> str:
    """``rows`` as CSV text with a header (``\\n`` line ends; floats to 6 decimals, NaN and None empty)."""
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _fmt(row[k]) for k in columns})
    return out.getvalue()


def write_results(rows: Sequence[dict], path: Path) -> Path:
    """Write ``results.csv`` atomically."""
    return atomic_write_text(path, csv_text(rows, RESULT_COLUMNS))


def _fmt(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, float):
        return f"{value:.6f}"
    return str(value)


def read_results(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a ``results.csv`` with their types (as ``result_rows`` made them, floats as written); one
    that is not a results file is refused in one line. Older files without the stage counts or the provenance
    columns are read (those columns empty)."""
    required = [c for c in RESULT_COLUMNS if c not in OPTIONAL_COLUMNS]
    rows = read_table(path, required, INTEGER_COLUMNS, FLOAT_COLUMNS, OPTIONAL_FLOAT_COLUMNS)
    return [{**{c: "" for c in OPTIONAL_COLUMNS}, **row} for row in rows]
