"""Shared fixtures. Rendering is headless (the package defaults MUJOCO_GL to egl before MuJoCo loads)."""

import os

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
