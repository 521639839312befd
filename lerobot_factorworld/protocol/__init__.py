"""Environment sampling and the evaluation protocol: training environments, shifted test environments,
the conditions of an evaluation, how episodes cover them, and what a dataset was collected in."""
