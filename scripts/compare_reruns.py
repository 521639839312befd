"""Does a rerun land within the intervals of the results it repeats? (``lerobot_factorworld/study/rerun.py``)

Give two study folders (or committed ``docs/results/<study>/`` folders), the first run's and the rerun's: every
evaluation step both ran (same key) is compared. Per cell: the first run's successes with its Wilson 95%
interval, the rerun's, whether the rerun's rate lies within that interval and its gap within the first run's
paired interval, and, where both folders hold ``episodes.parquet``, how many episodes end alike (same
success) and identically (same success and length). The last line is ``within: <cells within>/<cells>``;
the exit status is 1 when a cell lies outside (so a held-back rerun can be checked by a command).

    .venv/bin/python scripts/compare_reruns.py docs/results/f5_augmentation docs/results/f6_pretrained
    .venv/bin/python scripts/compare_reruns.py docs/results/f1_ordering outputs/study/findings/f1_ordering
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import _bench

_bench.add_repo_to_path()

from lerobot_factorworld.study.episodes import EPISODES_FILE, read_episodes  # noqa: E402
from lerobot_factorworld.study.rerun import compare_reruns  # noqa: E402
from lerobot_factorworld.study.results import RESULTS_FILE, read_results  # noqa: E402


def episode_rows(folder: Path) -> list[dict]:
    """The folder's episodes (``episodes.parquet``), or none when it has no such file."""
    path = folder / EPISODES_FILE
    return read_episodes(path) if path.is_file() else []


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first", type=Path, help="the first run's folder (holds results.csv)")
    parser.add_argument("rerun", type=Path, help="the rerun's folder (holds results.csv)")
    args = parser.parse_args()
    for folder in (args.first, args.rerun):
        if not (folder / RESULTS_FILE).is_file():
            sys.exit(f"error: no {RESULTS_FILE} in {folder}")
    try:
        found = compare_reruns(
            read_results(args.first / RESULTS_FILE),
            read_results(args.rerun / RESULTS_FILE),
            episode_rows(args.first),
            episode_rows(args.rerun),
        )
    except ValueError as error:
        sys.exit(f"error: {error}")
    print(
        f"{len(found.cells)} evaluation steps in both; {found.only_first} only in the first, {found.only_rerun} only in the rerun"
    )
    print()
    print(
        "| method | task | N | seed | widths | condition | first | rerun | rate within | gap first [95%] | gap rerun | gap within | same outcome | same length |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in found.cells:
        gap = "—" if c.gap_within is None else f"{c.gaps[0]:+.2f} [{c.gap_interval[0]:+.2f}, {c.gap_interval[1]:+.2f}]"
        gap_rerun = "—" if c.gap_within is None or math.isnan(c.gaps[1]) else f"{c.gaps[1]:+.2f}"
        print(
            "| " + " | ".join(str(v) for v in c.label) + f" | {c.successes[0]}/{c.episodes} [{c.interval[0]:.2f}, "
            f"{c.interval[1]:.2f}] | {c.successes[1]}/{c.episodes} | {'yes' if c.rate_within else 'NO'} | {gap} | "
            f"{gap_rerun} | {'—' if c.gap_within is None else ('yes' if c.gap_within else 'NO')} | "
            f"{'—' if c.same_outcome is None else c.same_outcome} | {'—' if c.same_length is None else c.same_length} |"
        )
    with_episodes = [c for c in found.cells if c.same_outcome is not None]
    print()
    print(f"identical cells (same successes and gap): {found.identical}/{len(found.cells)}")
    if with_episodes:
        total = sum(c.episodes for c in with_episodes)
        print(
            f"episodes ending alike: {sum(c.same_outcome for c in with_episodes)}/{total}; "
            f"identically (same length too): {sum(c.same_length for c in with_episodes)}/{total}"
        )
    print(f"within: {found.within}/{len(found.cells)}")
    sys.exit(0 if found.within == len(found.cells) else 1)


if __name__ == "__main__":
    main()
