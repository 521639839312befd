"""Seconds to write the F1 report (``docs/results/f1_ordering``) with the previous code and with this checkout's.

What is measured
    ``factorworld report``'s work, ``study.report.write.regenerate_report(results.csv, config.yaml, out)``: plots,
    report.md and report.html from the committed results, into a temporary folder. Two sides:

    - **old**: the package at ``--old`` (default: the merge base of ``HEAD`` and ``main``), checked out by
      ``git worktree add --detach`` into a temporary folder (removed at the end) and imported from there
      (``PYTHONPATH``), in this checkout's virtual environment: the same libraries, only the code differs;
    - **new**: this checkout's package.

    Each round runs one fresh interpreter per side, in alternating order (A B, B A, ...); each interpreter imports
    the package, writes the report once (``first``: what ``factorworld report`` pays after its imports, lazy
    imports such as matplotlib's included) and then ``--repeats`` more times into new folders (``warm``: the
    report's own computation and drawing). Both sides must write byte-identical report.md, report.html and PNGs.

    python scripts/bench_report.py [--rounds 3] [--repeats 2] [--old <commit>] [--study docs/results/f1_ordering]

The last line printed is exactly ``ratio: <float>`` = the old side's median warm seconds / the new side's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _bench

SIDES = ("old", "new")
OUTPUTS = ("report.md", "report.html", "methods.png", "ordering_per_task.png", "success_rates.png")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=2, help="warm reports per interpreter after the first")
    parser.add_argument("--old", default=None, help="the previous code's commit (default: merge base with main)")
    parser.add_argument("--study", type=Path, default=_bench.REPO_ROOT / "docs" / "results" / "f1_ordering")
    parser.add_argument("--child", nargs=3, metavar=("TREE", "OUT", "RESULT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        return _child(Path(args.child[0]), Path(args.child[1]), Path(args.child[2]), args.study, args.repeats)
    old = args.old or _git("merge-base", "HEAD", "main")
    start_load = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "old"
        _git("worktree", "add", "--detach", str(tree), old)
        try:
            trees = {"old": tree, "new": _bench.REPO_ROOT}
            times: dict[str, list[dict]] = {side: [] for side in SIDES}
            for r in range(args.rounds):
                for side in _bench.round_order(SIDES, r):
                    out = Path(tmp) / f"{side}-{r}"
                    result = out / "result.json"
                    command = [sys.executable, __file__, "--study", str(args.study), "--repeats", str(args.repeats)]
                    command += ["--child", str(trees[side]), str(out), str(result)]
                    env = {**os.environ, "PYTHONPATH": str(trees[side])}
                    proc = subprocess.run(command, stdout=sys.stderr, env=env, check=False)
                    if proc.returncode != 0:
                        raise SystemExit(f"the {side} side failed (exit {proc.returncode}); see its output above")
                    times[side].append(json.loads(result.read_text()))
            same = all(
                (Path(tmp) / f"old-{r}" / "0" / name).read_bytes() == (Path(tmp) / f"new-{r}" / "0" / name).read_bytes()
                for r in range(args.rounds)
                for name in OUTPUTS
            )
        finally:
            _git("worktree", "remove", "--force", str(tree))
    end_load = os.getloadavg()
    print(f"study: {args.study.name} | old: {old[:7]} | new: {_git('rev-parse', '--short', 'HEAD')} (+ working tree)")
    print(f"rounds: {args.rounds} (one interpreter per side each), {args.repeats} warm report(s) after the first")
    print(f"identical outputs ({', '.join(OUTPUTS)}): {'yes' if same else 'NO'}")
    _bench.print_table(
        "| side | import s (median) | first report s (median) | warm report s (median) | warm runs |",
        (
            f"| {side} | {statistics.median(t['import'] for t in times[side]):.2f} | "
            f"{statistics.median(t['first'] for t in times[side]):.2f} | "
            f"{statistics.median(w for t in times[side] for w in t['warm']):.2f} | "
            f"{sum(len(t['warm']) for t in times[side])} |"
            for side in SIDES
        ),
    )
    first = {side: statistics.median(t["first"] for t in times[side]) for side in SIDES}
    warm = {side: statistics.median(w for t in times[side] for w in t["warm"]) for side in SIDES}
    print(f"first report: old / new = {first['old'] / first['new']:.2f}")
    print(_bench.load_average_line(start_load, end_load))
    print(_bench.target_verdict(warm["old"] / warm["new"], 2))
    print(_bench.ratio_line(warm["old"] / warm["new"]))


def _child(tree: Path, out: Path, result: Path, study: Path, repeats: int) -> None:
    """One side in its own interpreter: the package must come from ``tree``."""
    _bench.setup_headless_gl()
    start = time.perf_counter()
    import lerobot_factorworld  # noqa: PLC0415 - from PYTHONPATH: the side's tree
    from lerobot_factorworld.study.report.write import regenerate_report  # noqa: PLC0415 - ditto

    imported = time.perf_counter() - start
    if Path(lerobot_factorworld.__file__).resolve().parents[1] != tree.resolve():
        raise SystemExit(f"imported {lerobot_factorworld.__file__}, not the package in {tree}")
    seconds = []
    for i in range(1 + repeats):
        start = time.perf_counter()
        regenerate_report(study / "results.csv", study / "config.yaml", out / str(i))
        seconds.append(time.perf_counter() - start)
    _bench.write_result(result, {"import": imported, "first": seconds[0], "warm": seconds[1:]})


def _git(*args: str) -> str:
    return subprocess.run(
        ["git", *args], cwd=_bench.REPO_ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()


if __name__ == "__main__":
    main()
