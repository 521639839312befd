"""Imported once by the collection workers' forkserver, so that forked workers start with LeRobot,
MuJoCo and Meta-World already loaded (a LeRobot import costs seconds). Creates no GL context."""

import lerobot.datasets.lerobot_dataset  # noqa: F401
import metaworld.env_dict  # noqa: F401
import metaworld.policies  # noqa: F401

import lerobot_factorworld.envs.factor_env  # noqa: F401
import lerobot_factorworld.experts  # noqa: F401
