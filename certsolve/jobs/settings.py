"""Service settings: where jobs live, where they run (local worker processes, or the Dask
cluster of ``scheduler``), per-job defaults and ceilings, who may use the service
(:mod:`.access`), how quick calls are bounded, how long jobs are kept."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

from .access import AccessTable, load_access

__all__ = ["LOOPBACK_HOSTS", "ServiceSettings", "default_workers"]

# the Host names a service without tokens answers by default (against DNS rebinding)
LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "::1")


def default_workers() -> int:
    """One worker per core available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class ServiceSettings:
    """Everything the job service needs; defaults suit a small single-host deployment.

    Per-job limits: a job may ask for its own ``timeout`` / ``max_boxes`` / ``memory_mb``
    (``params`` or ``limits`` of the request); when it does not, the ``default_*`` value
    applies, and asking for more than the ``max_*`` ceiling is refused (422).
    """

    data_dir: Path = field(default_factory=lambda: Path("certsolve-data"))
    workers: int = field(default_factory=default_workers)
    # a Dask scheduler (tcp://host:8786): jobs run on its cluster, not on ``workers``
    scheduler: str | None = None

    # -- per-job limits: defaults and ceilings ------------------------------------------------
    default_timeout: float = 600.0  # seconds of wall time
    max_timeout: float = 24 * 3600.0
    default_max_boxes: int = 50_000_000
    max_max_boxes: int = 2_000_000_000
    default_memory_mb: int = 4096  # address space of the worker while it runs the job
    max_memory_mb: int = 65536
    min_memory_mb: int = 512  # below this a worker cannot even hold its imports
    max_attempts: int = 2  # runs of a job whose worker died before it is failed

    # -- request limits -----------------------------------------------------------------------
    max_body_bytes: int = 16 * 2**20
    max_batch: int = 1000  # jobs per POST /v1/jobs/batch
    max_queued: int = 100_000  # queued jobs before new ones are refused (429)
    max_result_items: int = 20_000  # longer top-level result lists are truncated
    retry_after: int = 5  # seconds, in the Retry-After of a full queue (429)

    # -- access control (None: no tokens, every request allowed; see .access) --------------
    access: AccessTable | None = None
    quota_queued: int = 10_000  # queued jobs per client (its own max_queued overrides)
    quota_running: int | None = None  # running jobs per client (None: as many as workers)
    quota_requests_per_minute: int = 1200  # requests per client and minute
    auth_failure_delay: float = 0.5  # seconds a refused token waits for its 401
    # Host headers served when there are no tokens ("*": any); with tokens, any
    allowed_hosts: tuple[str, ...] = LOOPBACK_HOSTS

    # -- connections (certsolve serve: api.server) ----------------------------------------
    request_timeout: float = 10.0  # seconds to receive a whole request, else closed
    keep_alive_timeout: float = 5.0  # an idle kept-alive connection is closed after this
    max_connections: int = 256  # open connections; past this, 503

    # -- quick synchronous calls (/v1/ik, /v1/isotropic, /v1/fk/track; see .quick) ---------
    quick_workers: int = 2  # processes answering light calls
    quick_heavy_workers: int = 1  # processes answering heavy calls (a separate lane)
    quick_timeout: float = 10.0  # seconds a light call may run before it is stopped
    quick_heavy_timeout: float = 30.0  # seconds a heavy call may run
    quick_memory_mb: int = 1536  # address-space limit of a quick-call process
    quick_wait: float = 2.0  # seconds a call may wait for a free process before a 429
    quick_queue: int = 8  # calls waiting per lane before new ones get a 429 at once

    # -- retention ------------------------------------------------------------------------------
    keep_days: float | None = None  # finished jobs older than this are purged (None: kept)
    housekeeping_interval: float = 600.0  # seconds between purges / WAL checkpoints
    store_check_interval: float = 60.0  # /healthz re-runs the store's quick_check this often

    # -- timing ---------------------------------------------------------------------------------
    poll_interval: float = 0.25  # idle workers look for queued jobs this often (and on wake)
    progress_interval: float = 0.2  # running jobs report progress / read the cancel flag
    cancel_grace: float = 5.0  # a cancelled job still running after this is killed
    kill_grace: float = 5.0  # a job running past its time limit by this much is killed
    # ... unless its worker said it is storing its result: it has this long from then on
    finish_grace: float = 120.0
    memory_stop: float = 0.85  # a job stops (keeping its result) at this share of memory_mb
    supervise_interval: float = 0.2
    checkpoint_interval: float = 30.0  # a running search saves itself this often (s)

    # -- testing --------------------------------------------------------------------------------
    enable_test_kinds: bool = False  # the hidden ``sleep`` kind (tests, benchmarks)

    def __post_init__(self):
        object.__setattr__(self, "data_dir", Path(self.data_dir))
        if self.workers < 0:
            raise ValueError("workers must be >= 0")
        if self.max_attempts < 1:
            raise ValueError("max_attempts must be >= 1")
        if not 0 < self.default_timeout <= self.max_timeout:
            raise ValueError("need 0 < default_timeout <= max_timeout")
        if not 0 < self.default_max_boxes <= self.max_max_boxes:
            raise ValueError("need 0 < default_max_boxes <= max_max_boxes")
        if not 0 < self.min_memory_mb <= self.default_memory_mb <= self.max_memory_mb:
            raise ValueError("need 0 < min_memory_mb <= default_memory_mb <= max_memory_mb")
        if self.keep_days is not None and not self.keep_days > 0:
            raise ValueError("keep_days must be > 0")
        if self.quick_workers < 1 or self.quick_heavy_workers < 1:
            raise ValueError("quick_workers and quick_heavy_workers must be >= 1")
        if not 0 < self.memory_stop <= 1:
            raise ValueError("memory_stop must be in (0, 1]")
        if self.scheduler is not None and (
            not self.scheduler.strip() or any(c.isspace() for c in self.scheduler.strip())
        ):
            raise ValueError("scheduler: expected a scheduler address tcp://HOST:PORT")
        object.__setattr__(self, "allowed_hosts", tuple(h.lower() for h in self.allowed_hosts))
        if not self.allowed_hosts:
            raise ValueError("allowed_hosts: give at least one host name (or '*')")
        if not (self.request_timeout > 0 and self.keep_alive_timeout > 0):
            raise ValueError("request_timeout and keep_alive_timeout must be > 0 (seconds)")
        if self.max_connections < 1:
            raise ValueError("max_connections must be >= 1")
        if not self.auth_failure_delay >= 0:
            raise ValueError("auth_failure_delay must be >= 0 (seconds)")
        if not self.checkpoint_interval >= 0:
            raise ValueError("checkpoint_interval must be >= 0 (seconds)")

    @property
    def db_path(self) -> Path:
        return self.data_dir / "jobs.sqlite3"

    @property
    def lock_path(self) -> Path:
        return self.data_dir / "service.lock"

    def with_(self, **changes) -> ServiceSettings:
        """A copy with some fields changed (``None`` values are ignored)."""
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    @property
    def for_workers(self) -> ServiceSettings:
        """The settings worker processes get: without the token table."""
        return replace(self, access=None)

    @classmethod
    def from_env(cls, environ=None, **overrides) -> ServiceSettings:
        """Settings from ``CERTSOLVE_DATA_DIR``, ``CERTSOLVE_WORKERS``,
        ``CERTSOLVE_SCHEDULER`` (jobs on that Dask cluster), ``CERTSOLVE_TOKENS`` (the token
        table as JSON), ``CERTSOLVE_KEEP_DAYS``, ``CERTSOLVE_ALLOWED_HOSTS`` (Host names
        answered besides the loopback names, comma-separated), ``CERTSOLVE_TEST_KINDS`` (for
        ``uvicorn certsolve.api.app:create_app --factory``), then ``overrides``."""
        env = os.environ if environ is None else environ
        values: dict = {}
        if env.get("CERTSOLVE_DATA_DIR"):
            values["data_dir"] = Path(env["CERTSOLVE_DATA_DIR"])
        if env.get("CERTSOLVE_WORKERS"):
            values["workers"] = int(env["CERTSOLVE_WORKERS"])
        if env.get("CERTSOLVE_SCHEDULER", "").strip():
            values["scheduler"] = env["CERTSOLVE_SCHEDULER"].strip()
        if env.get("CERTSOLVE_KEEP_DAYS"):
            values["keep_days"] = float(env["CERTSOLVE_KEEP_DAYS"])
        if "access" not in overrides or overrides["access"] is None:
            values["access"] = load_access(None, env)
        if env.get("CERTSOLVE_ALLOWED_HOSTS", "").strip():
            hosts = env["CERTSOLVE_ALLOWED_HOSTS"].split(",")
            values["allowed_hosts"] = (*LOOPBACK_HOSTS, *(h.strip() for h in hosts if h.strip()))
        if env.get("CERTSOLVE_TEST_KINDS", "").lower() in ("1", "true", "yes"):
            values["enable_test_kinds"] = True
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)
