"""A stopping rule on paired sequences: look after every block, stop a sequence once its gap's confidence sequence
decides it.

Why it may stop on the data: the interval is a confidence sequence (:mod:`.confseq`), valid at every look at once,
so it is valid at a data-dependent stopping time too (Howard, Ramdas, McAuliffe, Sekhon (2021), "Time-uniform,
nonparametric, nonasymptotic confidence sequences", Annals of Statistics 49(2), section 2; the construction is
Waudby-Smith & Ramdas (2024), "Estimating means of bounded random variables by betting", JRSS-B 86(1)).

After each block a still-running sequence stops when its interval

- excludes 0 (``DECIDED``: a gap, with its sign),
- lies inside ``[-tolerance, +tolerance]`` (``WITHIN_TOLERANCE``: no gap larger than that), or
- has reached ``max_episodes`` (``BUDGET``: neither).

The rule is a deterministic function of the outcomes in order. Which error each sequence gets (a correction over
several sequences) is the caller's choice: ``alpha`` here is one sequence's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .confseq import BettingCS

RUNNING, DECIDED, WITHIN_TOLERANCE, BUDGET = 0, 1, 2, 3
REASONS = {DECIDED: "decided", WITHIN_TOLERANCE: "within tolerance", BUDGET: "budget"}


@dataclass(frozen=True)
class Stops:
    """Where the rule stopped each sequence: arrays of shape ``(*batch, k)``."""

    episodes: np.ndarray  # paired episodes used (the data's length where still running)
    reason: np.ndarray  # RUNNING, DECIDED, WITHIN_TOLERANCE or BUDGET
    gap: np.ndarray  # mean paired gap over those episodes
    low: np.ndarray  # the anytime-valid interval at the stop
    high: np.ndarray


def apply_rule(
    train: np.ndarray,
    shifted: np.ndarray,
    *,
    block: int,
    max_episodes: int,
    tolerance: float,
    alpha: float,
    grid: np.ndarray | None = None,
) -> Stops:
    """The rule on outcomes in seed order (Waudby-Smith & Ramdas 2024's sequence, stopped as Howard et al. 2021
    allow): ``train`` of shape ``(*batch, T)``, ``shifted`` ``(*batch, k, T)`` (``T`` the episodes run so far, a
    multiple of ``block``, or all there are: a replay caps the budget there). A sequence not stopped within
    ``T < max_episodes`` is ``RUNNING``. ``alpha``: each gap sequence's error; ``grid``: the candidate means
    (default :mod:`.confseq`'s; simulations use a coarser one, whose bounds are stepped outwards to it)."""
    train = np.asarray(train, dtype=float)
    shifted = np.asarray(shifted, dtype=float)
    batch, k_here, total = shifted.shape[:-2], shifted.shape[-2], shifted.shape[-1]
    if train.shape != (*batch, total):
        raise ValueError(f"train outcomes of shape {train.shape} do not pair with shifted ones {shifted.shape}")
    d = train[..., None, :] - shifted  # (*batch, k, T) in {-1, 0, 1}
    cs = BettingCS(alpha, (*batch, k_here), *(() if grid is None else (grid,)))
    shape = (*batch, k_here)
    episodes, reason = np.zeros(shape, dtype=int), np.full(shape, RUNNING)
    low, high, gap = np.full(shape, -1.0), np.full(shape, 1.0), np.zeros(shape)
    budget = min(max_episodes, total)
    for end in range(block, budget + block, block):
        end = min(end, budget)
        cs.extend((d[..., cs.t : end] + 1.0) / 2.0)
        lo, hi = cs.bounds()
        lo, hi = 2.0 * lo - 1.0, 2.0 * hi - 1.0
        running = reason == RUNNING
        now = np.where(
            (lo > 0) | (hi < 0),
            DECIDED,
            np.where((lo >= -tolerance) & (hi <= tolerance), WITHIN_TOLERANCE, RUNNING),
        )
        if end >= max_episodes:
            now = np.where(now == RUNNING, BUDGET, now)
        stop = running & (now != RUNNING)
        reason = np.where(stop, now, reason)
        low, high = np.where(running, lo, low), np.where(running, hi, high)
        episodes = np.where(running, end, episodes)
        gap = np.where(running, d[..., :end].mean(axis=-1), gap)
    return Stops(episodes, reason, gap, low, high)
