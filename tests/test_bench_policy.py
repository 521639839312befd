"""Smoke test for scripts/bench_policy.py: it runs end to end and ends with a parseable ``ratio: <float>`` line.

No speed threshold here (this machine is noisy and CI may be slower); the script only reports numbers.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench_policy.py"


def test_bench_policy_quick_prints_ratio_last():
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=SCRIPT.parents[1],
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr[-5000:]}"
    lines = proc.stdout.strip().splitlines()
    assert lines, proc.stderr[-5000:]
    match = re.fullmatch(r"ratio: (\S+)", lines[-1])
    assert match, f"last line is not 'ratio: <float>': {lines[-1]!r}"
    assert float(match.group(1)) > 0.0
    assert any(line.startswith("| small ") for line in lines), proc.stdout
