"""The study's analysis: every number a report shows, computed once from ``results.csv`` rows and the study's
config (:func:`analyze`), between ``results/`` (what computes) and ``report/`` (what renders)."""
