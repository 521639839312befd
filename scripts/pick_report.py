"""The pick run's table (docs/pick.md): success per condition next to the paper's real-robot numbers,
and per-object and per-phrasing breakdowns.

Reads ``<out>/eval/<condition>/eval_info.json`` (``lerobot-eval``, one run per condition) and recovers
each episode's instruction and named object exactly: episode ``i`` was reset with seed
``start_seed + i`` in the condition's environments, which depend only on the dataset and the condition
(``FactorWorldEnvConfig.suites``), so resetting a physics-only env with the same seed gives the same
episode record.

    .venv/bin/python scripts/pick_report.py --out=outputs/pick --test_envs=10 --start_seed=1000
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from lerobot_factorworld.envs.configs import FactorWorldEnvConfig
from lerobot_factorworld.pick.catalog import PICK_TASK
from lerobot_factorworld.pick.records import breakdown, episode_records
from lerobot_factorworld.study.metrics import PAPER_REAL_ROBOT, wilson_interval

PAPER = PAPER_REAL_ROBOT  # condition -> (the paper's name, its real-robot success %)


def condition_records(data_root: str, condition: str, n_episodes: int, test_envs: int, start_seed: int) -> list[dict]:
    """What every episode of ``condition`` asked for (instruction, named object), by re-resetting its envs."""
    shifts = [] if condition == "train" else [condition]
    cfg = FactorWorldEnvConfig(
        task=PICK_TASK, dataset_root=data_root, shifts=shifts, include_train=condition == "train", n_test_envs=test_envs
    )
    configs = cfg.suites(PICK_TASK)[condition]
    seeds = [start_seed + i for i in range(n_episodes)]
    return episode_records(configs, seeds, cfg.sampling.widths.get("object_pos"))


def rate(successes: list[bool]) -> str:
    k, n = sum(successes), len(successes)
    lo, hi = wilson_interval(k, n)
    return f"{100 * k / n:.1f}% ({k}/{n}, [{100 * lo:.0f}, {100 * hi:.0f}])"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="outputs/pick")
    parser.add_argument("--data", default=None, help="the dataset the policy was trained on (default: <out>/data)")
    parser.add_argument("--test_envs", type=int, default=10)
    parser.add_argument("--start_seed", type=int, default=1000)
    args = parser.parse_args()
    out = Path(args.out)
    data = Path(args.data) if args.data else out / "data"
    results, by_target, by_shape, by_template = {}, {}, {}, {}
    for condition in PAPER:
        path = out / "eval" / condition / "eval_info.json"
        if not path.is_file():
            continue
        successes = [bool(s) for s in json.loads(path.read_text())["per_task"][0]["metrics"]["successes"]]
        records = condition_records(str(data), condition, len(successes), args.test_envs, args.start_seed)
        results[condition] = successes
        for target, outcomes in breakdown(successes, records, "target").items():
            by_target[(condition, target)] = outcomes
        for shape, outcomes in breakdown(successes, records, "shape").items():
            by_shape[(condition, shape)] = outcomes
        for template, outcomes in breakdown(successes, records, "template").items():
            by_template[(condition, template)] = outcomes
    print("| condition | paper (real robot) | this run (simulation): success, 95% Wilson interval |")
    print("|---|---|---|")
    for condition, successes in results.items():
        name, paper = PAPER[condition]
        print(f"| {name} (`{condition}`) | {'—' if paper is None else f'{paper:.1f}%'} | {rate(successes)} |")
    shifted = [c for c in results if c != "train" and PAPER[c][1] is not None]
    if len(shifted) >= 2:
        sim = sorted(shifted, key=lambda c: -sum(results[c]) / len(results[c]))
        paper = sorted(shifted, key=lambda c: -PAPER[c][1])
        print(f"\nordering, easiest first: simulation {', '.join(sim)}; paper {', '.join(paper)}")
        print(
            f"Spearman rank correlation over the {len(shifted)} shifted conditions: {_spearman(results, shifted):.2f}"
        )
    tables = (("named object", by_target), ("named object's shape", by_shape), ("phrasing template", by_template))
    for title, table in tables:
        keys = sorted({k for _, k in table})
        conditions = list(results)
        print(f"\n| {title} | " + " | ".join(conditions) + " |")
        print("|---" * (len(conditions) + 1) + "|")
        for key in keys:
            cells = []
            for condition in conditions:
                values = table.get((condition, key), [])
                cells.append(f"{sum(values)}/{len(values)}" if values else "")
            print(f"| {key} | " + " | ".join(cells) + " |")


def _spearman(results: dict[str, list[bool]], conditions: list[str]) -> float:
    from lerobot_factorworld.study.metrics import spearman

    return spearman({c: sum(results[c]) / len(results[c]) for c in conditions}, {c: PAPER[c][1] for c in conditions})


if __name__ == "__main__":
    main()
