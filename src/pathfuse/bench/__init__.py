"""Benchmark sweeps at scale: experiment files, a SQLite result store, parallel runs.

>>> from pathfuse.bench import run_bench, load_experiment, ResultStore  # doctest: +SKIP

* :mod:`pathfuse.bench.experiment` - the YAML experiment format and its run list;
* :mod:`pathfuse.bench.store` - the OMPL-layout SQLite result store;
* :mod:`pathfuse.bench.runner` - :func:`run_bench` (local pool or Dask);
* :mod:`pathfuse.bench.execute` - what a worker runs;
* :mod:`pathfuse.bench.progress` - the progress bar.
"""

from pathfuse.bench.experiment import Experiment, RunSpec, load_experiment, parse_experiment
from pathfuse.bench.runner import SweepInterrupted, SweepSummary, run_bench
from pathfuse.bench.store import WALL_CLOCK_COLUMNS, ResultStore, comparable_rows

__all__ = [
    "run_bench",
    "SweepSummary",
    "SweepInterrupted",
    "Experiment",
    "RunSpec",
    "load_experiment",
    "parse_experiment",
    "ResultStore",
    "comparable_rows",
    "WALL_CLOCK_COLUMNS",
]
