"""The solver on standard test systems, against independent reference solutions.

The systems are the Minibex files in ``examples/systems/``; their real solutions inside the
domain were computed without certsolve (exact Groebner bases + real root isolation, or
rigorous interval arguments) by ``tests/reference/compute_reference.py`` and stored, to 40
digits, in ``tests/reference/reference.json``.

For every system: the search is complete, the certified solutions are exactly the reference
ones (each reference point lies in exactly one solution box, each box holds exactly one
reference point; the comparison is exact in binary, with a slack of a few ulps), and nothing
is undecided -- except for the singular root of ``double-root``, which must be undecided and
never certified.  Systems that take more than about 10 s are marked ``slow``.
"""

from __future__ import annotations

import json
import math
import re
from functools import cache
from pathlib import Path

import mpmath
import numpy as np
import pytest

from certsolve.expr.minibex import MinibexError, load_minibex, parse_minibex
from certsolve.solver import solve

ROOT = Path(__file__).resolve().parent.parent
SYSTEMS = ROOT / "examples" / "systems"
REFERENCE = json.loads((Path(__file__).parent / "reference" / "reference.json").read_text())

ULPS = 4  # slack when comparing a reference point with the float bounds of a box
DPS = 50  # reference points are read at this precision (they carry 40 digits)


def ref_points(name: str) -> list[list[mpmath.mpf]]:
    with mpmath.workdps(DPS):
        return [[mpmath.mpf(v) for v in s] for s in REFERENCE[name]["solutions"]]


def in_box(point, lo, hi, ulps: int = ULPS) -> bool:
    """``point`` (mpf) inside the float box ``[lo, hi]`` widened by ``ulps`` ulps per side."""
    for p, a, b in zip(point, lo, hi, strict=True):
        a, b = float(a), float(b)
        a -= ulps * math.ulp(a)
        b += ulps * math.ulp(b)
        if not (mpmath.mpf(a) <= p <= mpmath.mpf(b)):  # exact: mpf(float) is exact
            return False
    return True


@cache
def solved(name: str, eps: float, timeout: float):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    return system, solve(system, eps=eps, timeout=timeout)


def describe(result) -> str:
    st = result.stats
    return (
        f"{result.status}: {len(result.solutions)} solutions, {len(result.undecided)} undecided, "
        f"{len(result.pending)} pending, {st.boxes} boxes, {st.time:.1f} s, "
        f"stopped by {st.stopped_by}"
    )


def check_against_reference(name: str, system, result) -> None:
    ref = ref_points(name)
    assert result.status == "complete", describe(result)
    assert not result.undecided, describe(result) + f"\nundecided: {result.undecided[:5]}"
    assert len(result.solutions) == REFERENCE[name]["count"], describe(result)
    for k, p in enumerate(ref):
        hits = [s for s in result.solutions if in_box(p, s.lo, s.hi)]
        assert len(hits) == 1, f"reference solution {k} {p} is in {len(hits)} solution boxes"
    for s in result.solutions:
        assert s.certificate == "unique"
        hits = [p for p in ref if in_box(p, s.lo, s.hi)]
        assert len(hits) == 1, f"solution box {s.box} holds {len(hits)} reference solutions"
        # the unicity box contains the existence box, which is inside the domain
        assert np.all(s.ulo <= s.lo) and np.all(s.hi <= s.uhi)
        assert np.all(system.domain[:, 0] <= s.lo) and np.all(s.hi <= system.domain[:, 1])


# name, eps, timeout (s), slow?  (slow: more than about 10 s on one core)
CASES = [
    ("circle-line", 1e-8, 60, False),
    ("brown-5", 1e-8, 300, False),
    ("brown-5-vector", 1e-8, 300, False),  # vector, loop and dot product (Minibex syntax)
    ("discrete-boundary-10", 1e-8, 120, False),  # loops
    ("troesch-10", 1e-8, 120, False),  # loops, sinh
    ("broyden-banded-10", 1e-8, 120, False),
    ("eco-6", 1e-8, 300, False),
    ("eco-7", 1e-8, 900, False),
    ("katsura-5", 1e-8, 900, False),
    ("katsura-6", 1e-8, 3600, False),
    ("kin2-6r", 1e-8, 900, False),
    ("trig-exp", 1e-8, 60, False),
]


def _params(cases):
    for name, eps, timeout, slow in cases:
        marks = [pytest.mark.slow] if slow else []
        yield pytest.param(name, eps, timeout, marks=marks, id=name)


@pytest.mark.parametrize(("name", "eps", "timeout"), list(_params(CASES)))
def test_system_matches_reference(name, eps, timeout):
    system, result = solved(name, eps, timeout)
    check_against_reference(name, system, result)


def test_double_root_is_undecided_never_certified():
    _, result = solved("double-root", 1e-8, 60)
    assert result.status == "complete", describe(result)
    assert result.solutions == []
    assert len(result.undecided) >= 1
    (root,) = ref_points("double-root")  # (0, 1), multiplicity 2
    assert any(in_box(root, u.lo, u.hi) for u in result.undecided)
    # every undecided box is a tiny box at the singular root, nowhere else
    for u in result.undecided:
        assert u.reason == "eps"
        assert np.all(u.hi - u.lo <= 1e-6)
        assert np.all(np.abs(0.5 * (u.lo + u.hi) - [0.0, 1.0]) <= 1e-6)


def test_infeasible_is_complete_and_empty():
    _, result = solved("infeasible", 1e-8, 60)
    assert REFERENCE["infeasible"]["count"] == 0
    assert result.status == "complete", describe(result)
    assert result.solutions == [] and result.undecided == [] and result.pending == []


def test_solution_on_the_domain_boundary_is_not_certified():
    """Solutions exactly on the boundary cannot be proven inside: they are undecided.

    (1, 1) is the only solution of x^2 + y^2 = 2, x = y in [0, 1]^2, at a corner.
    """
    system = parse_minibex(
        "Variables\n  x in [0, 1];\n  y in [0, 1];\n"
        "Constraints\n  x^2 + y^2 = 2;\n  x - y = 0;\nend\n"
    )
    result = solve(system, eps=1e-8, timeout=60)
    assert result.status == "complete", describe(result)
    assert result.solutions == []
    assert any(in_box([1, 1], u.lo, u.hi) for u in result.undecided)


@pytest.mark.slow
def test_katsura_5_on_the_usual_domain_leaves_the_boundary_solution_undecided():
    """In [-1, 1]^6, katsura-5's solution (1, 0, ..., 0) is on the boundary.

    The 15 other real solutions are certified; that one is undecided (never certified, never
    lost).
    """
    text = (SYSTEMS / "katsura-5.mbx").read_text().replace("in [-2, 2]", "in [-1, 1]")
    result = solve(parse_minibex(text), eps=1e-8, timeout=900)
    assert result.status == "complete", describe(result)
    ref = ref_points("katsura-5")
    corner = [1, 0, 0, 0, 0, 0]
    assert corner in [[float(v) for v in p] for p in ref]
    assert len(result.solutions) == len(ref) - 1
    assert result.undecided and all(in_box(corner, u.lo, u.hi) for u in result.undecided)
    for p in ref:
        if [float(v) for v in p] != corner:
            assert sum(in_box(p, s.lo, s.hi) for s in result.solutions) == 1


# -- the files and the reference agree ------------------------------------------------------------
def system_files():
    return sorted(p.stem for p in SYSTEMS.glob("*.mbx"))


def test_every_system_file_has_a_reference():
    assert set(system_files()) <= set(REFERENCE)
    tested = {c[0] for c in CASES} | {"double-root", "infeasible"}
    assert set(system_files()) <= tested


@pytest.mark.parametrize("name", system_files())
def test_file_matches_reference_header(name):
    """Variables and domain of the file are those of the reference; the comment's count too."""
    text = (SYSTEMS / f"{name}.mbx").read_text()
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    ref = REFERENCE[name]
    assert list(system.variables) == ref["variables"]
    for (lo, hi), (rlo, rhi) in zip(system.domain, ref["domain"], strict=True):
        # the parser rounds decimal bounds outward by at most one ulp
        assert lo <= float(rlo) and float(rlo) - lo <= math.ulp(lo)
        assert hi >= float(rhi) and hi - float(rhi) <= math.ulp(hi)
    m = re.search(r"Expected: (\d+) real solution", text)
    assert m, "the header must state the expected number of real solutions"
    assert int(m.group(1)) == ref["count"] == len(ref["solutions"])


@pytest.mark.parametrize("name", system_files())
def test_reference_points_are_zeros_of_the_parsed_system(name):
    """The parsed equations, evaluated in interval arithmetic on the tightest float box
    around each (exact) reference solution, contain 0: the file and the reference agree."""
    from certsolve.expr.compiled import CompiledSystem

    csys = CompiledSystem(load_minibex(SYSTEMS / f"{name}.mbx"))
    for p in ref_points(name):
        lo, hi = float_enclosure(p)
        flo, fhi = csys.eval_f(lo[None, :], hi[None, :])
        assert np.all(flo[0] <= 0) and np.all(0 <= fhi[0]), (p, flo, fhi)


def float_enclosure(point):
    """The tightest float box holding the mpf ``point`` (reference values carry 40 digits,
    so this holds the exact solution unless it is within 1e-40 of a float)."""
    lo, hi = [], []
    for v in point:
        f = float(v)
        if mpmath.mpf(f) == v:
            a = b = f
        elif mpmath.mpf(f) < v:
            a, b = f, math.nextafter(f, math.inf)
        else:
            a, b = math.nextafter(f, -math.inf), f
        lo.append(a)
        hi.append(b)
    return np.array(lo), np.array(hi)


# -- parser error messages ---------------------------------------------------------------------
BAD = {
    "missing semicolon": (
        "Variables\n  x in [-1, 1];\n  y in [-1, 1]\nConstraints\n  x = y;\n  x*y = 1;\nend\n",
        3,
        "expected ';'",
    ),
    "unknown name": (
        "Variables\n  x, y in [-1, 1];\nConstraints\n  x + z = 0;\n  x - y = 0;\nend\n",
        4,
        "unknown name 'z'",
    ),
    "bad character": (
        "Variables\n  x in [-1, 1];\nConstraints\n  x @ 2 = 0;\nend\n",
        4,
        "unexpected character '@'",
    ),
    "integer index": (
        "Variables\n  x[3] in [0, 1];\nConstraints\n  x(1.5) = 0;\nend\n",
        4,
        "an index must be an integer constant",
    ),
    "empty domain": (
        "Variables\n  x in [1, 0];\nConstraints\n  x = 0.5;\nend\n",
        2,
        "empty interval [1.0, 0.0]",
    ),
    "no variables section": ("Constraints\n  x = 0.5;\nend\n", 1, "'Variables'"),
    "redeclared": (
        "Variables\n  x in [0, 1];\n  x in [0, 2];\nConstraints\n  x = 0.5;\nend\n",
        3,
        "already declared",
    ),
    "text after end": (
        "Variables\n  x in [0, 1];\nConstraints\n  x = 0.5;\nend\nfoo\n",
        6,
        "after 'end'",
    ),
    "unbalanced parenthesis": (
        "// comment\n# comment\nVariables\n  x in [0, 1];\nConstraints\n  (x + 1 = 0.5;\nend\n",
        6,
        "expected ')'",
    ),
    "wrong arity": (
        "Variables\n  x in [0, 1];\nConstraints\n  max(x) = 0.5;\nend\n",
        4,
        "max takes at least 2 arguments, got 1",
    ),
    "no relation": (
        "Variables\n  x in [0, 1];\nConstraints\n  x + 1;\nend\n",
        4,
        "expected '=', '==', '<=' or '>='",
    ),
}


@pytest.mark.parametrize("text,line,fragment", BAD.values(), ids=list(BAD))
def test_parser_errors_name_the_line(text, line, fragment):
    with pytest.raises(MinibexError) as info:
        parse_minibex(text)
    err = info.value
    assert fragment in str(err)
    assert str(err).startswith(f"line {err.line}, column {err.col}: ")
    if line is not None:
        assert err.line == line


def test_parser_error_on_overflowing_literal():
    with pytest.raises(MinibexError) as info:
        parse_minibex("Variables\n  x in [0, 1e400];\nConstraints\n  x = 0.5;\nend\n")
    assert info.value.line == 2


def test_parser_accepts_the_whole_subset():
    system = parse_minibex(
        "# header\n"
        "Constants\n  a = 2.5;\n  r = [0.1, 0.2];\n"
        "Variables\n  x in [-a, a], y in [-a, a];   // two at once\n  z in [-1e8, 1e8];\n"
        "Constraints\n"
        "  sqr(x) + y^2 == 1;\n"
        "  sqrt(abs(z) + 1) - exp(x) + log(2 + cos(y)) + sin(x) = min(x, y) - max(z, r);\n"
        "  x*y - z = 0;\n"
        "  x + y <= 2;\n  x - y >= -2;\n"
        "end\n"
    )
    assert list(system.variables) == ["x", "y", "z"]
    assert len(system.equations) == 3 and len(system.constraints) == 2
    assert system.domain[0][0] == -2.5 and system.domain[2][1] == 1e8
