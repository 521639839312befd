"""Pure statistics: functions of numbers, arrays and p-values that know nothing of studies, tasks or files.

Why a library apart: every interval, test and sample size the project reports is computed here, once, checked by
hand and against its reference; the study and its reports only choose what to feed it. It imports numpy and scipy
only, never the package (the import contract in pyproject.toml checks it). Its modules, one job each:

- ``estimate``: :class:`~.estimate.Estimate`, a point with its interval, level and method;
- ``proportions``: Wilson's interval of a success rate, Newcombe's intervals of a difference of two (paired,
  independent), the normal quantile;
- ``summaries``: the pair metric, the interaction, mean and standard error, and their vectorised forms;
- ``ranks``: ranks (ties averaged) and Spearman's rho;
- ``bootstrap``: the seed-level, cell-seeded bootstrap and its percentile interval;
- ``decision``: the decision interval (bootstrap and t-interval over seeds, hulled);
- ``multitest``: multiple testing over a vector of p-values (Holm, Bonferroni);
- ``confseq``: anytime-valid confidence sequences for bounded means (hedged betting);
- ``stopping``: the stopping rule on a batch of paired sequences, on those sequences;
- ``power``: the smallest effect a design resolves, and the episodes or seeds that would resolve one.
"""
