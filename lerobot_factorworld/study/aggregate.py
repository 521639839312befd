"""Aggregation of ``results.csv`` rows: one named selector per quantity the report shows, each called by
both the table and the figure that show it (so the two always agree on which rows they average).

Every selector averages over tasks (and any column not grouped by) per seed, then gives the mean,
standard error and number of seeds per group (:func:`summary`).
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence

from ..protocol.conditions import PAIR_SEPARATOR
from .metrics import interaction, mean_se, pair_metric
from .plan import DEFAULT_WIDTHS

Stats = dict[tuple, tuple[float, float, int]]  # group -> (mean over seeds, SE over seeds, number of seeds)


def per_seed(rows: Iterable[dict], value: str, keys: Sequence[str]) -> dict[tuple, dict[int, float]]:
    """``value`` averaged over tasks (and any column not in ``keys``), per group of ``keys`` and seed."""
    acc: dict[tuple, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        v = row[value]
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        acc[tuple(row[k] for k in keys)][row["seed"]].append(float(v))
    return {g: {s: sum(vs) / len(vs) for s, vs in seeds.items()} for g, seeds in acc.items()}


def summary(rows: Iterable[dict], value: str, keys: Sequence[str]) -> Stats:
    """Per group: (mean over seeds, standard error over seeds, number of seeds)."""
    return {g: (*mean_se(list(s.values())), len(s)) for g, s in per_seed(rows, value, keys).items()}


def main_grid(rows: Iterable[dict]) -> list[dict]:
    """The rows of the main grid (default sampling widths; not the radius sweep's extra runs)."""
    return [r for r in rows if r["widths"] == DEFAULT_WIDTHS]


# --- one selector per table and figure ------------------------------------------------------------


def gap_per_factor_and_n(rows: Sequence[dict]) -> Stats:
    """Gap per (method, condition, N), main grid: the gap table and ``gap_vs_n.png``."""
    return summary(main_grid(rows), "gap", ["method", "condition", "n_train_envs"])


def success_per_condition_and_n(rows: Sequence[dict]) -> Stats:
    """Success rate per (method, condition, N), main grid: the success-rate table and ``success_rates.png``."""
    return summary(main_grid(rows), "success_rate", ["method", "condition", "n_train_envs"])


def gap_per_factor(rows: Sequence[dict], factors: Sequence[str]) -> Stats:
    """Gap per (method, single factor of ``factors``) over N, main grid: the factor-ordering table (its
    first method) and ``methods.png``."""
    single = [r for r in main_grid(rows) if r["condition"] in factors]
    return summary(single, "gap", ["method", "condition"])


def radius_rows(rows: Sequence[dict], radius_factors: Sequence[str]) -> list[dict]:
    """The single-factor rows of the radius sweep's factors (every width, the main grid's included)."""
    return [r for r in rows if r["radius_m"] is not None and r["condition"] in radius_factors]


def gap_per_radius(rows: Sequence[dict], radius_factors: Sequence[str], per_n: bool = False) -> Stats:
    """Gap per (method, factor, radius) of the radius sweep's factors, over N (the radius table) or per
    N (``per_n``: ``gap_vs_radius.png``, keys (method, factor, N, radius))."""
    swept = radius_rows(rows, radius_factors)
    keys = ["method", "condition", "n_train_envs", "radius_m"] if per_n else ["method", "condition", "radius_m"]
    return summary(swept, "gap", keys)


def pair_rows(rows: Sequence[dict]) -> list[dict]:
    """Pair metric and interaction per method x task x N x seed x pair (main grid): the pairs table and
    ``pairs.png``."""
    index = {(r["method"], r["task"], r["n_train_envs"], r["seed"], r["condition"]): r for r in main_grid(rows)}
    out = []
    for key, row in index.items():
        if row["n_factors"] != 2:
            continue
        a, b = row["condition"].split(PAIR_SEPARATOR)
        ra, rb = index.get((*key[:4], a)), index.get((*key[:4], b))
        if ra is None or rb is None:
            continue
        out.append(
            {
                "method": key[0],
                "task": key[1],
                "n_train_envs": key[2],
                "seed": key[3],
                "pair": row["condition"],
                "pair_metric": pair_metric(row["success_rate"], ra["success_rate"], rb["success_rate"]),
                "interaction": interaction(row["gap"], ra["gap"], rb["gap"]),
            }
        )
    return out


def factor_ordering(rows: Sequence[dict], method: str, factors: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Mean gap (over N, tasks; mean and SE over seeds) per single factor of the main grid, for ``method``."""
    stats = gap_per_factor(rows, factors)
    return {f: stats[(method, f)][:2] for f in factors if (method, f) in stats}
