"""The seed-level bootstrap behind every summary's interval, and its percentile interval.

Why two levels: a training seed is one dataset and one checkpoint per task and N, so its cells move together;
within a cell, episodes are the noise. Each replicate resamples the seeds, then each drawn cell's episodes (a
two-stage, cluster bootstrap: Davison & Hinkley (1997), "Bootstrap Methods and their Application", section 3.8).
Draws are seeded by what a cell is, so one cell gets the same replicates in every table that holds it.

Reference for the resampling and the percentile interval: Efron & Tibshirani (1993), "An Introduction to the
Bootstrap", chapters 6 and 13 (>= 1000 resamples for percentile intervals).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Hashable, Sequence

import numpy as np

BOOTSTRAP_RESAMPLES = 2000  # resamples per interval (Efron & Tibshirani 1993: >= 1000 for percentile intervals)
BOOTSTRAP_SEED = 0  # every interval restarts numpy's PCG64 from this seed: a report is the same on every rebuild
BOOTSTRAP_CHUNK = 200  # resamples drawn (and held in memory) at a time


def seed_bootstrap(
    rates: np.ndarray,
    episodes: np.ndarray,
    statistic: Callable[[np.ndarray, np.ndarray], np.ndarray],
    n_boot: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
    seed_ids: Sequence[Hashable] | None = None,
    cell_ids: Sequence[Hashable] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Point estimate and ``n_boot`` bootstrap replicates of ``statistic``, resampling seeds then episodes (a
    two-stage bootstrap: Davison & Hinkley 1997, 3.8; Efron & Tibshirani 1993, ch. 6).

    ``rates`` and ``episodes`` are (S, C): cell ``c``'s success rate and episode count for training seed
    ``s`` (rate NaN: no such cell; episodes 0: count unknown, the rate is kept as it is). Each replicate
    draws S seeds with replacement (a training seed is one dataset and one checkpoint per task and N, so
    its cells move together), then resamples each drawn cell's episodes with replacement: its successes
    are Binomial(episodes, rate), which is what resampling a cell's own episodes gives. A seed drawn twice
    gets two independent episode resamples. Train and shifted cells are resampled independently (only
    their counts are in ``results.csv``), which ignores the positive correlation of paired episodes and
    so widens the intervals of gaps.

    With ``seed_ids`` (the training seeds, S) and ``cell_ids`` (what each column is, C), the draws depend on
    identities, not positions: the seeds are drawn from a generator of ``seed`` and the seeds' values, each
    column's episodes from one of ``seed`` and its cell's identity. A cell then gets the same replicates in
    every table that holds it with the same training seeds, whatever the other columns (one interval per
    cell); without them, one generator draws everything in column order.

    ``statistic(rates, episodes)`` maps (B, S, C) arrays to (B, ...); the point estimate is its value on
    the data itself. Returns (point (...), replicates (n_boot, ...)); deterministic for a given ``seed``.
    """
    rates = np.asarray(rates, dtype=float)
    episodes = np.asarray(episodes, dtype=float)
    if rates.shape != episodes.shape or rates.ndim != 2:
        raise ValueError(f"rates and episodes must both be (seeds, cells), got {rates.shape} and {episodes.shape}")
    point = np.asarray(statistic(rates[None], episodes[None]))[0]
    n_seeds = rates.shape[0]
    if cell_ids is not None:
        return point, _identified_replicates(rates, episodes, statistic, n_boot, seed, seed_ids, cell_ids)
    rng = np.random.default_rng(seed)
    out = []
    for start in range(0, n_boot, BOOTSTRAP_CHUNK):
        b = min(BOOTSTRAP_CHUNK, n_boot - start)
        idx = rng.integers(0, n_seeds, size=(b, n_seeds))
        r, n = rates[idx], episodes[idx]
        known = (n > 0) & ~np.isnan(r)
        k = rng.binomial(np.where(known, n, 0).astype(np.int64), np.where(known, r, 0.0).clip(0.0, 1.0))
        out.append(np.asarray(statistic(np.where(known, k / np.where(known, n, 1.0), r), n)))
    return point, np.concatenate(out)


def identity_seed(identity: Hashable) -> int:
    """A 64-bit seed from what a thing is (the first 8 bytes of the SHA-256 of its ``repr``, FIPS 180-4), the same
    on every machine and Python run (unlike ``hash``)."""
    return int.from_bytes(hashlib.sha256(repr(identity).encode()).digest()[:8], "little")


def _identified_replicates(
    rates: np.ndarray,
    episodes: np.ndarray,
    statistic: Callable[[np.ndarray, np.ndarray], np.ndarray],
    n_boot: int,
    seed: int,
    seed_ids: Sequence[Hashable] | None,
    cell_ids: Sequence[Hashable],
) -> np.ndarray:
    """:func:`seed_bootstrap`'s replicates drawn by identity: the seed draws from (``seed``, the seeds' values),
    each column's episode draws from (``seed``, its cell's identity)."""
    n_seeds, n_cells = rates.shape
    if len(cell_ids) != n_cells or (seed_ids is not None and len(seed_ids) != n_seeds):
        raise ValueError(f"{len(cell_ids)} cell ids for {n_cells} columns, or seed ids not one per seed")
    seeds = tuple(range(n_seeds)) if seed_ids is None else tuple(seed_ids)
    idx = np.random.default_rng([seed, identity_seed(seeds)]).integers(0, n_seeds, size=(n_boot, n_seeds))
    r, n = rates[idx], episodes[idx]  # (B, S, C)
    known = (n > 0) & ~np.isnan(r)
    k = np.zeros(r.shape)
    for c, cell in enumerate(cell_ids):
        rng = np.random.default_rng([seed, identity_seed(cell)])
        k[..., c] = rng.binomial(np.where(known[..., c], n[..., c], 0).astype(np.int64),
                                 np.where(known[..., c], r[..., c], 0.0).clip(0.0, 1.0))  # fmt: skip
    resampled = np.where(known, k / np.where(known, n, 1.0), r)
    out = [
        np.asarray(statistic(resampled[start : start + BOOTSTRAP_CHUNK], n[start : start + BOOTSTRAP_CHUNK]))
        for start in range(0, n_boot, BOOTSTRAP_CHUNK)
    ]
    return np.concatenate(out)


def percentile_interval(
    replicates: np.ndarray, level: float = 0.95, min_defined: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Efron & Tibshirani's (1993, ch. 13) percentile interval over axis 0, NaN replicates left out; NaN where
    fewer than ``min_defined`` of the replicates are defined (the statistic is undefined too often to have an
    interval)."""
    x = np.asarray(replicates, dtype=float)
    defined = np.isfinite(x)
    enough = defined.mean(axis=0) >= min_defined
    alpha = (1 - level) / 2
    filled = np.where(defined, x, np.nan)
    filled = np.where(enough, filled, 0.0)  # columns without an interval: any value, masked below
    lo = np.nanquantile(filled, alpha, axis=0)
    hi = np.nanquantile(filled, 1 - alpha, axis=0)
    return np.where(enough, lo, np.nan), np.where(enough, hi, np.nan)
