"""Who may use the service: API tokens, the client each names, and its quotas.

A token table is a JSON object mapping a client name to its token and rights::

    {"alice": {"token": "3f9c...", "admin": false},
     "ops":   {"token": "b71e...", "admin": true, "max_queued": 100000},
     "ci":    {"token": "0d44...", "max_running": 1, "requests_per_minute": 120}}

(``certsolve serve --tokens FILE``, or the same JSON in ``$CERTSOLVE_TOKENS``).  A request
carries ``Authorization: Bearer <token>``; its client owns the jobs it submits.  A client
sees and cancels only its own jobs; an admin sees all of them and may purge old ones.

Quotas per client (the service's defaults unless the entry sets them): ``max_queued`` jobs
waiting (more are refused, HTTP 429), ``max_running`` jobs running at once (the others wait
their turn in the queue: the workers skip them), ``requests_per_minute`` (HTTP 429 past
it).  Tokens are compared in constant time (:func:`hmac.compare_digest` of their SHA-256
digests, every entry compared) and never logged: the table's ``repr`` hides them.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, RootModel, ValidationError

__all__ = [
    "AccessError",
    "AccessTable",
    "Client",
    "MIN_TOKEN_CHARS",
    "load_access",
]

MIN_TOKEN_CHARS = 16
_NAME = r"^[A-Za-z0-9_.@-]{1,64}$"


class AccessError(ValueError):
    """A token table that cannot be used; the message names the entry and field."""


class _Entry(BaseModel):
    model_config = ConfigDict(extra="forbid")

    token: str = Field(min_length=MIN_TOKEN_CHARS, max_length=512, pattern=r"^[\x21-\x7e]+$")
    admin: bool = False
    max_queued: int | None = Field(default=None, ge=0)
    max_running: int | None = Field(default=None, ge=1)
    requests_per_minute: int | None = Field(default=None, ge=1)


class _Table(RootModel[dict[str, _Entry]]):
    pass


@dataclass(frozen=True, kw_only=True)
class Client:
    """A client of the service: its name (the owner of its jobs), rights and quotas
    (``None``: no limit of its own)."""

    name: str
    admin: bool = False
    max_queued: int | None = None
    max_running: int | None = None
    requests_per_minute: int | None = None


@dataclass(frozen=True, kw_only=True)
class AccessTable:
    """The clients and the SHA-256 digests of their tokens (the tokens themselves are not
    kept)."""

    clients: tuple[Client, ...]
    digests: tuple[bytes, ...] = field(repr=False)

    def client_for(self, token: str | None) -> Client | None:
        """The client whose token this is, or None; the time taken does not depend on
        which entry (if any) matches, nor on how much of a token is right."""
        if not token:
            return None
        digest = hashlib.sha256(token.encode("utf-8", "surrogateescape")).digest()
        found = None
        for client, known in zip(self.clients, self.digests, strict=True):
            if hmac.compare_digest(digest, known):
                found = client
        return found

    def names(self) -> list[str]:
        return [c.name for c in self.clients]


def _table(data: Any, source: str) -> AccessTable:
    try:
        table = _Table.model_validate(data).root
    except ValidationError as exc:
        parts = []
        for e in exc.errors()[:3]:
            loc = ".".join(str(p) for p in e["loc"])
            parts.append(f"{loc}: {e['msg']}" if loc else e["msg"])
        raise AccessError(f"{source}: " + "; ".join(parts)) from None
    if not table:
        raise AccessError(f"{source}: no clients (an object mapping names to tokens)")
    clients: list[Client] = []
    digests: list[bytes] = []
    seen: dict[bytes, str] = {}
    for name, entry in table.items():
        if not re.match(_NAME, name):
            raise AccessError(f"{source}: client name {name!r}: letters, digits, _ . @ - only")
        digest = hashlib.sha256(entry.token.encode()).digest()
        if digest in seen:
            raise AccessError(f"{source}: {name}.token: the same token as {seen[digest]}")
        seen[digest] = name
        clients.append(
            Client(
                name=name,
                admin=entry.admin,
                max_queued=entry.max_queued,
                max_running=entry.max_running,
                requests_per_minute=entry.requests_per_minute,
            )
        )
        digests.append(digest)
    return AccessTable(clients=tuple(clients), digests=tuple(digests))


def load_access(
    path: str | os.PathLike | None = None, environ: Mapping[str, str] | None = None
) -> AccessTable | None:
    """The token table from ``path`` (a JSON file), else ``$CERTSOLVE_TOKENS`` (the JSON
    itself), else None (no access control).  Raises :class:`AccessError`."""
    env = os.environ if environ is None else environ
    if path is not None:
        source = str(path)
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise AccessError(f"{source}: cannot read the token file ({exc.strerror})") from None
    elif env.get("CERTSOLVE_TOKENS"):
        source, text = "$CERTSOLVE_TOKENS", env["CERTSOLVE_TOKENS"]
    else:
        return None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise AccessError(f"{source}: invalid JSON at line {exc.lineno}: {exc.msg}") from None
    return _table(data, source)
