"""Multiple testing: which of ``m`` hypotheses to reject at a familywise error ``alpha``, as a pure function of
their p-values, the method named (as statsmodels' ``multipletests``).

Why apart from any verdict: the correction is a rule about ranks and levels; what counts as a rejection (a p-value
below its level, or an interval at that level excluding a threshold) is the caller's. :func:`rank_levels` and
:func:`step_down` are the two halves a caller with its own rejections uses; :func:`multipletests` puts them
together for p-values.

References: Holm (1979), "A simple sequentially rejective multiple test procedure", Scandinavian Journal of
Statistics 6(2); Bonferroni's correction as Dunn (1961), "Multiple comparisons among means", JASA 56(293).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

HOLM, BONFERRONI = "holm", "bonferroni"
METHODS = (HOLM, BONFERRONI)


@dataclass(frozen=True)
class MultipleTests:
    """The correction's outcome, each array in the order the p-values were given.

    Args:
        reject: Whether each hypothesis is rejected.
        pvals_corrected: The adjusted p-values (reject where at most ``alpha``).
        levels: The level each p-value was compared with.
    """

    reject: np.ndarray
    pvals_corrected: np.ndarray
    levels: np.ndarray


def rank_levels(m: int, alpha: float, method: str) -> tuple[float, ...]:
    """The level the k-th smallest of ``m`` p-values is tested at (k = 0 first): Holm's (1979) ``alpha / (m - k)``,
    or Bonferroni's (Dunn 1961) ``alpha / m`` for every one."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    return tuple(alpha / (m - k) if method == HOLM else alpha / m for k in range(m))


def step_down(passed: Sequence[bool]) -> list[bool]:
    """Holm's (1979) step-down, on hypotheses in the order tested (smallest p-value first): each one that passed
    its own level is rejected only if every one before it was; once one is kept, none after it is rejected."""
    out, going = [], True
    for ok in passed:
        going = going and bool(ok)
        out.append(going)
    return out


def multipletests(pvals: Sequence[float], alpha: float = 0.05, method: str = HOLM) -> MultipleTests:
    """Reject at familywise error ``alpha`` by Holm's (1979) step-down or Bonferroni's (Dunn 1961) single step, as
    statsmodels' ``multipletests(pvals, alpha, method)``: ties keep their given order."""
    p = np.asarray(pvals, dtype=float)
    if p.ndim != 1 or np.any(~((p >= 0) & (p <= 1))):
        raise ValueError(f"p-values must be a vector of numbers in [0, 1], got {pvals!r}")
    m = len(p)
    order = np.argsort(p, kind="stable")
    levels = np.array(rank_levels(m, alpha, method), dtype=float)
    passed = p[order] <= levels
    if method == HOLM:
        reject = np.array(step_down(passed.tolist()), dtype=bool)
        corrected = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order])) if m else p
    else:
        reject, corrected = passed, np.minimum(1.0, m * p[order])
    back = np.empty(m, dtype=int)
    back[order] = np.arange(m)
    return MultipleTests(reject[back], corrected[back], levels[back])
