"""How benchmarks/ibex_bench.py counts ibexsolve's solutions: the COV file it writes (the
layout ``ibexsolve --format`` gives), the boxes ``--trace`` prints, and the de-duplication of
one solution reported in adjacent boxes (overlapping or within 1e-6)."""

import importlib.util
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "ibex_bench.py"
_spec = importlib.util.spec_from_file_location("ibex_bench", SCRIPT)
assert _spec is not None and _spec.loader is not None
bench = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("ibex_bench", bench)  # dataclasses look their module up there
_spec.loader.exec_module(bench)


def cov_file(boxes, solutions, m, status, names, params=None):
    """A CovSolverData file: ``boxes`` (N, n, 2), the CovList indices of the ``solutions``."""
    n = len(names)
    u = lambda *k: struct.pack(f"<{len(k)}I", *k)  # noqa: E731
    out = b"IBEX COVERING FILE \0" + u(5) + u(0, 0, 0, 0, 0, 0) + u(1, 1, 1, 1, 1, 2) + u(n)
    out += u(len(boxes)) + np.asarray(boxes, dtype="<f8").tobytes()
    out += u(len(solutions), *solutions)  # inner boxes
    out += u(0) + u(len(solutions), *solutions)  # boundary type, boundary boxes
    out += u(m, 0, 0)
    if m > 0:
        out += u(len(solutions))
        for i in solutions:
            out += u(i) + (u(*params) if m < n else b"") + np.asarray(boxes[i], "<f8").tobytes()
    out += u(len(solutions))
    for i in solutions:
        out += u(i) + (u(*params) if 0 < m < n else b"")
    out += b"".join(name.encode() + b"\0" for name in names) + u(status)
    return out + u(3)  # what follows the status (its count of cells...) is not read


BOXES = [
    [[0.0, 0.1], [1.0, 1.1]],
    [[0.5, 0.5], [2.0, 2.0]],  # a solution
    [[-1.0, 0.0], [0.0, 1.0]],
    [[0.7, 0.7], [-2.0, -2.0]],  # a solution
]


@pytest.mark.parametrize("m, params", [(2, None), (1, [1])], ids=["square", "manifold"])
def test_read_cov_gives_the_solution_boxes_and_the_status(m, params):
    data = cov_file(BOXES, [1, 3], m=m, status=3, names=["x", "y"], params=params)
    sols, status, square = bench.read_cov(data)
    assert status == 3 and square == (m == 2)
    assert sols.tolist() == [BOXES[1], BOXES[3]]
    assert bench.IBEX_STATUS[status] == "timeout"


def test_read_cov_of_no_solution():
    sols, status, _ = bench.read_cov(cov_file(BOXES, [], m=2, status=1, names=["x", "y"]))
    assert len(sols) == 0 and bench.IBEX_STATUS[status] == "complete"


def test_read_cov_of_inequalities_only_gives_the_inner_boxes():
    data = cov_file(BOXES, [0, 2], m=0, status=0, names=["x", "y"])
    sols, _, square = bench.read_cov(data)
    assert sols.tolist() == [BOXES[0], BOXES[2]] and not square


def test_distinct_merges_overlapping_and_near_boxes_transitively():
    a = [[1.0, 1.0], [2.0, 2.0]]
    near = [[1.0 + 5e-7, 1.0 + 6e-7], [2.0, 2.0]]  # 5e-7 away: the same solution
    chain = [[1.0 + 1.4e-6, 1.0 + 1.5e-6], [2.0, 2.0]]  # 8e-7 from `near`, 1.4e-6 from `a`
    far = [[1.0 + 1e-5, 1.0 + 1e-5], [2.0, 2.0]]
    other_y = [[1.0, 1.0], [2.1, 2.1]]  # the same x, another y: another solution
    boxes = np.array([a, far, near, other_y, chain, a])
    assert bench.distinct(boxes) == 3
    assert bench.distinct(boxes[[0, 1]]) == 2
    assert bench.distinct(boxes[[0, 4]]) == 2  # 1.4e-6 apart without `near` between them
    assert bench.distinct(np.zeros((0, 2, 2))) == 0


def test_traced_solutions_reads_the_boxes_ibexsolve_prints():
    text = (
        "running............\n\n"
        " [solution] ([4, 4] ; [-3.13232e-14, 2.50391e-14] ; [10, 10])\n"
        " [unknown] ([0, 1] ; [0, 1] ; [0, 1])\n"
        " [solution] ([5.53641, 5.53641] ; [-4.87294, -4.87294] ; [8.94648, 8.94648])\n"
    )
    boxes = bench.traced_solutions(text)
    assert boxes.shape == (2, 3, 2)
    assert boxes[0].tolist() == [[4, 4], [-3.13232e-14, 2.50391e-14], [10, 10]]
    assert boxes[1, 1].tolist() == [-4.87294, -4.87294]
    assert bench.traced_solutions("running...\n").shape[0] == 0


def test_the_table_summarises_parses_completions_ratios_and_disagreements():
    Run, Row, Parsed = bench.Run, bench.Row, bench.Parsed
    args = bench.argparse.Namespace(timeout=5.0, eps=1e-8, runs=3, no_bytecode=False)
    rows = [
        Row(path="a.bch", parsed=Parsed(n=2, m=2), runs={
            "certsolve": [Run(status="complete", wall=w, solutions=2) for w in (1.0, 3.0, 2.0)],
            "ibexsolve": [Run(status="complete", wall=1.0, solutions=2)]}),
        Row(path="b.bch", parsed=Parsed(n=2, m=2), runs={
            "certsolve": [Run(status="complete", wall=4.0, solutions=1)],
            "ibexsolve": [Run(status="complete", wall=1.0, solutions=2, raw_solutions=3)]}),
        Row(path="c.bch", parsed=Parsed(n=3, m=2), runs={
            "certsolve": [Run(status="refused", wall=0.5, message="the system is not square")],
            "ibexsolve": [Run(status="timeout", wall=6.0, solutions=4, undecided=-1, boxes=-1,
                              message=bench.WALL_STOP)]}),
        Row(path="d.bch", parsed=Parsed(error="line 1, column 1: unexpected 'x'")),
    ]  # fmt: skip
    page = bench.markdown(rows, args, "python benchmarks/ibex_bench.py DIR")
    assert "**3 of 4 files parse**: 2 square systems, and 1 with" in page
    assert "**certsolve** completes 2 of the 3 files it ran" in page
    assert "median **3.0x** (min 2.00x, max 4x)" in page  # a: 2 s (1, 3, 2) over 1; b: 4 over 1
    assert "agree on 1 of them: not on `b.bch`" in page
    assert "| `a.bch` | 2 | 2 | complete | 2 | 0 | 0 | 2.00 (3) |" in page
    assert "| complete | 2 (3) |" in page  # b: ibexsolve's raw count beside the distinct one
    assert "refused: the system is not square" in page and "| timeout | 4 | ? | ? |" in page
    assert "parse error: line 1, column 1: unexpected 'x'" in page


def test_both_complete_keeps_the_files_both_finish_and_ibex_below_the_small_ones(tmp_path):
    """``--both-complete DIR``: the files whose last stored run is complete for both solvers;
    ``--ibex-below S``: of those, the ones where ibexsolve's median wall time is below S."""
    args = bench.argparse.Namespace(timeout=10.0, eps=1e-8, both_complete=tmp_path)

    def runs(status, *walls):
        return [{"status": status, "wall": w} for w in walls]

    stores = {
        "certsolve": {"a": runs("complete", 0.3), "b": runs("complete", 2.0),
                      "c": runs("timeout", 10.0), "d": runs("complete", 0.2)},
        "ibexsolve": {"a": runs("complete", 0.01, 0.5, 0.02), "b": runs("complete", 0.4),
                      "c": runs("complete", 0.01), "d": runs("timeout", 10.0)},
    }  # fmt: skip
    where = bench.argparse.Namespace(**{**vars(args), "results": tmp_path})
    for solver, store in stores.items():
        bench.save_store(bench.store_path(where, solver), store)
    assert bench.both_complete(args) == {"a", "b"}
    args.ibex_below = 0.1
    assert bench.both_complete(args) == {"a"}  # a: median 0.02 s; b: 0.4 s
