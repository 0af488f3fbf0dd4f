"""Minibex as IBEX writes it: declarations, vectors, loops, functions, every elementary
function, exact constants, errors with positions, limits, and fuzzing.

The fuzz tests feed random text and random mutations of valid files to the parser: whatever
the input, it returns a System or raises MinibexError, never anything else (no RecursionError,
no ZeroDivisionError, no OverflowError...).
"""

import contextlib
import io
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from certsolve.cli import main as cli_main
from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import LIMITS, Limits, MinibexError, load_minibex, parse_minibex
from certsolve.solver import solve

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"


def system(variables: str, constraints: str, constants: str = "", functions: str = ""):
    text = ""
    if constants:
        text += f"Constants\n{constants}\n"
    text += f"Variables\n{variables}\n{functions}\nConstraints\n{constraints}\nend\n"
    return parse_minibex(text)


def f_at(sys_, point):
    """Rigorous enclosure of the equations at a point (for checking what was parsed)."""
    csys = CompiledSystem(sys_)
    x = np.array(point, dtype=float)[None]
    lo, hi = csys.eval_f(x, x)
    return lo[0], hi[0]


# -- declarations ---------------------------------------------------------------------------------
def test_a_declaration_without_in_is_unbounded_as_in_ibex():
    s = system("x0, x1, x2 in [-2, 2];", "x0 = 1; x1 = 1; x2 = 1;")
    assert s.variables == ["x0", "x1", "x2"]
    assert s.domain.tolist() == [[-math.inf, math.inf], [-math.inf, math.inf], [-2.0, 2.0]]


def test_declarations_separated_by_commas_or_semicolons():
    s = system("x in [-1, 1], y in [0, 2]; z;", "x = 0; y = 1; z = 2;")
    assert s.domain.tolist() == [[-1, 1], [0, 2], [-math.inf, math.inf]]


def test_infinite_bounds():
    s = system("a in [-oo, 0]; b in [0, +oo]; c in [-oo, oo];", "a = -1; b = 1; c = 0;")
    assert s.domain.tolist() == [[-math.inf, 0], [0, math.inf], [-math.inf, math.inf]]


@pytest.mark.parametrize(
    "constants, value",
    [
        ("c = 0.5;", (0.5, 0.5)),
        ("c in 0.5;", (0.5, 0.5)),
        ("c in [1, 2];", (1.0, 2.0)),
        ("c := 2*3 - 1;", (5.0, 5.0)),
        ("c = 1/3;", (1 / 3, math.nextafter(1 / 3, 1))),  # tightest enclosure of 1/3
        ("c = 0.1;", (math.nextafter(0.1, 0), 0.1)),  # float 0.1 is above 1/10
        ("c = 2^10 + sqr(-3) + abs(-1) + max(1, 2, 7) - min(4, 3);", (1024 + 9 + 1 + 7 - 3,) * 2),
        ("a = 3; c = a^2 - a;", (6.0, 6.0)),
    ],
)
def test_constants(constants, value):
    s = system("x in [-10, 10];", "x - c = 0;", constants)
    (eq,) = s.equations
    assert eq.op == "sub" and eq.args[1].op == "const"
    assert eq.args[1].param == value


def test_vector_and_matrix_constants():
    s = system(
        "x in [-10, 10]; y in [-10, 10]; z in [-10, 10];",
        "x = c(2) + M(3, 1) + M[1][2]; y = d(1, 2); z = T(2, 1, 3) + Z(2, 2) + r(3);",
        "c[3] = (1; 2; 3);\n M[3][2] = ((0, 5); (0, 1); (7, 0));\n d[1][2] = (8, 9);\n"
        " T[2][2][3] = (((0, 1, 2); (3, 4, 5)); ((6, 7, 8); (9, 10, 11)));\n"
        " Z[2][2] in [0, 0];\n r[3] in ([1, 1]; 2; [3, 3]);",
    )
    consts = [e.args[1].param for e in s.equations]
    assert consts[:2] == [(14.0, 14.0), (9.0, 9.0)]  # exact
    assert consts[2][0] <= 8 + 0 + 3 <= consts[2][1] and consts[2][1] - consts[2][0] < 1e-14


def test_vector_variables_and_indexing():
    s = system(
        "x[3] in [-1, 1]; A[2][2] in [0, 5]; v[2] in ([-oo, 0]; [0, +oo]);",
        "x(1) + x[2] = 0; x(3) = 0.5; x(1) = 0.25; A(1, 2) + A[2][1] = 1; A(1,1) = A(2,2);"
        " A(2,2) = 1; A(1, 2) = 0.5;"
        " v(1) + v(2) = 0; v(2) = 1;",
    )
    assert s.variables == ["x[1]", "x[2]", "x[3]", "A[1][1]", "A[1][2]", "A[2][1]", "A[2][2]",
                           "v[1]", "v[2]"]  # fmt: skip
    assert s.domain[:3].tolist() == [[-1, 1]] * 3
    assert s.domain[7:].tolist() == [[-math.inf, 0], [0, math.inf]]
    lo, hi = f_at(s, [0.25, -0.25, 0.5, 1, 0.5, 0.5, 1, -1, 1])
    assert np.all(lo <= 0) and np.all(hi >= 0)


def test_loops_nested_and_with_constant_bounds():
    s = system(
        "x[4] in [-10, 10];",
        "for i = 1:n-1;\n  for j = i+1:i+1;\n    x(i) - x(j) + 1 = 0;\n  end\n end;\n"
        "for k = 3:1; x(k) = 100; end\n"  # an empty loop
        "x(1) = 0;",
        "n = 4;",
    )
    assert len(s.equations) == 4
    lo, hi = f_at(s, [0, 1, 2, 3])
    assert np.all(lo <= 0) and np.all(hi >= 0)


def test_matrix_times_vector_and_dot_product():
    s = system(
        "x[2] in [-10, 10];",
        "A*x = b; ",
        "A[2][2] = ((2, 1); (1, 3)); b[2] = (3; 5);",
    )
    lo, hi = f_at(s, [0.8, 1.4])  # A x = b: 2x+y = 3, x+3y = 5
    assert np.all(np.abs(lo) < 1e-12) and np.all(np.abs(hi) < 1e-12)
    s = system("x[2] in [-10, 10];", "x'*x = 1; x(1) = x(2);")
    lo, hi = f_at(s, [0.5**0.5, 0.5**0.5])  # x'x - 1 = 0 on the unit circle
    assert lo[0] <= 0 <= hi[0] and hi[0] - lo[0] < 1e-14


def test_functions_are_inlined():
    s = system(
        "x in [-5, 5]; y in [-5, 5];",
        "dist(x, y, 1, 2) = 2; norm2(rot(0.5, (x; y))) = 4;",
        functions=(
            "function dist(xa, ya, xb, yb)\n  return sqrt((xa - xb)^2 + (ya - yb)^2);\nend\n"
            "function rot(t, p[2])\n  c = cos(t); s = sin(t);\n"
            "  return ((c, -s); (s, c)) * p;\nend\n"
            "function norm2(v[2])\n  return v(1)^2 + v(2)^2;\nend\n"
        ),
    )
    lo, hi = f_at(s, [1.0, 2.0 + 2.0])  # dist = 2; |rot p|^2 = |p|^2 = 17
    assert lo[0] <= 0 <= hi[0]
    assert lo[1] <= 13 <= hi[1]


def test_function_calls_with_constant_arguments_are_evaluated():
    s = system("x in [0, 1];", "x = twice(0.25);", functions="function twice(u)\n return 2*u;\nend")
    (eq,) = s.equations
    assert eq.op == "sub" and eq.args[1].op == "const"
    lo, hi = eq.args[1].param
    assert lo <= 0.5 <= hi and hi - lo < 1e-15


# -- functions and powers -------------------------------------------------------------------------
FUNCS = "tan sinh cosh tanh atan asin acos asinh acosh atanh abs sign sqr sqrt exp log ln sin cos"


@pytest.mark.parametrize("name", FUNCS.split())
def test_every_unary_function(name):
    import mpmath

    point = {"acosh": 1.5}.get(name, 0.3)
    s = system("x in [-10, 10];", f"{name}(x) = 0;")
    lo, hi = f_at(s, [point])
    fn = {"sqr": lambda v: v * v, "abs": abs, "sign": mpmath.sign, "ln": mpmath.log}.get(
        name, getattr(mpmath, name, None)
    )
    exact = fn(mpmath.mpf(point))
    assert lo[0] <= exact <= hi[0]


def test_binary_functions_and_powers():
    s = system(
        "x in [0, 10]; y in [-3, 3];",
        "atan2(y, x) + min(x, y) + max(x, y, 2) = 0; x^0.5 + x^(1/3) + x^y + y^3 + x^-2 = 0;",
    )
    ops = {e.op for eq in s.equations for e in _walk(eq)}
    assert {"atan2", "min", "max", "rpow", "pow"} <= ops
    lo, hi = f_at(s, [4.0, 1.0])
    exact = [math.atan2(1, 4) + 1 + 4, 2 + 4 ** (1 / 3) + 4 + 1 + 1 / 16]
    assert np.all(lo <= exact) and np.all(np.array(exact) <= hi)
    # x^2.0 is the integer power (defined for negative x), x^0.5 the real one (x >= 0)
    s = system("x in [-3, 3];", "x^2.0 = 4;")
    assert solve(s, eps=1e-10).solutions and len(solve(s, eps=1e-10).solutions) == 2
    s = system("x in [-3, 3];", "x^0.5 = 1;")
    assert len(solve(s, eps=1e-10).solutions) == 1


def _walk(e):
    stack, seen = [e], set()
    while stack:
        x = stack.pop()
        if id(x) not in seen:
            seen.add(id(x))
            yield x
            stack.extend(x.args)


def test_systems_with_new_functions_are_solved_and_certified():
    s = system(
        "x in [0, 1.5]; y in [-2, 2];",
        "tan(x) = 1; sinh(y) + atan(y) - asin(x/2) = 0;",
    )
    r = solve(s, eps=1e-10)
    assert r.status == "complete" and len(r.solutions) == 1 and not r.undecided
    (sol,) = r.solutions
    assert sol.lo[0] <= math.pi / 4 <= sol.hi[0]


# -- errors ---------------------------------------------------------------------------------------
ERRORS = {
    "division by zero": (
        "Constants\n  a = 1/0;\nVariables\n  x;\nConstraints\n  x = a;\nend",
        2,
        8,
    ),
    "log(0)": ("Variables\n  x;\nConstraints\n  x = log(0);\nend", 4, 7),
    "sqrt(-1)": (
        "Constants\n  a = 2;\nVariables\n  x;\nConstraints\n  x*sqrt(1-a) = 1;\nend",
        6,
        5,
    ),
    "in the call of f: undefined constant: log(-1)": (
        "Variables\n  x;\nfunction f(u)\n  return log(u);\nend\nConstraints\n  x = f(-1);\nend",
        7,
        7,
    ),
    "nesting deeper than 100": (
        "Variables\n  x;\nConstraints\n  " + "(" * 150 + "x" + ")" * 150 + " = 0;\nend",
        4,
        None,
    ),
    "unknown name 'y'": ("Variables\n  x;\nConstraints\n  x + y = 0;\nend", 4, 7),
    "index 4 out of range 1..3": ("Variables\n  x[3];\nConstraints\n  x(4) = 0;\nend", 4, 5),
    "not visible inside a function": (
        "Variables\n  x;\nfunction f(u)\n  return u + x;\nend\nConstraints\n  f(1) = 0;\nend",
        4,
        14,
    ),
    "f takes 1 argument(s), got 2": (
        "Variables\n  x;\nfunction f(u)\n  return u;\nend\nConstraints\n  f(x, x) = 0;\nend",
        7,
        3,
    ),
    "oo (infinity) may only be a bound": ("Variables\n  x;\nConstraints\n  x + oo = 0;\nend", 4, 5),
    "Minimize": ("Variables\n  x;\nMinimize\n  x;\nConstraints\n x = 0;\nend", 3, 1),
    "unterminated comment": ("Variables\n  x; /* no end\nConstraints\n x = 0;\nend", 2, 6),
    "missing 'end' of the loop": ("Variables\n  x[2];\nConstraints\n for i=1:2; x(i) = 0;\n", 5, 1),
    "cannot add a vector of 2 and a number": (
        "Variables\n  x[2];\nConstraints\n  x + 1 = 0;\nend",
        4,
        5,
    ),
    "beyond the double-precision range": ("Variables\n  x;\nConstraints\n  x = 1e999;\nend", 4, 7),
    "the constraint involves no variable": (
        "Variables\n  x;\nConstraints\n  1 = 1;\n x = 0;\nend",
        4,
        3,
    ),
}


@pytest.mark.parametrize("name", list(ERRORS))
def test_errors_name_line_and_column(name):
    text, line, col = ERRORS[name]
    with pytest.raises(MinibexError) as info:
        parse_minibex(text)
    err = info.value
    assert name in err.reason, err
    assert err.line == line, err
    if col is not None:
        assert err.col == col, err
    assert str(err).startswith(f"line {err.line}, column {err.col}: ")


def test_nesting_limit_is_clean_and_configurable():
    deep = "Variables\n  x;\nConstraints\n  " + "(" * 90 + "x" + ")" * 90 + " = 0;\nend"
    parse_minibex(deep)  # 90 levels: fine
    with pytest.raises(MinibexError, match="nesting deeper than 50"):
        parse_minibex(deep, limits=Limits(max_depth=50))
    for opener in ("-", "sin(", "x^", "(1;"):
        text = "Variables\n  x;\nConstraints\n  " + opener * 5000 + "x = 0;\nend"
        with pytest.raises(MinibexError, match="nesting deeper than"):
            parse_minibex(text)


HUGE_LOOP = "Variables\n  x;\nConstraints\n  for i = 1:1000000000; x <= i; end\n x = 0;\nend"


def test_work_limit_stops_huge_loops():
    """A loop past ``max_work`` is refused (a small limit: the same path as the default's)."""
    with pytest.raises(MinibexError, match="too large: more than 20000 "):
        parse_minibex(HUGE_LOOP, limits=Limits(max_work=20_000))


@pytest.mark.slow
def test_the_default_work_limit_stops_huge_loops():
    """The default limits stop it too (~15 s of parsing: 5 million steps)."""
    with pytest.raises(MinibexError, match="too large"):
        parse_minibex(HUGE_LOOP)
    assert LIMITS.max_work >= 1_000_000


def test_cli_reports_deep_nesting_as_one_line(tmp_path):
    f = tmp_path / "deep.mbx"
    f.write_text(
        "Variables\n  x in [0, 1];\nConstraints\n  " + "(" * 250 + "x" + ")" * 250 + " = 0;\nend"
    )
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli_main(["solve", str(f)])
    assert code == 2
    assert (
        err.getvalue().startswith("error: line 4, column ")
        and "nesting deeper than 100" in err.getvalue()
    )
    assert err.getvalue().count("\n") == 1


def test_non_utf8_file(tmp_path):
    f = tmp_path / "bad.mbx"
    f.write_bytes(b"Variables\n x in [0, 1];\xff\xfe")
    with pytest.raises(MinibexError, match="not UTF-8"):
        load_minibex(f)


# -- fuzzing --------------------------------------------------------------------------------------
def parses_or_fails_cleanly(text: str) -> None:
    try:
        parse_minibex(text, limits=Limits(max_work=200_000))
    except MinibexError as exc:
        assert exc.line >= 1 and exc.col >= 1
        assert str(exc).startswith(f"line {exc.line}, column {exc.col}: ")


ALPHABET = st.sampled_from(
    list("xyzc0123456789.e+-*/^()[],;:='#/ \n\t")
    + ["Variables", "Constraints", "Constants", "end", "for", "in", "oo", "function", "return",
       "sqrt", "log", "max", "atan2", "x[2]", "1e308", "/*", "*/", "0", "i", "1:3"]
)  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.lists(ALPHABET, max_size=60))
def test_fuzz_token_soup(parts):
    parses_or_fails_cleanly("".join(parts))


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=300))
def test_fuzz_random_text(text):
    parses_or_fails_cleanly(text)


RICH = """
Constants
  n = 3; c[3] = (1; 2; 3); M[2][2] = ((1, 0); (0, 1)); r in [0.1, 0.2];
Variables
  x[n] in [-10, 10], y; z in [0, +oo];
function f(u, v[2])
  w = u * v(1);
  return w + v(2)^2;
end
Constraints
  for i = 1:n-1;
    x(i) * x(i+1) = c(i) + r;
  end
  f(y, (x(1); x(2))) = exp(-z) + atan2(y, 1);
  x(3)^0.5 + tan(y) - cosh(z) <= 2;
  (M * (x(1); x(2)))(1) - sinh(z) = 0;
  z - y^2 = 1;
end
"""


def valid_texts():
    return [RICH] + [p.read_text() for p in sorted(SYSTEMS.glob("*.mbx"))]


def test_the_rich_example_parses():
    s = parse_minibex(RICH)
    assert s.n == 5 and len(s.equations) == 5 and len(s.constraints) == 1


@settings(max_examples=400, deadline=None)
@given(
    st.sampled_from(valid_texts()),
    st.lists(
        st.tuples(st.floats(0, 1), st.integers(0, 8), st.sampled_from(["", "(", ")", "[", "]",
                  ";", ",", "-", "^", "x", "0", "end", "for i=1:2;", "1/0", "oo", "'"])),
        min_size=1,
        max_size=6,
    ),
)  # fmt: skip
def test_fuzz_mutations_of_valid_files(text, edits):
    for where, cut, insert in edits:
        k = int(where * len(text))
        text = text[:k] + insert + text[k + cut :]
    parses_or_fails_cleanly(text)


def test_the_examples_of_the_documentation_parse():
    import re

    doc = (Path(__file__).resolve().parent.parent / "docs" / "minibex.md").read_text()
    blocks = re.findall(r"```\n(.*?)```", doc, flags=re.S)
    s = parse_minibex(blocks[0])
    assert s.variables == ["x[1]", "x[2]", "x[3]", "y", "z"]
    assert s.domain[3].tolist() == [-math.inf, math.inf] and s.domain[4].tolist() == [0, math.inf]
    constants = next(b for b in blocks if b.startswith("Constants\n  a = 2.5;"))
    s = parse_minibex(constants + "Variables\n  x;\nConstraints\n  x = a + T(2, 1, 3);\nend\n")
    assert s.n == 1
    functions = next(b for b in blocks if b.startswith("function dist"))
    s = parse_minibex(
        "Variables\n  x; y;\n" + functions + "Constraints\n  dist(x, y, 0, 0) = 1;\n"
        "  euler(x, y)(1) = 0;\nend\n"
    )
    assert s.n == 2
