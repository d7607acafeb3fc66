"""``pathfuse serve``: a planning playground in the browser (``pip install "pathfuse[web]"``).

:func:`create_app` builds the Starlette application (the page and its JSON
API, see :mod:`pathfuse.web.app`); ``pathfuse serve`` runs it on uvicorn,
bound to 127.0.0.1 unless told otherwise.  The page is plain ES modules and
canvas, shipped in ``pathfuse/web/static``: no build step, no network.
"""

from __future__ import annotations

from typing import Any

__all__ = ["create_app"]


def create_app(**kwargs: Any) -> Any:
    """The web application (see :func:`pathfuse.web.app.create_app`)."""
    from pathfuse.web.app import create_app as _create

    return _create(**kwargs)
