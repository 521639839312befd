"""Everything LeRobot looks up by name: the ``factorworld`` env type, the ``rt1`` and ``bc`` policies, processor steps.

Imported by LeRobot's plugin discovery (distribution ``lerobot_env_factorworld``) or by
``--env.discover_packages_path=lerobot_factorworld``. Kept out of the package ``__init__`` because
importing LeRobot costs seconds.
"""

from .adapters.env_config import FactorWorldEnvConfig
from .policies.bc.configuration_bc import BCConfig
from .policies.common import language  # noqa: F401  (registers the rt1_language_embedding step)
from .policies.rt1.configuration_rt1 import RT1Config

__all__ = ["BCConfig", "FactorWorldEnvConfig", "RT1Config"]
