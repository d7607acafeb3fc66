"""Experiment files: what a benchmark sweep runs, and its deterministic run list.

An experiment is a YAML file naming maps, planners (with parameter grids),
seeds and limits.  :func:`load_experiment` validates it (every error is one
line naming the file and the key, e.g. ``planners[1].params.r1: ...``) and
:meth:`Experiment.expand` turns it into the list of runs, always in the same
order and each with a stable **run key**: the SHA-256 of the canonical JSON
of the run's full parameters.  The result store uses the key to skip runs
that are already stored, which is what makes an interrupted sweep resumable.

File layout
-----------
.. code-block:: yaml

    name: fusion-sweep               # default: the file name without suffix
    description: free text
    seeds: 100                       # 100 -> 0..99; also [1, 5, 7], "0:100", {start: 0, count: 100}
    limits: {time_limit_s: 5, max_iterations: 200000}   # per run (pathfuse.Budget)
    robot_radius_m: 0.0              # plan on the map inflated by this radius
    reference: astar                 # planner whose length defines R_length; null: none
                                     # (scen queries use the file's optimum instead)
    store_paths: false               # keep every path (float64 (N, 2)) in runs.path
    imports: [my_planners.py]        # modules / .py files that register extra planners
    maps:
      - name: paper                  # generated map: a fresh map for every seed
        map: paper                   # = {paper: {}}; start/goal default to the paper's
      - name: random-40
        map: {random: {size: [40, 40], density: 0.2}}
        queries: {random: 5, min_distance_m: 10}   # 5 random free pairs per seed
      - name: den312d
        map: {movingai: ../shared/data/movingai/den312d.map}
        scen: ../shared/data/movingai/den312d.map.scen
        lines: {sample: 50, seed: 0}  # or 50 (first 50), [2, 9], {every: 10}, {limit: 50}
        seeds: [0]                   # per-map seeds override the top-level ones
      - name: sandbox
        map: {ros: ../shared/data/rosmaps/nav2_tb3_sandbox/tb3_sandbox.yaml}
        queries: [{start: [-1.0, -0.5], goal: [1.5, 0.5]}]
      - name: crossing
        dynamic: scenarios/crossing.yaml      # dynamic world (pathfuse.world.simulate)
      - name: paper-dynamic                   # a generated family: one scenario per seed
        dynamic: {generate: {moving: 3, speed_range: [0.2, 0.8]}}
    planners:
      - astar
      - name: fusion
        label: fusion                # optional name in reports (default: name + swept values)
        params: {r1: [0.5, 1, 1.5, 2], r2: [1, 2], step: 0.5}   # lists are swept
        limits: {time_limit_s: 2}    # per-planner override
        kinds: [static]              # optional: only static maps (or dynamic)

A planner runs on the static maps when its name is a :func:`pathfuse.plan`
planner and on the dynamic entries when it is an online planner of
:mod:`pathfuse.world` (``kinds`` restricts this).  A list value in
``params`` is a grid axis; the runs take the cartesian product of all axes,
in the order the keys are written.  To give a parameter a list *value*, wrap
it: ``[[1, 2]]``.  Relative paths are relative to the experiment file.  For
generated maps (``paper``, ``random``) without an explicit ``seed`` the
run's seed is the map's seed.

Run order: maps (file order) > seeds > queries > planners (file order) >
parameter combinations (cartesian product, first key outermost).

Examples
--------
>>> import tempfile, pathlib
>>> text = '''
... name: demo
... seeds: 2
... maps:
...   - name: tiny
...     map: {rows: ["....", ".##.", "...."]}
...     start: [0.5, 0.5]
...     goal: [3.5, 2.5]
... planners:
...   - name: apf
... '''
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "demo.yaml"
...     _ = p.write_text(text)
...     exp = load_experiment(p)
...     runs = exp.expand()
>>> len(runs), [r.seed for r in runs]
(2, [0, 1])
>>> len(runs[0].key), runs[0].key == runs[1].key
(64, False)
"""

from __future__ import annotations

from pathfuse.bench.keys import (
    FILE_FAMILIES,
    GENERATED_FAMILIES,
    KEY_VERSION,
    Limits,
    canonical_json,
    file_digest,
    parse_seeds,
    run_key,
)
from pathfuse.bench.parse import experiment_from_dict, load_experiment, parse_experiment
from pathfuse.bench.spec import (
    Experiment,
    MapEntry,
    PlannerEntry,
    RunSpec,
    iter_groups,
    load_dynamic,
    load_map,
)

__all__ = [
    "Experiment",
    "MapEntry",
    "PlannerEntry",
    "RunSpec",
    "Limits",
    "KEY_VERSION",
    "load_experiment",
    "parse_experiment",
    "experiment_from_dict",
    "parse_seeds",
    "canonical_json",
    "run_key",
    "file_digest",
    "load_map",
    "load_dynamic",
    "iter_groups",
    "GENERATED_FAMILIES",
    "FILE_FAMILIES",
]
