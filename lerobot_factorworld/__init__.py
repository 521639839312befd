"""Factor World for LeRobot: Meta-World scenes with controlled factors of variation.

Importing the package registers the gymnasium ids ``FactorWorld/<task>-v0`` and stays light (no
torch, no LeRobot). LeRobot's ``factorworld`` env type and ``rt1`` policy are registered by
:mod:`lerobot_factorworld.lerobot_plugin`, which LeRobot's plugin discovery imports through the
``lerobot_env_factorworld`` distribution.
"""

import os

# Headless rendering by default; must be decided before MuJoCo is first imported.
os.environ.setdefault("MUJOCO_GL", "egl")
if os.environ["MUJOCO_GL"] == "egl":
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from .envs.registration import register_envs  # noqa: E402
from .factors.registry import FACTORS, support_matrix  # noqa: E402
from .factors.values import FactorValues, SceneConfig, SceneObject, load_configs, save_configs  # noqa: E402
from .tasks import TASKS, TaskSpec, get_task  # noqa: E402

register_envs()

__all__ = [
    "FACTORS",
    "TASKS",
    "FactorValues",
    "SceneConfig",
    "SceneObject",
    "TaskSpec",
    "get_task",
    "load_configs",
    "save_configs",
    "support_matrix",
]
__version__ = "0.1.0"
