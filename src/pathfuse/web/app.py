"""The Starlette application of ``pathfuse serve``: the page and its JSON API.

Endpoints (all JSON unless said otherwise):

=======================================  ================================================
``GET /``                                the page (``static/index.html``)
``GET /static/NAME``                     the page's scripts and styles, from a table
                                         read when the app is built
``GET /api/planners``                    every registered planner and its parameters
``GET /api/maps``                        the catalog: map ids and names
``GET /api/maps/{id}``                   one map as JSON (packed occupancy bits)
``POST /api/maps``                       upload a map file (multipart ``file``, optional
                                         ``resolution``); answers the map with its id
``POST /api/map``                        a map from a spec (paper + seed, random, rows,
                                         blank), kept under a new id
``POST /api/plan``                       one plan: the object of ``pathfuse plan --json``
``POST /api/field``                      the APF potential and forces of a map and goal
``POST /api/simulate``                   one episode among moving discs
``GET /api/scenarios``                   the catalog's scenario files
``GET /api/scenarios/{id}``              one of them, with its map
``POST /api/scenarios``                  upload a scenario YAML
``POST /api/scenario/export``            a scene as scenario YAML
=======================================  ================================================

Bad input is a 4xx answer ``{"error": MESSAGE}`` whose message is the
library's one line (the one the command line prints after
``pathfuse COMMAND: error:``).  No request names a file on the disk (see
:mod:`pathfuse.web.maps`).

Every computation, reading and checking its JSON body included, runs in a worker
process (:mod:`pathfuse.web.pool`; at most ``workers`` at once, ``max_queue`` more
waiting) and is answered within ``time_budget_s + grace_s`` of its arrival: past that
its worker is killed (its CPU stops at once) and the answer is 503.  A request that
finds the queue full is a 503 with ``Retry-After``; so is one whose time runs out while
it waits.  A client that goes away stops its computation the same way.  The page, its
files, ``/api/planners``, the map catalog and the scenario list are answered by the
server process itself, never queued behind computations.

Every request passes :class:`pathfuse.web.guard.HostOriginGuard` first (Host
allow-list, Origin check); a JSON body must be ``application/json`` (415 otherwise),
at most ``max_body_bytes`` (413) and nested at most ``max_json_depth`` levels (400).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time
from collections.abc import Awaitable, Callable, Iterable
from importlib import resources
from pathlib import Path
from typing import Any

import anyio
from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import Response
from starlette.routing import Route

from pathfuse.result import PathfuseError
from pathfuse.web.files import read_upload
from pathfuse.web.guard import LOOPBACK_NAMES, HostOriginGuard, json_body_problem
from pathfuse.web.maps import ApiError, Limits, MapStore, grid_to_json
from pathfuse.web.pool import JobCrashed, JobTimeout, PoolBusy, WorkerLost, WorkerPool

__all__ = ["create_app", "default_map_folders"]

_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".svg": "image/svg+xml", ".png": "image/png",
          ".ico": "image/x-icon", ".txt": "text/plain; charset=utf-8"}


def default_map_folders() -> list[tuple[str, Path]]:
    """``examples/`` and ``tests/data/`` of the source tree pathfuse runs from (a clone
    installed with ``pip install -e``), when they exist, as (label, folder); otherwise the
    examples shipped in the package (:mod:`pathfuse.shipped`)."""
    root = Path(__file__).resolve().parents[3]
    pairs = [("examples", root / "examples"), ("tests/data", root / "tests" / "data")]
    found = [(label, p) for label, p in pairs if p.is_dir()]
    if not found:
        from pathfuse.shipped import shipped_root

        try:
            packaged = shipped_root()
        except PathfuseError:
            return []
        found = [(label, packaged / label) for label in ("examples", "tests/data")
                 if (packaged / label).is_dir()]
    return found


def _static_files() -> dict[str, tuple[bytes, str]]:
    """The page's files, read once: name -> (content, media type)."""
    out: dict[str, tuple[bytes, str]] = {}
    base = resources.files("pathfuse.web") / "static"
    for entry in base.iterdir():
        name = entry.name
        suffix = Path(name).suffix
        if entry.is_file() and suffix in _TYPES:
            out[name] = (entry.read_bytes(), _TYPES[suffix])
    return out


def _clean(x: Any) -> Any:
    """JSON-safe: non-finite floats become None."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def _dumps(data: Any) -> bytes:
    return json.dumps(_clean(data), separators=(",", ":"), allow_nan=False).encode()


def _json(data: Any, status: int = 200, headers: dict[str, str] | None = None) -> Response:
    return Response(_dumps(data), status_code=status, media_type="application/json",
                    headers=headers)


def _error(status: int, message: str, headers: dict[str, str] | None = None) -> Response:
    return _json({"error": message}, status, headers)


# --------------------------------------------------------------------------- worker side
_JSON_ENDPOINTS = ("plan", "map", "field", "simulate", "export")


def _json_endpoint(name: str) -> Callable[[MapStore, Any, Limits], dict[str, Any]]:
    from pathfuse.web.episodes import export_request, simulate_request
    from pathfuse.web.service import field_request, map_request, plan_request

    table: dict[str, Callable[[MapStore, Any, Limits], dict[str, Any]]] = {
        "plan": plan_request, "map": lambda s, b, lim: map_request(s, b),
        "field": field_request, "simulate": simulate_request, "export": export_request}
    return table[name]


def _upload_map(store: MapStore, files: list[tuple[str, bytes]], fields: dict[str, str],
                limits: Limits) -> dict[str, Any]:
    from pathfuse import validate

    res = fields.get("resolution", "").strip()
    resolution = validate.number(res, "resolution", gt=0) if res else None
    grid = read_upload(files, limits, resolution)
    e = store.add_upload(grid, grid.name)
    return grid_to_json(grid, e.id)


def _one_map(store: MapStore, map_id: str) -> dict[str, Any]:
    e = store.get(map_id)
    assert e.grid is not None
    d = grid_to_json(e.grid, e.id)
    d["spec"] = e.spec
    return d


def run_job(store: MapStore, kind: str, args: tuple[Any, ...]
            ) -> tuple[int, bytes, list[Any]]:
    """Run one job in a worker process: ``(status, JSON body, maps it added)``.

    ``args`` starts with the request's deadline (:func:`time.monotonic`) and its limits;
    the planners get the time left before the deadline, less ``grace_s``.
    """
    from pathfuse.web.episodes import load_catalog_scenario, upload_scenario
    from pathfuse.web.service import parse_body

    deadline, limits, *rest = args
    left = deadline - time.monotonic() - limits.grace_s
    limits = dataclasses.replace(limits, time_budget_s=max(0.01, min(limits.time_budget_s,
                                                                      left)))
    store.take_added()
    try:
        if kind in _JSON_ENDPOINTS:
            body = parse_body(rest[0], limits.max_json_depth)
            data = _json_endpoint(kind)(store, body, limits)
        elif kind == "get_map":
            data = _one_map(store, rest[0])
        elif kind == "get_scenario":
            data = load_catalog_scenario(store, rest[0])
        elif kind == "upload_map":
            data = _upload_map(store, rest[0], rest[1], limits)
        elif kind == "upload_scenario":
            data = upload_scenario(store, rest[0], rest[1], limits)
        else:
            raise AssertionError(f"unknown job {kind!r}")
        return 200, _dumps(data), store.take_added()
    except ApiError as exc:
        return exc.status, _dumps({"error": str(exc)}), store.take_added()
    except PathfuseError as exc:
        return 400, _dumps({"error": str(exc)}), store.take_added()
    except RecursionError:
        return 400, _dumps({"error": "request: nested too deeply"}), []
    except MemoryError:
        return 413, _dumps({"error": "request: needs more memory than this server has"}), []


# Long on purpose (~240 lines of code): the route handlers are closures over one app's map
# store, worker pool and limits, so nothing is module-level state and two apps in one
# process (the tests run several) stay apart; each handler is a few lines, the request
# rules (body, JSON depth, Host and Origin, errors) are helpers of this module.
def create_app(*, map_folders: list[tuple[str, Path]] | None = None, limits: Limits | None = None,
               workers: int = 3, warm: bool = False, max_queue: int = 32,
               allowed_hosts: Iterable[str] | None = None) -> Starlette:
    """The web app.

    Parameters
    ----------
    map_folders : list of (str, Path), optional
        Folders whose maps and scenario files make the catalog, each with the
        label its ids start with (default: :func:`default_map_folders`).
    limits : Limits, optional
        Sizes and budgets of one request.
    workers : int
        Worker processes, hence computations that run at once.
    warm : bool
        Compile every planner's kernels in the background when the server starts
        (the workers forked afterwards have them).
    max_queue : int
        Computations that may wait for a worker; one more is a 503 with Retry-After.
    allowed_hosts : iterable of str, optional
        Host names a request's ``Host`` header may give (any port; ``"*"``: every
        host); default :data:`~pathfuse.web.guard.LOOPBACK_NAMES`.

    The app's ``state`` holds ``store`` (:class:`~pathfuse.web.maps.MapStore`),
    ``limits`` and ``pool`` (:class:`~pathfuse.web.pool.WorkerPool`).
    """
    import pathfuse.planners.registry  # loaded before the workers fork
    import pathfuse.web.episodes  # noqa: F401
    import pathfuse.web.layers  # noqa: F401
    import pathfuse.web.service  # noqa: F401

    limits = limits or Limits()
    folders = default_map_folders() if map_folders is None else list(map_folders)
    store = MapStore(folders, limits)
    static = _static_files()

    def setup_worker(ask: Callable[[Any], Any]) -> None:
        store.worker_mode(lambda map_id: ask(("map", map_id)))

    def answer(request: Any) -> Any:
        if isinstance(request, tuple) and len(request) == 2 and request[0] == "map":
            return store.upload_entry(str(request[1]))
        return None

    pool = WorkerPool(lambda kind, args: run_job(store, kind, args), answer,
                      size=workers, max_queue=max_queue, setup=[setup_worker])
    registry = pathfuse.planners.registry.REGISTRY
    seen = [_registry_key(registry)]

    def renew_if_registry_changed() -> None:
        """A planner registered (or replaced) since the workers were forked: fork anew."""
        key = _registry_key(registry)
        if key != seen[0]:
            seen[0] = key
            pool.renew()

    async def compute(request: Request, arrival: float, kind: str, *args: Any) -> Response:
        """Run a job in the pool; a client that disconnects cancels it (its worker is
        killed)."""
        deadline = arrival + limits.time_budget_s + limits.grace_s
        renew_if_registry_changed()
        outcome: list[Any] = []

        async def watch_disconnect(scope: anyio.CancelScope) -> None:
            while True:
                message = await request.receive()
                if message["type"] == "http.disconnect":
                    scope.cancel()
                    return

        async with anyio.create_task_group() as tg:
            tg.start_soon(watch_disconnect, tg.cancel_scope)
            try:
                outcome.append(await pool.run(kind, (deadline, limits, *args), deadline))
            except Exception as exc:  # noqa: BLE001 - answered below, never raised
                outcome.append(exc)
            tg.cancel_scope.cancel()
        if not outcome:  # the client went away: nobody reads this
            return _error(499, "client closed the request")
        got = outcome[0]
        if isinstance(got, PoolBusy):
            return _error(503, str(got), {"Retry-After": str(got.retry_after)})
        if isinstance(got, JobTimeout):
            return _error(503, f"the request took longer than this server's budget of "
                               f"{limits.time_budget_s:g} s")
        if isinstance(got, WorkerLost):
            return _error(503, str(got), {"Retry-After": "1"})
        if isinstance(got, JobCrashed):
            print(got.trace, file=sys.stderr, end="", flush=True)
            return _error(500, f"internal error: {got.message}")
        if isinstance(got, Exception):  # the pool itself failed (a fork refused, say)
            return _error(500, f"internal error: {type(got).__name__}: {got}")
        status, payload, added = got
        if added:
            store.adopt(added)
        return Response(payload, status_code=status, media_type="application/json")

    async def body_bytes(request: Request) -> bytes:
        problem = json_body_problem(request.headers.get("content-type"),
                                    request.headers.get("content-encoding"))
        if problem is not None:
            raise ApiError(*problem)
        size = request.headers.get("content-length")
        if size is not None and size.isdigit() and int(size) > limits.max_body_bytes:
            raise ApiError(413, f"request body: {size} bytes is more than this server's limit "
                                f"of {limits.max_body_bytes}")
        chunks = []
        total = 0
        async for chunk in request.stream():
            total += len(chunk)
            if total > limits.max_body_bytes:
                raise ApiError(413, f"request body: more than this server's limit of "
                                    f"{limits.max_body_bytes} bytes")
            chunks.append(chunk)
        return b"".join(chunks)

    def post_json(kind: str) -> Callable[[Request], Awaitable[Response]]:
        async def handler(request: Request) -> Response:
            arrival = time.monotonic()
            try:
                raw = await body_bytes(request)
            except ApiError as exc:
                return _error(exc.status, str(exc))
            return await compute(request, arrival, kind, raw)
        return handler

    # ------------------------------------------------------------------ handlers
    async def index(request: Request) -> Response:
        content, media = static["index.html"]
        return Response(content, media_type=media, headers={"Cache-Control": "no-cache"})

    async def static_file(request: Request) -> Response:
        hit = static.get(request.path_params["name"])
        if hit is None:
            return _error(404, "no such file")
        return Response(hit[0], media_type=hit[1], headers={"Cache-Control": "no-cache"})

    async def planners(request: Request) -> Response:
        from pathfuse.web.service import planners_json

        try:
            return _json(planners_json())
        except Exception as exc:  # noqa: BLE001 - a plug-in's metadata: say so, keep serving
            return _error(500, f"internal error: {type(exc).__name__}: {exc}")

    async def maps(request: Request) -> Response:
        return _json({"maps": store.catalog(),
                      "limits": {"max_cells": limits.max_cells,
                                 "max_upload_bytes": limits.max_upload_bytes,
                                 "time_budget_s": limits.time_budget_s,
                                 "max_ticks": limits.max_ticks,
                                 "max_discs": limits.max_discs}})

    async def get_map(request: Request) -> Response:
        return await compute(request, time.monotonic(), "get_map",
                             request.path_params["map_id"])

    async def read_files(request: Request) -> tuple[list[tuple[str, bytes]], dict[str, str]]:
        enc = request.headers.get("content-encoding")
        if enc is not None and enc.strip().lower() not in ("", "identity"):
            raise ApiError(415, "upload: compressed bodies are not accepted "
                                "(Content-Encoding); send the file as it is, or a .zip")
        size = request.headers.get("content-length")
        if size is None or not size.isdigit():
            raise ApiError(411, "upload: send a Content-Length header")
        if int(size) > limits.max_upload_bytes:
            raise ApiError(413, f"upload: {size} bytes is more than this server's limit of "
                                f"{limits.max_upload_bytes} bytes")
        ctype = request.headers.get("content-type", "")
        if not ctype.startswith("multipart/form-data"):
            raise ApiError(415, "upload: send the file as multipart/form-data (field 'file')")
        try:
            form = await request.form(max_files=4, max_fields=8,
                                      max_part_size=limits.max_upload_bytes)
        except Exception as exc:  # noqa: BLE001 - the multipart parser's own errors
            raise ApiError(400, f"upload: malformed multipart body ({exc})") from None
        files: list[tuple[str, bytes]] = []
        fields: dict[str, str] = {}
        try:
            for key, value in form.multi_items():
                if isinstance(value, str):
                    fields[key] = value
                else:
                    data = await value.read()
                    files.append((value.filename or key, data))
        finally:
            await form.close()
        return files, fields

    async def upload_map(request: Request) -> Response:
        arrival = time.monotonic()
        try:
            files, fields = await read_files(request)
        except ApiError as exc:
            return _error(exc.status, str(exc))
        return await compute(request, arrival, "upload_map", files, fields)

    async def upload_scenario(request: Request) -> Response:
        arrival = time.monotonic()
        try:
            files, _ = await read_files(request)
        except ApiError as exc:
            return _error(exc.status, str(exc))
        if len(files) != 1:
            return _error(400, f"upload: must be one scenario YAML file, got {len(files)}")
        return await compute(request, arrival, "upload_scenario", files[0][0], files[0][1])

    async def scenarios(request: Request) -> Response:
        return _json({"scenarios": [{"id": k, "name": Path(k).name}
                                    for k in sorted(store.scenarios)]})

    async def get_scenario(request: Request) -> Response:
        return await compute(request, time.monotonic(), "get_scenario",
                             request.path_params["sid"])

    routes = [
        Route("/", index),
        Route("/index.html", index),
        Route("/static/{name}", static_file),
        Route("/api/planners", planners),
        Route("/api/maps", maps, methods=["GET"]),
        Route("/api/maps", upload_map, methods=["POST"]),
        Route("/api/maps/{map_id:path}", get_map),
        Route("/api/map", post_json("map"), methods=["POST"]),
        Route("/api/plan", post_json("plan"), methods=["POST"]),
        Route("/api/field", post_json("field"), methods=["POST"]),
        Route("/api/simulate", post_json("simulate"), methods=["POST"]),
        Route("/api/scenarios", scenarios, methods=["GET"]),
        Route("/api/scenarios", upload_scenario, methods=["POST"]),
        Route("/api/scenarios/{sid:path}", get_scenario),
        Route("/api/scenario/export", post_json("export"), methods=["POST"]),
    ]

    async def not_found(request: Request, exc: Exception) -> Response:
        return _error(404, f"no such endpoint: {request.method} {request.url.path}")

    async def not_allowed(request: Request, exc: Exception) -> Response:
        return _error(405, f"method {request.method} not allowed on {request.url.path}")

    def lifespan(app: Starlette):  # type: ignore[no-untyped-def]
        import contextlib
        import threading

        @contextlib.asynccontextmanager
        async def ctx(_app: Starlette):  # type: ignore[no-untyped-def]
            if warm:
                threading.Thread(target=_warm_all, args=(pool,), daemon=True,
                                 name="pathfuse-warm").start()
            try:
                yield
            finally:
                await anyio.to_thread.run_sync(pool.close)

        return ctx(app)

    hosts = LOOPBACK_NAMES if allowed_hosts is None else tuple(allowed_hosts)
    app = Starlette(routes=routes, exception_handlers={404: not_found, 405: not_allowed},
                    middleware=[Middleware(HostOriginGuard, allowed_hosts=hosts)],
                    lifespan=lifespan)
    app.state.store = store
    app.state.limits = limits
    app.state.pool = pool
    return app


def _registry_key(registry: dict[str, Any]) -> tuple[tuple[str, int], ...]:
    return tuple((name, id(spec)) for name, spec in list(registry.items()))


def _warm_all(pool: WorkerPool) -> None:
    """Compile (or load from numba's cache) every planner's kernels and the page's layer
    kernels in the server process, then have the pool fork fresh workers that have them."""
    from pathfuse.planners.registry import REGISTRY, planner_names
    from pathfuse.planners.run import warm as warm_one

    for n in planner_names():
        try:
            for online in (False, True):  # the playground plans and simulates
                warm_one(REGISTRY[n], online=online)
        except Exception:  # noqa: BLE001 - a plug-in's warm-up is its own
            pass
    try:  # the page's layers, the metrics of extras and an episode's world
        import pathfuse
        from pathfuse.grid import GridMap
        from pathfuse.metrics import evaluate
        from pathfuse.web.layers import potential_field

        g = GridMap.from_rows(["....", ".#..", "...."])
        potential_field(g, (3.5, 2.5), 40.0, 5.0, 2.0)
        evaluate(g, pathfuse.plan(g, (0.5, 0.5), (3.5, 2.5)), 0.1)
        pathfuse.simulate({"map": {"rows": ["......", "......"]}, "start": [0.5, 0.5],
                           "goal": [5.5, 0.5], "time_limit": 1.0,
                           "obstacles": [{"position": [3, 1.5], "velocity": [0, -0.1],
                                          "radius": 0.2}]})
    except Exception:  # noqa: BLE001 - warming is best effort
        pass
    pool.renew()
