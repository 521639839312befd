"""Smoke test for scripts/bench_env.py: it runs end to end and ends with a parseable ``ratio: <float>`` line.

No speed threshold here (this machine is noisy and CI may be slower); the >= 8x target lives in the script.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench_env.py"


def test_bench_env_quick_prints_ratio_last():
    env = {**os.environ}
    env.setdefault("MUJOCO_GL", "egl")
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"],
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
        cwd=SCRIPT.parents[1],
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr}"
    lines = proc.stdout.strip().splitlines()
    assert lines, proc.stderr
    match = re.fullmatch(r"ratio: (\S+)", lines[-1])
    assert match, f"last line is not 'ratio: <float>': {lines[-1]!r}"
    ratio = float(match.group(1))
    assert ratio > 0.0
    assert any(line.startswith("Factor World (front, fast)") for line in lines)
    assert any(line.startswith("Meta-World (corner2, defaults)") for line in lines)
