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
  reported (:func:`~.coverage.coverage`, and at the end of every ``lerobot-eval`` run by
  :class:`~.coverage.CoverageLog`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence

from ..factors.registry import check_factor_names
from ..factors.values import SceneConfig
from ..families import TaskFamily, all_families, condition_family, family_of
from .sampling import SamplingOptions, sample_configs, shift_configs

TRAIN_SUITE = "train"
PAIR_SEPARATOR = "+"
SHIFT_SEED_OFFSET = 1  # test environments draw with seed + 1 (and the held-out split): never the training values


def parse_shift(shift: str) -> tuple[str, ...]:
    """``"camera_pos"`` -> one factor; ``"light+distractors"`` -> a pair; a task family's own condition
    (the pick family's ``held_out_phrasings``, ``held_out_objects``) stands alone."""
    factors = tuple(part.strip() for part in shift.split(PAIR_SEPARATOR) if part.strip())
    if len(factors) == 1 and factors[0] in family_conditions():
        return factors
    check_factor_names(factors)
    if not 1 <= len(factors) <= 2 or len(set(factors)) != len(factors):
        raise ValueError(f"a shift names one factor or a pair of distinct factors joined by '+', got {shift!r}")
    return factors


def shifted_factors(condition: str) -> tuple[str, ...]:
    """The factors a condition shifts (none for ``train``; a family's own condition counts as one)."""
    return () if condition == TRAIN_SUITE else tuple(condition.split(PAIR_SEPARATOR))


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
    suites = {TRAIN_SUITE: train}
    for shift in shifts:
        factors = parse_shift(shift)
        name = condition_name(factors)
        if name in suites:
            raise ValueError(f"condition {name!r} is listed twice")
        owner = condition_family(name)
        if owner is not None:  # a family's own condition (pick: held-out phrasings / objects)
            suites[name] = condition_configs(train, name, n_test_envs, seed + SHIFT_SEED_OFFSET, owner)
            continue
        suites[name] = shift_configs(train, factors, n_test_envs, seed + SHIFT_SEED_OFFSET, "eval", options)
    return suites


def fingerprint(configs: Sequence[SceneConfig], object_pos_width: str | None = None) -> str:
    """A short stable hash of a condition's environments (what a result row was measured on)."""
    payload = {"configs": [c.to_dict() for c in configs], "object_pos_width": object_pos_width or "default"}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


def family_conditions() -> tuple[str, ...]:
    """The evaluation conditions task families add to the factor shifts (pick: its language conditions)."""
    return tuple(c for family in all_families() for c in family.conditions)


def is_family_condition(condition: str) -> bool:
    return condition_family(condition) is not None


def check_condition(condition: str, tasks: Sequence[str]) -> None:
    """A family's condition applies to its tasks only (the error names the others)."""
    owner = condition_family(condition)
    if owner is None:
        raise ValueError(f"unknown condition {condition!r}; family conditions: {', '.join(family_conditions())}")
    owner.check_condition(condition, tasks)


def condition_configs(
    base: Sequence[SceneConfig], condition: str, n: int, seed: int, owner: TaskFamily | None = None
) -> list[SceneConfig]:
    """The ``n`` test environments of a family's condition, derived from training environments ``base``."""
    owner = owner or condition_family(condition) or family_of(base[0].task)
    return owner.condition_configs(base, condition, n, seed)
