"""Evaluation conditions of a study: the training environments and, per shifted factor (or pair),
test environments that copy them with that factor re-drawn from the held-out split."""

from __future__ import annotations

from collections.abc import Sequence

from ..factors.registry import check_factor_names
from ..factors.sampling import SamplingOptions, sample_configs, shift_configs
from ..factors.values import SceneConfig

TRAIN_SUITE = "train"
PAIR_SEPARATOR = "+"


def parse_shift(shift: str) -> tuple[str, ...]:
    """``"camera_pos"`` -> one factor; ``"light+distractors"`` -> a pair."""
    factors = tuple(part.strip() for part in shift.split(PAIR_SEPARATOR) if part.strip())
    check_factor_names(factors)
    if not 1 <= len(factors) <= 2 or len(set(factors)) != len(factors):
        raise ValueError(f"a shift names one factor or a pair of distinct factors joined by '+', got {shift!r}")
    return factors


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
    """``{"train": [...], "<factor>": [...], "<a>+<b>": [...]}`` for one task."""
    train = (
        list(train_configs)
        if train_configs
        else sample_configs(task, n_train_envs, seed, "train", train_factors, options)
    )
    suites = {TRAIN_SUITE: train}
    for k, shift in enumerate(shifts):
        factors = parse_shift(shift)
        suites[PAIR_SEPARATOR.join(factors)] = shift_configs(train, factors, n_test_envs, seed + 1 + k, "eval", options)
    return suites
