"""One sweep at a time per study database.

Two ``pathfuse bench`` commands on one database would both run every missing
run (the store keeps the first result of each, so the data stay right, but
the work is done twice).  :func:`study_lock` takes an exclusive lock on a
file beside the database, ``STUDY.db.lock``, for the duration of a sweep,
and refuses a second sweep at once with a :class:`StudyLocked` error naming
the sweep that holds it (pid, host, start time, command).

The lock is the operating system's (``flock`` on POSIX, ``msvcrt.locking``
on Windows), so it is released when its holder ends in any way, ``kill -9``
included: there is never a stale lock to delete by hand.  The lock file is
removed when the sweep ends.  Readers (``pathfuse report``) take no lock.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sys
from collections.abc import Iterator
from datetime import datetime, timezone
from pathlib import Path

from pathfuse.result import ConfigError

__all__ = ["study_lock", "StudyLocked", "lock_path"]


class StudyLocked(ConfigError):
    """Another sweep is writing this study database."""


def lock_path(db_path: str | os.PathLike[str]) -> Path:
    """The lock file of a study database: ``STUDY.db.lock`` beside it."""
    p = Path(db_path)
    return p.with_name(p.name + ".lock")


def _try_lock(fd: int) -> bool:
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        import msvcrt

        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)  # type: ignore[attr-defined]
            return True
        except OSError:
            return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False


def _holder(path: Path) -> str:
    try:
        info = json.loads(path.read_text(encoding="utf-8") or "{}")
    except (OSError, ValueError):
        info = {}
    if not isinstance(info, dict) or "pid" not in info:
        return "another process"
    cmd = f", {info['command']}" if info.get("command") else ""
    return (f"pid {info['pid']} on {info.get('host', '?')}, started "
            f"{info.get('started', '?')}{cmd}")


def _command() -> str:
    argv = list(sys.argv) or ["python"]
    name = os.path.basename(argv[0])
    argv[0] = "pathfuse" if name in ("pathfuse", "__main__.py") else name
    return " ".join(argv)


@contextlib.contextmanager
def study_lock(db_path: str | os.PathLike[str], what: str = "") -> Iterator[None]:
    """Hold the study's lock for the ``with`` block; :class:`StudyLocked` if another has it.

    ``db_path`` ``":memory:"`` takes no lock.  ``what`` describes the holder
    (shown to a second sweep; default: this process's command line).

    Examples
    --------
    >>> import tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> with study_lock(os.path.join(d, "s.db")):
    ...     try:
    ...         with study_lock(os.path.join(d, "s.db")):
    ...             pass
    ...     except StudyLocked as exc:
    ...         print(str(exc)[str(exc).index("another"):].split(" (")[0])
    another pathfuse sweep is writing this study
    >>> os.path.exists(os.path.join(d, "s.db.lock"))
    False
    """
    if str(db_path) == ":memory:":
        yield
        return
    path = lock_path(db_path)
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise ConfigError(f"{db_path}: cannot create the lock file {path} "
                              f"({exc.strerror or exc})") from None
        if not _try_lock(fd):
            os.close(fd)
            raise StudyLocked(
                f"{db_path}: another pathfuse sweep is writing this study ({_holder(path)}); "
                "wait for it to finish, or stop it (its stored runs are kept) and run this "
                "command again")
        try:  # the previous holder may have removed the file we opened: lock the current one
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        info = {"pid": os.getpid(), "host": socket.gethostname(),
                "started": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
                "command": (what or _command())[:200]}
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps(info).encode("utf-8"))
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)  # still holding the lock: nobody else owns this file
        os.close(fd)
