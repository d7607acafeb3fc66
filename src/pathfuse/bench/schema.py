"""The layout of a study database: OMPL's tables as OMPL writes them, pathfuse's side tables.

See :mod:`pathfuse.bench.store` for what each table holds.  This module only
declares the layout: the column lists, the SQL that creates the tables and
views, and the mapping of pathfuse's statuses onto OMPL's ``status`` enum.

OMPL's tables are exactly those of OMPL's ``ompl_benchmark_statistics``
(``ompl/tools/_benchmark_statistics.py``, OMPL 2.0.1): ``experiments`` with
its twelve columns, ``plannerConfigs`` with three, ``enums``, ``runs``
starting with ``id, experimentid, plannerid`` and ``progress`` starting with
``runid, time``.  ``runs`` holds only numeric columns with OMPL's type words
(``REAL``, ``INTEGER``, ``BOOLEAN``, ``ENUM``), because Planner Arena offers
every column after the third as a plot attribute; everything else pathfuse
keeps is in tables whose names start with ``pathfuse_``, keyed by the run,
experiment or configuration id.

>>> ompl_status("SUCCESS", True), ompl_status("LOCAL_MINIMUM", False)
(6, 8)
>>> OMPL_STATUS_TEXT[ompl_status("ERROR", False)]
'Crash'
"""

from __future__ import annotations

import enum
import json
from collections.abc import Collection, Mapping, Sequence
from typing import Any

from pathfuse.result import Status

__all__ = [
    "SCHEMA_VERSION",
    "OmplStatus",
    "OMPL_STATUS_TEXT",
    "STATUS_TO_OMPL",
    "STATUS_NAMES",
    "OMPL_RUN_COLUMNS",
    "ATTRIBUTE_COLUMNS",
    "SIDE_COLUMNS",
    "PATH_COLUMNS",
    "RUN_COLUMNS",
    "COLUMN_TABLE",
    "EXPERIMENT_COLUMNS",
    "ompl_status",
    "q",
    "schema_sql",
    "schema_markdown",
    "distinct_config_name",
]

SCHEMA_VERSION = 2
"""1: pathfuse's columns inside OMPL's tables (before issue 22); 2: side tables."""


class OmplStatus(enum.IntEnum):
    """OMPL's ``ompl::base::PlannerStatus::StatusType`` (``ompl/base/PlannerStatus.h``)."""

    UNKNOWN = 0
    INVALID_START = 1
    INVALID_GOAL = 2
    UNRECOGNIZED_GOAL_TYPE = 3
    TIMEOUT = 4
    APPROXIMATE_SOLUTION = 5
    EXACT_SOLUTION = 6
    CRASH = 7
    ABORT = 8
    INFEASIBLE = 9


OMPL_STATUS_TEXT: tuple[str, ...] = (
    "Unknown status", "Invalid start", "Invalid goal", "Unrecognized goal type", "Timeout",
    "Approximate solution", "Exact solution", "Crash", "Abort", "Infeasible problem")
"""``enums`` rows of ``status``: OMPL's ``PlannerStatus::asString`` for 0-7.  OMPL 2.0.1's
``asString`` has no text for ABORT and INFEASIBLE (its logs print "Unknown status" for
them); pathfuse writes the meaning of the enum value instead."""

STATUS_NAMES: tuple[str, ...] = tuple(s.name for s in Status) + ("ERROR",)
"""pathfuse's status vocabulary (:class:`~pathfuse.result.Status`, then ``ERROR`` for a run
that raised or whose worker crashed): the rows of ``pathfuse_status``."""

STATUS_TO_OMPL: Mapping[str, OmplStatus] = {
    Status.SUCCESS.name: OmplStatus.EXACT_SOLUTION,
    Status.NO_PATH.name: OmplStatus.INFEASIBLE,
    Status.START_OCCUPIED.name: OmplStatus.INVALID_START,
    Status.START_OUT_OF_BOUNDS.name: OmplStatus.INVALID_START,
    Status.GOAL_OCCUPIED.name: OmplStatus.INVALID_GOAL,
    Status.GOAL_OUT_OF_BOUNDS.name: OmplStatus.INVALID_GOAL,
    Status.LOCAL_MINIMUM.name: OmplStatus.ABORT,
    Status.MAX_ITERATIONS.name: OmplStatus.TIMEOUT,
    Status.TIMEOUT.name: OmplStatus.TIMEOUT,
    Status.COLLISION.name: OmplStatus.ABORT,
    "ERROR": OmplStatus.CRASH,
}
"""pathfuse status -> OMPL status: success is an exact solution; a spent time or iteration
budget a timeout; a search that exhausted the map proved the query infeasible; a bad start
or goal is an invalid start or goal; a local minimum, a stall or a collision of an episode
ended the run without a solution "for some other reason" (ABORT); a run that raised or
whose worker died is a crash."""


def ompl_status(name: str | None, solved: bool) -> int:
    """OMPL's status code of a run whose pathfuse status is ``name``.

    An unknown name (a plug-in's own status) is an exact solution when the run
    solved its query and ``Unknown status`` otherwise.
    """
    code = STATUS_TO_OMPL.get(name or "ERROR")
    if code is None:
        code = OmplStatus.EXACT_SOLUTION if solved else OmplStatus.UNKNOWN
    return int(code)


EXPERIMENT_COLUMNS: tuple[str, ...] = (
    "id", "name", "totaltime", "timelimit", "memorylimit", "runcount", "version", "hostname",
    "cpuinfo", "date", "seed", "setup")
"""``experiments`` as OMPL creates it (Planner Arena reads columns 13 on as problem
parameters, so pathfuse adds none)."""

# (name, declared type, doc): created with the table
OMPL_RUN_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("id", "INTEGER PRIMARY KEY AUTOINCREMENT", "OMPL: row id"),
    ("experimentid", "INTEGER", "OMPL: experiments.id (the map entry)"),
    ("plannerid", "INTEGER", "OMPL: plannerConfigs.id"),
    ("time", "REAL", "OMPL: planning time in s (numba compilation excluded)"),
    ("solved", "BOOLEAN", "OMPL: 1 for an exact solution (pathfuse: status SUCCESS)"),
    ("status", "ENUM", "OMPL: OMPL's status code, an index into enums(name='status')"),
    ("memory", "REAL", "OMPL: peak resident memory of the worker in MB"),
    ("solution_length", "REAL", "OMPL: path length in m (NULL unless solved)"),
    ("solution_clearance", "REAL", "OMPL: smallest obstacle clearance of the path in m"),
    ("solution_smoothness", "REAL", "OMPL: smoothness as pathfuse.metrics defines it"),
    ("solution_segments", "INTEGER", "OMPL: number of path segments"),
)

# numeric run properties of pathfuse: added to runs when a run first reports one, as
# OMPL's script adds a column for each property a log names
ATTRIBUTE_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("expansions", "INTEGER", "grid search expansions"),
    ("iterations", "INTEGER", "local planner steps / episode steps"),
    ("steps", "INTEGER", "path steps as pathfuse.metrics counts them"),
    ("collision_free", "BOOLEAN", "path collision-free for the robot radius"),
    ("collisions", "INTEGER", "number of collisions (0 when collision-free)"),
    ("time_to_goal", "REAL", "dynamic runs: simulated time to reach the goal in s"),
    ("path_length", "REAL", "length in m of the returned path, also when not solved (a local "
     "planner's partial path; the driven trajectory of a dynamic run)"),
    ("R_length", "REAL", "(solution_length - reference_length) / reference_length"),
    ("wall_time", "REAL", "wall-clock seconds of the whole run incl. metrics"),
)

SIDE_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("runid", "INTEGER PRIMARY KEY", "runs.id"),
    ("run_key", "TEXT NOT NULL UNIQUE", "SHA-256 of params (the run's identity)"),
    ("status_name", "TEXT", "pathfuse's status (a name of pathfuse_status: Status or ERROR)"),
    ("problem_key", "TEXT", "identity of map + query (pairs planners on a problem)"),
    ("kind", "TEXT", "run kind: static or dynamic"),
    ("map_name", "TEXT", "map entry name"),
    ("planner", "TEXT", "planner registry name"),
    ("seed", "INTEGER", "the run's seed"),
    ("query_index", "INTEGER", "index of the query within the map entry and seed"),
    ("scen_line", "INTEGER", "line of the MovingAI .scen file, if any"),
    ("start_x", "REAL", "start x in m"),
    ("start_y", "REAL", "start y in m"),
    ("goal_x", "REAL", "goal x in m"),
    ("goal_y", "REAL", "goal y in m"),
    ("reference_length", "REAL", "scen optimum or reference planner length in m"),
    ("reference_source", "TEXT", "'scen' or the reference planner's name"),
    ("message", "TEXT", "the planner's message"),
    ("error", "TEXT", "one-line error text of a run that raised"),
    ("traceback", "TEXT", "traceback of a run that raised"),
    ("params", "TEXT", "full run parameters, canonical JSON (hashed into run_key)"),
    ("metrics", "TEXT", "JSON of every scalar metric"),
    ("info", "TEXT", "JSON of the planner's scalar extras (clock readings excluded)"),
    ("timing", "TEXT", "JSON of the planner's clock readings (keys naming a time/rate)"),
    ("pathfuse_version", "TEXT", "pathfuse version of the worker"),
    ("host", "TEXT", "host name of the worker"),
    ("worker", "TEXT", "worker process id or Dask worker address"),
    ("started_at", "TEXT", "UTC start of the run (ISO 8601)"),
    ("finished_at", "TEXT", "UTC end of the run (ISO 8601)"),
)

PATH_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("runid", "INTEGER PRIMARY KEY", "runs.id"),
    ("path", "BLOB", "little-endian float64 (N, 2) path, with store_paths"),
    ("headings", "BLOB", "little-endian float64 (N,) heading in rad at each path point (dynamic "
     "runs whose robot has a heading), with store_paths"),
)

RUN_COLUMNS: tuple[tuple[str, str, str], ...] = (
    OMPL_RUN_COLUMNS + ATTRIBUTE_COLUMNS + SIDE_COLUMNS[1:] + PATH_COLUMNS[1:])
"""Every column of a run as :meth:`ResultStore.results` returns it (name, type, doc)."""

COLUMN_TABLE: Mapping[str, str] = {
    **{c: "runs" for c, _, _ in OMPL_RUN_COLUMNS + ATTRIBUTE_COLUMNS},
    **{c: "pathfuse_runs" for c, _, _ in SIDE_COLUMNS[1:]},
    **{c: "pathfuse_paths" for c, _, _ in PATH_COLUMNS[1:]},
}
"""The table that stores each column of :data:`RUN_COLUMNS`."""


def q(name: str) -> str:
    """``name`` quoted as an SQL identifier."""
    return '"' + name.replace('"', '""') + '"'


def _cols(cols: tuple[tuple[str, str, str], ...]) -> str:
    return ", ".join(f"{q(c)} {t}" for c, t, _ in cols)


_SIDE_SELECT = ", ".join(f"p.{q(c)}" for c, _, _ in SIDE_COLUMNS[1:])


def schema_sql() -> list[str]:
    """The statements that create every table, index and view (``IF NOT EXISTS``)."""
    return [
        # OMPL's tables, column for column as ompl_benchmark_statistics creates them
        "CREATE TABLE IF NOT EXISTS experiments (id INTEGER PRIMARY KEY AUTOINCREMENT, "
        "name VARCHAR(512), totaltime REAL, timelimit REAL, memorylimit REAL, "
        "runcount INTEGER, version VARCHAR(128), hostname VARCHAR(1024), cpuinfo TEXT, "
        "date DATETIME, seed VARCHAR(24), setup TEXT)",
        "CREATE TABLE IF NOT EXISTS plannerConfigs (id INTEGER PRIMARY KEY AUTOINCREMENT, "
        "name VARCHAR(512) NOT NULL, settings TEXT)",
        "CREATE TABLE IF NOT EXISTS enums (name VARCHAR(512), value INTEGER, "
        "description TEXT, PRIMARY KEY (name, value))",
        f"CREATE TABLE IF NOT EXISTS runs ({_cols(OMPL_RUN_COLUMNS)}, "
        "FOREIGN KEY (experimentid) REFERENCES experiments(id) ON DELETE CASCADE, "
        "FOREIGN KEY (plannerid) REFERENCES plannerConfigs(id) ON DELETE CASCADE)",
        "CREATE TABLE IF NOT EXISTS progress (runid INTEGER, time REAL, "
        "PRIMARY KEY (runid, time), "
        "FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE)",
        # pathfuse's side tables
        "CREATE TABLE IF NOT EXISTS pathfuse_meta (key TEXT PRIMARY KEY, value TEXT)",
        "CREATE TABLE IF NOT EXISTS pathfuse_experiments (experimentid INTEGER PRIMARY KEY "
        "REFERENCES experiments(id) ON DELETE CASCADE, study TEXT, entry TEXT, kind TEXT)",
        "CREATE TABLE IF NOT EXISTS pathfuse_configs (plannerid INTEGER PRIMARY KEY "
        "REFERENCES plannerConfigs(id) ON DELETE CASCADE, planner TEXT, label TEXT)",
        "CREATE TABLE IF NOT EXISTS pathfuse_status (name TEXT PRIMARY KEY, "
        "ompl_status INTEGER, description TEXT)",
        f"CREATE TABLE IF NOT EXISTS pathfuse_runs ({_cols(SIDE_COLUMNS)}, "
        "FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE)",
        f"CREATE TABLE IF NOT EXISTS pathfuse_paths ({_cols(PATH_COLUMNS)}, "
        "FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE)",
        "CREATE TABLE IF NOT EXISTS pathfuse_sessions (id INTEGER PRIMARY KEY AUTOINCREMENT, "
        "study TEXT, experiment_file TEXT, experiment_sha256 TEXT, experiment_text TEXT, "
        "started_at TEXT, finished_at TEXT, state TEXT, host TEXT, pathfuse_version TEXT, "
        "python TEXT, workers INTEGER, scheduler TEXT, planned INTEGER, skipped INTEGER, "
        "ran INTEGER, errors INTEGER)",
        "CREATE INDEX IF NOT EXISTS runs_experiment_planner ON runs (experimentid, plannerid)",
        "CREATE INDEX IF NOT EXISTS pathfuse_runs_problem ON pathfuse_runs (problem_key, seed)",
        "CREATE INDEX IF NOT EXISTS pathfuse_configs_label ON pathfuse_configs (label)",
        # runs.* is expanded when the view is used: it follows the columns added later
        "CREATE VIEW IF NOT EXISTS pathfuse_results AS "
        f"SELECT r.*, {_SIDE_SELECT}, pp.path, pp.headings, "
        "e.name AS experiment, c.name AS config, en.description AS status_text "
        "FROM runs r "
        "JOIN experiments e ON e.id = r.experimentid "
        "JOIN plannerConfigs c ON c.id = r.plannerid "
        "LEFT JOIN pathfuse_runs p ON p.runid = r.id "
        "LEFT JOIN pathfuse_paths pp ON pp.runid = r.id "
        "LEFT JOIN enums en ON en.name = 'status' AND en.value = r.status",
        "CREATE VIEW IF NOT EXISTS bestPlannerConfigsPerExperiment AS "
        "SELECT plannerid, experimentid, AVG(solved) AS avg_solved, AVG(time) AS avg_total_time "
        "FROM runs GROUP BY plannerid, experimentid ORDER BY avg_solved DESC, avg_total_time ASC",
        "CREATE VIEW IF NOT EXISTS bestPlannerConfigs AS "
        "SELECT plannerid, AVG(solved) AS avg_solved, AVG(time) AS avg_total_time "
        "FROM runs GROUP BY plannerid ORDER BY avg_solved DESC, avg_total_time ASC",
    ]


def schema_markdown() -> str:
    """A Markdown table of a run's columns and the table each is stored in."""
    lines = ["| column | type | table | meaning |", "|---|---|---|---|"]
    lines += [f"| `{c}` | {t.split()[0]} | `{COLUMN_TABLE[c]}` | {doc} |"
              for c, t, doc in RUN_COLUMNS]
    return "\n".join(lines)


def distinct_config_name(name: str, settings: str, rivals: Sequence[str],
                         taken: Collection[str]) -> str:
    """A ``plannerConfigs.name`` for a configuration that no other configuration has.

    Planner Arena shows configurations by name, so two configurations never
    share one.  ``rivals`` are the settings of the configurations already
    named ``name``; ``taken`` every name in use.  ``name`` itself when free;
    otherwise ``name[k=v,...]`` over the parameters whose values differ from
    the rivals' (when the settings are JSON objects), else ``name#2``, ``name#3``...

    >>> distinct_config_name("astar", '{"h": "octile"}', ['{"h": "euclidean"}'], {"astar"})
    'astar[h=octile]'
    >>> distinct_config_name("x", "a;", ["b;"], {"x"})
    'x#2'
    """
    if name not in taken:
        return name
    mine = _json_object(settings)
    others = [_json_object(s) for s in rivals]
    if mine is not None and others and all(o is not None for o in others):
        keys = sorted(k for k in set(mine).union(*others)  # type: ignore[arg-type]
                      if any(o.get(k) != mine.get(k) for o in others if o is not None))
        if keys:
            inner = ",".join(f"{k}={_text(mine.get(k))}" for k in keys)
            candidate = f"{name}[{inner}]"
            if candidate not in taken:
                return candidate
    n = 2
    while f"{name}#{n}" in taken:
        n += 1
    return f"{name}#{n}"


def _json_object(text: str) -> dict[str, Any] | None:
    try:
        v = json.loads(text)
    except (TypeError, ValueError):
        return None
    return v if isinstance(v, dict) else None


def _text(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return v if isinstance(v, str) else json.dumps(v, sort_keys=True)
