"""Amorph from Python.

Designs (:class:`Genome`) are lists of 3-D Gaussian points, judged in a task's :class:`Scene`
(a cantilever beam that must deflect into a profile, a soft robot that must walk, a stiff
cantilever) at a voxel resolution. Evaluate them one at a time or many at once, run Amorph's own
search (:func:`run`, :class:`Run`), read any run's store (:func:`open_run`), or lend Amorph's
workers to an optimizer of your own (:class:`Cluster`).
"""

from ._amorph import (
    GENOME_COLUMNS,
    Cluster,
    Failure,
    Genome,
    Outcome,
    Scene,
    __version__,
)
from ._encoding import unit_genome
from ._runs import Run, RunStore, Table, open_run, run

__all__ = [
    "GENOME_COLUMNS",
    "Cluster",
    "Failure",
    "Genome",
    "Outcome",
    "Run",
    "RunStore",
    "Scene",
    "Table",
    "__version__",
    "open_run",
    "run",
    "unit_genome",
]
