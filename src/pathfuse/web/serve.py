"""Run the web app on uvicorn: what ``pathfuse serve`` does.

The listening socket is bound first, so a busy or invalid port is one line and exit
status 2 before anything else is printed, and the URL banner appears only once the
port accepts connections.  A stop signal (SIGTERM, Ctrl-C) kills the worker processes at
once, so the requests in flight end (503) and the server exits within about a second
(``timeout_graceful_shutdown``) however long their computations were to take.
"""

from __future__ import annotations

import socket
import sys
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import Any, TextIO

import uvicorn

from pathfuse.result import PathfuseError

__all__ = ["ServeError", "bind", "serve"]

_WILDCARDS = ("0.0.0.0", "::", "")


class ServeError(PathfuseError):
    """The server cannot start (a busy port, an unknown host)."""


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (``port`` 0: a free port).

    Raises
    ------
    ServeError
        A port outside 0-65535, a host that is not an address of this machine, a port in
        use or not allowed; one line.
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ServeError(f"port: must be an integer from 0 to 65535, got {port!r}")
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as exc:
        sock.close()
        where = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
        raise ServeError(f"cannot listen on {where}: {exc.strerror or exc}") from None
    return sock


def serve(*, host: str = "127.0.0.1", port: int = 8000,
          map_folders: list[tuple[str, Path]] | None = None, limits: Any = None,
          workers: int = 3, max_queue: int = 32, warm: bool = True,
          allow_hosts: Sequence[str] = (), open_browser: bool = False,
          log_level: str = "warning", out: TextIO | None = None) -> int:
    """Bind, print the URL, serve until a stop signal; returns 0.

    Parameters are those of :func:`pathfuse.web.app.create_app` and of ``pathfuse
    serve``; ``allow_hosts`` adds to the loopback names (and to ``host`` itself when it
    is a specific address) the Host names a request may give.
    """
    from pathfuse.web.app import create_app
    from pathfuse.web.guard import LOOPBACK_NAMES

    out = sys.stderr if out is None else out
    sock = bind(host, port)
    pool = None
    try:
        allowed = [*LOOPBACK_NAMES, *allow_hosts]
        if host not in _WILDCARDS:
            allowed.append(host)
        app = create_app(map_folders=map_folders, limits=limits, workers=workers, warm=warm,
                         max_queue=max_queue, allowed_hosts=allowed)
        pool = app.state.pool
        bound = sock.getsockname()[1]
        url = f"http://{'[' + host + ']' if ':' in host else host}:{bound}/"
        if host not in ("127.0.0.1", "localhost", "::1"):
            extra = [h for h in allow_hosts if h not in LOOPBACK_NAMES]
            names = "any Host" if "*" in extra else \
                "Host " + ", ".join(sorted({*LOOPBACK_NAMES, *extra} | (
                    {host} if host not in _WILDCARDS else set())))
            print(f"pathfuse serve: listening on {host}: anyone who can reach this machine "
                  f"can use the app (requests naming {names}; --allow-host adds a name)",
                  file=out)
        print(f"pathfuse serve: {url}  (Ctrl-C stops it)", file=out, flush=True)
        if open_browser:
            import threading
            import webbrowser

            threading.Timer(0.5, lambda: webbrowser.open(url)).start()
        config = uvicorn.Config(app, host=host, port=bound, log_level=log_level,
                                timeout_keep_alive=5, limit_concurrency=64,
                                timeout_graceful_shutdown=1)
        _Server(config, pool).run(sockets=[sock])
    finally:
        sock.close()
        if pool is not None:
            pool.close()
    return 0


class _Server(uvicorn.Server):
    """uvicorn's server that kills the worker processes when told to stop."""

    def __init__(self, config: uvicorn.Config, pool: Any) -> None:
        super().__init__(config)
        self._pool = pool

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        if self._pool is not None:
            self._pool.stop_now()
        super().handle_exit(sig, frame)
