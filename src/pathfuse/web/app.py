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
``pathfuse COMMAND: error:``).  Every computation runs in a worker thread
(at most ``workers`` at once) under the time budget; past it the answer is
503 and the page stays responsive.  No request names a file on the disk.
"""

from __future__ import annotations

import json
import math
from collections.abc import Awaitable, Callable
from functools import partial
from importlib import resources
from pathlib import Path
from typing import Any

import anyio
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import Response
from starlette.routing import Route

from pathfuse.result import PathfuseError
from pathfuse.web.maps import ApiError, Limits, MapStore, grid_to_json, read_upload

__all__ = ["create_app", "default_map_folders"]

_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".svg": "image/svg+xml", ".png": "image/png",
          ".ico": "image/x-icon", ".txt": "text/plain; charset=utf-8"}


def default_map_folders() -> list[tuple[str, Path]]:
    """``examples/`` and ``tests/data/`` of the source tree pathfuse runs from (a clone
    installed with ``pip install -e``), when they exist, as (label, folder)."""
    root = Path(__file__).resolve().parents[3]
    pairs = [("examples", root / "examples"), ("tests/data", root / "tests" / "data")]
    return [(label, p) for label, p in pairs if p.is_dir()]


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


def _json(data: Any, status: int = 200) -> Response:
    body = json.dumps(_clean(data), separators=(",", ":"), allow_nan=False)
    return Response(body, status_code=status, media_type="application/json")


def _error(status: int, message: str) -> Response:
    return _json({"error": message}, status)


def create_app(*, map_folders: list[tuple[str, Path]] | None = None, limits: Limits | None = None,
               workers: int = 2, warm: bool = False) -> Starlette:
    """The web app.

    Parameters
    ----------
    map_folders : list of (str, Path), optional
        Folders whose maps and scenario files make the catalog, each with the
        label its ids start with (default: :func:`default_map_folders`).
    limits : Limits, optional
        Sizes and budgets of one request.
    workers : int
        Computations that run at once (each in a worker thread).
    warm : bool
        Compile every planner's kernels in the background when the server starts.
    """
    limits = limits or Limits()
    folders = default_map_folders() if map_folders is None else list(map_folders)
    store = MapStore(folders, limits)
    static = _static_files()
    limiter = anyio.CapacityLimiter(max(1, int(workers)))

    async def compute(fn: Callable[..., Any], *args: Any) -> Response:
        try:
            with anyio.fail_after(limits.time_budget_s + limits.grace_s):
                data = await anyio.to_thread.run_sync(partial(fn, *args), limiter=limiter,
                                                      abandon_on_cancel=True)
        except TimeoutError:
            return _error(503, f"the request took longer than this server's budget of "
                               f"{limits.time_budget_s:g} s")
        except ApiError as exc:
            return _error(exc.status, str(exc))
        except PathfuseError as exc:
            return _error(400, str(exc))
        except Exception as exc:  # noqa: BLE001 - a bug (or a plug-in's): say so, keep serving
            import traceback

            traceback.print_exc()
            return _error(500, f"internal error: {type(exc).__name__}: {exc}")
        return _json(data)

    async def body_json(request: Request) -> Any:
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
        raw = b"".join(chunks)
        try:
            return json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ApiError(400, f"request body: not valid JSON ({exc})") from None

    def post_json(fn: Callable[..., Any]) -> Callable[[Request], Awaitable[Response]]:
        async def handler(request: Request) -> Response:
            try:
                body = await body_json(request)
            except ApiError as exc:
                return _error(exc.status, str(exc))
            return await compute(fn, store, body, limits)
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

        return await compute(planners_json)

    async def maps(request: Request) -> Response:
        return _json({"maps": store.catalog(),
                      "limits": {"max_cells": limits.max_cells,
                                 "max_upload_bytes": limits.max_upload_bytes,
                                 "time_budget_s": limits.time_budget_s,
                                 "max_ticks": limits.max_ticks,
                                 "max_discs": limits.max_discs}})

    def _one_map(map_id: str) -> dict[str, Any]:
        e = store.get(map_id)
        assert e.grid is not None
        d = grid_to_json(e.grid, e.id)
        d["spec"] = e.spec
        return d

    async def get_map(request: Request) -> Response:
        return await compute(_one_map, request.path_params["map_id"])

    async def read_files(request: Request) -> tuple[list[tuple[str, bytes]], dict[str, str]]:
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
        from pathfuse import validate

        try:
            files, fields = await read_files(request)
        except ApiError as exc:
            return _error(exc.status, str(exc))

        def work() -> dict[str, Any]:
            res = fields.get("resolution", "").strip()
            resolution = validate.number(res, "resolution", gt=0) if res else None
            grid = read_upload(files, limits, resolution)
            e = store.add_upload(grid, grid.name)
            return grid_to_json(grid, e.id)

        return await compute(work)

    async def upload_scenario(request: Request) -> Response:
        from pathfuse.web.episodes import upload_scenario as read_scenario

        try:
            files, _ = await read_files(request)
        except ApiError as exc:
            return _error(exc.status, str(exc))
        if len(files) != 1:
            return _error(400, f"upload: expected one scenario YAML file, got {len(files)}")
        return await compute(read_scenario, store, files[0][0], files[0][1], limits)

    async def scenarios(request: Request) -> Response:
        return _json({"scenarios": [{"id": k, "name": Path(k).name}
                                    for k in sorted(store.scenarios)]})

    async def get_scenario(request: Request) -> Response:
        from pathfuse.web.episodes import load_catalog_scenario

        return await compute(load_catalog_scenario, store, request.path_params["sid"])

    from pathfuse.web.episodes import export_request, simulate_request
    from pathfuse.web.service import field_request, map_request, plan_request

    routes = [
        Route("/", index),
        Route("/index.html", index),
        Route("/static/{name}", static_file),
        Route("/api/planners", planners),
        Route("/api/maps", maps, methods=["GET"]),
        Route("/api/maps", upload_map, methods=["POST"]),
        Route("/api/maps/{map_id:path}", get_map),
        Route("/api/map", post_json(lambda s, b, lim: map_request(s, b)), methods=["POST"]),
        Route("/api/plan", post_json(plan_request), methods=["POST"]),
        Route("/api/field", post_json(field_request), methods=["POST"]),
        Route("/api/simulate", post_json(simulate_request), methods=["POST"]),
        Route("/api/scenarios", scenarios, methods=["GET"]),
        Route("/api/scenarios", upload_scenario, methods=["POST"]),
        Route("/api/scenarios/{sid:path}", get_scenario),
        Route("/api/scenario/export", post_json(export_request), methods=["POST"]),
    ]

    async def not_found(request: Request, exc: Exception) -> Response:
        return _error(404, f"no such endpoint: {request.method} {request.url.path}")

    async def not_allowed(request: Request, exc: Exception) -> Response:
        return _error(405, f"method {request.method} not allowed on {request.url.path}")

    def lifespan_warm(app: Starlette):  # type: ignore[no-untyped-def]
        import contextlib
        import threading

        @contextlib.asynccontextmanager
        async def ctx(_app: Starlette):  # type: ignore[no-untyped-def]
            if warm:
                def run() -> None:
                    from pathfuse.planners.registry import REGISTRY, planner_names
                    from pathfuse.planners.run import warm as warm_one

                    for n in planner_names():
                        try:
                            warm_one(REGISTRY[n])
                        except Exception:  # noqa: BLE001 - a plug-in's warm-up is its own
                            pass

                threading.Thread(target=run, daemon=True, name="pathfuse-warm").start()
            yield

        return ctx(app)

    app = Starlette(routes=routes, exception_handlers={404: not_found, 405: not_allowed},
                    lifespan=lifespan_warm)
    app.state.store = store
    app.state.limits = limits
    return app
