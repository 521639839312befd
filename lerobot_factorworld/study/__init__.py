"""The generalization-gap study (``factorworld study``), as its pipeline, bottom-up (each subpackage imports only
from those listed before it; the layer contract in pyproject.toml checks it):

- ``sequential``: the settings of ``eval.episodes=auto``'s stopping rule (its computation, and every other
  statistic, is :mod:`lerobot_factorworld.stats`, beneath the whole package);
- ``paper``: the paper's reference numbers;
- ``run``: one step (collect, ``lerobot-train``, LeRobot's evaluation), cached by its key, and the executors;
- ``plan``: the study's config, its grid as steps, the ``--dry-run`` cost and power, stale steps;
- ``results``: ``results.csv``, ``episodes.parquet``, the aggregations and the claims' verdicts;
- ``analysis``: one typed analysis of a study's rows, computed once per report for every view;
- ``report``: ``report.md``, ``report.html``, the figures and the published tables;
- ``runner``: plan -> run what is not cached -> report (:func:`runner.run_study`, :func:`runner.inspect_study`).

The evaluation protocol (conditions, coverage, the training condition read from a dataset) is
:mod:`lerobot_factorworld.protocol`.
"""
