"""The generalization-gap study (``factorworld study``), one module per job:

- ``conditions``: evaluation conditions and the protocol (condition-independent test environments,
  paired episode seeds, coverage, the training condition read from a dataset); used by the env config;
- ``config``: the study's settings (a draccus dataclass, checked before any work starts);
- ``plan``: the grid as content-hashed steps, and the ``--dry-run`` cost model;
- ``steps``: running one step (collect, ``lerobot-train``, LeRobot's evaluation), cached by its key;
- ``executors``: a local process pool or Ray, which only run the steps they are handed;
- ``metrics``: pure functions (Wilson and Newcombe intervals, pair metric, Spearman);
- ``report``: ``results.csv``, PNG plots and ``report.md``;
- ``runner``: plan -> run what is not cached -> report.
"""
