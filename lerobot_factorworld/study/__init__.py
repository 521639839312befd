"""The generalization-gap study (``factorworld study``), one module per job or artefact:

- ``config``: the study's settings (a draccus dataclass, checked before any work starts);
- ``inputs``: the typed inputs of collect, train and eval steps (what a step's key hashes);
- ``plan``: the grid as content-hashed steps;
- ``cost``: the ``--dry-run`` text and its rough cost model;
- ``steps``: running one step (collect, ``lerobot-train``, LeRobot's evaluation), cached by its key;
- ``executors``: a local process pool or Ray, which only run the steps they are handed;
- ``metrics``: pure functions (Wilson and Newcombe intervals, pair metric, Spearman);
- ``paper``: the paper's reference numbers (factor ordering, real-robot success rates);
- ``results``: ``results.csv``, one row per finished evaluation;
- ``aggregate``: one selector per table and figure, over the rows of ``results.csv``;
- ``plots``: the PNG plots; ``markdown``: ``report.md``;
- ``report``: writes all of them (and the task families' sections) from the finished steps;
- ``runner``: plan -> run what is not cached -> report.

The evaluation protocol (conditions, coverage, the training condition read from a dataset) is
:mod:`lerobot_factorworld.protocol`.
"""
