"""Smoke test for scripts/bench_collect.py: it runs end to end and ends with a parseable ``ratio: <float>`` line.

No speed threshold here (this machine is noisy and CI may be slower); the >= 10x target lives in the script.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench_collect.py"


@pytest.mark.slow
def test_bench_collect_quick_prints_ratio_last():
    env = {**os.environ}
    env.setdefault("MUJOCO_GL", "egl")
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=SCRIPT.parents[1],
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-5000:]}"
    lines = proc.stdout.strip().splitlines()
    assert lines, proc.stderr[-5000:]
    match = re.fullmatch(r"ratio: (\S+)", lines[-1])
    assert match, f"last line is not 'ratio: <float>': {lines[-1]!r}"
    assert float(match.group(1)) > 0.0
    for label in ("Factor World, 1 worker", "Factor World, all workers", "Meta-World, naive"):
        assert any(line.startswith(label) for line in lines), label
