"""Benchmark sweeps at scale: experiment files, a SQLite result store, parallel runs.

* :mod:`pathfuse.bench.experiment` - the YAML experiment format and its run list;
* :mod:`pathfuse.bench.store` - the SQLite result store that OMPL's tools read;
* :mod:`pathfuse.bench.runner` - :func:`run_bench` (local pool or Dask);
* :mod:`pathfuse.bench.execute` - what a worker runs;
* :mod:`pathfuse.bench.progress` - the progress bar.

Examples
--------
>>> import pathlib, shutil, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = (d / "exp.yaml").write_text('''
... seeds: 3
... maps:
...   - map: {rows: ["....", ".##.", "...."]}
...     start: [0.5, 0.5]
...     goal: [3.5, 2.5]
... planners: [astar]
... ''')
>>> s = run_bench(d / "exp.yaml", d / "study.db", workers=1, progress=False)
>>> s.ran, s.succeeded, s.errors
(3, 3, 0)
>>> again = run_bench(d / "exp.yaml", d / "study.db", workers=1, progress=False)
>>> again.ran, again.skipped                    # resumed: nothing left to run
(0, 3)
>>> with ResultStore(d / "study.db", readonly=True) as st:
...     rows = st.results()
>>> sorted({(r["config"], r["status_name"], r["status_text"], r["R_length"])
...         for r in rows})        # pathfuse's status, OMPL's; A* is the reference
[('astar', 'SUCCESS', 'Exact solution', 0.0)]
>>> shutil.rmtree(d)
"""

from pathfuse.bench.experiment import Experiment, RunSpec, load_experiment, parse_experiment
from pathfuse.bench.runner import (
    ClusterLost,
    StudyLocked,
    SweepInterrupted,
    SweepSummary,
    run_bench,
)
from pathfuse.bench.store import WALL_CLOCK_COLUMNS, ResultStore, comparable_rows

__all__ = [
    "run_bench",
    "SweepSummary",
    "SweepInterrupted",
    "ClusterLost",
    "StudyLocked",
    "Experiment",
    "RunSpec",
    "load_experiment",
    "parse_experiment",
    "ResultStore",
    "comparable_rows",
    "WALL_CLOCK_COLUMNS",
]
