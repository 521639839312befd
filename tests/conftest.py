"""Shared fixtures. Rendering is headless (the package defaults MUJOCO_GL to egl before MuJoCo loads)."""

import os
import subprocess
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest  # noqa: E402

from lerobot_factorworld.envs.factor_env import FactorWorldEnv  # noqa: E402


@pytest.fixture
def make_env():
    """Build FactorWorldEnvs that are closed after the test."""
    envs = []

    def _make(*args, **kwargs):
        env = FactorWorldEnv(*args, **kwargs)
        envs.append(env)
        return env

    yield _make
    for env in envs:
        env.close()


def _run_tool(tool: str, *args: str, timeout: int = 900) -> subprocess.CompletedProcess:
    """Run one of the venv's console scripts (``lerobot-train``, ``lerobot-eval``, ...) headless; assert it succeeded."""
    proc = subprocess.run(
        [str(Path(sys.executable).parent / tool), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "MUJOCO_GL": "egl"},
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


@pytest.fixture
def run_tool():
    """Run a venv console script (``lerobot-train``, ``lerobot-eval``) headless and assert it succeeded."""
    return _run_tool
