"""The result store: one SQLite database per study, in the layout of OMPL's benchmarks.

The tables ``experiments``, ``plannerConfigs``, ``enums``, ``runs`` and
``progress`` have the layout that OMPL's ``ompl_benchmark_statistics.py``
writes (and Planner Arena reads): ``runs`` starts with ``id, experimentid,
plannerid`` and holds one row per run with OMPL's property columns (spaces
in OMPL's property names become underscores, as OMPL's log reader does),
declared with OMPL's type words ``REAL``, ``INTEGER``, ``BOOLEAN``, ``ENUM``
(an index into ``enums``).  pathfuse adds its own columns after them, and
tables/views whose names start with ``pathfuse_``.

Mapping to OMPL's concepts: an OMPL *experiment* is one map entry of the
study (``experiments.name = "<study>/<map entry>"``), a *planner config* is a
planner with one parameter combination (``plannerConfigs.name`` like
``fusion(r1=0.5,r2=2)``, ``settings`` = the full parameters as JSON), and a
run is one (map, seed, query, planner config).

Tables
------
experiments
    ``id``, ``name`` ("study/entry"), ``totaltime`` (s, sum of run wall times),
    ``timelimit`` (s per run, 0 if none), ``memorylimit`` (0), ``runcount``
    (runs per planner config), ``version`` ("pathfuse X.Y.Z"), ``hostname``,
    ``cpuinfo``, ``date`` (first session), ``seed`` (first seed), ``setup``
    (the map entry as JSON); pathfuse: ``study``, ``entry``, ``kind``.
plannerConfigs
    ``id``, ``name``, ``settings`` (canonical JSON of the full parameters);
    pathfuse: ``planner`` (registry name).
enums
    ``name``, ``value``, ``description``: ``name = 'status'`` lists the run
    statuses (pathfuse's :class:`~pathfuse.Status` names, then ``ERROR`` for a
    run that raised or whose worker crashed).
runs (OMPL columns)
    ``id``; ``experimentid``; ``plannerid``; ``time`` (REAL, planning time in
    s, ``PlanResult.time_s``, numba compilation excluded); ``solved``
    (BOOLEAN); ``status`` (ENUM); ``memory`` (REAL, peak resident memory of
    the worker process in MB); ``solution_length`` (REAL, m, NULL unless
    solved); ``solution_clearance`` (REAL, m, smallest obstacle clearance);
    ``solution_smoothness`` (REAL, as ``pathfuse.metrics`` defines it);
    ``solution_segments`` (INTEGER, waypoints - 1).
runs (pathfuse columns)
    ``run_key`` (TEXT UNIQUE, SHA-256 of ``params``); ``problem_key`` (map +
    query, to pair planners on the same problem); ``kind`` (static/dynamic);
    ``map_name``; ``planner``; ``seed``; ``query_index``; ``scen_line``;
    ``start_x``, ``start_y``, ``goal_x``, ``goal_y`` (m); ``status_name``;
    ``expansions``; ``iterations``; ``steps``; ``collision_free`` (BOOLEAN);
    ``collisions`` (INTEGER); ``time_to_goal`` (REAL, s, dynamic runs); ``path_length``
    (REAL, m: the returned path's length, also when not solved; the driven trajectory's
    for a dynamic run);
    ``reference_length`` (m: the scen file's optimum, or the reference
    planner's length on the same query); ``reference_source``; ``R_length``
    (``(solution_length - reference_length) / reference_length``, the
    paper's R_length against the reference); ``message``; ``error`` (one
    line, runs that raised); ``traceback``; ``params`` (the run's full
    parameters, canonical JSON); ``metrics`` (JSON of every scalar metric);
    ``info`` (JSON of the planner's scalar extras); ``timing`` (JSON of
    the extras that are clock readings: keys with time, rate, ``_s``);
    ``path`` (BLOB,
    little-endian float64 (N, 2), only with ``store_paths``); ``headings``
    (BLOB, little-endian float64 (N,), the heading at each path point of a
    dynamic run whose robot has one, only with ``store_paths``);
    ``pathfuse_version``; ``host``; ``worker``; ``started_at``;
    ``finished_at``; ``wall_time`` (s, whole run incl. metrics).
progress
    ``runid``, ``time`` (OMPL layout; more columns are added as a run kind
    reports progress samples).
pathfuse_meta
    ``key``, ``value``: ``schema_version``, ``created_at``.
pathfuse_sessions
    One row per invocation: ``study``, ``experiment_file``,
    ``experiment_sha256``, ``experiment_text``, ``started_at``,
    ``finished_at``, ``state`` (running / finished / interrupted / failed),
    ``host``, ``pathfuse_version``, ``python``, ``workers``, ``scheduler``,
    ``planned``, ``skipped``, ``ran``, ``errors``.

Views
-----
pathfuse_results
    Every run with ``experiment`` (name), ``config`` (planner config name)
    and ``status_text``: one flat table for reports.
bestPlannerConfigsPerExperiment, bestPlannerConfigs
    OMPL's summary views: mean ``solved`` and mean ``time`` per config.

Durability: WAL journal, one writer (the sweep's client process); each
batch of finished runs is one transaction, so a run is either stored whole
or not at all, and a killed sweep loses only runs that were not committed.

Examples
--------
>>> import tempfile, os
>>> with tempfile.TemporaryDirectory() as d:
...     with ResultStore(os.path.join(d, "s.db")) as st:
...         e = st.ensure_experiment("study", "paper", "static", runcount=2)
...         p = st.ensure_planner_config("astar", "astar", "{}")
...         n = st.insert_runs([{"run_key": "k1", "experimentid": e, "plannerid": p,
...                          "status_name": "SUCCESS", "solved": True, "time": 0.01,
...                          "solution_length": 14.14}])
...         done, count = sorted(st.done_keys()), st.count()
>>> n, done, count
(1, ['k1'], 1)
"""

from __future__ import annotations

import json
import os
import platform
import socket
import sqlite3
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from pathfuse.result import ConfigError, PathfuseError, Status

__all__ = [
    "ResultStore",
    "RUN_COLUMNS",
    "WALL_CLOCK_COLUMNS",
    "SCHEMA_VERSION",
    "STATUS_NAMES",
    "comparable_rows",
    "schema_markdown",
]

SCHEMA_VERSION = 1

STATUS_NAMES: tuple[str, ...] = tuple(s.name for s in Status) + ("ERROR",)
"""Initial ``enums`` values of ``status`` (new names are appended, never renumbered)."""

# (name, declared type, doc)
RUN_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("id", "INTEGER PRIMARY KEY AUTOINCREMENT", "OMPL: row id"),
    ("experimentid", "INTEGER", "OMPL: experiments.id (the map entry)"),
    ("plannerid", "INTEGER", "OMPL: plannerConfigs.id"),
    ("time", "REAL", "OMPL: planning time in s (numba compilation excluded)"),
    ("solved", "BOOLEAN", "OMPL: 1 when status is SUCCESS"),
    ("status", "ENUM", "OMPL: index into enums(name='status')"),
    ("memory", "REAL", "OMPL: peak resident memory of the worker in MB"),
    ("solution_length", "REAL", "OMPL: path length in m (NULL unless solved)"),
    ("solution_clearance", "REAL", "OMPL: smallest obstacle clearance of the path in m"),
    ("solution_smoothness", "REAL", "OMPL: smoothness as pathfuse.metrics defines it"),
    ("solution_segments", "INTEGER", "OMPL: number of path segments"),
    ("run_key", "TEXT NOT NULL UNIQUE", "SHA-256 of params (the run's identity)"),
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
    ("status_name", "TEXT", "status as text (Status name or ERROR)"),
    ("expansions", "INTEGER", "grid search expansions"),
    ("iterations", "INTEGER", "local planner steps / episode steps"),
    ("steps", "INTEGER", "path steps as pathfuse.metrics counts them"),
    ("collision_free", "BOOLEAN", "path collision-free for the robot radius"),
    ("collisions", "INTEGER", "number of collisions (0 when collision-free)"),
    ("time_to_goal", "REAL", "dynamic runs: simulated time to reach the goal in s"),
    ("path_length", "REAL", "length in m of the returned path, also when not solved (a local "
     "planner's partial path; the driven trajectory of a dynamic run)"),
    ("reference_length", "REAL", "scen optimum or reference planner length in m"),
    ("reference_source", "TEXT", "'scen' or the reference planner's name"),
    ("R_length", "REAL", "(solution_length - reference_length) / reference_length"),
    ("message", "TEXT", "the planner's message"),
    ("error", "TEXT", "one-line error text of a run that raised"),
    ("traceback", "TEXT", "traceback of a run that raised"),
    ("params", "TEXT", "full run parameters, canonical JSON (hashed into run_key)"),
    ("metrics", "TEXT", "JSON of every scalar metric"),
    ("info", "TEXT", "JSON of the planner's scalar extras (clock readings excluded)"),
    ("timing", "TEXT", "JSON of the planner's clock readings (keys naming a time/rate)"),
    ("path", "BLOB", "little-endian float64 (N, 2) path, with store_paths"),
    ("headings", "BLOB", "little-endian float64 (N,) heading in rad at each path point (dynamic "
     "runs whose robot has a heading), with store_paths"),
    ("pathfuse_version", "TEXT", "pathfuse version of the worker"),
    ("host", "TEXT", "host name of the worker"),
    ("worker", "TEXT", "worker process id or Dask worker address"),
    ("started_at", "TEXT", "UTC start of the run (ISO 8601)"),
    ("finished_at", "TEXT", "UTC end of the run (ISO 8601)"),
    ("wall_time", "REAL", "wall-clock seconds of the whole run incl. metrics"),
)

WALL_CLOCK_COLUMNS: frozenset[str] = frozenset({
    "id", "time", "memory", "host", "worker", "started_at", "finished_at", "wall_time",
    "timing",
})
"""Columns that differ between two otherwise identical sweeps (timing, placement)."""

_RUN_COLS = [c for c, _, _ in RUN_COLUMNS]
_INSERT_COLS = [c for c in _RUN_COLS if c != "id"]
_INSERT_SET = frozenset(_INSERT_COLS)


def _q(name: str) -> str:
    return '"' + name.replace('"', '""') + '"'


_INSERT_SQL = (
    f"INSERT INTO runs ({', '.join(_q(c) for c in _INSERT_COLS)}) "
    f"VALUES ({', '.join('?' for _ in _INSERT_COLS)}) ON CONFLICT(run_key) DO UPDATE SET "
    + ", ".join(f"{_q(c)} = excluded.{_q(c)}" for c in _INSERT_COLS if c != "run_key")
    + " WHERE runs.status_name = 'ERROR'")
"""One run's insert: a new key is stored, a stored ERROR is replaced, anything else kept."""


_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS experiments
    (id INTEGER PRIMARY KEY AUTOINCREMENT, name VARCHAR(512), totaltime REAL,
     timelimit REAL, memorylimit REAL, runcount INTEGER, version VARCHAR(128),
     hostname VARCHAR(1024), cpuinfo TEXT, date DATETIME, seed INTEGER, setup TEXT,
     study TEXT, entry TEXT, kind TEXT);
CREATE TABLE IF NOT EXISTS plannerConfigs
    (id INTEGER PRIMARY KEY AUTOINCREMENT, name VARCHAR(512) NOT NULL, settings TEXT,
     planner TEXT);
CREATE TABLE IF NOT EXISTS enums
    (name VARCHAR(512), value INTEGER, description TEXT, PRIMARY KEY (name, value));
CREATE TABLE IF NOT EXISTS runs
    ({", ".join(f"{_q(c)} {t}" for c, t, _ in RUN_COLUMNS)},
     FOREIGN KEY (experimentid) REFERENCES experiments(id) ON DELETE CASCADE,
     FOREIGN KEY (plannerid) REFERENCES plannerConfigs(id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS progress
    (runid INTEGER, time REAL, PRIMARY KEY (runid, time),
     FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS pathfuse_meta (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE IF NOT EXISTS pathfuse_sessions
    (id INTEGER PRIMARY KEY AUTOINCREMENT, study TEXT, experiment_file TEXT,
     experiment_sha256 TEXT, experiment_text TEXT, started_at TEXT, finished_at TEXT,
     state TEXT, host TEXT, pathfuse_version TEXT, python TEXT, workers INTEGER,
     scheduler TEXT, planned INTEGER, skipped INTEGER, ran INTEGER, errors INTEGER);
CREATE INDEX IF NOT EXISTS runs_experiment_planner ON runs (experimentid, plannerid);
CREATE INDEX IF NOT EXISTS runs_problem ON runs (problem_key, seed);
CREATE VIEW IF NOT EXISTS pathfuse_results AS
    SELECT runs.*, experiments.name AS experiment, plannerConfigs.name AS config,
           enums.description AS status_text
    FROM runs
    JOIN experiments ON experiments.id = runs.experimentid
    JOIN plannerConfigs ON plannerConfigs.id = runs.plannerid
    LEFT JOIN enums ON enums.name = 'status' AND enums.value = runs.status;
CREATE VIEW IF NOT EXISTS bestPlannerConfigsPerExperiment AS
    SELECT plannerid, experimentid, AVG(solved) AS avg_solved, AVG(time) AS avg_total_time
    FROM runs GROUP BY plannerid, experimentid
    ORDER BY avg_solved DESC, avg_total_time ASC;
CREATE VIEW IF NOT EXISTS bestPlannerConfigs AS
    SELECT plannerid, AVG(solved) AS avg_solved, AVG(time) AS avg_total_time
    FROM runs GROUP BY plannerid ORDER BY avg_solved DESC, avg_total_time ASC;
"""


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


class ResultStore:
    """An open study database (created on first use).

    Parameters
    ----------
    path : path-like
        The SQLite file (``":memory:"`` for tests).
    readonly : bool
        Open an existing database for reading only.
    check : bool
        Check the file first (:func:`~pathfuse.bench.dbcheck.check_study_file`); False
        when the caller just did.

    Raises
    ------
    ConfigError
        The file is a folder, not SQLite, another application's database, damaged
        (SQLite's ``quick_check``), read-only when opened for writing, or written by
        a newer schema (:func:`~pathfuse.bench.dbcheck.check_study_file`; the
        file is not touched before these checks).
    """

    def __init__(self, path: str | os.PathLike[str], readonly: bool = False, *,
                 check: bool = True) -> None:
        self.path = str(path)
        if self.path != ":memory:" and check:
            from pathfuse.bench.dbcheck import check_study_file

            check_study_file(self.path, write=not readonly)  # only reads the file
        if readonly:
            uri = Path(self.path).resolve().as_uri() + "?mode=ro"
            self.conn = sqlite3.connect(uri, uri=True, timeout=60.0)
        else:
            self.conn = sqlite3.connect(self.path, timeout=60.0, isolation_level=None)
        self.conn.row_factory = sqlite3.Row
        try:
            self.conn.execute("PRAGMA foreign_keys = ON")
            if not readonly:
                self.conn.execute("PRAGMA journal_mode = WAL")
                self.conn.execute("PRAGMA synchronous = NORMAL")
                self._create()
            self._status_values = self._load_enums()
        except sqlite3.DatabaseError as exc:
            self.conn.close()
            raise ConfigError(f"{self.path}: not a usable result database ({exc})") from None

    # ---------------------------------------------------------------- setup
    def _create(self) -> None:
        c = self.conn
        c.execute("BEGIN IMMEDIATE")
        try:
            for stmt in _split_sql(_SCHEMA):
                c.execute(stmt)
            row = c.execute("SELECT value FROM pathfuse_meta WHERE key='schema_version'") \
                .fetchone()
            if row is None:
                c.execute("INSERT INTO pathfuse_meta VALUES ('schema_version', ?)",
                          (str(SCHEMA_VERSION),))
                c.execute("INSERT INTO pathfuse_meta VALUES ('created_at', ?)", (_now(),))
            elif int(row[0]) > SCHEMA_VERSION:
                raise ConfigError(f"{self.path}: written by a newer pathfuse "
                                  f"(schema {row[0]} > {SCHEMA_VERSION})")
            have = {r[1] for r in c.execute("PRAGMA table_info(runs)")}
            for name, typ, _ in RUN_COLUMNS:  # forward-compatible: add new columns
                if name not in have:
                    c.execute(f"ALTER TABLE runs ADD COLUMN {_q(name)} "
                              f"{typ.replace('NOT NULL UNIQUE', '')}")
            existing = {r[0] for r in c.execute(
                "SELECT description FROM enums WHERE name='status'")}
            nxt = c.execute("SELECT COALESCE(MAX(value) + 1, 0) FROM enums "
                            "WHERE name='status'").fetchone()[0]
            for s in STATUS_NAMES:
                if s not in existing:
                    c.execute("INSERT INTO enums VALUES ('status', ?, ?)", (nxt, s))
                    nxt += 1
            c.execute("COMMIT")
        except BaseException:
            c.execute("ROLLBACK")
            raise

    def _load_enums(self) -> dict[str, int]:
        try:
            rows = self.conn.execute(
                "SELECT description, value FROM enums WHERE name='status'").fetchall()
        except sqlite3.OperationalError as exc:
            raise ConfigError(f"{self.path}: not a pathfuse/OMPL result database ({exc})") \
                from None
        return {r[0]: int(r[1]) for r in rows}

    def _status_value(self, name: str) -> int:
        if name not in self._status_values:
            v = self.conn.execute("SELECT COALESCE(MAX(value) + 1, 0) FROM enums "
                                  "WHERE name='status'").fetchone()[0]
            self.conn.execute("INSERT INTO enums VALUES ('status', ?, ?)", (v, name))
            self._status_values[name] = int(v)
        return self._status_values[name]

    # ---------------------------------------------------------------- context
    def close(self) -> None:
        self.conn.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---------------------------------------------------------------- registry rows
    def ensure_experiment(self, study: str, entry: str, kind: str, *, timelimit: float = 0.0,
                          runcount: int = 0, seed: int = 0, setup: str = "") -> int:
        """The id of experiment ``study/entry``, inserting it on first use."""
        name = f"{study}/{entry}"
        row = self.conn.execute("SELECT id FROM experiments WHERE name = ?", (name,)).fetchone()
        if row is not None:
            self.conn.execute("UPDATE experiments SET runcount = ?, timelimit = ?, setup = ? "
                              "WHERE id = ?", (runcount, timelimit, setup, row[0]))
            return int(row[0])
        from pathfuse._version import __version__

        cur = self.conn.execute(
            "INSERT INTO experiments (name, totaltime, timelimit, memorylimit, runcount, "
            "version, hostname, cpuinfo, date, seed, setup, study, entry, kind) "
            "VALUES (?, 0, ?, 0, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (name, timelimit, runcount, f"pathfuse {__version__}", socket.gethostname(),
             _cpuinfo(), _now(), seed, setup, study, entry, kind))
        return int(cur.lastrowid)  # type: ignore[arg-type]

    def ensure_planner_config(self, name: str, planner: str, settings: str) -> int:
        """The id of planner config (``name``, ``settings``), inserting it on first use."""
        row = self.conn.execute("SELECT id FROM plannerConfigs WHERE name = ? AND settings = ?",
                                (name, settings)).fetchone()
        if row is not None:
            return int(row[0])
        cur = self.conn.execute("INSERT INTO plannerConfigs (name, settings, planner) "
                                "VALUES (?, ?, ?)", (name, settings, planner))
        return int(cur.lastrowid)  # type: ignore[arg-type]

    def transaction(self) -> _Tx:
        """``with store.transaction(): ...`` — one atomic write."""
        return _Tx(self.conn)

    # ---------------------------------------------------------------- runs
    def done_keys(self, include_errors: bool = True) -> set[str]:
        """Run keys already stored (optionally not counting runs that raised)."""
        sql = "SELECT run_key FROM runs"
        if not include_errors:
            sql += " WHERE status_name IS NOT 'ERROR'"
        return {r[0] for r in self.conn.execute(sql)}

    def count(self) -> int:
        return int(self.conn.execute("SELECT COUNT(*) FROM runs").fetchone()[0])

    def insert_runs(self, rows: Sequence[Mapping[str, Any]]) -> int:
        """Store finished runs in one transaction; returns how many were new.

        A row whose ``run_key`` is already stored replaces it only when the
        stored run is an ``ERROR`` (a retried failure); otherwise it is
        ignored (first result wins), so a run is never stored twice.
        """
        if not rows:
            return 0
        sql = _INSERT_SQL
        new = 0
        with self.transaction():
            for row in rows:
                values = dict(row)
                values["status"] = self._status_value(str(values.get("status_name")
                                                          or "ERROR"))
                unknown = values.keys() - _INSERT_SET - {"progress"}
                if unknown:
                    raise PathfuseError(f"unknown result column(s): {sorted(unknown)}")
                cur = self.conn.execute(sql, [_sqlval(values.get(c)) for c in _INSERT_COLS])
                if cur.rowcount:
                    new += 1
                    if values.get("progress"):
                        runid = self.conn.execute("SELECT id FROM runs WHERE run_key = ?",
                                                  (values["run_key"],)).fetchone()[0]
                        self._insert_progress(runid, values["progress"])
        return new

    def _insert_progress(self, runid: int, samples: Iterable[Mapping[str, Any]]) -> None:
        have = {r[1] for r in self.conn.execute("PRAGMA table_info(progress)")}
        self.conn.execute("DELETE FROM progress WHERE runid = ?", (runid,))
        for s in samples:
            for k in s:
                if k not in have:
                    self.conn.execute(f"ALTER TABLE progress ADD COLUMN {_q(k)} REAL")
                    have.add(k)
            cols = ["runid", *s.keys()]
            self.conn.execute(
                f"INSERT OR IGNORE INTO progress ({', '.join(map(_q, cols))}) "
                f"VALUES ({', '.join('?' for _ in cols)})", [runid, *map(_sqlval, s.values())])

    def update_totals(self) -> None:
        """experiments.totaltime = sum of the wall times of its stored runs."""
        with self.transaction():
            self.conn.execute(
                "UPDATE experiments SET totaltime = COALESCE((SELECT SUM(wall_time) FROM runs "
                "WHERE runs.experimentid = experiments.id), 0)")

    # ---------------------------------------------------------------- sessions
    def start_session(self, **fields: Any) -> int:
        from pathfuse._version import __version__

        fields = {"started_at": _now(), "state": "running", "host": socket.gethostname(),
                  "pathfuse_version": __version__, "python": platform.python_version(),
                  **fields}
        cols = list(fields)
        with self.transaction():
            cur = self.conn.execute(
                f"INSERT INTO pathfuse_sessions ({', '.join(cols)}) "
                f"VALUES ({', '.join('?' for _ in cols)})", [fields[c] for c in cols])
        return int(cur.lastrowid)  # type: ignore[arg-type]

    def end_session(self, session_id: int, **fields: Any) -> None:
        fields = {"finished_at": _now(), **fields}
        sets = ", ".join(f"{k} = ?" for k in fields)
        with self.transaction():
            self.conn.execute(f"UPDATE pathfuse_sessions SET {sets} WHERE id = ?",
                              [*fields.values(), session_id])

    # ---------------------------------------------------------------- reading
    def rows_by_key(self, keys: Sequence[str]) -> dict[str, dict[str, Any]]:
        """The stored ``runs`` rows of the given run keys (missing keys are left out)."""
        out: dict[str, dict[str, Any]] = {}
        keys = list(keys)
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            marks = ", ".join("?" for _ in chunk)
            for r in self.conn.execute(f"SELECT * FROM runs WHERE run_key IN ({marks})", chunk):
                out[r["run_key"]] = dict(r)
        return out

    def results(self, where: str = "", params: Sequence[Any] = ()) -> list[dict[str, Any]]:
        """Rows of the ``pathfuse_results`` view (optionally filtered by SQL ``where``)."""
        sql = "SELECT * FROM pathfuse_results" + (f" WHERE {where}" if where else "") + \
              " ORDER BY id"
        return [dict(r) for r in self.conn.execute(sql, params)]


class _Tx:
    def __init__(self, conn: sqlite3.Connection) -> None:
        self.conn = conn

    def __enter__(self) -> sqlite3.Connection:
        self.conn.execute("BEGIN IMMEDIATE")
        return self.conn

    def __exit__(self, exc_type: object, *rest: object) -> None:
        self.conn.execute("COMMIT" if exc_type is None else "ROLLBACK")


def _split_sql(script: str) -> list[str]:
    return [s.strip() for s in script.split(";") if s.strip()]


_NATIVE = frozenset({str, bytes, int, bool, type(None)})


def _sqlval(v: Any) -> Any:
    t = type(v)
    if t in _NATIVE:  # the common cases, without isinstance
        return v
    if t is float:
        return None if v != v else v  # NaN -> NULL
    if v is None or isinstance(v, (str, bytes, int, float)):
        if isinstance(v, float) and v != v:  # NaN -> NULL
            return None
        return v
    if hasattr(v, "item"):
        return _sqlval(v.item())
    if isinstance(v, (dict, list, tuple)):
        return json.dumps(v, sort_keys=True)
    return str(v)


def _cpuinfo() -> str:
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}; {os.cpu_count()} logical CPUs; {platform.platform()}"


def comparable_rows(path: str | os.PathLike[str],
                    exclude: Iterable[str] = WALL_CLOCK_COLUMNS) -> dict[str, dict[str, Any]]:
    """``run_key -> row`` of a study, without wall-clock columns, ids resolved to names.

    Two sweeps of the same experiment give equal dicts whether or not they
    were interrupted, resumed, run in parallel or on a Dask cluster.
    """
    excl = set(exclude)
    with ResultStore(path, readonly=True) as st:
        rows = st.conn.execute(
            "SELECT runs.*, experiments.name AS experiment_name, "
            "plannerConfigs.name AS config_name, plannerConfigs.settings AS config_settings "
            "FROM runs JOIN experiments ON experiments.id = runs.experimentid "
            "JOIN plannerConfigs ON plannerConfigs.id = runs.plannerid").fetchall()
    out: dict[str, dict[str, Any]] = {}
    for r in rows:
        d = {k: r[k] for k in r.keys() if k not in excl
             and k not in ("experimentid", "plannerid")}
        out[d["run_key"]] = d
    return out


def schema_markdown() -> str:
    """A Markdown table of the ``runs`` columns (for documentation)."""
    lines = ["| column | type | meaning |", "|---|---|---|"]
    lines += [f"| `{c}` | {t.split()[0]} | {doc} |" for c, t, doc in RUN_COLUMNS]
    return "\n".join(lines)
