"""Service settings: where jobs live, how many workers, per-job defaults and ceilings."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

__all__ = ["ServiceSettings", "default_workers"]


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
    sync_concurrency: int = 2  # simultaneous quick synchronous calls (/v1/ik, ...)

    # -- timing ---------------------------------------------------------------------------------
    poll_interval: float = 0.25  # idle workers look for queued jobs this often (and on wake)
    progress_interval: float = 0.2  # running jobs report progress / read the cancel flag
    cancel_grace: float = 1.5  # a cancelled job still running after this is killed
    kill_grace: float = 5.0  # a job running past its time limit by this much is killed
    supervise_interval: float = 0.2

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

    @property
    def db_path(self) -> Path:
        return self.data_dir / "jobs.sqlite3"

    @property
    def lock_path(self) -> Path:
        return self.data_dir / "service.lock"

    def with_(self, **changes) -> ServiceSettings:
        """A copy with some fields changed (``None`` values are ignored)."""
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    @classmethod
    def from_env(cls, environ=None, **overrides) -> ServiceSettings:
        """Settings from ``CERTSOLVE_DATA_DIR``, ``CERTSOLVE_WORKERS``, ``CERTSOLVE_TEST_KINDS``
        (for ``uvicorn certsolve.api.app:create_app --factory``), then ``overrides``."""
        env = os.environ if environ is None else environ
        values: dict = {}
        if env.get("CERTSOLVE_DATA_DIR"):
            values["data_dir"] = Path(env["CERTSOLVE_DATA_DIR"])
        if env.get("CERTSOLVE_WORKERS"):
            values["workers"] = int(env["CERTSOLVE_WORKERS"])
        if env.get("CERTSOLVE_TEST_KINDS", "").lower() in ("1", "true", "yes"):
            values["enable_test_kinds"] = True
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)
