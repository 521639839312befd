"""The benchmark scripts run end to end and end with a parseable ``ratio: <float>`` line.

No speed thresholds here (this machine is noisy and CI may be slower): the targets live in the scripts.
"""

from __future__ import annotations

import os
import platform
import re
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


@pytest.mark.parametrize(
    ("script", "expected_rows", "timeout"),
    [
        pytest.param("bench_env.py", ("Factor World (front, fast)", "Meta-World (corner2, defaults)"), 180, id="env"),
        pytest.param("bench_policy.py", ("| small",), 300, id="policy"),
        pytest.param(
            "bench_malloc.py",
            ("| default |", "| keep_freed |", "identical weights"),
            180,
            id="malloc",
            marks=pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt's settings are glibc's"),
        ),
        pytest.param("bench_collect.py", (), 300, id="collect", marks=pytest.mark.slow),
        pytest.param("bench_bc.py", ("| cpu    | bc conv ", "| cpu    | act "), 600, id="bc", marks=pytest.mark.slow),
    ],
)
def test_bench_script_quick_prints_ratio_last(script, expected_rows, timeout):
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.run(
        [sys.executable, str(SCRIPTS / script), "--quick"],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        cwd=SCRIPTS.parent,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-4000:]}"
    lines = proc.stdout.strip().splitlines()
    match = re.fullmatch(r"ratio: (\S+)", lines[-1]) if lines else None
    assert match, f"last line is not 'ratio: <float>': {lines[-1:]!r}"
    assert float(match.group(1)) > 0.0
    for row in expected_rows:
        assert any(line.startswith(row) for line in lines), row


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
