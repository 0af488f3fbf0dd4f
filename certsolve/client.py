"""A small Python client of the certsolve job service (``certsolve serve``), stdlib only.

>>> from certsolve.client import ServiceClient
>>> svc = ServiceClient("http://127.0.0.1:8000")                    # doctest: +SKIP
>>> job = svc.submit({"kind": "solve", "system": open("circle-line.mbx").read()})
>>> record = svc.wait(job["id"])        # the job record once final, with its result
>>> record["status"], record["result"]["status"]
('done', 'complete')

Every method is one HTTP request (``wait`` polls ``GET /v1/jobs/{id}``) and returns the
service's JSON as plain Python values; an error answer or an unreachable service raises
:class:`ClientError` with the service's one-line message and the HTTP status.  With
``token``, each request carries ``Authorization: Bearer <token>``.  The endpoints and
their bodies are in ``docs/api.md``.
"""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterable
from typing import Any

from .jobs.status import JobStatus

__all__ = ["DEFAULT_SERVER", "ClientError", "ServiceClient"]

DEFAULT_SERVER = "http://127.0.0.1:8000"


class ClientError(Exception):
    """The service refused a request (``status`` is the HTTP status) or could not be
    reached (``status`` is None)."""

    def __init__(self, message: str, status: int | None = None, body: Any = None):
        super().__init__(message)
        self.status = status
        self.body = body


class ServiceClient:
    """Talks to one service at ``server`` (``http://host:port``)."""

    def __init__(
        self, server: str = DEFAULT_SERVER, *, token: str | None = None, timeout: float = 60.0
    ):
        server = server.rstrip("/")
        parts = urllib.parse.urlsplit(server)
        if parts.scheme not in ("http", "https") or not parts.netloc:
            raise ValueError(f"server: expected http://host:port, got {server!r}")
        self.server = server
        self.token = token
        self.timeout = timeout
        local = (parts.hostname or "") in ("localhost", "127.0.0.1", "::1")
        handlers = [urllib.request.ProxyHandler({})] if local else []  # no proxy for loopback
        self._opener = urllib.request.build_opener(*handlers)

    # -- the one request ----------------------------------------------------------------------
    def request(
        self, method: str, path: str, body: Any = None, *, ok: Iterable[int] = (200, 202)
    ) -> Any:
        """``method path`` with a JSON ``body``; the decoded JSON answer."""
        headers = {"Accept": "application/json"}
        data = None
        if body is not None:
            data = json.dumps(body, allow_nan=False).encode()
            headers["Content-Type"] = "application/json"
        if self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        req = urllib.request.Request(self.server + path, data=data, method=method, headers=headers)
        try:
            with self._opener.open(req, timeout=self.timeout) as resp:
                raw, status = resp.read(), resp.status
        except urllib.error.HTTPError as exc:
            raw, status = exc.read(), exc.code
        except (urllib.error.URLError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            raise ClientError(f"cannot reach the service at {self.server} ({reason})") from None
        try:
            payload = json.loads(raw) if raw else None
        except ValueError:
            payload = None
        if status not in tuple(ok):
            msg = payload.get("error") if isinstance(payload, dict) else None
            text = msg or raw[:200].decode(errors="replace")
            raise ClientError(f"service answered {status}: {text}", status, payload)
        return payload

    @staticmethod
    def _job_path(job_id: str) -> str:
        return "/v1/jobs/" + urllib.parse.quote(job_id, safe="")

    # -- jobs ---------------------------------------------------------------------------------
    def submit(self, job: dict[str, Any]) -> dict[str, Any]:
        """Queue one job (as for ``POST /v1/jobs``): ``{"id", "url", "status"}``."""
        return self.request("POST", "/v1/jobs", job)

    def submit_batch(self, jobs: list[dict[str, Any]]) -> dict[str, Any]:
        """Queue jobs all or none: ``{"batch", "url", "ids"}``."""
        return self.request("POST", "/v1/jobs/batch", {"jobs": jobs})

    def status(self, job_id: str) -> dict[str, Any]:
        """The job record without its result (status, progress, error ...)."""
        return self.request("GET", self._job_path(job_id) + "?result=false")

    def job(self, job_id: str) -> dict[str, Any]:
        """The job record with its result (None until there is one)."""
        return self.request("GET", self._job_path(job_id))

    def result(self, job_id: str) -> Any:
        """Only the result; :class:`ClientError` (409) while the job has none."""
        return self.request("GET", self._job_path(job_id) + "/result")

    def cancel(self, job_id: str) -> dict[str, Any]:
        """Cancel (a queued job at once, a running one within about a second)."""
        return self.request("DELETE", self._job_path(job_id))

    def list(
        self,
        *,
        status: JobStatus | str | None = None,
        kind: str | None = None,
        batch: str | None = None,
        limit: int = 50,
        cursor: str | None = None,
    ) -> dict[str, Any]:
        """One page of job records, newest first: ``{"items", "next_cursor"}``."""
        query: dict[str, Any] = {"limit": limit}
        for name, value in (("status", status), ("kind", kind), ("batch", batch)):
            if value is not None:
                query[name] = str(value)
        if cursor is not None:
            query["cursor"] = cursor
        return self.request("GET", "/v1/jobs?" + urllib.parse.urlencode(query))

    def wait(
        self, job_id: str, *, poll: float = 0.5, timeout: float | None = None
    ) -> dict[str, Any]:
        """Poll until the job is final; its record with the result.  :class:`TimeoutError`
        after ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            rec = self.job(job_id)
            if JobStatus(rec["status"]).final:
                return rec
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"job {job_id} is still {rec['status']} after {timeout} s")
            time.sleep(max(0.05, poll))

    # -- service ------------------------------------------------------------------------------
    def health(self) -> dict[str, Any]:
        return self.request("GET", "/healthz")

    def kinds(self) -> dict[str, Any]:
        return self.request("GET", "/v1/kinds")
