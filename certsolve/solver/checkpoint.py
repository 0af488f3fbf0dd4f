"""Checkpoints: a search saved as it goes, and resumed from where it was saved.

A search is fully described by its pending boxes and what its step recorded: the search
driver's guarantee (:mod:`.search`) is that the two together cover the initial boxes.  So
one snapshot serves every step kind (solver, forward kinematics, workspace paving ...):

* **snapshot**: the pending boxes (the buffer, plus the slices handed out to workers and
  not back yet) as two ``(P, n)`` arrays, and their hints (:mod:`.buffer`) if any; the
  step's records ``step.found(state)`` (the protocol the executors already use to bring a
  task's findings home; for the driver's own state, started with nothing known, it is
  *everything* recorded); the driver's counters;
  and a **fingerprint** of the problem;
* **restore**: ``state = step.start()``, ``step.merge(state, found)``, push the pending
  boxes.  A serial search then goes on exactly as if it had not stopped: the buffer is in
  the same order, so the batches, the records and the counters are the same as those of
  an uninterrupted run.

The fingerprint is a SHA-256 over the step's class, its own description of the problem and
of the settings that change the answer (``step.fingerprint()`` when it has one: the
solver's equations, domain, parameters, ``eps`` ...), the initial boxes and the caller's
``key``.  A checkpoint of another problem is refused (:class:`CheckpointError`).

**Format.** An ``.npz`` archive (numpy's zip of ``.npy`` files, read with
``allow_pickle=False``): ``meta`` (UTF-8 JSON: format version, fingerprint and the *shape*
of the records: the step's records, the pending boxes ``lo`` / ``hi``, the counters) and
``a0, a1, ...`` (the records' arrays).  The records are written by a small codec (:func:`encode`) of
``None``, numbers, strings, tuples, lists, string-keyed dicts, numpy arrays and dataclass
instances of ``certsolve`` itself -- lists of same-shape arrays, of tuples and of
dataclasses are stored as columns, one array each.  Nothing is unpickled: a checkpoint
file cannot run code.

**When.** :meth:`Checkpoint.tick` writes after a batch (or a worker task) when
``interval`` seconds have passed since the last write, and the driver writes once more
when the search stops (complete, a limit, a cancel).  A process killed between two writes
resumes from the last one: at most ``interval`` seconds of work are done again.
:meth:`Checkpoint.file` writes a file atomically (a temporary file in the same directory,
``fsync``, ``os.replace``): a reader sees the previous checkpoint or the new one, never a
torn file.

**Limits.** The limits of a run (time, boxes) apply to that run: a resumed search gets a
fresh time limit and box budget; ``max_solutions`` counts every solution, those restored
included.  The counters (``boxes``, ``time``, ``cpu`` ...) go on from their saved values;
``resumed`` counts the restores and ``resumed_boxes`` is the boxes already processed at
the last one.

Every search that checkpoints runs on the driver, the certified design
(:mod:`certsolve.force.design`) included: one snapshot format, one restore.
"""

from __future__ import annotations

import dataclasses
import importlib
import io
import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .protocol import RunningSearch, SearchStats, Step

__all__ = [
    "Checkpoint",
    "CheckpointError",
    "decode",
    "encode",
    "fingerprint",
    "pack",
    "unpack",
    "write_atomic",
]

FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint that cannot be resumed here: another problem, or an unreadable file."""


# -- the codec of the records ------------------------------------------------------------------
def _array(a: np.ndarray, arrays: list) -> int:
    if a.dtype.hasobject:
        raise TypeError("cannot checkpoint an array of Python objects")
    arrays.append(a)
    return len(arrays) - 1


def _same_arrays(items: list) -> bool:
    first = items[0]
    return all(
        isinstance(x, np.ndarray) and x.shape == first.shape and x.dtype == first.dtype
        for x in items
    )


def encode(obj: Any, arrays: list[np.ndarray]) -> Any:
    """``obj`` as JSON data, its arrays appended to ``arrays`` (see the module docstring)."""
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, (int, float)):
        return obj
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return {"$a": _array(obj, arrays)}
    if isinstance(obj, tuple):
        return {"$t": [encode(x, arrays) for x in obj]}
    if isinstance(obj, dict):
        if not all(isinstance(k, str) for k in obj):
            raise TypeError("cannot checkpoint a dict with keys that are not strings")
        return {"$m": {k: encode(v, arrays) for k, v in obj.items()}}
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        fields = {f.name: encode(getattr(obj, f.name), arrays) for f in dataclasses.fields(obj)}
        return {"$d": _class_name(type(obj)), "f": fields}
    if isinstance(obj, list):
        return _encode_list(obj, arrays)
    raise TypeError(f"cannot checkpoint a {type(obj).__name__}")


def _encode_list(items: list, arrays: list) -> Any:
    if len(items) < 2:
        return [encode(x, arrays) for x in items]
    first = items[0]
    if isinstance(first, np.ndarray) and not first.dtype.hasobject:
        if _same_arrays(items):  # e.g. existence boxes: one (k, n) array
            return {"$s": _array(np.stack(items), arrays)}
        if first.ndim >= 1 and all(
            isinstance(x, np.ndarray) and x.shape[1:] == first.shape[1:] and x.dtype == first.dtype
            for x in items
        ):  # e.g. the paving's decided boxes, one array per batch
            sizes = [int(x.shape[0]) for x in items]
            return {"$c": _array(np.concatenate(items), arrays), "n": sizes}
    if isinstance(first, tuple) and all(
        isinstance(x, tuple) and len(x) == len(first) for x in items
    ):
        return {"$lt": [_encode_list(list(col), arrays) for col in zip(*items, strict=True)]}
    cls = type(first)
    if dataclasses.is_dataclass(first) and all(type(x) is cls for x in items):
        cols = {
            f.name: _encode_list([getattr(x, f.name) for x in items], arrays)
            for f in dataclasses.fields(first)
        }
        return {"$ld": _class_name(cls), "f": cols}
    return [encode(x, arrays) for x in items]


def _class_name(cls: type) -> str:
    name = f"{cls.__module__}:{cls.__qualname__}"
    if not cls.__module__.startswith("certsolve."):
        raise TypeError(f"cannot checkpoint a {cls.__qualname__} (not a certsolve record)")
    return name


def _class_of(name: str) -> type:
    """A dataclass of certsolve named in a checkpoint (nothing else is looked up)."""
    module, _, qual = str(name).partition(":")
    if not module.startswith("certsolve.") or not qual.isidentifier():
        raise CheckpointError(f"checkpoint names an unknown record type {name!r}")
    try:
        cls = getattr(importlib.import_module(module), qual)
    except (ImportError, AttributeError):
        raise CheckpointError(f"checkpoint names an unknown record type {name!r}") from None
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise CheckpointError(f"checkpoint names an unknown record type {name!r}")
    return cls


def decode(data: Any, arrays: list[np.ndarray]) -> Any:
    """The inverse of :func:`encode`."""
    if isinstance(data, list):
        return [decode(x, arrays) for x in data]
    if not isinstance(data, dict):
        return data
    if "$a" in data:
        return arrays[data["$a"]]
    if "$t" in data:
        return tuple(decode(x, arrays) for x in data["$t"])
    if "$m" in data:
        return {k: decode(v, arrays) for k, v in data["$m"].items()}
    if "$d" in data:
        cls = _class_of(data["$d"])
        return cls(**{k: decode(v, arrays) for k, v in data["f"].items()})
    if "$s" in data:
        return list(arrays[data["$s"]])
    if "$c" in data:
        whole = arrays[data["$c"]]
        ends = np.cumsum(data["n"])
        return [whole[e - k : e] for e, k in zip(ends.tolist(), data["n"], strict=True)]
    if "$lt" in data:
        cols = [decode(c, arrays) for c in data["$lt"]]
        return list(zip(*cols, strict=True)) if cols else []
    if "$ld" in data:
        cls = _class_of(data["$ld"])
        fields = {k: decode(v, arrays) for k, v in data["f"].items()}
        rows = zip(*fields.values(), strict=True)
        return [cls(**dict(zip(fields, row, strict=True))) for row in rows]
    raise CheckpointError("checkpoint: unreadable records")


# -- fingerprint -----------------------------------------------------------------------------
def fingerprint(step: Step, lo: np.ndarray | None, hi: np.ndarray | None, key: str = "") -> str:
    """SHA-256 of what defines the search (module docstring), hex."""
    import hashlib  # (OpenSSL: ~5 ms of start-up a solve without checkpoint need not pay)

    h = hashlib.sha256()
    h.update(f"{type(step).__module__}.{type(step).__qualname__}\n".encode())
    describe = getattr(step, "fingerprint", None)
    if callable(describe):
        h.update(str(describe()).encode())
    for a in (lo, hi):
        if a is not None:
            a = np.ascontiguousarray(np.atleast_2d(a), dtype=np.float64)
            h.update(repr(a.shape).encode())
            h.update(a.tobytes())
    h.update(b"\nkey:" + str(key).encode())
    return h.hexdigest()


# -- the checkpoint object -----------------------------------------------------------------------
class Checkpoint:
    """Where a search saves itself and what it resumes from.

    ``save(data)`` stores the latest snapshot (bytes); ``load()`` returns the stored one,
    or ``None``.  ``interval``: seconds between two writes while the search runs.
    ``key``: the caller's description of settings the step does not know (part of the
    fingerprint).  ``strict=False``: a stored snapshot that does not fit is ignored (the
    search starts afresh) instead of raising :class:`CheckpointError`.

    After a run: ``writes``, ``write_time`` (seconds spent writing), ``size`` (bytes of the
    last snapshot), ``resumed_from`` (boxes processed when it was restored, or None) and
    ``error`` (why the last failed write was skipped, or None).
    """

    def __init__(
        self,
        save: Callable[[bytes], Any],
        load: Callable[[], bytes | None] = lambda: None,
        *,
        interval: float = 30.0,
        key: str = "",
        strict: bool = True,
    ):
        if not interval >= 0:
            raise ValueError("checkpoint interval must be >= 0 (seconds)")
        self._save = save
        self._load = load
        self.interval = float(interval)
        self.key = key
        self.strict = strict
        self.fingerprint: str | None = None
        self.writes = 0
        self.write_time = 0.0
        self.size = 0
        self.resumed_from: int | None = None
        self.ignored: str | None = None  # why a stored snapshot was not used (strict=False)
        self.error: str | None = None  # why the last write failed (it was skipped)
        self._last = time.monotonic()

    @classmethod
    def file(cls, path: str | os.PathLike, *, interval: float = 30.0, key: str = "") -> Checkpoint:
        """A checkpoint in the file ``path``: resumed from if it exists, replaced atomically."""
        p = Path(path)

        def load() -> bytes | None:
            try:
                return p.read_bytes()
            except FileNotFoundError:
                return None

        return cls(lambda data: write_atomic(p, data), load, interval=interval, key=key)

    # -- the driver's side ---------------------------------------------------------------------
    def begin(self, step: Step, lo, hi) -> tuple[Any, SearchStats] | None:
        """Fingerprint the search; the restored ``(state, counters)`` if a snapshot of the
        same search is stored, else ``None``."""
        self.fingerprint = fingerprint(step, lo, hi, self.key)
        self._last = time.monotonic()
        data = self._load()
        if data is None:
            return None
        try:
            return self.restore(step, data)
        except CheckpointError as exc:
            if self.strict:
                raise
            self.ignored = str(exc)
            return None

    def tick(self, search: RunningSearch) -> None:
        """Write if ``interval`` seconds passed since the last write."""
        if time.monotonic() - self._last >= self.interval:
            self.write(search)

    def write(self, search: RunningSearch) -> None:
        """Save a snapshot now.  A snapshot that cannot be built or stored (out of memory,
        disk full) is skipped -- the search goes on, the previous one stays -- and
        :attr:`error` says why."""
        self._write(lambda: self.snapshot(search))

    def _write(self, build: Callable[[], bytes]) -> None:
        t0 = time.perf_counter()
        try:
            data = build()
            self._save(data)
        except (OSError, MemoryError) as exc:
            self.error = f"{type(exc).__name__}: {exc}"
            self._last = time.monotonic()
            return
        self._last = time.monotonic()
        self.writes += 1
        self.size = len(data)
        self.write_time += time.perf_counter() - t0

    # -- snapshot and restore ------------------------------------------------------------------
    def snapshot(self, search: RunningSearch) -> bytes:
        """The search as bytes (module docstring)."""
        lo, hi = search.pending_boxes()
        records = {
            "found": search.step.found(search.state),
            "lo": lo,
            "hi": hi,
            "hints": search.pending_hints(),
            "stats": search.counters().to_dict(),
        }
        return pack(self.fingerprint, type(search.step).__qualname__, records)

    def restore(self, step: Step, data: bytes) -> tuple[Any, SearchStats]:
        """``(state, counters)`` from a snapshot of this search (:meth:`snapshot`)."""
        records = unpack(data, self.fingerprint)
        state = step.start()
        step.merge(state, records["found"])
        state.stack.push(records["lo"], records["hi"], records.get("hints"))
        names = {f.name for f in dataclasses.fields(SearchStats)}
        stats = SearchStats(**{k: v for k, v in records["stats"].items() if k in names})
        self.resumed_from = stats.boxes
        stats.resumed += 1
        stats.resumed_boxes = stats.boxes
        return state, stats


def pack(fingerprint: str | None, what: str, records: Any) -> bytes:
    """``records`` (see :func:`encode`) as an ``.npz`` archive (module docstring)."""
    arrays: list[np.ndarray] = []
    meta = {
        "format": FORMAT,
        "fingerprint": fingerprint,
        "what": what,
        "records": encode(records, arrays),
        "saved_at": time.time(),
    }
    buf = io.BytesIO()
    text = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    named: dict[str, Any] = {f"a{i}": a for i, a in enumerate(arrays)}
    np.savez(buf, meta=text, **named)
    return buf.getvalue()


def unpack(data: bytes, fingerprint: str | None) -> Any:
    """The records of an archive written by :func:`pack` for the same ``fingerprint``."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            meta = json.loads(z["meta"].tobytes().decode())
            arrays = [z[f"a{i}"] for i in range(sum(k.startswith("a") for k in z.files))]
    except (OSError, ValueError, KeyError, EOFError) as exc:
        raise CheckpointError(f"checkpoint unreadable: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise CheckpointError("checkpoint format not supported")
    if meta.get("fingerprint") != fingerprint:
        raise CheckpointError(
            f"the checkpoint is of another search ({meta.get('what')}: another problem "
            "or other settings); remove it or choose another file to start afresh"
        )
    return decode(meta["records"], arrays)


def write_atomic(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data``: a temporary file next to it, flushed to disk, renamed."""
    import tempfile

    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
