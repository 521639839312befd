"""The experiment as data: the study's grid (``config``, with the paper's claims it tests in ``claim_config``),
the grid as content-hashed steps (``grid``), what ``--dry-run`` prints (``cost``, ``power``), which cached steps
are stale (``stale``), timings of finished runs (``profile``), and the configs shipped by name (``named``).
``policy_profile`` turns ``factorworld profile``'s checkpoint into a one-method study.
"""
