"""Studies written by an older pathfuse: migrated to the current layout, or refused.

Schema 1 (pathfuse before issue 22) kept pathfuse's columns inside OMPL's
tables (``runs.run_key``, ``plannerConfigs.planner``, ``experiments.kind``
...) and its own status codes in ``enums``.  :func:`migrate` rewrites such a
database into schema 2 in one transaction: OMPL's tables rebuilt column for
column as OMPL writes them, pathfuse's data moved into the ``pathfuse_*`` side
tables under the same run, experiment and configuration ids, ``status``
recoded into OMPL's enum (:data:`~pathfuse.bench.schema.STATUS_TO_OMPL`) and
configurations that shared a name renamed apart.  A failure rolls everything
back, leaving the file as it was.

``pathfuse bench`` migrates the file it is about to write.  A reader
(``pathfuse report``, a read-only :class:`~pathfuse.bench.store.ResultStore`)
never writes: :func:`open_current` migrates a copy in memory.  A database of
a newer schema, or of a version this code does not know, is refused with a
:class:`~pathfuse.result.ConfigError` naming the file and both versions.
"""

from __future__ import annotations

import sqlite3
from datetime import datetime, timezone
from pathlib import Path

from pathfuse.bench.schema import (
    ATTRIBUTE_COLUMNS,
    OMPL_RUN_COLUMNS,
    OMPL_STATUS_TEXT,
    PATH_COLUMNS,
    SCHEMA_VERSION,
    SIDE_COLUMNS,
    STATUS_NAMES,
    STATUS_TO_OMPL,
    OmplStatus,
    distinct_config_name,
    q,
    schema_sql,
)
from pathfuse.result import ConfigError

__all__ = ["stored_version", "check_version", "migrate", "open_current", "fill_status_tables"]

_V1_VIEWS = ("pathfuse_results", "bestPlannerConfigsPerExperiment", "bestPlannerConfigs")


def stored_version(conn: sqlite3.Connection) -> int | None:
    """The ``schema_version`` of ``pathfuse_meta`` (None: no such table or row yet)."""
    try:
        row = conn.execute("SELECT value FROM pathfuse_meta WHERE key = 'schema_version'") \
            .fetchone()
    except sqlite3.OperationalError:
        return None
    if row is None:
        return None
    try:
        return int(row[0])
    except (TypeError, ValueError):
        return -1


def check_version(conn: sqlite3.Connection, path: str) -> int | None:
    """The stored schema version, or :class:`ConfigError` when no code here can read it."""
    v = stored_version(conn)
    if v is None or v in (1, SCHEMA_VERSION):
        return v
    if v > SCHEMA_VERSION:
        raise ConfigError(f"{path}: written by a newer pathfuse (schema {v} > "
                          f"{SCHEMA_VERSION}); upgrade pathfuse to read or extend it")
    raise ConfigError(f"{path}: unknown pathfuse schema version "
                      f"{_shown_version(conn)!r} (this pathfuse reads 1 and {SCHEMA_VERSION})")


def _shown_version(conn: sqlite3.Connection) -> str:
    row = conn.execute("SELECT value FROM pathfuse_meta WHERE key = 'schema_version'") \
        .fetchone()
    return str(row[0])[:40]


def migrate(conn: sqlite3.Connection, path: str) -> bool:
    """Bring the database on ``conn`` (autocommit mode) to the current schema.

    Returns True when it migrated.  :class:`ConfigError` when the version is
    newer or unknown, or when the old database breaks its own foreign keys (then
    nothing is changed).
    """
    if check_version(conn, path) != 1:
        return False
    conn.execute("PRAGMA foreign_keys = OFF")  # tables are rebuilt under the same ids
    try:
        conn.execute("BEGIN IMMEDIATE")
        try:
            _v1_to_v2(conn)
            bad = conn.execute("PRAGMA foreign_key_check").fetchall()
            if bad:
                raise ConfigError(
                    f"{path}: cannot migrate the schema-1 study: {len(bad)} row(s) refer to "
                    f"missing rows (first: table {bad[0][0]}, row {bad[0][1]} -> {bad[0][2]}); "
                    "the file is left unchanged")
            conn.execute("COMMIT")
        except BaseException:
            conn.execute("ROLLBACK")
            raise
    finally:
        conn.execute("PRAGMA foreign_keys = ON")
    return True


def open_current(path: str) -> sqlite3.Connection:
    """A read-only view of the study at ``path`` in the current schema.

    The file is opened read-only; a schema-1 study is copied into memory and
    the copy migrated (the file is never written).
    """
    uri = Path(path).resolve().as_uri() + "?mode=ro"
    conn = sqlite3.connect(uri, uri=True, timeout=60.0)
    try:
        version = check_version(conn, path)
        if version != 1:
            return conn
        mem = sqlite3.connect(":memory:", isolation_level=None)
        conn.backup(mem)
    except BaseException:
        conn.close()
        raise
    conn.close()
    try:
        migrate(mem, path)
    except BaseException:
        mem.close()
        raise
    return mem


def fill_status_tables(conn: sqlite3.Connection) -> None:
    """OMPL's ``status`` enum and pathfuse's ``pathfuse_status`` vocabulary (missing rows)."""
    for value, text in enumerate(OMPL_STATUS_TEXT):
        conn.execute("INSERT OR IGNORE INTO enums VALUES ('status', ?, ?)", (value, text))
    for name in STATUS_NAMES:
        code = STATUS_TO_OMPL[name]
        conn.execute("INSERT OR IGNORE INTO pathfuse_status VALUES (?, ?, ?)",
                     (name, int(code), OMPL_STATUS_TEXT[code]))


# --------------------------------------------------------------------------- 1 -> 2
def _columns(conn: sqlite3.Connection, table: str) -> list[str]:
    return [r[1] for r in conn.execute(f"PRAGMA table_info({q(table)})")]


def _pick(old: list[str], name: str) -> str:
    return q(name) if name in old else "NULL"


def _status_case() -> str:
    """SQL of OMPL's code for a schema-1 row (its ``status_name`` and ``solved``)."""
    whens = " ".join(f"WHEN '{n}' THEN {int(c)}" for n, c in STATUS_TO_OMPL.items())
    return (f"CASE COALESCE(status_name, 'ERROR') {whens} ELSE CASE WHEN solved THEN "
            f"{int(OmplStatus.EXACT_SOLUTION)} ELSE {int(OmplStatus.UNKNOWN)} END END")


def _v1_to_v2(c: sqlite3.Connection) -> None:
    old_runs = _columns(c, "runs")
    old_exp = _columns(c, "experiments")
    old_cfg = _columns(c, "plannerConfigs")
    for v in _V1_VIEWS:
        c.execute(f"DROP VIEW IF EXISTS {q(v)}")
    c.execute("DROP INDEX IF EXISTS runs_problem")
    for stmt in schema_sql():  # the side tables (OMPL's tables exist: skipped)
        if "VIEW" not in stmt and "INDEX" not in stmt:
            c.execute(stmt)
    _move_experiments(c, old_exp)
    _move_configs(c, old_cfg)
    _move_runs(c, old_runs)
    c.execute("DELETE FROM enums WHERE name = 'status'")
    fill_status_tables(c)
    extra = sorted({r[0] for r in c.execute("SELECT DISTINCT status_name FROM pathfuse_runs")
                    if r[0] is not None} - set(STATUS_NAMES))
    for name in extra:  # a plug-in's own status names
        c.execute("INSERT OR IGNORE INTO pathfuse_status VALUES (?, ?, ?)",
                  (name, int(OmplStatus.UNKNOWN), OMPL_STATUS_TEXT[OmplStatus.UNKNOWN]))
    for stmt in schema_sql():
        c.execute(stmt)
    now = datetime.now(timezone.utc).isoformat(timespec="seconds")
    c.execute("UPDATE pathfuse_meta SET value = ? WHERE key = 'schema_version'",
              (str(SCHEMA_VERSION),))
    c.execute("INSERT OR REPLACE INTO pathfuse_meta VALUES ('migrated_from_schema', '1')")
    c.execute("INSERT OR REPLACE INTO pathfuse_meta VALUES ('migrated_at', ?)", (now,))


def _rebuild(c: sqlite3.Connection, table: str, create: str, select: str) -> None:
    """Replace ``table`` by the table ``create`` makes (as ``<table>_v2``) filled by ``select``."""
    c.execute(create)
    c.execute(f"INSERT INTO {q(table + '_v2')} {select}")
    c.execute(f"DROP TABLE {q(table)}")
    c.execute(f"ALTER TABLE {q(table + '_v2')} RENAME TO {q(table)}")


def _create_as(table: str) -> str:
    stmt = next(s for s in schema_sql() if s.startswith(f"CREATE TABLE IF NOT EXISTS {table} "))
    return stmt.replace(f"IF NOT EXISTS {table} ", f"{q(table + '_v2')} ", 1)


def _move_experiments(c: sqlite3.Connection, old: list[str]) -> None:
    c.execute("INSERT INTO pathfuse_experiments SELECT id, "
              f"{_pick(old, 'study')}, {_pick(old, 'entry')}, {_pick(old, 'kind')} "
              "FROM experiments")
    cols = ("id, name, totaltime, timelimit, memorylimit, runcount, version, hostname, "
            "cpuinfo, date, CAST(seed AS TEXT), setup")
    _rebuild(c, "experiments", _create_as("experiments"), f"SELECT {cols} FROM experiments")


def _move_configs(c: sqlite3.Connection, old: list[str]) -> None:
    rows = c.execute(f"SELECT id, name, settings, {_pick(old, 'planner')} FROM plannerConfigs "
                     "ORDER BY id").fetchall()
    _rebuild(c, "plannerConfigs", _create_as("plannerConfigs"),
             "SELECT id, name, settings FROM plannerConfigs")
    taken: set[str] = set()
    by_label: dict[str, list[str]] = {}
    for cid, name, settings, planner in rows:
        label = str(name)
        shown = distinct_config_name(label, str(settings), by_label.get(label, []), taken)
        taken.add(shown)
        by_label.setdefault(label, []).append(str(settings))
        if shown != label:
            c.execute("UPDATE plannerConfigs SET name = ? WHERE id = ?", (shown, cid))
        c.execute("INSERT INTO pathfuse_configs VALUES (?, ?, ?)", (cid, planner or label, label))


def _move_runs(c: sqlite3.Connection, old: list[str]) -> None:
    side = ", ".join(_pick(old, n) for n, _, _ in SIDE_COLUMNS[1:])
    c.execute(f"INSERT INTO pathfuse_runs SELECT id, {side} FROM runs")
    paths = [n for n, _, _ in PATH_COLUMNS[1:] if n in old]
    if paths:
        have = " OR ".join(f"{q(n)} IS NOT NULL" for n in paths)
        c.execute(f"INSERT INTO pathfuse_paths SELECT id, "
                  f"{', '.join(_pick(old, n) for n, _, _ in PATH_COLUMNS[1:])} "
                  f"FROM runs WHERE {have}")
    attrs = [(n, t) for n, t, _ in ATTRIBUTE_COLUMNS if n in old and c.execute(
        f"SELECT 1 FROM runs WHERE {q(n)} IS NOT NULL LIMIT 1").fetchone()]
    create = _create_as("runs")
    cut = create.index(", FOREIGN KEY")
    create = create[:cut] + "".join(f", {q(n)} {t}" for n, t in attrs) + create[cut:]
    core = [n for n, _, _ in OMPL_RUN_COLUMNS]
    select = ", ".join(_status_case() if n == "status" else _pick(old, n) for n in core)
    select += "".join(f", {q(n)}" for n, _ in attrs)
    names = ", ".join(q(n) for n in core + [n for n, _ in attrs])
    c.execute(create)
    c.execute(f"INSERT INTO runs_v2 ({names}) SELECT {select} FROM runs")
    c.execute("DROP TABLE runs")
    c.execute("ALTER TABLE runs_v2 RENAME TO runs")
