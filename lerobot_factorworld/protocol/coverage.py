"""How the seeded episodes of an evaluation cover a condition's environments, and a vector env that says so.

Episode ``i`` of an evaluation started at seed ``s`` is reset with seed ``s + i`` and runs in environment
``(s + i) % n`` (:func:`~lerobot_factorworld.envs.factor_env.env_index_for_seed`): a multiple of ``n``
episodes visits every environment equally; anything else is reported (:func:`coverage`, and at the end of
every ``lerobot-eval`` run by :class:`CoverageLog`).
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

from ..envs.factor_env import env_index_for_seed

logger = logging.getLogger(__name__)


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
