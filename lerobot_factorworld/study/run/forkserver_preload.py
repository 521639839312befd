"""Imported by the forkserver of a ``grouped`` study that cannot fork its own process (:class:`~.executors.
LocalExecutor`): the server imports what steps import and reads the code's provenance once, and every worker
forked from it starts with both, instead of each spawned worker importing for 8-20 s. Importing this module
is its whole job (``multiprocessing``'s forkserver preloads modules by name)."""

from ...core import provenance
from .worker import warm_up

warm_up()
provenance.current()  # of the code the server imported, which its workers run (they inherit both)
