"""Everything LeRobot looks up by name: the ``factorworld`` env type (and, later, the ``rt1`` policy).

Imported by LeRobot's plugin discovery (distribution ``lerobot_env_factorworld``) or by
``--env.discover_packages_path=lerobot_factorworld``. Kept out of the package ``__init__`` because
importing LeRobot costs seconds.
"""

from .envs.configs import FactorWorldEnvConfig

__all__ = ["FactorWorldEnvConfig"]
