"""The generalization-gap study (``factorworld study``), as its pipeline, bottom-up (each subpackage imports only
from those listed before it; the layer contract in pyproject.toml checks it):

- ``confseq``: anytime-valid confidence sequences for bounded means (the hedged betting construction);
- ``sequential``: the stopping rule of ``eval.episodes=auto`` built on them;
- ``metrics``, ``paper``: pure statistics (Wilson and Newcombe intervals, the pair metric, Spearman) and the
  paper's reference numbers;
- ``run``: one step (collect, ``lerobot-train``, LeRobot's evaluation), cached by its key, and the executors;
- ``plan``: the study's config, its grid as steps, the ``--dry-run`` cost and power, stale steps;
- ``results``: ``results.csv``, ``episodes.parquet``, the aggregations and the claims' verdicts;
- ``report``: ``report.md``, ``report.html``, the figures and the published tables;
- ``runner``: plan -> run what is not cached -> report (:func:`runner.run_study`, :func:`runner.inspect_study`).

The evaluation protocol (conditions, coverage, the training condition read from a dataset) is
:mod:`lerobot_factorworld.protocol`.
"""
