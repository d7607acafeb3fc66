"""Who may talk to ``pathfuse serve``: the Host allow-list, the Origin check and the JSON
body rules, before any route runs.

A server on 127.0.0.1 is still reachable from every web page the user opens: a page can
POST to it (a ``text/plain`` or form body needs no CORS preflight) and, through DNS
rebinding (a name of the attacker's that resolves to 127.0.0.1), even read its answers.
So:

* **Host.**  A request whose ``Host`` header does not name an allowed host is refused
  (400).  Allowed by default: the loopback names ``localhost``, ``127.0.0.1`` and
  ``::1``; ``pathfuse serve --allow-host NAME`` adds more (``*`` allows any).  A rebound
  name is never on the list, so a rebinding page gets nothing.
* **Origin.**  A request that carries an ``Origin`` header (browsers send it on every
  POST and on cross-origin fetches) must come from the server's own origin, the scheme
  and host of its ``Host`` header; anything else, ``null`` included, is refused (403).
  So is a browser request marked ``Sec-Fetch-Site: cross-site`` that is not a top-level
  navigation.
* **JSON only.**  A POST with a JSON body must say ``Content-Type: application/json``
  (UTF-8); anything else is a 415, and so is a compressed body (``Content-Encoding``).
  JSON cannot be sent cross-origin without a CORS preflight, which this server never
  grants.

Examples
--------
>>> host_name("LocalHost:8000"), host_name("[::1]:80"), host_name("127.0.0.1")
('localhost', '::1', '127.0.0.1')
>>> json_body_problem("text/plain", None)
(415, "request body: send JSON with Content-Type: application/json, not 'text/plain'")
>>> json_body_problem("application/json; charset=UTF-8", None) is None
True
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from typing import Any

from pathfuse.validate import short

__all__ = ["LOOPBACK_NAMES", "HostOriginGuard", "host_name", "json_body_problem"]

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
"""The hosts allowed by default."""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]


def host_name(host: str) -> str:
    """The host of a ``Host`` header, lower case, without port, brackets or a final dot."""
    h = host.strip().lower()
    if h.startswith("["):
        end = h.find("]")
        h = h[1:end] if end > 0 else h[1:]
    elif h.count(":") == 1:
        h = h.split(":", 1)[0]
    return h.rstrip(".")


def json_body_problem(content_type: str | None, content_encoding: str | None
                      ) -> tuple[int, str] | None:
    """Why a JSON request body is refused (status, message), or None when it is fine."""
    if content_encoding is not None and content_encoding.strip().lower() not in ("", "identity"):
        return 415, (f"request body: compressed bodies are not accepted (Content-Encoding: "
                     f"{short(content_encoding, 40)})")
    if content_type is None:
        return 415, "request body: send JSON with Content-Type: application/json"
    media, _, params = content_type.partition(";")
    if media.strip().lower() != "application/json":
        return 415, (f"request body: send JSON with Content-Type: application/json, not "
                     f"{short(media.strip(), 60)}")
    for p in params.split(";"):
        key, _, value = p.partition("=")
        if key.strip().lower() == "charset" and \
                value.strip().strip('"').lower() not in ("utf-8", "utf8"):
            return 415, f"request body: JSON must be UTF-8, not {short(value.strip(), 40)}"
    return None


class HostOriginGuard:
    """ASGI middleware: the Host allow-list and the Origin check (see the module docstring).

    Parameters
    ----------
    app : ASGI application
    allowed_hosts : iterable of str
        Host names (any port); ``"*"`` allows every host.
    """

    def __init__(self, app: ASGIApp, allowed_hosts: Iterable[str]) -> None:
        self.app = app
        names = {host_name(h) for h in allowed_hosts if h.strip()}
        self.any_host = "*" in names
        self.allowed = frozenset(names - {"*"})

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        problem = self.problem(headers)
        if problem is None:
            await self.app(scope, receive, send)
            return
        status, message = problem
        body = json.dumps({"error": message}).encode()
        await send({"type": "http.response.start", "status": status,
                    "headers": [(b"content-type", b"application/json"),
                                (b"content-length", str(len(body)).encode())]})
        await send({"type": "http.response.body", "body": body})

    def problem(self, headers: dict[str, str]) -> tuple[int, str] | None:
        """(status, message) when the request is refused, else None."""
        host = headers.get("host")
        if not host:
            return 400, "request: a Host header is required"
        name = host_name(host)
        if not self.any_host and name not in self.allowed:
            return 400, (f"Host {short(name, 80)} is not served here (allowed: "
                         f"{', '.join(sorted(self.allowed))}; start pathfuse serve with "
                         f"--allow-host NAME to allow another name)")
        origin = headers.get("origin")
        if origin is not None:
            o = origin.strip().lower()
            if o not in (f"http://{host.strip().lower()}", f"https://{host.strip().lower()}"):
                return 403, (f"cross-origin request refused: Origin {short(origin, 80)} is "
                             "not this server's")
        if headers.get("sec-fetch-site", "").lower() == "cross-site" and \
                headers.get("sec-fetch-mode", "").lower() != "navigate":
            return 403, "cross-site request refused"
        return None
