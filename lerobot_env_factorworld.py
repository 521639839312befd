"""Import hook for LeRobot's plugin discovery (distributions named ``lerobot_env_*`` are imported)."""

import lerobot_factorworld  # noqa: F401  (registers the factorworld env type and the rt1 policy)
