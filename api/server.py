"""How ``certsolve serve`` runs the application under uvicorn: bounded waits for slow
clients, and an access log that never holds a token.

Slow clients.  uvicorn closes an idle keep-alive connection after ``timeout_keep_alive``
seconds, but a connection whose request is only partly sent (headers without their blank
line, or a body shorter than its ``Content-Length``) has no timer at all: a client can hold
it open for ever, and a few hundred such clients exhaust the server (slowloris).
:class:`TimedH11Protocol` arms a timer when a request starts (the connection opens, or
its first byte arrives on a kept-alive connection) and closes the connection if the
request has not been fully received ``request_timeout`` seconds later; once it has, the
timer is off and the application takes as long as it needs.  ``limit_concurrency``
(``settings.max_connections``) answers 503 past that many open connections.

Access log.  uvicorn logs each request's path with its query string; a client that puts
its token there (``?token=...``) would have it written to the log.  :class:`QueryRedactor`
keeps the parameter names and replaces every value with ``...`` (the API reads no secret
from a query, but nothing in a query string is logged).
"""

from __future__ import annotations

import asyncio
import logging
import re
from typing import Any

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

from certsolve.jobs.settings import ServiceSettings

__all__ = ["QueryRedactor", "TimedH11Protocol", "redact_query", "timed_h11", "uvicorn_options"]

ACCESS_LOGGER = "uvicorn.access"
_QUERY_VALUE = re.compile(r"=[^&#\s]*")


class TimedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a time limit on receiving each request (module doc)."""

    request_timeout: float = 10.0

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._request_timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def data_received(self, data: bytes) -> None:
        if self._request_timer is None and self.conn.their_state is h11.IDLE:
            self._arm()  # a new request on a kept-alive connection
        super().data_received(data)
        if self.conn.their_state is not h11.IDLE and self.conn.their_state is not h11.SEND_BODY:
            self._disarm()  # received whole (or the connection is closing)

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def _arm(self) -> None:
        self._disarm()
        self._request_timer = self.loop.call_later(self.request_timeout, self._too_slow)

    def _disarm(self) -> None:
        if self._request_timer is not None:
            self._request_timer.cancel()
            self._request_timer = None

    def _too_slow(self) -> None:
        self._request_timer = None
        if self.conn.their_state in (h11.IDLE, h11.SEND_BODY) and not self.transport.is_closing():
            self.logger.info("closing a connection whose request took too long to arrive")
            self.transport.close()


def timed_h11(request_timeout: float) -> type[TimedH11Protocol]:
    """The protocol class with this request timeout (uvicorn builds one per connection)."""
    return type("TimedH11Protocol", (TimedH11Protocol,), {"request_timeout": request_timeout})


def redact_query(path: str) -> str:
    """``/v1/jobs?token=abc&limit=5`` -> ``/v1/jobs?token=...&limit=...``."""
    head, sep, query = path.partition("?")
    return head + sep + _QUERY_VALUE.sub("=...", query) if sep else path


class QueryRedactor(logging.Filter):
    """Rewrites the path argument of uvicorn's access-log records (:func:`redact_query`)."""

    def filter(self, record: logging.LogRecord) -> bool:
        args = record.args
        if isinstance(args, tuple) and len(args) >= 3 and isinstance(args[2], str):
            record.args = (*args[:2], redact_query(args[2]), *args[3:])
        return True


def uvicorn_options(settings: ServiceSettings) -> dict[str, Any]:
    """The ``uvicorn.run`` options that bound what slow or many clients can hold."""
    return {
        "http": timed_h11(settings.request_timeout),
        "timeout_keep_alive": settings.keep_alive_timeout,
        "limit_concurrency": settings.max_connections,
    }
