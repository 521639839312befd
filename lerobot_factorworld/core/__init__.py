"""Primitives every layer may use and that import nothing else of the package: split names, seeded
RNG helpers, atomic file writes, pure setting checks, and one-line parsing of command settings.

The package reads bottom-up (``make lint`` checks it): core -> tasks and task families -> assets and
factor values -> scene compilation -> simulation (envs, experts) -> environment sampling and the
evaluation protocol -> datasets, LeRobot adapters, policies -> study -> task-family plug-ins -> command line.
"""
