"""Studies: presets of the one study engine (:mod:`pathfuse.bench`).

* :mod:`pathfuse.studies.paper` - ``pathfuse paper``: the paper's Tables I and
  II and Fig. 3 over many seeded maps;
* :mod:`pathfuse.studies.dynamic` - ``pathfuse dynamic``: every planner online
  among moving discs.

Each builds an experiment, runs it with the engine's runner into a result
store (the same worker pool, store, progress bar and resume as ``pathfuse
bench``), reads the stored runs back, reduces them with
:func:`pathfuse.bench.summary.group_stats` and writes its own tables and
figures.
"""
