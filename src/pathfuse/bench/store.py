"""The result store: one SQLite database per study, that OMPL's own tools read.

OMPL's tables are written exactly as OMPL's ``ompl_benchmark_statistics``
writes them, so Planner Arena loads a study and ``ompl_benchmark_statistics
-a -d STUDY.db RUN.log`` appends OMPL's runs to it; everything else pathfuse
keeps is in side tables whose names start with ``pathfuse_``, keyed by the
run, experiment or configuration id (:mod:`pathfuse.bench.schema` declares
the layout, :mod:`pathfuse.bench.migrate` upgrades a study of an older
pathfuse).

Mapping to OMPL's concepts: an OMPL *experiment* is one map entry of the
study (``experiments.name = "<study>/<map entry>"``), a *planner config* is a
planner with one parameter combination (``plannerConfigs.name`` like
``fusion(r1_m=0.5,r2_m=2,step_m=0.1)``, unique in the database;
``settings`` = the full parameters as JSON), and a run is one (map, seed,
query, planner config).

Tables
------
experiments (OMPL)
    ``id``, ``name`` ("study/entry"), ``totaltime`` (s, sum of run wall times),
    ``timelimit`` (s per run, 0 if none), ``memorylimit`` (0), ``runcount``
    (runs per planner config), ``version`` ("pathfuse X.Y.Z"), ``hostname``,
    ``cpuinfo``, ``date`` (first session), ``seed`` (first seed, text as in
    OMPL), ``setup`` (the map entry as JSON).
plannerConfigs (OMPL)
    ``id``, ``name``, ``settings`` (canonical JSON of the full parameters).
enums (OMPL)
    ``name``, ``value``, ``description``: ``name = 'status'`` is OMPL's
    ``PlannerStatus`` (0 Unknown status ... 4 Timeout, 5 Approximate solution,
    6 Exact solution, 7 Crash, 8 Abort, 9 Infeasible problem).
runs (OMPL)
    ``id``, ``experimentid``, ``plannerid``, ``time`` (REAL, planning time in
    s, numba compilation excluded), ``solved`` (BOOLEAN, an exact solution),
    ``status`` (ENUM, OMPL's code: :data:`~pathfuse.bench.schema.STATUS_TO_OMPL`),
    ``memory`` (REAL, peak resident memory of the worker in MB),
    ``solution_length``, ``solution_clearance``, ``solution_smoothness``
    (REAL), ``solution_segments`` (INTEGER); then pathfuse's numeric
    properties, each added when a run first has a value, as OMPL's script adds
    a column per property: ``expansions``, ``iterations``, ``steps``,
    ``collision_free`` (BOOLEAN), ``collisions``, ``time_to_goal``,
    ``path_length``, ``R_length``, ``wall_time``.
progress (OMPL)
    ``runid``, ``time``, then one REAL column per value a run samples: episodes
    of the ``dynamic`` kind sample ``distance_to_goal`` and ``clearance`` (m)
    against the simulated ``time`` (s).
pathfuse_runs
    One row per pathfuse run, ``runid`` = ``runs.id``: ``run_key``
    (SHA-256 of ``params``), ``status_name`` (pathfuse's status), ``problem_key``,
    ``kind``, ``map_name``, ``planner``, ``seed``, ``query_index``,
    ``scen_line``, ``start_x``, ``start_y``, ``goal_x``, ``goal_y``, ``reference_length``,
    ``reference_source``, ``message``, ``error``, ``traceback``, ``params``,
    ``metrics``, ``info``, ``timing`` (JSON), ``pathfuse_version``, ``host``,
    ``worker``, ``started_at``, ``finished_at``.
pathfuse_paths
    ``runid``, ``path`` (BLOB, little-endian float64 (N, 2)) and ``headings``
    (BLOB, float64 (N,)), only with ``store_paths``.
pathfuse_status
    pathfuse's status vocabulary: ``name``, ``ompl_status``, ``description``.
pathfuse_experiments, pathfuse_configs
    ``study``, ``entry``, ``kind`` of each pathfuse experiment; ``planner``
    (registry name) and ``label`` (the name pathfuse asked for) of each
    pathfuse configuration.
pathfuse_meta, pathfuse_sessions
    ``schema_version`` and ``created_at``; one row per invocation.

Runs appended from OMPL's logs have no ``pathfuse_runs`` row.  The view
``pathfuse_results`` joins every run back to one flat row (with ``experiment``,
``config`` and ``status_text``, OMPL's text of its status);
``bestPlannerConfigs`` and ``bestPlannerConfigsPerExperiment`` are OMPL's
summary views (OMPL's script replaces them with its own when it runs).

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
...         row = st.results()[0]
>>> n, row["run_key"], row["status"], row["status_text"]
(1, 'k1', 6, 'Exact solution')
"""

from __future__ import annotations

import json
import os
import platform
import socket
import sqlite3
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime, timezone
from typing import Any

from pathfuse.bench.migrate import check_version, fill_status_tables, migrate, open_current
from pathfuse.bench.schema import (
    ATTRIBUTE_COLUMNS,
    COLUMN_TABLE,
    OMPL_RUN_COLUMNS,
    OMPL_STATUS_TEXT,
    PATH_COLUMNS,
    RUN_COLUMNS,
    SCHEMA_VERSION,
    SIDE_COLUMNS,
    STATUS_NAMES,
    distinct_config_name,
    ompl_status,
    q,
    schema_markdown,
    schema_sql,
)
from pathfuse.result import ConfigError, PathfuseError

__all__ = [
    "ResultStore",
    "RUN_COLUMNS",
    "WALL_CLOCK_COLUMNS",
    "SCHEMA_VERSION",
    "STATUS_NAMES",
    "comparable_rows",
    "schema_markdown",
]

WALL_CLOCK_COLUMNS: frozenset[str] = frozenset({
    "id", "time", "memory", "host", "worker", "started_at", "finished_at", "wall_time",
    "timing",
})
"""Columns that differ between two otherwise identical sweeps (timing, placement)."""

_CORE = tuple(c for c, _, _ in OMPL_RUN_COLUMNS if c != "id")
_ATTR_TYPES = {c: t for c, t, _ in ATTRIBUTE_COLUMNS}
_SIDE = tuple(c for c, _, _ in SIDE_COLUMNS[1:])
_PATHS = tuple(c for c, _, _ in PATH_COLUMNS[1:])
_KNOWN = frozenset(COLUMN_TABLE) - {"id", "status"}
_SIDE_SQL = (f"INSERT INTO pathfuse_runs (runid, {', '.join(map(q, _SIDE))}) "
             f"VALUES (?{', ?' * len(_SIDE)})")
_PATH_SQL = (f"INSERT INTO pathfuse_paths (runid, {', '.join(map(q, _PATHS))}) "
             f"VALUES (?{', ?' * len(_PATHS)})")


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


class ResultStore:
    """An open study database (created on first use, migrated when older).

    Parameters
    ----------
    path : path-like
        The SQLite file (``":memory:"`` for tests).
    readonly : bool
        Open an existing database for reading only (a study of an older schema is
        migrated in a copy in memory; the file is not written).
    check : bool
        Check the file first (:func:`~pathfuse.bench.dbcheck.check_study_file`); False
        when the caller just did.

    Raises
    ------
    ConfigError
        The file is a folder, not SQLite, another application's database, damaged
        (SQLite's ``quick_check``), read-only when opened for writing, or of a newer or
        unknown schema (the file is not touched before these checks).
    """

    def __init__(self, path: str | os.PathLike[str], readonly: bool = False, *,
                 check: bool = True) -> None:
        self.path = str(path)
        if self.path != ":memory:" and check:
            from pathfuse.bench.dbcheck import check_study_file

            check_study_file(self.path, write=not readonly)  # only reads the file
        try:
            self.conn = open_current(self.path) if readonly else \
                sqlite3.connect(self.path, timeout=60.0, isolation_level=None)
        except sqlite3.DatabaseError as exc:
            raise ConfigError(f"{self.path}: not a usable result database ({exc})") from None
        self.conn.row_factory = sqlite3.Row
        try:
            self._open(readonly)
        except sqlite3.DatabaseError as exc:
            self.conn.close()
            raise ConfigError(f"{self.path}: not a usable result database ({exc})") from None
        except BaseException:
            self.conn.close()
            raise

    # ---------------------------------------------------------------- setup
    def _open(self, readonly: bool) -> None:
        self.conn.execute("PRAGMA foreign_keys = ON")
        if not readonly:
            migrate(self.conn, self.path)  # or refuse a newer schema, before any write
            self.conn.execute("PRAGMA journal_mode = WAL")
            self.conn.execute("PRAGMA synchronous = NORMAL")
            self._create()
        self._runs_cols = self._columns("runs")
        if not self._runs_cols or not self._columns("pathfuse_runs"):
            raise ConfigError(f"{self.path}: not a pathfuse study database (no table runs "
                              "or pathfuse_runs)")
        self._status_names = {r[0] for r in self.conn.execute("SELECT name FROM pathfuse_status")}
        self._progress_cols = self._columns("progress")
        self._sql: dict[tuple[str, ...], str] = {}

    def _create(self) -> None:
        c = self.conn
        with self.transaction():
            for stmt in schema_sql():
                c.execute(stmt)
            if check_version(c, self.path) is None:
                c.execute("INSERT OR REPLACE INTO pathfuse_meta VALUES ('schema_version', ?)",
                          (str(SCHEMA_VERSION),))
                c.execute("INSERT OR REPLACE INTO pathfuse_meta VALUES ('created_at', ?)",
                          (_now(),))
            fill_status_tables(c)

    def _columns(self, table: str) -> set[str]:
        return {r[1] for r in self.conn.execute(f"PRAGMA table_info({q(table)})")}

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
        """The id of pathfuse's experiment ``study/entry``, inserting it on first use.

        An experiment of the same name appended from an OMPL log is another experiment.
        """
        name = f"{study}/{entry}"
        row = self.conn.execute(
            "SELECT e.id FROM experiments e JOIN pathfuse_experiments p "
            "ON p.experimentid = e.id WHERE e.name = ?", (name,)).fetchone()
        if row is not None:
            self.conn.execute("UPDATE experiments SET runcount = ?, timelimit = ?, setup = ? "
                              "WHERE id = ?", (runcount, timelimit, setup, row[0]))
            return int(row[0])
        from pathfuse._version import __version__

        cur = self.conn.execute(
            "INSERT INTO experiments (name, totaltime, timelimit, memorylimit, runcount, "
            "version, hostname, cpuinfo, date, seed, setup) "
            "VALUES (?, 0, ?, 0, ?, ?, ?, ?, ?, ?, ?)",
            (name, timelimit, runcount, f"pathfuse {__version__}", socket.gethostname(),
             _cpuinfo(), _now(), str(seed), setup))
        eid = int(cur.lastrowid)  # type: ignore[arg-type]
        self.conn.execute("INSERT INTO pathfuse_experiments VALUES (?, ?, ?, ?)",
                          (eid, study, entry, kind))
        return eid

    def ensure_planner_config(self, name: str, planner: str, settings: str) -> int:
        """The id of planner config (``name``, ``settings``), inserting it on first use.

        The stored ``plannerConfigs.name`` is ``name`` unless another configuration
        has it already (:func:`~pathfuse.bench.schema.distinct_config_name`).
        """
        row = self.conn.execute(
            "SELECT c.id FROM plannerConfigs c JOIN pathfuse_configs p ON p.plannerid = c.id "
            "WHERE p.label = ? AND c.settings = ?", (name, settings)).fetchone()
        if row is not None:
            return int(row[0])
        taken = {r[0] for r in self.conn.execute("SELECT name FROM plannerConfigs")}
        rivals = [r[0] for r in self.conn.execute(
            "SELECT c.settings FROM plannerConfigs c LEFT JOIN pathfuse_configs p "
            "ON p.plannerid = c.id WHERE c.name = ? OR p.label = ? ORDER BY c.id",
            (name, name))]
        shown = distinct_config_name(name, settings, rivals, taken)
        cur = self.conn.execute("INSERT INTO plannerConfigs (name, settings) VALUES (?, ?)",
                                (shown, settings))
        pid = int(cur.lastrowid)  # type: ignore[arg-type]
        self.conn.execute("INSERT INTO pathfuse_configs VALUES (?, ?, ?)", (pid, planner, name))
        return pid

    def transaction(self) -> _Tx:
        """``with store.transaction(): ...`` — one atomic write."""
        return _Tx(self.conn)

    # ---------------------------------------------------------------- runs
    def done_keys(self, include_errors: bool = True) -> set[str]:
        """Run keys already stored (optionally not counting runs that raised)."""
        sql = "SELECT run_key FROM pathfuse_runs"
        if not include_errors:
            sql += " WHERE status_name IS NOT 'ERROR'"
        return {r[0] for r in self.conn.execute(sql)}

    def count(self) -> int:
        """The number of pathfuse's runs (runs appended from OMPL logs not counted)."""
        return int(self.conn.execute("SELECT COUNT(*) FROM pathfuse_runs").fetchone()[0])

    def insert_runs(self, rows: Sequence[Mapping[str, Any]]) -> int:
        """Store finished runs in one transaction; returns how many were new.

        A row whose ``run_key`` is already stored replaces it (under the same
        ``runs.id``) only when the stored run is an ``ERROR`` (a retried
        failure); otherwise it is ignored (first result wins), so a run is never
        stored twice.  ``status`` is derived from ``status_name`` and ``solved``;
        a row's ``progress`` (a list of ``{"time": s, name: value}``) goes to the
        ``progress`` table.

        Raises
        ------
        PathfuseError
            A row names a column the store does not know, or has no ``run_key``
            (nothing of the batch is written).
        """
        if not rows:
            return 0
        for row in rows:
            unknown = row.keys() - _KNOWN - {"progress"}
            if unknown:
                raise PathfuseError(f"{self.path}: unknown result column(s): {sorted(unknown)}")
            if not isinstance(row.get("run_key"), str) or not row["run_key"]:
                raise PathfuseError(f"{self.path}: a result row without its run_key (run_key "
                                    f"= {row.get('run_key')!r})")
        with self.transaction():
            self._add_attribute_columns(rows)
            todo = self._new_rows(rows)
            self._write(todo)
        return len(todo)

    def _new_rows(self, rows: Sequence[Mapping[str, Any]]
                  ) -> list[tuple[int, Mapping[str, Any]]]:
        """``(runs.id, row)`` of the rows to write: new keys get fresh ids, a retried
        ERROR its old id (the old run is deleted with its side rows)."""
        stored = self._stored([str(r["run_key"]) for r in rows])
        nxt = int(self.conn.execute(
            "SELECT MAX(COALESCE((SELECT MAX(id) FROM runs), 0), COALESCE((SELECT seq FROM "
            "sqlite_sequence WHERE name = 'runs'), 0)) + 1").fetchone()[0])
        todo: list[tuple[int, Mapping[str, Any]]] = []
        for row in rows:
            key = str(row["run_key"])
            old = stored.get(key)
            if old is not None and old[1] != "ERROR":
                continue
            if old is not None:
                self.conn.execute("DELETE FROM runs WHERE id = ?", (old[0],))
                rid = old[0]
            else:
                rid, nxt = nxt, nxt + 1
            stored[key] = (rid, row.get("status_name"))
            todo.append((rid, row))
        return todo

    def _stored(self, keys: Sequence[str]) -> dict[str, tuple[int, Any]]:
        out: dict[str, tuple[int, Any]] = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            for r in self.conn.execute(
                    "SELECT run_key, runid, status_name FROM pathfuse_runs WHERE run_key IN "
                    f"({', '.join('?' for _ in chunk)})", chunk):
                out[r[0]] = (int(r[1]), r[2])
        return out

    def _add_attribute_columns(self, rows: Sequence[Mapping[str, Any]]) -> None:
        for name, typ in _ATTR_TYPES.items():
            if name not in self._runs_cols and any(r.get(name) is not None for r in rows):
                self.conn.execute(f"ALTER TABLE runs ADD COLUMN {q(name)} {typ}")
                self._runs_cols.add(name)

    def _write(self, todo: Sequence[tuple[int, Mapping[str, Any]]]) -> None:
        """The ``runs``, ``pathfuse_runs``, ``pathfuse_paths`` and ``progress`` rows."""
        by_cols: dict[tuple[str, ...], list[list[Any]]] = {}
        for rid, row in todo:
            name = row.get("status_name")
            status = ompl_status(None if name is None else str(name), bool(row.get("solved")))
            if name is not None and str(name) not in self._status_names:
                self._new_status(str(name), status)
            cols = _CORE + tuple(c for c in _ATTR_TYPES if row.get(c) is not None)
            by_cols.setdefault(cols, []).append(
                [rid, *(status if c == "status" else _sqlval(row.get(c)) for c in cols)])
        for cols, values in by_cols.items():
            self.conn.executemany(self._runs_sql(cols), values)
        self.conn.executemany(_SIDE_SQL, [[rid, *(_sqlval(row.get(c)) for c in _SIDE)]
                                          for rid, row in todo])
        paths = [[rid, *(_sqlval(row.get(c)) for c in _PATHS)] for rid, row in todo
                 if any(row.get(c) is not None for c in _PATHS)]
        if paths:
            self.conn.executemany(_PATH_SQL, paths)
        for rid, row in todo:
            if row.get("progress"):
                self._insert_progress(rid, row["progress"])

    def _runs_sql(self, cols: tuple[str, ...]) -> str:
        sql = self._sql.get(cols)
        if sql is None:
            sql = self._sql[cols] = (f"INSERT INTO runs (id, {', '.join(map(q, cols))}) "
                                     f"VALUES (?{', ?' * len(cols)})")
        return sql

    def _new_status(self, name: str, code: int) -> None:
        """A status name that is not pathfuse's (a plug-in's) joins ``pathfuse_status``."""
        self.conn.execute("INSERT OR IGNORE INTO pathfuse_status VALUES (?, ?, ?)",
                          (name, code, OMPL_STATUS_TEXT[code]))
        self._status_names.add(name)

    def _insert_progress(self, runid: int, samples: Iterable[Mapping[str, Any]]) -> None:
        by_cols: dict[tuple[str, ...], list[list[Any]]] = {}
        for s in samples:
            by_cols.setdefault(tuple(s), []).append([runid, *map(_sqlval, s.values())])
        for cols, values in by_cols.items():
            for k in cols:
                if k not in self._progress_cols:
                    self.conn.execute(f"ALTER TABLE progress ADD COLUMN {q(k)} REAL")
                    self._progress_cols.add(k)
            self.conn.executemany(
                f"INSERT OR IGNORE INTO progress (runid, {', '.join(map(q, cols))}) "
                f"VALUES (?{', ?' * len(cols)})", values)

    def update_totals(self) -> None:
        """experiments.totaltime = sum of the wall times of its stored runs (pathfuse's
        experiments only: an appended OMPL experiment keeps OMPL's total)."""
        if "wall_time" not in self._runs_cols:
            return
        with self.transaction():
            self.conn.execute(
                "UPDATE experiments SET totaltime = COALESCE((SELECT SUM(wall_time) FROM runs "
                "WHERE runs.experimentid = experiments.id), 0) "
                "WHERE id IN (SELECT experimentid FROM pathfuse_experiments)")

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
        """The stored runs of the given run keys, as :meth:`results` gives them (missing
        keys are left out)."""
        out: dict[str, dict[str, Any]] = {}
        keys = list(keys)
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            marks = ", ".join("?" for _ in chunk)
            for r in self.results(f"run_key IN ({marks})", chunk):
                out[r["run_key"]] = r
        return out

    def results(self, where: str = "", params: Sequence[Any] = ()) -> list[dict[str, Any]]:
        """Rows of the ``pathfuse_results`` view (optionally filtered by SQL ``where``).

        Every column of :data:`RUN_COLUMNS` is a key (None where the run has no
        value, e.g. a property no run has reported yet, or pathfuse's columns of
        a run appended from an OMPL log).
        """
        sql = "SELECT * FROM pathfuse_results" + (f" WHERE {where}" if where else "") + \
              " ORDER BY id"
        blank = dict.fromkeys(c for c, _, _ in RUN_COLUMNS)
        return [{**blank, **dict(r)} for r in self.conn.execute(sql, params)]


class _Tx:
    def __init__(self, conn: sqlite3.Connection) -> None:
        self.conn = conn

    def __enter__(self) -> sqlite3.Connection:
        self.conn.execute("BEGIN IMMEDIATE")
        return self.conn

    def __exit__(self, exc_type: object, *rest: object) -> None:
        self.conn.execute("COMMIT" if exc_type is None else "ROLLBACK")


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
    """``run_key -> row`` of a study's pathfuse runs: the columns of :data:`RUN_COLUMNS`
    without wall-clock columns, ids resolved to names (``experiment_name``,
    ``config_name``, ``config_settings``).

    Two sweeps of the same experiment give equal dicts whether or not they
    were interrupted, resumed, run in parallel or on a Dask cluster.
    """
    excl = set(exclude) | {"experimentid", "plannerid"}
    keep = [c for c, _, _ in RUN_COLUMNS if c not in excl]  # not the columns of OMPL's logs
    with ResultStore(path, readonly=True) as st:
        settings = {int(r[0]): r[1] for r in st.conn.execute(
            "SELECT id, settings FROM plannerConfigs")}
        rows = st.results("run_key IS NOT NULL")
    out: dict[str, dict[str, Any]] = {}
    for r in rows:
        d = {k: r[k] for k in keep}
        d.update(experiment_name=r["experiment"], config_name=r["config"],
                 config_settings=settings.get(r["plannerid"]))
        out[d["run_key"]] = d
    return out
