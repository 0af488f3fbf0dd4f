"""Property-based run of the whole OpenAPI schema (schemathesis): no 5xx, ever.

Every operation gets schema-conforming (positive) and non-conforming (negative) requests;
the only 5xx allowed is 501 from a quick endpoint whose library function is not in this
build.  The app runs in-process without workers (queued jobs just stay queued).  The schema
is loaded inside the test, so collecting this module costs nothing when it is deselected.
"""

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis.errors import Unsatisfiable

from certsolve.api.app import create_app
from certsolve.jobs import ServiceSettings

N_EXAMPLES = 15


def _operations(tmp_path):
    schemathesis = pytest.importorskip("schemathesis")
    from schemathesis.generation import GenerationMode

    app = create_app(ServiceSettings(data_dir=tmp_path, workers=0, max_queued=1_000_000))
    schema = schemathesis.openapi.from_asgi("/openapi.json", app)
    ops = [r.ok() for r in schema.get_all_operations()]
    assert len(ops) >= 10
    return ops, (GenerationMode.POSITIVE, GenerationMode.NEGATIVE)


def _check(op, mode):
    @settings(max_examples=N_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
    @given(case=op.as_strategy(generation_mode=mode))
    def run(case):
        response = case.call()
        assert response.status_code < 500 or response.status_code == 501, (
            f"{case.method} {case.formatted_path} -> {response.status_code}: {response.text[:300]}"
        )

    try:
        run()
    except Unsatisfiable:  # nothing to make invalid (an operation without inputs)
        assert mode.name == "NEGATIVE"


@pytest.mark.slow
def test_no_server_errors_full(tmp_path):
    ops, modes = _operations(tmp_path)
    for op in ops:
        for mode in modes:
            _check(op, mode)


def test_no_server_errors_job_submission(tmp_path):
    """The default run: the two job-submission operations, positive and negative."""
    ops, modes = _operations(tmp_path)
    chosen = [op for op in ops if op.method.upper() == "POST" and op.path.startswith("/v1/jobs")]
    assert len(chosen) == 2
    for op in chosen:
        for mode in modes:
            _check(op, mode)
