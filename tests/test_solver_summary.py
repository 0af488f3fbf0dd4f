"""Bounded answers: undecided and pending boxes listed as hulls with counts, never lost."""

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.expr.minibex import load_minibex, parse_minibex
from certsolve.solver import Limits, Solver, run_search, solve
from certsolve.solver.summary import chunk_hulls, merge_touching, summarize


@st.composite
def grid_boxes(draw):
    """Boxes on an integer grid (many touch exactly along faces or corners)."""
    n = draw(st.integers(1, 3))
    N = draw(st.integers(1, 60))
    seed = draw(st.integers(0, 2**31))
    rng = np.random.default_rng(seed)
    lo = rng.integers(0, 12, size=(N, n)).astype(float)
    hi = lo + rng.integers(0, 3, size=(N, n))
    return lo, hi


@settings(max_examples=200, deadline=None)
@given(grid_boxes())
def test_merge_only_touching_boxes_and_keeps_every_box(boxes):
    lo, hi = boxes
    mlo, mhi, cnt = merge_touching(lo, hi)
    assert cnt.sum() == lo.shape[0] and np.all(cnt >= 1)
    assert np.all(cnt[:-1] >= cnt[1:])  # largest groups first
    for k in range(lo.shape[0]):  # every box lies in a hull
        assert np.any(np.all((mlo <= lo[k]) & (hi[k] <= mhi), axis=1))
    # what is merged touches: no hull of a single box, no box outside every hull
    assert len(cnt) <= lo.shape[0]


@settings(max_examples=50, deadline=None)
@given(st.integers(1, 8), st.integers(0, 2**31))
def test_separated_clusters_stay_apart(k, seed):
    """Clusters of touching boxes far from each other give one hull each."""
    rng = np.random.default_rng(seed)
    los, his = [], []
    for c in range(k):
        centre = np.array([100.0 * c, 50.0 * (c % 2)])
        steps = np.cumsum(rng.uniform(0, 1, size=(20, 2)), axis=0)  # a touching chain
        lo = centre + steps
        los.append(lo)
        his.append(lo + 1.0)
    lo, hi = np.concatenate(los), np.concatenate(his)
    order = rng.permutation(lo.shape[0])
    mlo, mhi, cnt = merge_touching(lo[order], hi[order])
    assert len(cnt) == k and np.all(cnt == 20)


def test_merge_finds_chains_and_clusters():
    # a chain of 1000 touching unit boxes, and 50 isolated ones far away
    lo = np.c_[np.arange(1000.0), np.zeros(1000)]
    hi = lo + 1.0
    iso = np.c_[np.full(50, 5000.0), np.arange(50) * 10.0]
    mlo, mhi, cnt = merge_touching(np.r_[lo, iso], np.r_[hi, iso + 1.0])
    assert cnt[0] == 1000 and len(cnt) == 51
    assert mlo[0].tolist() == [0.0, 0.0] and mhi[0].tolist() == [1000.0, 1.0]


@given(st.integers(1, 5000), st.integers(1, 50), st.integers(1, 4))
def test_chunk_hulls_hold_their_boxes(N, cap, n):
    rng = np.random.default_rng(N)
    lo = rng.normal(size=(N, n))
    hi = lo + rng.uniform(0, 1, size=(N, n))
    clo, chi, cnt = chunk_hulls(lo, hi, cap)
    assert len(cnt) == min(N, cap) and cnt.sum() == N
    owner = np.repeat(np.arange(len(cnt)), cnt)  # chunks are runs of consecutive boxes
    assert np.all(clo[owner] <= lo) and np.all(hi <= chi[owner])


def test_summarize_counts_and_reasons():
    und = [(np.array([0.0]), np.array([1.0]), "eps"), (np.array([1.0]), np.array([2.0]), "eps")]
    und += [(np.array([1.5]), np.array([1.6]), "boundary")]  # touches, but another reason
    und += [(np.array([10.0 + k]), np.array([10.5 + k]), "eps") for k in range(5)]
    p = np.zeros((0, 1))
    s = summarize(und, p, p, max_undecided=3)
    assert s.undecided_total == 8
    listed = [(h[0][0], h[1][0], h[2], h[3]) for h in s.undecided]
    assert listed[0] == (0.0, 2.0, "eps", 2)
    assert len(listed) == 3 and s.undecided_dropped == 8 - sum(h[3] for h in s.undecided)
    assert s.pending_total == 0 and s.pending_lo.shape == (0, 1)
    s = summarize(und, p, p, max_undecided=0)
    assert s.undecided == [] and s.undecided_dropped == 8


def test_the_cap_makes_a_result_incomplete_and_says_so():
    """tan(x) = 1 on the real line: infinitely many solutions and undecided boxes far out."""
    system = parse_minibex("Variables x; Constraints tan(x) = 1; end")
    r = solve(system, eps=1e-8, max_boxes=20000, max_undecided=5)
    assert r.status == "max_boxes"
    assert len(r.undecided) <= 5
    d = r.to_dict()
    assert d["undecided_total"] == sum(u["boxes"] for u in d["undecided"]) + d["undecided_dropped"]
    r_all = solve(system, eps=1e-8, max_boxes=20000, max_undecided=10**9)
    assert r_all.undecided_dropped == 0
    assert r_all.undecided_total == r.undecided_total


def test_pending_hulls_cover_the_stack():
    system = parse_minibex(
        "Variables x in [-1e6, 1e6]; y in [-1e6, 1e6]; Constraints x - y = 0; 2*x - 2*y = 0; end"
    )
    solver = Solver.default(system, eps=1e-12, max_pending=7, max_undecided=5)
    dom = system.domain
    run = run_search(solver, dom[:, 0][None], dom[:, 1][None], limits=Limits(max_boxes=20000))
    raw_lo, raw_hi = run.state.stack.snapshot()
    r = solver.result(run)
    assert r.status == "max_boxes" and r.pending_total == raw_lo.shape[0] > 7
    assert r.pending_lo.shape == (7, 2) and r.pending_boxes.sum() == r.pending_total
    inside = np.all(
        (r.pending_lo[None] <= raw_lo[:, None]) & (raw_hi[:, None] <= r.pending_hi[None]), axis=2
    )
    assert np.all(inside.any(axis=1))
    d = r.to_dict()
    assert len(d["pending"]) == 7 and d["pending_total"] == r.pending_total
    assert len(json.dumps(d)) < 5000


def test_complete_results_list_everything():
    r = solve(
        parse_minibex("Variables x in [-2, 2]; y in [-2, 2]; Constraints x^2 + y^2 = 1; y = 1; end")
    )
    assert r.status == "complete" and r.undecided_dropped == 0 and r.pending_total == 0
    assert r.undecided_total == sum(u.boxes for u in r.undecided) >= 1
    with pytest.raises(ValueError, match="max_pending"):
        Solver.default(parse_minibex("Variables x; Constraints x = 1; end"), max_pending=0)


def test_a_complete_search_with_unlisted_undecided_boxes_is_truncated():
    """Nothing pending, but the double root's undecided boxes are only counted."""
    system = load_minibex(Path(__file__).parent.parent / "examples/systems/double-root.mbx")
    full = solve(system)
    assert full.status == "complete" and full.undecided_total > 0
    cut = solve(system, max_undecided=0)
    assert cut.status == "truncated" and cut.pending_total == 0
    assert cut.undecided == [] and cut.undecided_dropped == full.undecided_total


@st.composite
def graphs(draw):
    """An undirected graph: ``N`` nodes, random edges (self-loops and repeats included)."""
    N = draw(st.integers(1, 80))
    E = draw(st.integers(0, 3 * N))
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    return rng.integers(0, N, E), rng.integers(0, N, E), N


@settings(max_examples=200, deadline=None)
@given(graphs())
def test_components_are_scipys(graph):
    """The merge's connected components: scipy's count and labels (in the order of each
    component's smallest node), so the hulls are the same as with scipy's."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from certsolve.solver.summary import _components

    i, j, N = graph
    count, labels = _components(i, j, N)
    adjacency = coo_matrix((np.ones(i.size, dtype=np.int8), (i, j)), shape=(N, N))
    want, want_labels = connected_components(adjacency, directed=False)
    assert count == want
    assert np.array_equal(labels, want_labels)


def test_components_of_a_long_path_given_backwards():
    from certsolve.solver.summary import _components

    N = 1000
    count, labels = _components(np.arange(N - 1)[::-1], np.arange(1, N)[::-1], N)
    assert count == 1 and not labels.any()


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 40), st.integers(1, 4), st.integers(0, 2**31), st.booleans())
def test_median_of_columns_is_numpys(rows, cols, seed, odd_values):
    from certsolve.solver.summary import _median_of_columns

    rng = np.random.default_rng(seed)
    a = rng.normal(size=(rows, cols)) * 10.0 ** rng.integers(-300, 300, size=(rows, cols))
    if odd_values:
        a[rng.integers(0, rows), 0] = np.nan
        a[rng.integers(0, rows), -1] = np.inf
    assert np.array_equal(_median_of_columns(a), np.median(a, axis=0), equal_nan=True)


def test_merging_imports_neither_scipy_nor_numpy_ma():
    """A result with touching undecided boxes is summarised with numpy alone: scipy's
    import costs ~0.12 s of CPU, numpy.ma's ~5 ms, a small solve's whole call ~0.1-0.5 s."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from certsolve.solver.summary import merge_touching\n"
        "lo = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])\n"
        "_, _, counts = merge_touching(lo, lo + 1.0)\n"
        "assert counts.tolist() == [2, 1], counts\n"
        "print(sorted(m for m in ('scipy', 'numpy.ma') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[-2] == "[]"
