"""One factor's gap in two studies and their difference, with seed-level bootstrap 95% intervals.

For a question that spans two committed studies (``lerobot_factorworld/study/compare.py`` says how the interval
is made): each side is one method on one task (at one N), over the training seeds both studies hold.

    .venv/bin/python scripts/compare_gaps.py docs/results/f7_object_texture_168px docs/results/f1_ordering \\
        --factor object_texture --task pick-place
    .venv/bin/python scripts/compare_gaps.py docs/results/f7_object_texture_colours \\
        docs/results/f7_object_texture_images --factor object_texture --task pick-place

The last line is ``difference (first minus second): <value> [<low>, <high>]``. A bad folder, method, task or factor
is refused in one line that names the valid choices.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import _bench

_bench.add_repo_to_path()

from lerobot_factorworld.study.compare import Side, compare_gaps  # noqa: E402
from lerobot_factorworld.study.results import RESULTS_FILE, read_results  # noqa: E402


def _rows(folder: str) -> list[dict]:
    path = Path(folder)
    return read_results(path / RESULTS_FILE if path.is_dir() else path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first", help="a study folder (or its results.csv)")
    parser.add_argument("second", help="another study folder (or its results.csv)")
    parser.add_argument("--factor", required=True, help="the shifted condition, e.g. object_texture")
    parser.add_argument("--task", required=True)
    parser.add_argument("--method", default="bc", help="the method on both sides (default bc)")
    parser.add_argument("--second-method", default=None, help="the second study's method, if another")
    parser.add_argument(
        "--n-train-envs", type=int, default=None, help="N on both sides (needed where a study has several)"
    )
    args = parser.parse_args()
    try:
        first, second = _rows(args.first), _rows(args.second)
        sides = (
            Side(args.method, args.task, args.n_train_envs),
            Side(args.second_method or args.method, args.task, args.n_train_envs),
        )
        result = compare_gaps(first, second, args.factor, sides)
    except (ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None
    seeds = ", ".join(map(str, result.seeds))
    print(f"{args.factor} on {args.task}, seeds {seeds} (seed-level bootstrap 95% intervals)")
    for name, side, (gap, low, high), counts in zip(
        (args.first, args.second), sides, result.gaps, result.episodes, strict=True
    ):
        episodes = "-".join(map(str, sorted({counts[0], counts[-1]})))
        print(f"  {name} ({side.method}, {episodes} episodes per cell): gap {gap:+.3f} [{low:+.3f}, {high:+.3f}]")
    difference, low, high = result.difference
    print(f"difference (first minus second): {difference:+.3f} [{low:+.3f}, {high:+.3f}]")


if __name__ == "__main__":
    main()
