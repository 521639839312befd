"""Import hook for LeRobot's plugin discovery: LeRobot imports every installed ``lerobot_env_*``
distribution by name, and this module registers Factor World's env type and policies."""

import lerobot_factorworld.lerobot_plugin  # noqa: F401
