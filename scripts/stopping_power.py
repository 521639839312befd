"""When ``eval.episodes=auto`` saves episodes: its stopping rule (lerobot_factorworld/stats/stopping.py, its
settings in study/sequential.py) on simulated profiles of one checkpoint, against a fixed number of episodes per condition equal to its budget, and
what no valid test can do with fewer episodes.

Four parts:

1. The floor. A non-randomised test that declares each sign at ``alpha/(2k)`` (as this rule and a corrected
   two-sided interval do) cannot declare a gap from ``n`` paired episodes that all favour train unless
   ``2**-n <= alpha/(2k)``: a condition with no gap, whose paired differences are +1 or -1 with probability 1/2
   each, shows ``n`` differences of +1 with probability ``2**-n``. With 7 factors at 95% that is 9 episodes. The
   rule's own floor (the first look at which differences that are all +1 decide) is printed beside it.
2. The power bound. For independent paired episodes whose discordant pairs (train succeeds and the shift fails,
   or the reverse) come at rates ``p10`` and ``p01``, no test valid at ``alpha/k`` for a gap of 0 (randomised or
   not, sequential or fixed-n) declares a gap (either sign) within ``n`` episodes more often than the most powerful
   test (Neyman-Pearson) of the one null that keeps the ties and splits the discordant rate evenly: a valid test
   holds its level there too. Printed at ``n`` = 10 and 20 for the simulation's rates and for the rates of F1's
   committed episodes (bc, its 15 cells pooled: docs/results/f1_ordering/episodes.parquet).
3. The bound per cell. F1's committed cells (method, task, seed) differ: each cell's bound at 10 episodes from its
   own rates (estimated from its 20 paired episodes), summed over the cell's factors, is the most decisions any
   test valid at ``alpha/k`` can be expected to make at half F1's episodes, if those rates were the truth. Printed
   beside the decisions of Newcombe's paired interval on all 20 episodes, uncorrected and corrected.
4. Profiles simulated as the tests simulate them (tests/test_sequential.py): each condition's outcome of an
   episode seed comes, with probability ``--copula``, from one latent difficulty of that seed shared by every
   condition, else from the condition's own draw (so train and a shift share it with probability copula**2).
   The default train success rate and gaps are F1's bc means (P_T 0.917; gaps 0.437 table_pos, 0.423
   table_texture, 0.117 camera_pos, 0.090 object_texture, 0.077 floor_texture, 0.053 light, 0.023 distractors).
   For each budget, it prints the share of the fixed design's episodes the rule runs, and how often each
   condition is decided by the rule and by the fixed-n analysis at the budget: Newcombe's paired 95% interval
   uncorrected, as results.csv has it, and corrected (Bonferroni over the ``k`` conditions, the family-wise
   guarantee the rule gives, without its stopping).

    python scripts/stopping_power.py [--profiles 400] [--budgets 20,40,100,200] [--block 5] [--tolerance 0.1]
"""

from __future__ import annotations

import argparse
import math
from statistics import NormalDist

import numpy as np
from replay_stopping import cells as committed_cells  # the replay's reading of committed episodes (scripts/)
from tqdm import tqdm

from lerobot_factorworld.stats.confseq import candidate_grid
from lerobot_factorworld.stats.proportions import paired_gap
from lerobot_factorworld.stats.stopping import DECIDED
from lerobot_factorworld.study.sequential import StopRule

F1_FACTORS = ("table_pos", "table_texture", "camera_pos", "object_texture", "floor_texture", "light", "distractors")
F1_GAPS = (0.437, 0.423, 0.117, 0.090, 0.077, 0.053, 0.023)  # bc's mean gaps over F1's 15 cells
F1_P_TRAIN = 0.917
F1_STUDY = "f1_ordering"  # its committed episodes: docs/results/f1_ordering/episodes.parquet
SIM_POINTS = 401  # candidate means of the simulations (bounds stepped outwards to them); shipped: confseq.GRID_POINTS


def corrected_z(alpha: float, k: int) -> float:
    """The normal quantile of a two-sided interval at ``alpha``, Bonferroni-corrected over ``k`` conditions."""
    return NormalDist().inv_cdf(1 - alpha / (2 * k))


def valid_test_floor(alpha: float, k: int) -> int:
    """The fewest paired episodes at which a valid test declaring either sign at ``alpha/(2k)`` can declare one."""
    return math.ceil(math.log2(2 * k / alpha))


def rule_floor(rule: StopRule, k: int, points: int = SIM_POINTS) -> int:
    """The first look of ``rule`` (blocks of 1) at which paired differences that are all +1 decide a gap."""
    one = StopRule(1, rule.max_episodes, rule.tolerance, rule.confidence)
    train, shifted = np.ones((1, rule.max_episodes)), np.zeros((1, k, rule.max_episodes))
    stops = one.apply(train, shifted, grid=candidate_grid(points))
    return int(stops.episodes[0, 0]) if stops.reason[0, 0] == DECIDED else -1


def discordance(p_train: float, gap: float, copula: float) -> tuple[float, float]:
    """``(p10, p01)`` of the simulation's paired outcomes (:func:`profiles`): comonotone when both conditions
    use the shared difficulty (probability ``copula**2``), else independent."""
    p_shift, shared = p_train - float(np.clip(gap, p_train - 1, p_train)), copula**2  # as profiles() clips it
    p10 = shared * max(p_train - p_shift, 0) + (1 - shared) * p_train * (1 - p_shift)
    p01 = shared * max(p_shift - p_train, 0) + (1 - shared) * (1 - p_train) * p_shift
    return p10, p01


def committed_pairs(method: str | None = None) -> dict[tuple, dict[str, list[tuple[bool, bool]]]]:
    """F1's committed paired outcomes, as the replay reads them: cell -> factor -> [(train, shift)] in seed order."""
    pairs: dict[tuple, dict[str, list[tuple[bool, bool]]]] = {}
    for cell, conditions in committed_cells(F1_STUDY).items():
        if method in (None, cell[0]) and "train" in conditions:
            train = dict(conditions["train"])
            pairs[cell] = {c: [(train[seed], ok) for seed, ok in e] for c, e in conditions.items() if c != "train"}
    return pairs


def rates(pairs: list[tuple[bool, bool]]) -> tuple[float, float]:
    """``(p10, p01)``: the shares of pairs where only train succeeds, and only the shift."""
    return sum(t and not s for t, s in pairs) / len(pairs), sum(s and not t for t, s in pairs) / len(pairs)


def committed_discordance(factors: list[str], method: str = "bc") -> dict[str, tuple[float, float]]:
    """``(p10, p01)`` per factor in F1's committed episodes of ``method``, its cells pooled."""
    pooled: dict[str, list[tuple[bool, bool]]] = {}
    for by_factor in committed_pairs(method).values():
        for factor, pairs in by_factor.items():
            pooled.setdefault(factor, []).extend(pairs)
    return {factor: rates(pooled[factor]) for factor in factors if factor in pooled}


def per_cell_bound(n: int, alpha: float) -> str:
    """The expected decisions at ``n`` episodes that no test valid at ``alpha/k`` exceeds, over F1's cells, each at
    its own rates, beside Newcombe's decisions on all the committed episodes."""
    bound = fixed = corrected = conditions = 0.0
    cells = committed_pairs()
    lengths = sorted({len(pairs) for by_factor in cells.values() for pairs in by_factor.values()})
    for by_factor in cells.values():
        k = len(by_factor)
        z = corrected_z(alpha, k)
        for pairs in by_factor.values():
            p10, p01 = rates(pairs)
            # declaring either sign is one test of the null, at alpha/k in all: the bound holds for it as it is
            bound += power_bound(p10, p01, n, alpha / k)
            train, shift = [t for t, _ in pairs], [s for _, s in pairs]
            for z_level, counter in ((None, "fixed"), (z, "corrected")):
                _, low, high = paired_gap(train, shift) if z_level is None else paired_gap(train, shift, z=z_level)
                if low > 0 or high < 0:
                    fixed, corrected = (fixed + 1, corrected) if counter == "fixed" else (fixed, corrected + 1)
            conditions += 1
    return (
        f"per cell: F1's {len(cells)} committed cells, {int(conditions)} conditions: at {n} episodes no test valid "
        f"at {alpha:g}/k makes more than {bound:.1f} decisions in expectation (each cell's own rates as the truth); "
        f"Newcombe's interval on all {'/'.join(map(str, lengths))} episodes decides {int(corrected)} corrected, "
        f"{int(fixed)} uncorrected"
    )


def power_bound(p10: float, p01: float, n: int, alpha: float) -> float:
    """The most often a test valid at ``alpha`` for a gap of 0 can declare a gap (of either sign: any rejection)
    within ``n`` independent paired episodes: the Neyman-Pearson power against the null with the same ties and
    ``p10 = p01``."""
    q, tie = (p10 + p01) / 2, 1 - p10 - p01
    outcomes = []  # (likelihood ratio, null probability, alternative probability) of (n10, n01)
    for n10 in range(n + 1):
        for n01 in range(n + 1 - n10):
            ways = math.comb(n, n10) * math.comb(n - n10, n01) * tie ** (n - n10 - n01)
            null, alternative = ways * q ** (n10 + n01), ways * p10**n10 * p01**n01
            outcomes.append((alternative / null if null else math.inf, null, alternative))
    size = power = 0.0
    for _, null, alternative in sorted(outcomes, key=lambda o: -o[0]):
        if size + null > alpha:
            return power + alternative * (alpha - size) / null
        size, power = size + null, power + alternative
    return power


def profiles(p_train: float, gaps: np.ndarray, n: int, episodes: int, copula: float, rng) -> tuple[np.ndarray, ...]:
    """``n`` profiles of paired, correlated outcomes (``train`` ``(n, T)``, shifted ``(n, k, T)``)."""
    rates = p_train - np.clip(gaps, p_train - 1, p_train)
    shared = rng.random((n, 1, episodes))
    own = rng.random((n, len(gaps) + 1, episodes))
    u = np.where(rng.random((n, len(gaps) + 1, episodes)) < copula, shared, own)
    return (u[:, 0] < p_train).astype(float), (u[:, 1:] < rates[None, :, None]).astype(float)


def compare(budget: int, args, gaps: np.ndarray, rng) -> list[str]:
    rule = StopRule(args.block, budget, args.tolerance, args.confidence)
    train, shifted = profiles(args.p_train, gaps, args.profiles, budget, args.copula, rng)
    stops = rule.apply(train, shifted, grid=candidate_grid(args.grid_points))
    used = stops.episodes.max(axis=1) + stops.episodes.sum(axis=1)  # train runs as long as its longest condition
    share = used.mean() / ((len(gaps) + 1) * budget)
    fixed = np.zeros(stops.episodes.shape, dtype=bool)
    corrected = np.zeros(stops.episodes.shape, dtype=bool)
    z = corrected_z(1 - args.confidence, len(gaps))
    for p in range(args.profiles):
        for c in range(len(gaps)):
            pair = train[p].astype(bool), shifted[p, c].astype(bool)
            _, low, high = paired_gap(*pair)
            fixed[p, c] = low > 0 or high < 0
            _, low, high = paired_gap(*pair, z=z)
            corrected[p, c] = low > 0 or high < 0
    auto = stops.reason == DECIDED
    sign = np.sign(stops.low + stops.high)
    same = (auto == corrected).mean()
    lines = [
        f"budget {budget}: auto runs {share:.1%} of the fixed design's episodes (train {stops.episodes.max(axis=1).mean():.1f}"
        f" per profile); conditions decided per profile by auto / fixed-n / fixed-n corrected: "
        f"{auto.sum(axis=1).mean():.2f} / {fixed.sum(axis=1).mean():.2f} / {corrected.sum(axis=1).mean():.2f}; "
        f"auto's decision that of fixed-n corrected {same:.1%}; auto's wrong signs {(auto & (sign != np.sign(gaps))).sum()}",
    ]
    for c, name in enumerate(args.factors):
        lines.append(
            f"  {name:<15} gap {gaps[c]:+.3f}: auto decides {auto[:, c].mean():6.1%} (median stop "
            f"{int(np.median(stops.episodes[:, c]))}), fixed-n {fixed[:, c].mean():6.1%}, corrected "
            f"{corrected[:, c].mean():6.1%}"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profiles", type=int, default=400)
    parser.add_argument("--budgets", default="20,40,100,200")
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--tolerance", type=float, default=0.1)
    parser.add_argument("--confidence", type=float, default=0.95)
    parser.add_argument("--p_train", type=float, default=F1_P_TRAIN)
    parser.add_argument("--gaps", default=",".join(str(g) for g in F1_GAPS))
    parser.add_argument("--factors", default=",".join(F1_FACTORS))
    parser.add_argument("--copula", type=float, default=0.6)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--grid_points", type=int, default=SIM_POINTS, help="candidate means (shipped: 2001)")
    args = parser.parse_args()
    gaps = np.array([float(g) for g in args.gaps.split(",")])
    args.factors = args.factors.split(",")
    if len(args.factors) != len(gaps):
        parser.error(f"--factors names {len(args.factors)} conditions, --gaps gives {len(gaps)}")
    budgets = [int(b) for b in args.budgets.split(",")]
    if any(b % args.block for b in budgets):
        parser.error(f"every budget must be a multiple of --block={args.block}")
    k, alpha = len(gaps), 1 - args.confidence
    rng = np.random.default_rng(args.seed)
    print(
        f"stopping power of eval.episodes=auto: {k} shifted conditions, P_T {args.p_train}, block {args.block}, "
        f"tolerance {args.tolerance}, confidence {args.confidence} (Bonferroni over the {k}), {args.profiles} "
        f"simulated profiles per budget (copula {args.copula}, seed {args.seed}, {args.grid_points} candidate means); fixed-n = Newcombe's paired 95% "
        f"interval at the budget, uncorrected and corrected (Bonferroni over the {k})"
    )
    print(
        f"floor: no valid non-randomised test declaring each sign at {alpha:g}/(2x{k}) declares a gap before "
        f"{valid_test_floor(alpha, k)} paired episodes, all favouring train; this rule first decides at {rule_floor(StopRule(1, 200, args.tolerance, args.confidence), k, args.grid_points)}"
        " (all favouring train, blocks of 1)"
    )
    committed = committed_discordance(args.factors)
    for c, name in enumerate(args.factors):
        rates = {"simulated": discordance(args.p_train, gaps[c], args.copula), "F1 committed": committed.get(name)}
        bounds = [
            f"{label} (p10 {p10:.3f}, p01 {p01:.3f}) <= {power_bound(p10, p01, 10, alpha / k):.1%} at 10, "
            f"{power_bound(p10, p01, 20, alpha / k):.1%} at 20"
            for label, pair in rates.items()
            if pair is not None
            for p10, p01 in [pair]
        ]
        print(f"power bound, {name}: " + "; ".join(bounds))
    print(per_cell_bound(10, alpha))
    for budget in tqdm(budgets, desc="budgets", leave=False):
        print("\n".join(compare(budget, args, gaps, rng)))


if __name__ == "__main__":
    main()
