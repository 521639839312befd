"""``eval.episodes=auto``: evaluate in blocks of paired seeds and stop each shifted condition once decided.

Why: a profile's factors differ in how many episodes they need (a gap of +0.44 is resolved in twenty paired
episodes, a gap of +0.01 not in a thousand), and stopping on a fixed-n interval looked at after every block
inflates false findings. Here every shifted condition carries an anytime-valid confidence sequence for its
paired gap (``stats/confseq.py``: the betting construction of Waudby-Smith and Ramdas), corrected for the number
of conditions by **Bonferroni**: with ``k`` shifted conditions each sequence is at level ``1 - alpha / k``, so with
probability at least ``1 - alpha`` every condition's interval holds at every look, whatever the stopping.

After each block (the same reset seeds in every condition) a still-running condition stops when its interval

- excludes 0 (``decided``: a gap, with its sign),
- lies inside ``[-tolerance, +tolerance]`` (``within tolerance``: no gap larger than that), or
- has reached ``max_episodes`` (``budget``: neither);

``train`` runs as long as any condition it pairs with does. The rule is a deterministic function of the outcomes
in seed order, so the same seeds give the same episodes and the same stopping points. Success rates get
sequences of their own (Bonferroni over the ``k + 1`` conditions), for the report. The rule's computation on the
outcomes is :func:`lerobot_factorworld.stats.stopping.apply_rule`; this module holds its settings, as a study
config and a step key state them, and what a run records of each condition's stop.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from ..stats.confseq import mean_cs
from ..stats.multitest import BONFERRONI, rank_levels
from ..stats.stopping import REASONS, Stops, apply_rule

AUTO = "auto"  # eval.episodes' value that asks for this rule
PAIRED = "paired"  # train's reason: it ran as long as the condition that ran longest
CONSTRUCTION = "betting-hedged-bonferroni"  # what the rule computes: in every step key that uses it
INTERVAL_LABEL = "anytime-valid"


@dataclass(frozen=True)
class StopRule:
    """The settings of the rule (all in an evaluation's key when it is used).

    Attributes:
        block: Paired episodes added to every running condition between two looks.
        max_episodes: Episodes at which a condition stops undecided (a multiple of ``block``).
        tolerance: Half-width of the gap band a condition may stop inside (``within tolerance``).
        confidence: Simultaneous level of the gap intervals (all conditions, all looks).
    """

    block: int
    max_episodes: int
    tolerance: float
    confidence: float = 0.95

    def __post_init__(self) -> None:
        if self.block < 1 or self.max_episodes < self.block or self.max_episodes % self.block:
            raise ValueError(
                f"eval.max_episodes={self.max_episodes} must be a positive multiple of eval.block={self.block}"
            )
        if not 0 <= self.tolerance < 1:
            raise ValueError(f"eval.tolerance must be in [0, 1), got {self.tolerance}")
        if not 0 < self.confidence < 1:
            raise ValueError(f"eval.confidence must be in (0, 1), got {self.confidence}")

    @property
    def alpha(self) -> float:
        return 1.0 - self.confidence

    def gap_alpha(self, k: int) -> float:
        """Each of ``k`` gap sequences' error (Bonferroni: ``alpha / k``)."""
        return rank_levels(max(1, k), self.alpha, BONFERRONI)[0]

    def success_alpha(self, k: int) -> float:
        """Each success-rate sequence's error, over ``train`` and ``k`` shifted conditions (Bonferroni)."""
        return rank_levels(k + 1, self.alpha, BONFERRONI)[0]

    def to_dict(self) -> dict:
        return {**asdict(self), "construction": CONSTRUCTION}

    def apply(
        self, train: np.ndarray, shifted: np.ndarray, k: int | None = None, grid: np.ndarray | None = None
    ) -> Stops:
        """The rule on outcomes in seed order (:func:`~lerobot_factorworld.stats.stopping.apply_rule`): ``train``
        ``(*batch, T)``, ``shifted`` ``(*batch, k, T)``; ``k``: the conditions the correction counts (default:
        ``shifted``'s); ``grid``: the candidate means (default ``stats.confseq``'s)."""
        k_here = np.shape(shifted)[-2]
        return apply_rule(
            train, shifted, block=self.block, max_episodes=self.max_episodes, tolerance=self.tolerance,
            alpha=self.gap_alpha(k or k_here), grid=grid,
        )  # fmt: skip

    @classmethod
    def from_dict(cls, data: Mapping) -> StopRule:
        return cls(int(data["block"]), int(data["max_episodes"]), float(data["tolerance"]), float(data["confidence"]))


@dataclass(frozen=True)
class ConditionStop:
    """One condition's stop, as reports and step results state it."""

    condition: str
    episodes: int
    reason: str  # REASONS' values, PAIRED for train, "running" while undecided within the data
    gap: float | None  # None for train
    gap_low: float | None
    gap_high: float | None
    success_rate: float
    success_low: float
    success_high: float

    def to_dict(self) -> dict:
        return asdict(self)


def decide(train: Sequence[bool], shifted: Mapping[str, Sequence[bool]], rule: StopRule) -> dict[str, ConditionStop]:
    """Each condition's stop, ``train`` first, from its outcomes in seed order (``train``'s the longest; a shifted
    condition's beyond its own stop are ignored, as a run never has them)."""
    names = list(shifted)
    k = len(names)
    total = len(train)
    if not names:
        raise ValueError("the rule needs at least one shifted condition")
    padded = np.zeros((k, total))
    for i, name in enumerate(names):
        outcomes = np.asarray(shifted[name], dtype=float)[:total]
        padded[i, : len(outcomes)] = outcomes
    lengths = {name: min(len(shifted[name]), total) for name in names}
    stops = rule.apply(np.asarray(train, dtype=float), padded)
    out: dict[str, ConditionStop] = {}
    s_alpha = rule.success_alpha(k)
    for i, name in enumerate(names):
        n = int(stops.episodes[i])
        if n > lengths[name]:
            raise ValueError(f"condition {name!r} has {lengths[name]} outcomes but the rule ran it to {n}")
        code = int(stops.reason[i])
        outcomes = padded[i, :n]
        s_low, s_high = mean_cs(outcomes, s_alpha)
        out[name] = ConditionStop(
            name, n, REASONS.get(code, "running"), float(stops.gap[i]), float(stops.low[i]), float(stops.high[i]),
            float(outcomes.mean()) if n else float("nan"), s_low, s_high,
        )  # fmt: skip
    n_train = max(c.episodes for c in out.values())
    t_low, t_high = mean_cs(np.asarray(train, float)[:n_train], s_alpha)
    head = ConditionStop("train", n_train, PAIRED, None, None, None, float(np.mean(train[:n_train])), t_low, t_high)
    return {"train": head, **out}


def running(stops: Mapping[str, ConditionStop]) -> list[str]:
    """The shifted conditions the rule has not stopped yet."""
    return [name for name, stop in stops.items() if stop.reason == "running"]
