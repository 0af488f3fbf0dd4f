import logging
import os

import pytest
from hypothesis import settings

settings.register_profile("ci", max_examples=150, deadline=None)
settings.register_profile("thorough", max_examples=2000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="module")
def dask_client():
    """A client of a ``distributed.LocalCluster``, one per test module: 2 worker processes
    of one thread and 1 GiB each, ``allowed-failures = 0`` (a task on a killed worker fails
    at once: the caller, not the scheduler, must run it again)."""
    distributed = pytest.importorskip("distributed")
    import dask

    config = {
        "distributed.scheduler.allowed-failures": 0,
        # Dask's MALLOC_TRIM_THRESHOLD_=65536 doubles the time of numpy-heavy batches
        "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
        # the cluster hard-closes the nanny of a worker lost 15 s earlier (by default) if no
        # worker of that name is registered at that instant -- even one its nanny restarted
        # since and that died again just then: a test that kills workers 15 s after another
        # did lost a nanny for good (a slow machine, 2026-11-29).  The nannies restart them.
        "distributed.deploy.lost-worker-timeout": "1h",
    }
    # set while the cluster lives: it reads them again as workers are lost and restarted
    with dask.config.set(config):
        cluster = distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            memory_limit="1GiB",
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        )
        client = distributed.Client(cluster, set_as_default=False)
        yield client
        client.close()
        cluster.close()
