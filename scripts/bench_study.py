"""Study throughput, both ways side by side: one small fixed study grid run with ``--execution=per_step``
(the earlier path: ``lerobot-train`` as a subprocess per training, every evaluation its own task) and
with ``--execution=grouped`` (the default: training inside the persistent worker, all conditions of a
checkpoint evaluated in one task as soon as it exists), each in a fresh temporary study folder and a fresh
``factorworld study`` process. Prints the wall time of each way, their ratio, and whether the results are
identical: ``results.csv``, every checkpoint's files and every dataset's files, byte for byte.

    MUJOCO_GL=egl .venv/bin/python scripts/bench_study.py            # about 3 minutes on 2 cores
    MUJOCO_GL=egl .venv/bin/python scripts/bench_study.py --quick    # the smoke test's scale
    MUJOCO_GL=egl .venv/bin/python scripts/bench_study.py --quality lod   # the grid at the lod quality, both ways

Target: a ratio >= 2 on 2 cores with identical results. The last line is ``ratio: <float>``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _bench import REPO_ROOT, add_repo_to_path, load_average_line, ratio_line, setup_headless_gl, target_verdict

TARGET = 2.0
WAYS = ("per_step", "grouped")

# The fixed grid: door-open, N = 2, one seed, three shifted factors (4 conditions per checkpoint).
GRID = {
    "name": "bench",
    "tasks": ["door-open"],
    "n_train_envs": [2],
    "seeds": [0],
    "factors": ["camera_pos", "table_texture", "light"],
    "methods": [{"name": "bc", "policy": {"type": "bc"}}],
    "collect": {"demos": 6},
    "train": {"steps": 200, "batch_size": 16},
    "eval": {"n_test_envs": 2, "episodes": 4, "max_episode_steps": 60},
    "workers": 2,
}
# The smoke test's scale: fewer demos, steps and episodes, the same grid (every factor, so every report section the
# default grid writes is written here too).
QUICK = {"collect": {"demos": 2}, "train": {"steps": 10, "batch_size": 4}, "eval": {"n_test_envs": 2, "episodes": 2,
         "max_episode_steps": 20}}  # fmt: skip


def run_way(way: str, grid: dict, folder: Path) -> float:
    """Wall seconds of one ``factorworld study`` run of ``grid`` with ``--execution=way`` in ``folder``."""
    config = folder / "study.yaml"
    config.write_text(json.dumps({**grid, "out_dir": str(folder / "study")}))
    log = folder / "study.log"
    command = [
        sys.executable,
        "-m",
        "lerobot_factorworld.cli",
        "study",
        f"--config_path={config}",
        f"--execution={way}",
    ]
    start = time.perf_counter()
    with open(log, "w") as out:
        proc = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, cwd=REPO_ROOT, env=os.environ.copy())
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{way}: factorworld study failed (exit {proc.returncode}):\n{log.read_text()[-3000:]}")
    return seconds


# How a checkpoint's data was loaded (``train_step.loader_args``: in process, or by a lent worker), which its
# ``train_config.json`` records: the weights and processors are the same either way, byte for byte.
LOADER_FIELDS = ("num_workers", "persistent_workers", "dataloader_multiprocessing_context", "prefetch_factor")


def digests(study: Path) -> dict[str, str]:
    """SHA-256 of every file that is a result: ``results.csv``, the checkpoints, the datasets. Byte for byte,
    except three things that are not results: a JSON file is compared as data with its keys sorted (LeRobot
    writes a dataset's ``stats.json`` keys in set order, which changes with every process's hash seed), the
    study folder's own path (a checkpoint's ``train_config.json`` names its dataset and output folder) is
    replaced by ``<study>``, and ``train_config.json``'s data-loading settings (``LOADER_FIELDS``) are left out."""
    files = [study / "results.csv"]
    files += sorted((study / "steps" / "train").glob("*/train/checkpoints/**/pretrained_model/*"))
    files += sorted(p for p in (study / "steps" / "collect").glob("*/data/**/*") if p.is_file())
    out = {}
    for path in files:
        if not path.is_file():
            continue
        data = path.read_bytes()
        if path.suffix == ".json":
            content = json.loads(data)
            if path.name == "train_config.json":
                content = {k: v for k, v in content.items() if k not in LOADER_FIELDS}
            text = json.dumps(content, sort_keys=True).replace(str(study.resolve()), "<study>")
            data = text.encode()
        out[str(path.relative_to(study))] = hashlib.sha256(data).hexdigest()
    return out


def compare(first: Path, second: Path) -> list[str]:
    """What differs between two study folders' results (empty: identical)."""
    a, b = digests(first), digests(second)
    lines = [f"only in {WAYS[0]}: {name}" for name in sorted(set(a) - set(b))]
    lines += [f"only in {WAYS[1]}: {name}" for name in sorted(set(b) - set(a))]
    lines += [f"differs: {name}" for name in sorted(set(a) & set(b)) if a[name] != b[name]]
    csv_a, csv_b = (first / "results.csv").read_text(), (second / "results.csv").read_text()
    if csv_a != csv_b:
        import difflib

        lines += list(difflib.unified_diff(csv_a.splitlines(), csv_b.splitlines(), *WAYS, lineterm=""))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the smallest grid (a smoke test, not a measurement)")
    parser.add_argument("--keep", default="", help="keep the two study folders under this folder")
    parser.add_argument("--profile", action="store_true", help="also print each way's `--profile` table")
    parser.add_argument(
        "--quality", default="fast", help="the grid's render quality (collect.quality: fast, lod or full)"
    )
    args = parser.parse_args()
    setup_headless_gl()
    add_repo_to_path()
    grid = {**GRID, **QUICK} if args.quick else dict(GRID)
    grid["collect"] = {**grid["collect"], "quality": args.quality}  # both ways; another than fast: other results
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_study_"))
    load_start = os.getloadavg()
    seconds = {}
    for way in WAYS:
        folder = base / way
        folder.mkdir(parents=True, exist_ok=False)
        seconds[way] = run_way(way, grid, folder)
        print(f"{way:9s} {seconds[way]:7.1f} s", flush=True)
        if args.profile:
            config = folder / "study.yaml"
            subprocess.run(
                [sys.executable, "-m", "lerobot_factorworld.cli", "study", f"--config_path={config}", "--profile=true"],
                cwd=REPO_ROOT,
                check=True,
            )
    diff = compare(base / WAYS[0] / "study", base / WAYS[1] / "study")
    ratio = seconds[WAYS[0]] / seconds[WAYS[1]]
    n_files = len(digests(base / WAYS[1] / "study"))
    print(f"grid: {json.dumps(grid)}")
    print(load_average_line(load_start, os.getloadavg()))
    print(f"{WAYS[0]} / {WAYS[1]} wall time: {ratio:.2f}x ({target_verdict(ratio, TARGET)})")
    if diff:
        print("results DIFFER:\n" + "\n".join(diff[:60]))
    else:
        print(f"identical results (results.csv, checkpoints and datasets: {n_files} files byte for byte)")
    if not args.keep:
        import shutil

        shutil.rmtree(base, ignore_errors=True)
    print(ratio_line(ratio))
    if diff:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
