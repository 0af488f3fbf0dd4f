"""Minibex texts that are not square systems: read as a Model (as IBEX reads them), and
passed on as a non-square System (the solver's over- and under-determined searches).

IBEX's ``benchs/solver`` has over-determined files (``Ex14-2-3``: 9 equations, 6 unknowns),
under-determined ones (``Prolog``, truncated ``Bratu-0065``) and inequalities only
(``exnewton``).  The parser reads all of them.
"""

import math
import os
from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.minibex import (
    MinibexError,
    Model,
    load_minibex,
    load_model,
    parse_minibex,
    read_minibex,
)

OVER = """Variables
  x, y in [-2, 2];
Constraints
  x^2 + y^2 = 1;
  x - y = 0;
  x + y = sqrt(2);
end
"""

UNDER = """Constants
  c[2] = (1; 2);
Variables
  p[3] in [-5, 5];
Constraints
  for i = 1:2;
    p(i) + p(i+1) = c(i);
  end
end
"""

INEQUALITIES_ONLY = """variables
  x1 in [0.5, 1.35];
  x2 in [0, 2.33];
constraints
  x2 <= x1^2 + 0.5;
  x2 >= 2.5 * sin(4*x1 + 1) + 2;
  x2 >= sqrt(x1 - 0.5);
end
"""


@pytest.mark.parametrize(
    "text, n, m, k",
    [(OVER, 2, 3, 0), (UNDER, 3, 2, 0), (INEQUALITIES_ONLY, 2, 0, 3)],
    ids=["over-determined", "under-determined", "inequalities-only"],
)
def test_a_non_square_text_is_read(text, n, m, k):
    model = read_minibex(text)
    assert isinstance(model, Model)
    assert (len(model.variables), len(model.equations), len(model.constraints)) == (n, m, k)
    assert model.domain.shape == (n, 2)


@pytest.mark.parametrize(
    "text, n, m",
    [(OVER, 2, 3), (UNDER, 3, 2), (INEQUALITIES_ONLY, 2, 0)],
)
def test_a_non_square_text_parses_to_a_non_square_system(text, n, m):
    """The solver takes over- and under-determined systems (``solver/nonsquare.py``): the
    parser passes them on, with both counts, as the Model read them."""
    system = parse_minibex(text)
    assert (system.n, len(system.equations), system.square) == (n, m, False)
    assert read_minibex(text).system().variables == system.variables


def test_the_model_of_an_under_determined_text_holds_its_loop_and_constants():
    model = read_minibex(UNDER)
    assert model.variables == ["p[1]", "p[2]", "p[3]"]
    assert model.domain.tolist() == [[-5, 5]] * 3
    # p(1) + p(2) = 1 and p(2) + p(3) = 2 hold at (0, 1, 1): the equations enclose 0 there
    from certsolve.expr.compiled import CompiledSystem

    square = read_minibex(UNDER.replace("end\nend", "end\n  p(1) = 0;\nend"))
    csys = CompiledSystem(square.system())
    x = np.array([[0.0, 1.0, 1.0]])
    lo, hi = csys.eval_f(x, x)
    assert np.all(lo <= 0) and np.all(hi >= 0)
    x = np.array([[0.0, 1.0, 1.5]])
    lo, hi = csys.eval_f(x, x)
    assert not (np.all(lo <= 0) and np.all(hi >= 0))


def test_a_square_model_gives_the_system_parse_minibex_gives():
    text = OVER.replace("  x + y = sqrt(2);\n", "")
    model = read_minibex(text)
    s, t = model.system("circle"), parse_minibex(text, name="circle")
    assert s.name == t.name == "circle"
    assert s.variables == t.variables == ["x", "y"]
    assert np.array_equal(s.domain, t.domain)
    assert [str(e) for e in s.equations] == [str(e) for e in t.equations]


def test_load_model_and_load_minibex_read_a_non_square_file(tmp_path):
    path = tmp_path / "ex14-like.bch"
    path.write_text(OVER)
    model = load_model(path)
    assert len(model.equations) == 3
    assert len(load_minibex(path).equations) == 3
    path.write_bytes(b"Variables\n x in [0, 1];\xff\n")
    with pytest.raises(MinibexError, match="not UTF-8 text"):
        load_model(path)


IBEX_SOLVER_BENCHS = Path(os.environ.get("IBEX_BENCHS", "/work/ibex-benchs/benchs/solver"))


@pytest.mark.slow
@pytest.mark.skipif(not IBEX_SOLVER_BENCHS.is_dir(), reason="IBEX's benchs/solver not here")
def test_every_file_of_ibex_benchs_solver_is_read():
    """All 264 files of IBEX 2.9's ``benchs/solver`` (set IBEX_BENCHS to the directory):
    each is read, with at least one variable, finite-or-infinite ordered bounds and a
    constraint of some kind."""
    files = sorted(IBEX_SOLVER_BENCHS.rglob("*.bch"))
    assert files
    for path in files:
        model = load_model(path)
        assert model.variables, path
        assert all(lo <= hi for lo, hi in model.domain), path
        assert model.equations or model.constraints, path
        assert not any(math.isnan(b) for b in model.domain.ravel()), path
