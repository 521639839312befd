"""Evaluation conditions of a study, and the protocol that keeps their numbers honest.

A condition is ``train`` (the N training environments) or a shift: one factor, or a pair ``a+b``,
re-drawn from the held-out split on top of the training environments. The rules:

- The test environments of a condition depend only on the seed and the condition's factor names
  (every factor draws from its own RNG keyed by ``[seed, split, factor]``), never on which other
  conditions are listed: a pair ``a+b`` even reuses the values that conditions ``a`` and ``b`` got,
  so the pair metric compares like with like.
- Episode ``i`` of an evaluation started at seed ``s`` is reset with seed ``s + i`` (LeRobot's
  ``eval_policy`` does this whatever the batch size), which picks environment ``(s + i) % n``
  (:func:`~lerobot_factorworld.envs.factor_env.env_index_for_seed`) and the object's start. Train and
  shifted conditions therefore share object starts episode by episode (paired), and when
  ``n_test_envs`` is a multiple of N, test environment ``j`` derives from the training environment
  that the same episode sees in ``train``.
- ``episodes`` that are a multiple of ``n`` visit every environment equally; anything else is
  reported (:func:`coverage`, and at the end of every ``lerobot-eval`` run by :class:`CoverageLog`).
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from ..factors.registry import check_factor_names
from ..factors.sampling import SamplingOptions, sample_configs, shift_configs
from ..factors.values import SceneConfig

TRAIN_SUITE = "train"
PAIR_SEPARATOR = "+"
SHIFT_SEED_OFFSET = 1  # test environments draw with seed + 1 (and the held-out split): never the training values
DATASET_SIDECAR = "meta/factorworld.json"

logger = logging.getLogger(__name__)


def parse_shift(shift: str) -> tuple[str, ...]:
    """``"camera_pos"`` -> one factor; ``"light+distractors"`` -> a pair; a pick family's language
    condition (``held_out_phrasings``, ``held_out_objects``) stands alone."""
    from ..pick.sampling import CONDITIONS as LANGUAGE_CONDITIONS

    factors = tuple(part.strip() for part in shift.split(PAIR_SEPARATOR) if part.strip())
    if len(factors) == 1 and factors[0] in LANGUAGE_CONDITIONS:
        return factors
    check_factor_names(factors)
    if not 1 <= len(factors) <= 2 or len(set(factors)) != len(factors):
        raise ValueError(f"a shift names one factor or a pair of distinct factors joined by '+', got {shift!r}")
    return factors


def condition_name(factors: Sequence[str]) -> str:
    return PAIR_SEPARATOR.join(factors)


def evaluation_suites(
    task: str,
    n_train_envs: int,
    train_factors: Sequence[str],
    shifts: Sequence[str],
    n_test_envs: int,
    seed: int = 0,
    options: SamplingOptions | None = None,
    train_configs: Sequence[SceneConfig] | None = None,
) -> dict[str, list[SceneConfig]]:
    """``{"train": [...], "<factor>": [...], "<a>+<b>": [...]}`` for one task.

    Each shifted suite depends only on ``(seed, its factor names)`` and the training environments.
    """
    train = (
        list(train_configs)
        if train_configs
        else sample_configs(task, n_train_envs, seed, "train", train_factors, options)
    )
    from ..pick.sampling import CONDITIONS as LANGUAGE_CONDITIONS
    from ..pick.sampling import language_shift

    suites = {TRAIN_SUITE: train}
    for shift in shifts:
        factors = parse_shift(shift)
        name = condition_name(factors)
        if name in suites:
            raise ValueError(f"condition {name!r} is listed twice")
        if factors[0] in LANGUAGE_CONDITIONS:
            suites[name] = language_shift(train, name, n_test_envs, seed + SHIFT_SEED_OFFSET)
            continue
        suites[name] = shift_configs(train, factors, n_test_envs, seed + SHIFT_SEED_OFFSET, "eval", options)
    return suites


def fingerprint(configs: Sequence[SceneConfig], object_pos_width: str | None = None) -> str:
    """A short stable hash of a condition's environments (what a result row was measured on)."""
    payload = {"configs": [c.to_dict() for c in configs], "object_pos_width": object_pos_width or "default"}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


# --- coverage ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Coverage:
    """How the episodes of one evaluation spread over a condition's ``n_envs`` environments."""

    n_envs: int
    episodes: int
    visited: int
    min_visits: int
    max_visits: int

    @property
    def equal(self) -> bool:
        return self.visited == self.n_envs and self.min_visits == self.max_visits

    def describe(self, condition: str) -> str:
        if self.equal:
            return (
                f"{condition}: {self.episodes} episodes visit each of its {self.n_envs} environments {self.max_visits}x"
            )
        return (
            f"{condition}: {self.episodes} episodes visit {self.visited} of its {self.n_envs} environments "
            f"({self.min_visits}..{self.max_visits} visits each); use a multiple of {self.n_envs} episodes "
            "to weigh every environment equally"
        )


def coverage(seeds: Sequence[int], n_envs: int) -> Coverage:
    """Visits per environment for episodes reset with ``seeds``."""
    from ..envs.factor_env import env_index_for_seed

    counts = Counter(env_index_for_seed(s, n_envs) for s in seeds)
    visits = [counts.get(i, 0) for i in range(n_envs)]
    return Coverage(n_envs, len(seeds), sum(v > 0 for v in visits), min(visits), max(visits))


def reset_coverage(seeds: Sequence[int], n_envs: int, batch: int, condition: str) -> tuple[bool, str]:
    """(certainly unequal?, message) for the seeds a vector env of ``batch`` envs was reset with.

    ``lerobot-eval`` resets whole batches and scores only the first ``--eval.n_episodes`` episodes, so
    with ``batch > 1`` the last batch may hold up to ``batch - 1`` unscored (padding) episodes: the
    scored count is one of the last ``batch`` prefixes, and the message says so rather than claim a
    coverage the scored episodes may not have.
    """
    seeds = list(seeds)
    full = coverage(seeds, n_envs)
    if batch <= 1:
        return not full.equal, full.describe(condition)
    prefixes = range(max(1, len(seeds) - batch + 1), len(seeds) + 1)
    equal = [n for n in prefixes if coverage(seeds[:n], n_envs).equal]
    if len(equal) == len(prefixes):
        return False, full.describe(condition)
    if not equal:
        return True, full.describe(condition) + f" (whatever padding the last batch of {batch} held)"
    return False, (
        f"{condition}: {len(seeds)} episodes were reset in batches of {batch}; the scored ones visit its "
        f"{n_envs} environments equally only if --eval.n_episodes is one of {', '.join(map(str, equal))} "
        f"(a multiple of {n_envs})"
    )


class CoverageLog:
    """Mixin for a vector env: records the seeds it is reset with and reports coverage on close.

    ``lerobot-eval`` resets every batch with explicit seeds; when the episodes do not visit the
    condition's environments equally (fewer episodes than environments, or not a multiple), this says
    so in the log instead of silently weighing some environments more (:func:`reset_coverage`).
    """

    def setup_coverage(self, condition: str, n_envs: int) -> None:
        self._coverage_condition = condition
        self._coverage_n_envs = n_envs
        self._coverage_seeds: list[int] = []

    def reset(self, *, seed=None, options=None):  # noqa: D102 - gymnasium's signature
        if seed is not None and getattr(self, "_coverage_n_envs", None):
            self._coverage_seeds.extend([seed] if isinstance(seed, int) else [s for s in seed if s is not None])
        return super().reset(seed=seed, options=options)

    def close(self, **kwargs):
        seeds = getattr(self, "_coverage_seeds", None)
        if seeds:
            batch = int(getattr(self, "num_envs", 1))
            unequal, message = reset_coverage(seeds, self._coverage_n_envs, batch, self._coverage_condition)
            (logger.warning if unequal else logger.info)("factorworld coverage: " + message)
            self._coverage_seeds = []
        return super().close(**kwargs)


def checked_vector_env(vector_cls: type) -> type:
    """``vector_cls`` (Sync/AsyncVectorEnv) with :class:`CoverageLog` mixed in."""
    return _CHECKED.setdefault(vector_cls, type(f"Coverage{vector_cls.__name__}", (CoverageLog, vector_cls), {}))


_CHECKED: dict[type, type] = {}


# --- the training condition of a dataset --------------------------------------------------------


@dataclass(frozen=True)
class DatasetCondition:
    """What a Factor World dataset was collected in (its ``meta/factorworld.json``)."""

    root: str
    tasks: tuple[str, ...]
    n_envs: int
    factors: tuple[str, ...]
    seed: int
    sampling: SamplingOptions
    environments: tuple[SceneConfig, ...]

    def train_configs(self, task: str) -> list[SceneConfig]:
        configs = sorted((c for c in self.environments if c.task == task), key=lambda c: c.env_id)
        if not configs:
            raise ValueError(
                f"dataset {self.root} holds no environment of task {task!r}; its tasks: {', '.join(self.tasks)}"
            )
        return configs


def read_dataset_condition(root: str | Path) -> DatasetCondition:
    """The training environments and sampling settings a dataset was collected with."""
    path = Path(root) / DATASET_SIDECAR
    if not path.is_file():
        raise FileNotFoundError(
            f"{root} is not a Factor World dataset ({DATASET_SIDECAR} is missing); collect it with `factorworld collect`"
        )
    sidecar = json.loads(path.read_text())
    settings = sidecar["settings"]
    environments = tuple(
        SceneConfig.from_dict(c) for c in sidecar["environments"] if c.get("split", "train") == "train"
    )
    tasks = tuple(t.strip() for t in settings["task"].split(",") if t.strip())
    per_task = Counter(c.task for c in environments)
    return DatasetCondition(
        root=str(root),
        tasks=tasks,
        n_envs=max(per_task.values()) if per_task else int(settings["n_envs"]),
        factors=tuple(settings["factors"]),
        seed=int(settings["seed"]),
        sampling=SamplingOptions(**settings.get("sampling", {})),
        environments=environments,
    )


def check_against_dataset(dataset: DatasetCondition, requested: dict[str, Any]) -> None:
    """Refuse settings given explicitly (not ``None``) that disagree with what the dataset was collected with."""
    recorded = {
        "n_train_envs": dataset.n_envs,
        "train_factors": sorted(dataset.factors),  # each factor has its own RNG: the order does not matter
        "seed": dataset.seed,
        "sampling": dataset.sampling,
    }
    requested = {k: sorted(v) if k == "train_factors" and v is not None else v for k, v in requested.items()}
    wrong = [
        f"{key}={value!r} but the dataset has {recorded[key]!r}"
        for key, value in requested.items()
        if value is not None and _normalise(value) != _normalise(recorded[key])
    ]
    if wrong:
        raise ValueError(
            f"the training condition disagrees with dataset {dataset.root}: {'; '.join(wrong)}. "
            "Leave these settings out to take them from the dataset."
        )


def _normalise(value: Any) -> Any:
    if isinstance(value, SamplingOptions):
        return json.dumps(asdict(value), sort_keys=True)
    if isinstance(value, (list, tuple)):
        return [_normalise(v) for v in value]
    return value
