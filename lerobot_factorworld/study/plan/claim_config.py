"""A claim of the paper that a study tests, as data (``StudyConfig.claims``): one predicate of a few kinds,
with the paper's place for it. The verdicts are computed from the study's intervals (``claims.py``), never
written by hand.

Kinds (the paper's direction in brackets):

- ``gap_opens``: ``factors``' mean gap is above 0 (one factor, or a group's mean);
- ``gap_exceeds``: ``factors[0]``'s mean gap exceeds ``factors[1]``'s;
- ``ordering``: ``tiers``, hardest first: every factor of a tier has a larger gap than every factor of a later tier
  (one comparison per cross-tier pair);
- ``trend``: ``factors``' mean gap ``shrinks`` or ``grows`` (``direction``) ``over`` N (the gap at the largest N
  minus the gap at the smallest) or the sampling ``radius`` (the least-squares slope);
- ``pair``: ``pair``'s metric (P_A+B - P_min) / P_min is ``within`` ±``tolerance`` of 0 (it adds up) or below
  -``tolerance`` (``synergistic``);
- ``method_shrinks``: ``method``'s mean gap over ``factors`` is smaller than ``baseline``'s.

``method`` defaults to the study's first method, ``task`` to every task (pooled).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ...core.checks import check_choice
from ..paper import PAPER_PAIR_TOLERANCE

CLAIM_KINDS = ("gap_opens", "gap_exceeds", "ordering", "trend", "pair", "method_shrinks")
TREND_OVER = ("n", "radius")
TREND_DIRECTIONS = ("shrinks", "grows")
PAIR_RELATIONS = ("within", "synergistic")


@dataclass
class ClaimConfig:
    """One claim of the paper (the kinds: the module docstring). Checked by :meth:`validate` against its study's
    methods, tasks, factors and pairs, which a claim alone does not know.

    Args:
        kind: One of :data:`CLAIM_KINDS`.
        text: The claim in words (the claims table prints it).
        source: Where the paper makes it: section, figure or text.
        method: The method it is about (``None``: the study's first).
        task: The task it is about (``None``: every task, pooled).
        factors: The factors it names (``gap_opens``, ``gap_exceeds``, ``trend``, ``method_shrinks``).
        tiers: ``ordering``'s tiers of factors, hardest first.
        over: ``trend``'s axis, ``n`` or ``radius``.
        direction: ``trend``'s direction, ``shrinks`` or ``grows``.
        pair: ``pair``'s condition, ``a+b``.
        relation: ``pair``'s relation, ``within`` ±``tolerance`` of 0 or ``synergistic`` (below -``tolerance``).
        tolerance: ``pair``'s band around 0.
        baseline: ``method_shrinks``'s other method.
    """

    kind: str = ""
    text: str = ""
    source: str = ""
    method: str | None = None
    task: str | None = None
    factors: list[str] = field(default_factory=list)
    tiers: list[list[str]] = field(default_factory=list)
    over: str = "n"
    direction: str = "shrinks"
    pair: str | None = None
    relation: str = "within"
    tolerance: float = PAPER_PAIR_TOLERANCE
    baseline: str | None = None

    def validate(self, methods: list[str], tasks: list[str], factors: list[str], pairs: list[str]) -> None:
        """Raise naming the valid choices: a claim names only what its study has."""
        check_choice("claim kind", self.kind, CLAIM_KINDS)
        if not self.text or not self.source:
            raise ValueError(f"a {self.kind} claim needs its text and its source in the paper (text:, source:)")
        for name in (self.method, self.baseline):
            if name is not None:
                check_choice("claim method", name, methods)
        if self.task is not None:
            check_choice("claim task", self.task, tasks)
        named = [f for tier in self.tiers for f in tier] + list(self.factors)
        for factor in named:
            check_choice(f"factor of the claim {self.text!r}", factor, factors)
        needs = {
            "gap_opens": len(self.factors) >= 1,
            "gap_exceeds": len(self.factors) == 2,
            "ordering": len([t for t in self.tiers if t]) >= 2,
            "trend": len(self.factors) >= 1,
            "pair": self.pair is not None,
            "method_shrinks": len(self.factors) >= 1 and self.baseline is not None,
        }
        if not needs[self.kind]:
            raise ValueError(
                f"claim {self.text!r}: a {self.kind} claim needs "
                + {
                    "gap_opens": "factors: [factor, ...]",
                    "gap_exceeds": "factors: [harder, easier]",
                    "ordering": "tiers: [[hardest, ...], [next, ...], ...] (two or more)",
                    "trend": "factors: [factor, ...]",
                    "pair": "pair: a+b",
                    "method_shrinks": "factors: [factor, ...] and baseline: <method>",
                }[self.kind]
            )
        if self.kind == "trend":
            check_choice("claim over", self.over, TREND_OVER)
            check_choice("claim direction", self.direction, TREND_DIRECTIONS)
        if self.kind == "pair":
            check_choice("claim relation", self.relation, PAIR_RELATIONS)
            check_choice("claim pair", self.pair, pairs)
