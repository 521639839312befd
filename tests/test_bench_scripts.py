"""The benchmark scripts run end to end at their smallest size and print what they measured: each table row is
checked against the script's own other numbers (a median against its rounds, ms per step against the rate, the
ratio on the last line against the rows it is computed from) and against what is known without timing (render
settings, parameter counts, batch sizes, counts of demos and frames).

No speed thresholds here (this machine is noisy and CI may be slower): the targets live in the scripts. Each
run starts processes and imports torch, LeRobot or MuJoCo (10-60 s), so every run is a slow test.
"""

from __future__ import annotations

import os
import platform
import re
import statistics
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
RATIO = re.compile(r"ratio: (\d+\.\d{4})")


def run_script(script: str, args: tuple[str, ...], timeout: int) -> tuple[list[str], float]:
    """The script's stdout lines and the ratio on its last line (which must be exactly ``ratio: <float>``)."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.run(
        [sys.executable, str(SCRIPTS / script), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        cwd=SCRIPTS.parent,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-4000:]}"
    lines = proc.stdout.strip().splitlines()
    match = RATIO.fullmatch(lines[-1]) if lines else None
    assert match, f"last line is not 'ratio: <float>': {lines[-1:]!r}"
    return lines, float(match.group(1))


def table_rows(lines: list[str], first_cell: str) -> list[list[str]]:
    """The cells of the markdown table rows whose first cell starts with ``first_cell``."""
    rows = [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in lines if line.startswith("|")]
    return [row for row in rows if row[0].startswith(first_cell)]


def close(value: float, digits: int, exact: float, *printed: tuple[float, int]) -> bool:
    """``value``, printed to ``digits`` decimals, equals ``exact`` computed from other printed numbers (each
    ``(number, its digits)``), within what those roundings allow (to first order)."""
    relative = sum(0.5 * 10.0**-d / abs(number) for number, d in printed)
    return abs(value - exact) <= 0.5 * 10.0**-digits + abs(exact) * relative * 1.01 + 1e-12


def check_env(lines: list[str], ratio: float) -> None:
    assert "tasks: pick-place | 2 steps x 3 rounds per mode | seed 0" in lines
    settings = {"Factor World (front, fast)": (0, 0), "Meta-World (corner2, defaults)": (4096, 4)}
    ms = {}
    for label, (shadowsize, samples) in settings.items():
        (setting,) = [line for line in lines if line.strip().startswith(label) and "shadowsize=" in line]
        assert f"shadowsize={shadowsize} offsamples={samples} frame=(84, 84, 3)" in setting  # what each renders
        (row,) = [line for line in lines if line.startswith(label) and "shadowsize=" not in line]
        *rounds, median, ms[label] = (float(x) for x in row[len(label) :].split())
        assert len(rounds) == 3 and min(rounds) > 0
        assert median == statistics.median(rounds)  # the middle round's rate (3 rounds: not their mean)
        assert close(median, 1, 1000.0 / ms[label], (ms[label], 2))  # ms/step = 1000 / the median
    fw, mw = (ms[label] for label in settings)
    assert close(ratio, 4, mw / fw, (fw, 2), (mw, 2))  # FW steps/s over MW steps/s
    verdict = "meets" if ratio >= 8 else "BELOW"
    assert f"Factor World / Meta-World: {ratio:.2f}x ({verdict} the >= 8x target)" in lines


def check_policy(lines: list[str], ratio: float) -> None:
    import torch
    from lerobot.configs import FeatureType, PolicyFeature

    from lerobot_factorworld.policies.rt1.configuration_rt1 import PRESETS, RT1Config
    from lerobot_factorworld.policies.rt1.modeling_rt1 import RT1Policy

    (row,) = table_rows(lines, "small")
    params, px, batch, rate, ms_step, on, off, speedup = row[1:]
    config = RT1Config(
        preset="small",
        device="cpu",
        input_features={"observation.images.front": PolicyFeature(FeatureType.VISUAL, (3, 84, 84))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (4,))},
    )
    torch.manual_seed(0)
    assert float(params) == round(sum(p.numel() for p in RT1Policy(config).parameters()) / 1e6, 2)
    assert int(px) == PRESETS["small"]["image_size"] and int(batch) == 1
    assert close(float(rate), 1, 1000.0 * int(batch) / float(ms_step), (float(ms_step), 1))
    on, off = float(on), float(off)
    assert min(on, off) > 0 and speedup.endswith("x")
    assert close(float(speedup[:-1]), 2, off / on, (on, 2), (off, 2))  # latency OFF / ON
    assert close(ratio, 4, off / on, (on, 2), (off, 2))  # the ratio is small's speedup
    (rounds,) = [line for line in lines if line.startswith("small: train samples/s per round [")]
    assert rounds.endswith(
        "(1 steps each); select_action 2 timed calls per mode (2 per round, 6 warm-up after each reset)"
    )
    check_speed_rows(lines)


def check_speed_rows(lines: list[str]) -> None:
    """bc's and rt1's (small preset) updates per second at speed=default and speed=fast, and their ratio."""
    rows = {row[0]: row for row in table_rows(lines, "") if row[0] in ("bc conv", "rt1 small")}
    assert list(rows) == ["bc conv", "rt1 small"]
    for label, unit in (("bc conv", "samples/s"), ("rt1 small", "windows/s")):
        _, batch, printed_unit, default, fast, ratio = rows[label]
        default, fast = float(default), float(fast)
        assert int(batch) == 1 and printed_unit == unit and min(default, fast) > 0 and ratio.endswith("x")
        assert close(float(ratio[:-1]), 2, fast / default, (default, 2), (fast, 2))  # fast / default
        (rounds,) = [line for line in lines if line.startswith(f"{label}: {unit} per round, default [")]
        assert rounds == f"{label}: {unit} per round, default [{default:.2f}]; fast [{fast:.2f}] (1 steps each)"


def check_malloc(lines: list[str], ratio: float) -> None:
    ms = {}
    for way in ("default", "keep_freed"):
        (row,) = table_rows(lines, way)
        assert row[0] == way and row[1] == row[2]  # one round: its median is that round
        ms[way] = float(row[1])
    assert "bc conv, batch 1, 1 updates per process, one thread" in lines and "identical weights" in lines
    assert close(ratio, 4, ms["default"] / ms["keep_freed"], (ms["default"], 1), (ms["keep_freed"], 1))


def check_collect(lines: list[str], ratio: float) -> None:
    assert "task: pick-place | 2 demos per mode | 1 round(s) | seed 0" in lines
    modes = {"Factor World, 1 worker": 1, "Factor World, all workers": os.cpu_count(), "Meta-World, naive": 1}
    fps, frames = {}, {}
    for label, workers in modes.items():
        (row,) = [line for line in lines if line.startswith(label)]
        printed_workers, *numbers = row[len(label) :].split()
        kept, failed, frames[label], seconds, fps[label] = (float(x) for x in numbers)
        assert int(printed_workers) == workers and kept == 2 and failed >= 0 and frames[label] >= 2
        assert close(fps[label], 1, frames[label] / seconds, (seconds, 2))
    fw1, fwall, mw = modes
    assert frames[fw1] == frames[fwall]  # the same collection, however many workers
    assert close(ratio, 4, fps[fwall] / fps[mw], (fps[fwall], 1), (fps[mw], 1))


def check_bc(lines: list[str], ratio: float) -> None:
    (header,) = [line for line in lines if line.startswith("task door-open: ")]
    assert re.fullmatch(
        r"task door-open: \d+ frames per dataset \| batch 2 \| 0 dataloader workers \| 1 round\(s\) \| seed 0", header
    )
    rows = {(row[1], row[3]): row for row in table_rows(lines, "cpu")}
    assert set(rows) == {(p, s) for p in ("bc conv", "act") for s in ("video", "image")}
    ms = {}
    for (policy, storage), row in rows.items():
        params, batch, rate, data, ms_step = row[2], int(row[4]), float(row[5]), row[6], float(row[7])
        total, trainable = re.fullmatch(r"(\d+\.\d\d) \((\d+\.\d\d)\)", params).groups()
        assert total == trainable and batch == 2 and 0 <= float(data.rstrip("%")) <= 100  # nothing frozen here
        if policy == "bc conv":
            assert total == "0.68"  # the paper's CNN: 677,604 parameters
        assert close(rate, 1, 1000.0 * batch / ms_step, (ms_step, 1))
        median, mean = (float(x) for x in row[8].split(" / "))
        assert median > 0 and mean > 0
        ms[policy, storage] = ms_step
    conv, act = ms["bc conv", "image"], ms["act", "image"]
    assert close(ratio, 4, act / conv, (conv, 1), (act, 1))  # conv samples/s over ACT's, image storage


Check = Callable[[list[str], float], None]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("script", "args", "check", "timeout"),
    [
        pytest.param("bench_env.py", ("--steps", "2", "--rounds", "3"), check_env, 180, id="env"),
        pytest.param(
            "bench_policy.py",
            ("--presets", "small", "--rounds", "1", "--train-steps", "1", "--infer-steps", "2", "--batch-size", "1")
            + ("--warmup", "6"),  # the fewest warm-up calls that fill the 6-frame window
            check_policy,
            300,
            id="policy",
        ),
        pytest.param(
            "bench_malloc.py",
            ("--steps", "1", "--rounds", "1", "--batch-size", "1"),
            check_malloc,
            180,
            id="malloc",
            marks=pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt's settings are glibc's"),
        ),
        pytest.param("bench_collect.py", ("--demos", "2"), check_collect, 300, id="collect"),
        pytest.param("bench_bc.py", ("--quick",), check_bc, 600, id="bc"),  # its smallest: 2 demos, 1 step
    ],
)
def test_bench_script_prints_consistent_rows_and_the_ratio_last(script, args, check: Check, timeout):
    lines, ratio = run_script(script, args, timeout)
    assert ratio > 0.0
    check(lines, ratio)


def test_bench_collect_refuses_fewer_demos_than_environments_in_one_line():
    """The collector takes one demo per environment at least: said before any work, not as a child's traceback."""
    proc = subprocess.run(
        [sys.executable, str(SCRIPTS / "bench_collect.py"), "--demos", "1"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert (
        proc.stderr.strip()
        .splitlines()[-1]
        .endswith("--demos must be at least 2 (one per environment) and --rounds at least 1")
    )


@pytest.mark.slow
def test_bench_frame_cache_reads_the_same_samples_faster_and_prints_the_ratio(tiny_dataset):
    """``scripts/bench_frame_cache.py`` on a collected dataset (``--root``; its default collects one first, as the
    committed run did): both readers' rows, the identity check and the ratio computed from them."""
    lines, ratio = run_script("bench_frame_cache.py", ("--root", str(tiny_dataset), "--samples", "60"), 300)
    (header,) = [line for line in lines if line.startswith("dataset: ")]
    assert re.fullmatch(r"dataset: 3 episodes, (\d+) frames \| window 6 \| 60 samples \| .+", header)
    frames = header.split(", ")[1].split()[0]
    assert f"frames decoded once: {frames} rows, " in "\n".join(lines)  # the cache held every frame
    readers = ("as LeRobot reads it", "frame cache")
    rates = {row[0]: (float(row[1]), float(row[2])) for row in table_rows(lines, "") if row[0] in readers}
    assert len(rates) == 2 and "samples: identical" in lines
    for seconds, rate in rates.values():
        assert close(rate, 1, 60 / seconds, (seconds, 2))
    plain, cached = rates["as LeRobot reads it"][1], rates["frame cache"][1]
    assert close(ratio, 4, cached / plain, (plain, 1), (cached, 1))
