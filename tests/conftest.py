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
    }
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
