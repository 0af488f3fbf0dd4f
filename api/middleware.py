"""Plain ASGI middleware: the request-body size limit (413), access control (401, 429),
the Host allow-list of a service without tokens (400) and the security headers of every
response."""

from __future__ import annotations

import asyncio
import json
import math
import time

from .errors import error_body, problem

__all__ = [
    "PAGE_CSP",
    "AccessMiddleware",
    "BodyLimitMiddleware",
    "HostMiddleware",
    "SecurityHeadersMiddleware",
]

# the page (api/static) loads its script and style sheet from /static, draws pictures from
# blob: URLs and its favicon from data:, talks to this origin only; no inline script/style
PAGE_CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
    "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'"
)


class SecurityHeadersMiddleware:
    """Every response gets ``Content-Security-Policy`` (:data:`PAGE_CSP`, unless the route
    set its own: the API reference pages, :mod:`.routers.docs`), ``X-Content-Type-Options:
    nosniff``, ``X-Frame-Options: DENY`` (with the CSP's ``frame-ancestors 'none'``: no
    page of the service can be framed) and ``Referrer-Policy: no-referrer``."""

    HEADERS = (
        (b"x-content-type-options", b"nosniff"),
        (b"x-frame-options", b"DENY"),
        (b"referrer-policy", b"no-referrer"),
    )

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_with_headers(msg):
            if msg["type"] == "http.response.start":
                headers = list(msg.get("headers", ()))
                names = {name.lower() for name, _ in headers}
                if b"content-security-policy" not in names:
                    headers.append((b"content-security-policy", PAGE_CSP.encode()))
                headers += [h for h in self.HEADERS if h[0] not in names]
                msg = {**msg, "headers": headers}
            await send(msg)

        await self.app(scope, receive, send_with_headers)


class HostMiddleware:
    """Without tokens, answer only requests whose ``Host`` is one of ``allowed`` (loopback
    names by default; ``"*"`` allows any), 400 otherwise.

    A service on 127.0.0.1 without tokens trusts whoever reaches the port; a web page from
    elsewhere that rebinds its own name to 127.0.0.1 (DNS rebinding) reaches it from the
    user's browser, but with its own name in ``Host``.  With tokens (``active`` False) the
    token is the check.
    """

    def __init__(self, app, allowed: tuple[str, ...], active: bool):
        self.app = app
        self.allowed = frozenset(h.lower().strip("[]") for h in allowed)
        self.active = active and "*" not in self.allowed

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or not self.active:
            await self.app(scope, receive, send)
            return
        host = ""
        for name, value in scope.get("headers", ()):
            if name == b"host":
                host = value.decode("latin-1").strip().lower()
                break
        if _host_name(host) not in self.allowed:
            msg = (
                f"this service answers the host names {', '.join(sorted(self.allowed))}, "
                f"not {host or 'an empty Host header'} (certsolve serve --allow-host NAME)"
            )
            await _send_error(send, 400, msg, ("header", "Host"), "host_not_allowed")
            return
        await self.app(scope, receive, send)


def _host_name(host: str) -> str:
    """``Host`` without its port: ``localhost:8000`` -> ``localhost``, ``[::1]:80`` ->
    ``::1``."""
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


class BodyLimitMiddleware:
    """Refuse requests whose body exceeds ``max_bytes`` with 413, before any parsing.

    ``Content-Length`` is checked first; chunked bodies are read up to the limit and then
    handed to the application unchanged.
    """

    def __init__(self, app, max_bytes: int):
        self.app = app
        self.max_bytes = int(max_bytes)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or scope.get("method") in ("GET", "HEAD", "OPTIONS"):
            await self.app(scope, receive, send)
            return
        for name, value in scope.get("headers", ()):
            if name == b"content-length":
                try:
                    too_big = int(value) > self.max_bytes
                except ValueError:
                    too_big = False
                if too_big:
                    await self._refuse(send)
                    return
        chunks: list[bytes] = []
        size = 0
        while True:
            msg = await receive()
            if msg["type"] == "http.disconnect":
                return
            body = msg.get("body", b"")
            size += len(body)
            if size > self.max_bytes:
                await self._refuse(send)
                return
            chunks.append(body)
            if not msg.get("more_body", False):
                break
        data = b"".join(chunks)
        sent = False

        async def replay():
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": data, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    async def _refuse(self, send) -> None:
        msg = f"request body too large (at most {self.max_bytes} bytes)"
        await _send_error(send, 413, msg, ("body",), "too_large", [(b"connection", b"close")])


class AccessMiddleware:
    """Bearer tokens and per-client request rates for every path under ``/v1/``.

    With a token table (:class:`certsolve.jobs.access.AccessTable`) a request without a
    valid ``Authorization: Bearer <token>`` gets 401 (with ``WWW-Authenticate``) before its
    body is read; a valid one has its client put in ``scope["state"]["client"]`` (read by
    :func:`api.deps.get_caller`).  Each client may make ``requests_per_minute`` requests (a
    token bucket of that size, refilled continuously); past it the answer is 429 with
    ``Retry-After``.  Without a table every request passes (client None).  ``/healthz`` and
    the documentation are public.  Tokens are never logged or echoed.  A refused token
    waits ``failure_delay`` seconds for its 401, which slows guessing down.
    """

    def __init__(self, app, access, default_rate: int, failure_delay: float = 0.0):
        self.app = app
        self.access = access
        self.default_rate = int(default_rate)
        self.failure_delay = float(failure_delay)
        self._buckets: dict[str, tuple[float, float]] = {}  # client -> (tokens, time)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or self.access is None or not scope["path"].startswith("/v1/"):
            await self.app(scope, receive, send)
            return
        token = None
        for name, value in scope.get("headers", ()):
            if name == b"authorization":
                scheme, _, rest = value.decode("latin-1").strip().partition(" ")
                if scheme.lower() == "bearer":
                    token = rest.strip()
                break
        client = self.access.client_for(token)
        if client is None:
            given = token is not None
            msg = "invalid token" if given else "this service needs a token"
            msg += ": send Authorization: Bearer <token>"
            challenge = 'Bearer realm="certsolve"' + (', error="invalid_token"' if given else "")
            if given and self.failure_delay > 0:
                await asyncio.sleep(self.failure_delay)
            await _send_error(
                send, 401, msg, ("header", "Authorization"), "unauthorized",
                [(b"www-authenticate", challenge.encode())],
            )  # fmt: skip
            return
        wait = self._spend(client.name, client.requests_per_minute or self.default_rate)
        if wait > 0:
            retry = max(1, math.ceil(wait))
            msg = f"too many requests from {client.name}; retry in {retry} s"
            await _send_error(
                send, 429, msg, (), "rate_limited", [(b"retry-after", str(retry).encode())]
            )
            return
        scope.setdefault("state", {})["client"] = client
        await self.app(scope, receive, send)

    def _spend(self, name: str, per_minute: int) -> float:
        """Take one request from ``name``'s bucket: 0, or the seconds until one is free."""
        now = time.monotonic()
        tokens, then = self._buckets.get(name, (float(per_minute), now))
        tokens = min(float(per_minute), tokens + (now - then) * per_minute / 60.0)
        if tokens < 1.0:
            self._buckets[name] = (tokens, now)
            return (1.0 - tokens) * 60.0 / per_minute
        self._buckets[name] = (tokens - 1.0, now)
        return 0.0


async def _send_error(send, status: int, msg: str, loc, typ: str, headers=()) -> None:
    body = json.dumps(error_body(status, msg, [problem(msg, loc, typ)])).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                *headers,
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})
