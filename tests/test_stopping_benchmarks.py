"""The committed outputs of the stopping rule's benchmarks (docs/benchmarks/replay_stopping.txt and
stopping_power.txt), which docs/profile.md quotes, are what their commands print now: each file holds its
commands (``$ python scripts/...``) and their outputs, and both scripts are deterministic (seeded simulation,
committed episodes), so a change to the rule or to the episodes that moves a quoted number fails here."""

from __future__ import annotations

import importlib.util
import math
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ("replay_stopping.txt", "stopping_power.txt")


def _runs(text: str) -> list[tuple[list[str], str]]:
    """(command arguments, its output) for every ``$ python ...`` line of a committed output."""
    runs: list[tuple[list[str], list[str]]] = []
    for line in text.splitlines():
        if line.startswith("$ python "):
            runs.append((shlex.split(line[len("$ python ") :]), []))
        else:
            runs[-1][1].append(line)
    return [(args, "\n".join(lines).strip()) for args, lines in runs]


@pytest.mark.parametrize("output", OUTPUTS)
def test_a_committed_output_is_what_its_commands_print(output):
    runs = _runs((ROOT / "docs" / "benchmarks" / output).read_text())
    assert runs, f"{output} names no command"
    for args, committed in runs:
        proc = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, cwd=ROOT)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert proc.stdout.strip() == committed, f"{' '.join(args)} prints something else than {output} holds"


def test_the_floor_and_the_power_bound_no_valid_test_can_beat(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))  # as `python scripts/...` has it: the replay beside it
    spec = importlib.util.spec_from_file_location("stopping_power", ROOT / "scripts" / "stopping_power.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    discordance, power_bound, profiles = script.discordance, script.power_bound, script.profiles
    rule_floor, valid_test_floor = script.rule_floor, script.valid_test_floor

    from lerobot_factorworld.study.sequential import StopRule

    assert valid_test_floor(0.05, 7) == 9 and valid_test_floor(0.05, 1) == 6  # 2**-9 <= 0.05/14 < 2**-8
    floor = rule_floor(StopRule(1, 100, 0.1, 0.95), 7)
    assert valid_test_floor(0.05, 7) <= floor <= 20  # the rule is valid, so never below the floor
    # the power bound: against the null itself it is the test's level; it grows with the episodes and the gap
    assert power_bound(0.2, 0.2, 10, 0.01) == pytest.approx(0.01)
    assert power_bound(0.437, 0.0, 10, 0.05 / 7) < power_bound(0.437, 0.0, 20, 0.05 / 7)
    assert power_bound(0.14, 0.023, 20, 0.05 / 7) < power_bound(0.437, 0.013, 20, 0.05 / 7) < 1
    assert power_bound(1.0, 0.0, 9, 0.05 / 7) == 1.0  # nine discordant pairs all favouring train: always declared
    # no ties: the randomised binomial test of 1/2, written out (10 pairs at 0.05: n10 >= 9, and n10 = 8 in part)
    null = [math.comb(10, j) / 2**10 for j in range(11)]
    part = (0.05 - null[9] - null[10]) / null[8]
    alternative = [math.comb(10, j) * 0.8**j * 0.2 ** (10 - j) for j in range(11)]
    expected = alternative[9] + alternative[10] + part * alternative[8]
    assert power_bound(0.8, 0.2, 10, 0.05) == pytest.approx(expected, rel=1e-9)
    # the simulation's discordant-pair rates are those of the outcomes it draws
    import numpy as np

    train, shifted = profiles(0.9, np.array([0.4, 0.05]), 400, 500, 0.6, np.random.default_rng(0))
    for c, gap in enumerate((0.4, 0.05)):
        p10, p01 = discordance(0.9, gap, 0.6)
        assert (train * (1 - shifted[:, c])).mean() == pytest.approx(p10, abs=0.005)
        assert ((1 - train) * shifted[:, c]).mean() == pytest.approx(p01, abs=0.005)
