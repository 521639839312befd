"""Adapters to host frameworks: LeRobot's ``factorworld`` env type (:mod:`.env_config`)."""
