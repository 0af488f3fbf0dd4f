"""Independent reference solutions for the test systems in ``examples/systems/``.

Run by hand (it is not part of the test suite; it needs sympy and takes about 20 minutes,
mostly the sympy Groebner bases of katsura-6 and eco-7)::

    /tmp/venv/bin/pip install sympy
    /tmp/venv/bin/python tests/reference/compute_reference.py               # every system
    /tmp/venv/bin/python tests/reference/compute_reference.py eco-7 kin2-6r # some systems
    /tmp/venv/bin/python tests/reference/compute_reference.py --list

    # optional second computer-algebra system, to cross-check every Groebner basis:
    apt-get install --no-install-recommends singular-ui singular-modules singular-data
    /tmp/venv/bin/python tests/reference/compute_reference.py --cross-check

It rewrites ``tests/reference/reference.json``, replacing only the entries of the systems
computed.  Nothing here uses certsolve (neither its parser nor its solver): every system is
written again below from its mathematical definition (the ``.mbx`` files are written from
the same definitions; the tests check that the two agree, since every reference solution
must fall in a certified solution box and vice versa).

Methods
-------
``groebner-lex``  (polynomial systems)
    Exact reduced Groebner basis over Q (sympy: grevlex with F5B, then FGLM to lex; decimal
    coefficients converted exactly with ``Rational(str)``).  The lex basis is checked to be
    in *shape position*, ``x_i - g_i(t)`` (i < n) and ``p(t)`` with ``p`` square-free, where
    ``t`` is the last variable or, when that fails, a separating linear form
    ``t = sum c_i x_i`` with small integer ``c_i``; then the complex solutions are exactly
    ``deg p`` and the real ones are in bijection with the real roots of ``p``.  Those are
    isolated exactly (sympy ``Poly.intervals``: Vincent-Akritas-Strzebonski continued
    fractions, rational isolating intervals) and refined to width ``10**-(2*DIGITS)``; every
    coordinate ``g_i(root)`` is then enclosed with ``mpmath.iv`` (outward-rounded interval
    arithmetic at increasing precision) until each enclosure is narrower than
    ``10**-DIGITS`` relative.  Membership in the domain is decided on these enclosures
    (an enclosure straddling a domain bound is an error).  Non-radical ideals (the
    double-root system) are first replaced by their radical (Seidenberg: add the
    square-free part of the univariate eliminant of every variable).
    Finally the original equations are evaluated at every solution (residual check).
    With ``--cross-check`` the lex basis is computed a second time by Singular
    (``modStd(I, 1)``: multi-modular, verified; then ``fglm``) and the real solutions
    must agree.
``newton-multistart-krawczyk (certified lower bound) + literature count``  (kin2)
    The exact method is out of reach here: kin2 has 64 complex solutions and 9-digit decimal
    coefficients, and neither sympy nor Singular's modStd finished its basis over Q within
    40 minutes (over a prime field Singular gives dim 0, vdim 64 in 0.1 s).  So: Newton on
    the four joint angles from 100000 random starts (fixed seed) finds 10 distinct real
    solutions (in trial runs all 10 already within the first 5000 starts); each is refined in mpmath
    on the 8-variable polynomial system and certified by a Krawczyk test in ``mpmath.iv``
    on a box of radius 1e-50 (exactly one solution in it).  That there are no others is the
    literature count (10, Van Hentenryck, McAllester and Kapur 1997).  Every real solution
    is in the domain since x1^2 + x2^2 = 1 etc.  ``--kin2-singular SECONDS`` tries the exact
    method as well.
``interval-1d``  (trig-exp)
    The system is reduced to one equation ``h(x) = 0`` in one variable (the other one is an
    explicit function of it); ``[lo, hi]`` is subdivided recursively with ``mpmath.iv``: a
    piece is discarded when ``0 notin h(piece)``; it holds exactly one root when
    ``0 notin h'(piece)`` and ``h`` has strictly opposite signs at its end points; otherwise
    it is bisected.  Roots are then polished with ``mpmath.findroot`` (checked to stay in
    their piece).
``monotone-newton-krawczyk``  (discrete boundary value problem, Troesch)
    The system is ``A x + phi(x) = b`` with ``A = tridiag(-1, 2, -1)`` (positive definite) and
    ``phi_i`` an increasing function of ``x_i`` alone: it is the gradient of a strictly convex,
    coercive function, so it has exactly one real zero (the count, by this argument).  The zero
    is computed by Newton in mpmath at 120 digits and certified by a Krawczyk test in
    ``mpmath.iv`` on a box of radius 1e-45 around it; it must lie in the domain.
``interval-contraction-krawczyk``  (Broyden banded)
    Every solution in the domain satisfies ``x_i = h^-1(S_i(x) - 1)`` with ``h(t) = 2t + 5t^3``
    strictly increasing and ``S_i = sum_(j in J_i) x_j (1 + x_j)``: iterating this
    (Gauss-Seidel, outward rounded, ``mpmath.iv``) from the domain shrinks it to a box ``B``
    that still holds every solution; a Krawczyk test ``K(B) in int(B)`` (``mpmath.iv``)
    then proves that ``B`` holds exactly one.  So the count is 1, with no Groebner basis
    (the Bezout number is 3^10).
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mpmath
import sympy as sp
from mpmath import iv, mp

HERE = Path(__file__).resolve().parent
OUT = HERE / "reference.json"
DIGITS = 40  # significant digits written to reference.json (all of them certified)


# ---------------------------------------------------------------------------------------------
# The systems, from their definitions
# ---------------------------------------------------------------------------------------------
def R(s) -> sp.Rational:
    return sp.Rational(str(s))


def sys_circle_line():
    x, y = sp.symbols("x y")
    return [x**2 + y**2 - 1, x - y], [x, y], [(-2, 2)] * 2


def sys_brown(n=5):
    x = sp.symbols(f"x1:{n + 1}")
    s = sum(x)
    eqs = [x[i] + s - (n + 1) for i in range(n - 1)] + [sp.Mul(*x) - 1]
    return eqs, list(x), [(R("-1e8"), R("1e8"))] * n


def sys_brown_vector(n=5):
    """brown-5 written with a vector: the same equations, variables ``x[1]..x[n]``."""
    x = sp.symbols(" ".join(f"x[{i}]" for i in range(1, n + 1)))
    s = sum(x)
    eqs = [x[i] + s - (n + 1) for i in range(n - 1)] + [sp.Mul(*x) - 1]
    return eqs, list(x), [(R("-1e8"), R("1e8"))] * n


def sys_katsura(n):
    x = sp.symbols(f"x0:{n + 1}")

    def X(k):
        return x[abs(k)] if abs(k) <= n else 0

    eqs = [sum(X(k) * X(m - k) for k in range(-n, n + 1)) - x[m] for m in range(n)]
    eqs.append(sum(X(k) for k in range(-n, n + 1)) - 1)
    return eqs, list(x), [(-2, 2)] * (n + 1)


def sys_eco(n, box):
    x = sp.symbols(f"x1:{n + 1}")
    eqs = []
    for k in range(1, n - 1):
        eqs.append(
            (x[k - 1] + sum(x[i - 1] * x[i + k - 1] for i in range(1, n - k))) * x[n - 1] - k
        )
    eqs.append(x[n - 2] * x[n - 1] - (n - 1))
    eqs.append(sum(x[: n - 1]) + 1)
    return eqs, list(x), [box] * n


KIN2_ROWS = [
    "-0.249150680 1.609135400 0.279423430 1.434801600 0 0.400263840 -0.800527680 0 0.074052388 "
    "-0.083050031 -0.386159610 -0.755266030 0.504201680 -1.091628700 0 0.049207290 0.049207290",
    "0.125016350 -0.686607360 -0.119228120 -0.719940470 -0.432419270 0 0 -0.864838550 "
    "-0.037157270 0.035436896 0.085383482 0 -0.039251967 0 -0.432419270 0 0.013873010",
    "-0.635550077 -0.115719920 -0.666404480 0.110362110 0.290702030 1.258776700 -0.629388360 "
    "0.581404060 0.195946620 -1.228034200 0 -0.079034221 0.026387877 -0.057131430 -1.162808100 "
    "1.258776700 2.162575000",
    "1.48947730 0.23062341 1.32810730 -0.25864503 1.16517200 -0.26908494 0.53816987 0.58258598 "
    "-0.20816985 2.68683200 -0.69910317 0.35744413 1.24991170 1.46773600 1.16517200 1.07633970 "
    "-0.69686809",
]


def sys_kin2():
    x = sp.symbols("x1:9")
    x1, x2, x3, x4, x5, x6, x7, x8 = x
    mono = [x1 * x3, x1 * x4, x2 * x3, x2 * x4, x5 * x7, x5 * x8, x6 * x7, x6 * x8,
            x1, x2, x3, x4, x5, x6, x7, x8, 1]  # fmt: skip
    eqs = [x1**2 + x2**2 - 1, x3**2 + x4**2 - 1, x5**2 + x6**2 - 1, x7**2 + x8**2 - 1]
    for row in KIN2_ROWS:
        a = [R(c) for c in row.split()]
        assert len(a) == 17
        eqs.append(sum(c * m for c, m in zip(a, mono)))
    return eqs, list(x), [(-1, 1)] * 8


def sys_double_root():
    x, y = sp.symbols("x y")
    return [x**2 + y**2 - 1, y - 1], [x, y], [(-2, 2)] * 2


def sys_infeasible():
    x, y = sp.symbols("x y")
    return [x**2 + y**2 - 1, x * y - R("0.501")], [x, y], [(-2, 2)] * 2


CITE = {
    "brown": "K. M. Brown, SIAM J. Numer. Anal. 6 (1969); More, Garbow, Hillstrom, ACM TOMS 7 "
    "(1981), problem 27; IBEX benchmark Brown-5",
    "katsura": "S. Katsura, in New Trends in Magnetism (1990); PoSSo / PHCpack test suite",
    "eco": "A. Morgan, Solving Polynomial Systems Using Continuation for Engineering and "
    "Scientific Problems, Prentice-Hall 1987, p. 148; PoSSo / PHCpack test suite",
    "kin2": "A. Morgan, A. Sommese, Appl. Math. Comput. 24 (1987); P. Van Hentenryck, "
    "D. McAllester, D. Kapur, SIAM J. Numer. Anal. 34 (1997), problem kin2: 10 solutions",
    "broyden": "More, Garbow, Hillstrom, ACM TOMS 7 (1981), problem 31; Van Hentenryck, "
    "McAllester, Kapur, SIAM J. Numer. Anal. 34 (1997): 1 solution in [-1, 1]^n",
    "discrete-boundary": "More, Garbow, Hillstrom, ACM TOMS 7 (1981), problem 28; IBEX "
    "benchmark DiscreteBoundary",
    "troesch": "B. A. Troesch, J. Comput. Phys. 21 (1976); IBEX benchmark Troesch20",
}


# ---------------------------------------------------------------------------------------------
# Exact polynomial solving
# ---------------------------------------------------------------------------------------------
def _iv_rational(q: sp.Rational):
    q = sp.Rational(q)
    return iv.mpf(int(q.p)) / iv.mpf(int(q.q))


def _iv_poly(coeffs, X):
    """Horner in interval arithmetic; ``coeffs`` highest degree first."""
    acc = iv.mpf(0)
    for c in coeffs:
        acc = acc * X + c
    return acc


def _shape(G, gens, t):
    """``(p, [g_1..g_m])`` if the lex basis ``G`` is ``gens[i] - g_i(t)``, ``p(t)``, else None."""
    if len(G) != len(gens) + 1:
        return None
    p = None
    g = {}
    for e in G:
        P = sp.Poly(e, *gens, t)
        free = P.free_symbols - {t}
        if not free:
            if p is not None:
                return None
            p = sp.Poly(e, t)
            continue
        if len(free) != 1:
            return None
        (v,) = free
        Pv = sp.Poly(e, v)
        if Pv.degree() != 1:
            return None
        lc = Pv.coeff_monomial(v)
        if lc.free_symbols:
            return None
        rest = sp.expand(-(e - lc * v) / lc)
        if rest.free_symbols - {t}:
            return None
        g[v] = sp.Poly(rest, t)
    if p is None or len(g) != len(gens):
        return None
    return p, [g[v] for v in gens]


def _lex_basis(eqs, gens):
    G = sp.groebner(eqs, *gens, order="grevlex", method="f5b")
    if G.exprs == [1]:
        return [1]
    return list(G.fglm("lex").exprs)


def _radical(eqs, gens):
    """Seidenberg: add the square-free part of each variable's univariate eliminant."""
    extra = []
    for v in gens:
        order = [w for w in gens if w != v] + [v]
        G = _lex_basis(eqs, order)
        uni = [e for e in G if sp.Poly(e, *order).free_symbols <= {v}]
        p = sp.Poly(uni[-1], v)
        extra.append(sp.sqf_part(p).as_expr())
    return list(eqs) + extra


def solve_polynomial(eqs, gens, domain, log=print, lex_basis=None):
    """Real solutions of a zero-dimensional polynomial system over Q inside ``domain``.

    ``lex_basis``: a function computing the reduced lex Groebner basis (default: sympy).
    """
    eqs = [sp.nsimplify(sp.expand(e), rational=True) for e in eqs]
    info = {}
    t0 = time.perf_counter()
    G = (lex_basis or _lex_basis)(eqs, gens)
    if len(str(G)) < 300:
        info["lex_basis"] = str(G)
    if G == [1]:
        info["complex_solutions"] = 0
        return [], info
    # try the last variable itself as the separating element
    t = gens[-1]
    shape = _shape(G, list(gens[:-1]), t)
    if shape is not None and sp.gcd(shape[0], shape[0].diff(t)).degree() == 0:
        p, g = shape
        coords = g + [sp.Poly(t, t)]
        info["separating"] = str(t)
    else:
        # non-radical ideal or last variable not separating: radical + linear form
        rad = _radical(eqs, gens)
        info["radical"] = "not radical or not in shape position: used the radical (Seidenberg)"
        T = sp.Symbol("t_sep")
        for cs in (
            [1] + [0] * (len(gens) - 1),
            *[[k**i for i in range(len(gens))] for k in (2, 3, 5, 7)],
        ):
            lin = T - sum(c * v for c, v in zip(cs, reversed(gens)))
            G = _lex_basis(rad + [lin], list(gens) + [T])
            shape = _shape(G, list(gens), T)
            if shape is not None and sp.gcd(shape[0], shape[0].diff(T)).degree() == 0:
                p, coords = shape
                info["separating"] = str(lin.as_expr())
                break
        else:
            raise RuntimeError("no separating linear form found")
        t = T
    info["groebner_seconds"] = round(time.perf_counter() - t0, 3)
    info["complex_solutions"] = p.degree()
    log(f"  lex basis in shape position, deg p = {p.degree()} ({info['groebner_seconds']} s)")
    # exact real root isolation, one irreducible factor of p at a time: on the roots of an
    # irreducible q, g_i(t) = (g_i mod q)(t), and a constant remainder is the exact value
    # (so coordinates that are exactly 0 or 1/3 come out exact)
    sols = []
    n_real = 0
    small = max(len(str(c)) for c in p.all_coeffs()) < 1000
    factors = sp.factor_list(p)[1] if small else [(p, 1)]  # factoring huge p is too slow
    for q, mult in factors:
        assert mult == 1
        rems = [c.rem(q) for c in coords] if small else coords
        for (a, b), m in q.intervals(eps=sp.Rational(1, 10 ** (2 * DIGITS))):
            assert m == 1
            n_real += 1
            point = _enclose_point(q, rems, a, b)
            if _in_domain(point, domain):
                mp.dps = 3 * DIGITS  # convert while iv.dps is still that of the enclosure
                sols.append([_mpf(v) for v in point])
    iv.dps = 15
    # residual check with the original equations
    mp.dps = 3 * DIGITS
    f = sp.lambdify(gens, eqs, modules="mpmath")
    for s in sols:
        xs = [mpmath.mpf(v) for v in s]
        res = max(abs(r) for r in f(*xs))
        scale = 1 + max(abs(v) for v in xs) ** 8
        assert res <= scale * mpmath.mpf(10) ** (-DIGITS), res
    info["real_solutions_total"] = n_real
    return sols, info


def _mpf(v):
    """A coordinate (exact sympy Rational or mpmath interval) as an mpf at mp.dps."""
    if isinstance(v, sp.Rational):
        return mpmath.mpf(int(v.p)) / int(v.q)
    return mpmath.mpf(v.mid.a)


def _enclose_point(q, rems, a, b):
    """Exact values (constant remainders) or tight iv enclosures of every coordinate.

    ``[a, b]`` isolates a root of ``q``; it is refined along with the precision.
    """
    for k in range(6):
        iv.dps = 3 * DIGITS * 2**k
        if k:
            a, b = q.refine_root(a, b, eps=sp.Rational(1, 10 ** (2 * DIGITS * 2**k)))
        T = iv.mpf([_iv_rational(a).a, _iv_rational(b).b])
        point = []
        for r in rems:
            if r.degree() <= 0:
                point.append(sp.Rational(r.as_expr()))
            else:
                point.append(_iv_poly([_iv_rational(c) for c in r.all_coeffs()], T))
        tight = all(
            isinstance(e, sp.Rational)
            or (0 not in e and e.delta <= abs(e.mid) * mpmath.mpf(10) ** (-DIGITS - 5))
            for e in point
        )
        if tight:
            return point
    raise RuntimeError("could not enclose a solution tightly enough")


def _in_domain(point, domain) -> bool:
    inside = []
    for e, (lo, hi) in zip(point, domain):
        lo, hi = sp.Rational(lo), sp.Rational(hi)
        if isinstance(e, sp.Rational):
            inside.append(bool(lo <= e <= hi))
            continue
        ilo, ihi = _iv_rational(lo), _iv_rational(hi)
        if e.a >= ilo.b and e.b <= ihi.a:
            inside.append(True)
        elif e.b < ilo.a or e.a > ihi.b:
            inside.append(False)
        else:
            raise RuntimeError(f"solution enclosure {e} straddles a domain bound")
    return all(inside)


# ---------------------------------------------------------------------------------------------
# Singular backend (for kin2: sympy's Groebner bases are far too slow on its 64 solutions with
# 9-digit decimal coefficients)
# ---------------------------------------------------------------------------------------------
def lex_basis_singular(eqs, gens, timeout=None):
    """Reduced lex basis computed by Singular (Debian package ``singular-ui``).

    ``modStd(I, 1)`` (modstd.lib): multi-modular Groebner basis over Q with the final
    verification tests switched on (exactness 1: the result is a Groebner basis of I, not
    only probably), then FGLM to lex.
    """
    exe = shutil.which("Singular")
    if exe is None:
        raise FileNotFoundError("Singular is not installed (apt-get install singular-ui)")
    names = ", ".join(map(str, gens))
    polys = ",\n  ".join(str(sp.expand(e)).replace("**", "^") for e in eqs)
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "lex.txt"
        script = Path(d) / "run.sing"
        script.write_text(
            'LIB "modstd.lib";\n'
            f"ring r = 0, ({names}), dp;\nshort = 0;\noption(redSB);\n"
            f"ideal i =\n  {polys};\n"
            "ideal g = modStd(i, 1);\n"
            f"ring s = 0, ({names}), lp;\nshort = 0;\n"
            "ideal l = fglm(r, g);\n"
            f'write(":w {out}", l);\nquit;\n'
        )
        subprocess.run([exe, "-q", str(script)], check=True, timeout=timeout, capture_output=True)
        text = out.read_text()
    return [_parse_singular(t, list(gens)) for t in text.split(",")]


def _parse_singular(text, gens):
    """A polynomial printed by Singular over Q (``-3/7*x1*x8^2+...``) as a sympy expression."""
    index = {str(g): k for k, g in enumerate(gens)}
    poly = {}
    for term in re.findall(r"[+-]?[^+-]+", re.sub(r"\s", "", text)):
        sign = -1 if term[0] == "-" else 1
        coef = sp.Integer(sign)
        exps = [0] * len(gens)
        for f in term.lstrip("+-").split("*"):
            if f[0].isdigit():
                coef *= sp.Rational(f)
            else:
                name, _, e = f.partition("^")
                exps[index[name]] += int(e or 1)
        poly[tuple(exps)] = poly.get(tuple(exps), 0) + coef
    return sp.Poly.from_dict(poly, *gens).as_expr()


# ---------------------------------------------------------------------------------------------
# Certified numerics (kin2 without Singular): multistart Newton + Krawczyk in mpmath.iv
# ---------------------------------------------------------------------------------------------
def _iv_polys(polys, gens):
    """Polynomials as lists of (iv coefficient, exponents), for interval evaluation."""
    out = []
    for e in polys:
        P = sp.Poly(e, *gens)
        out.append([(_iv_rational(c), m) for m, c in zip(P.monoms(), P.coeffs())])
    return out


def _iv_eval(terms, X):
    acc = iv.mpf(0)
    for c, m in terms:
        t = c
        for x, k in zip(X, m):
            if k:
                t = t * x**k
        acc += t
    return acc


def krawczyk(eqs, gens, x0, radius):
    """True if the box ``x0 +- radius`` holds exactly one solution (Krawczyk, mpmath.iv)."""
    n = len(gens)
    F = _iv_polys(eqs, gens)
    Jt = [_iv_polys([sp.diff(e, v) for v in gens], gens) for e in eqs]
    m = [iv.mpf(v) for v in x0]
    B = [iv.mpf([v - radius, v + radius]) for v in x0]
    Jm = mp.matrix([[_iv_eval(Jt[i][j], m).mid for j in range(n)] for i in range(n)])
    Y = mp.inverse(Jm)
    Fm = [_iv_eval(f, m) for f in F]
    JB = [[_iv_eval(Jt[i][j], B) for j in range(n)] for i in range(n)]
    return krawczyk_inside(m, B, Y, Fm, JB)


def krawczyk_inside(m, B, Y, Fm, JB) -> bool:
    """``K(B) = m - Y F(m) + (I - Y J(B)) (B - m)`` inside ``int B`` (mpmath.iv)."""
    n = len(m)
    for i in range(n):
        k = m[i] - sum((iv.mpf(Y[i, q]) * Fm[q] for q in range(n)), iv.mpf(0))
        for j in range(n):
            c = iv.mpf(1 if i == j else 0)
            for q in range(n):
                c -= iv.mpf(Y[i, q]) * JB[q][j]
            k += c * (B[j] - m[j])
        if not (B[i].a < k.a and k.b < B[i].b):
            return False
    return True


def kin2_numeric(log=print, starts=100_000, seed=1):
    """Real solutions of kin2 by multistart Newton on the angles, each certified by Krawczyk.

    A certified lower bound; that there are no others rests on the literature count.
    """
    import numpy as np

    eqs, gens, _ = sys_kin2()
    A = np.array([[float(v) for v in row.split()] for row in KIN2_ROWS])

    def F(th):
        C, S = np.cos(th), np.sin(th)
        x1, x3, x5, x7 = C.T
        x2, x4, x6, x8 = S.T
        one = np.ones_like(x1)
        M = np.stack([x1 * x3, x1 * x4, x2 * x3, x2 * x4, x5 * x7, x5 * x8, x6 * x7, x6 * x8,
                      x1, x2, x3, x4, x5, x6, x7, x8, one], 1)  # fmt: skip
        return M @ A.T

    rng = np.random.default_rng(seed)
    found = []
    for _ in range(starts // 5000):
        th = rng.uniform(-np.pi, np.pi, (5000, 4))
        with np.errstate(all="ignore"):
            for _ in range(60):
                J = np.empty((th.shape[0], 4, 4))
                for k in range(4):
                    e = np.zeros(4)
                    e[k] = 1e-7
                    J[:, :, k] = (F(th + e) - F(th - e)) / 2e-7
                ok = np.abs(np.linalg.det(J)) > 1e-14
                th, J = th[ok], J[ok]
                d = np.linalg.solve(J, F(th)[..., None])[..., 0]
                th = th - np.clip(d, -0.5, 0.5)
        good = np.max(np.abs(F(th)), 1) < 1e-12
        for p in np.angle(np.exp(1j * th[good])):
            if not any(np.max(np.abs(np.angle(np.exp(1j * (p - q))))) < 1e-6 for q in found):
                found.append(p)
    log(f"  multistart Newton: {len(found)} distinct real solutions from {starts} starts")
    mp.dps = 3 * DIGITS
    iv.dps = 3 * DIGITS
    f = sp.lambdify(gens, eqs, modules="mpmath")
    jac = sp.lambdify(gens, sp.Matrix(eqs).jacobian(gens), modules="mpmath")
    sols = []
    for p in found:
        x = mp.matrix([v for a in p for v in (mp.cos(a), mp.sin(a))])
        for _ in range(12):  # Newton in mpmath on the 8-variable polynomial system
            x = x - mp.lu_solve(mp.matrix(jac(*x)), mp.matrix(f(*x)))
        x = [x[i] for i in range(8)]
        if not krawczyk(eqs, gens, x, mpmath.mpf(10) ** -(DIGITS + 10)):
            raise RuntimeError(f"Krawczyk failed at {x}")
        sols.append(x)
    iv.dps = 15
    log(f"  Krawczyk: {len(sols)} certified, each alone in its box")
    return sols, {"starts": starts, "seed": seed}


# ---------------------------------------------------------------------------------------------
# trig-exp: rigorous 1-D root counting
# ---------------------------------------------------------------------------------------------
def _trig_y(X, m):
    return m.sin(3 * X) + m.log(2 + X) / 4


def _trig_h(X, m):
    Y = _trig_y(X, m)
    return X**2 + Y**2 - m.exp(X * 0.3) * m.cos(Y / 2)


def _trig_dh(X, m):
    Y = _trig_y(X, m)
    dY = 3 * m.cos(3 * X) + 1 / (4 * (2 + X))
    E = m.exp(X * 0.3)
    C, S = m.cos(Y / 2), m.sin(Y / 2)
    return 2 * X + 2 * Y * dY - 0.3 * E * C + E * S * dY / 2


def solve_trig_exp(log=print):
    iv.dps = 30
    lo, hi = mpmath.mpf("-1.5"), mpmath.mpf("1.5")
    todo = [(lo, hi)]
    pieces = []
    while todo:
        a, b = todo.pop()
        X = iv.mpf([a, b])
        if 0 not in _trig_h(X, iv):
            continue
        if 0 not in _trig_dh(X, iv):
            ha, hb = _trig_h(iv.mpf(a), iv), _trig_h(iv.mpf(b), iv)
            if (ha.b < 0 < hb.a) or (hb.b < 0 < ha.a):
                pieces.append((a, b))
                continue
            if 0 not in ha and 0 not in hb:  # same strict sign, monotone: no root
                continue
        if b - a < mpmath.mpf(10) ** -20:
            raise RuntimeError(f"cannot decide [{a}, {b}]")
        c = (a + b) / 2
        todo += [(a, c), (c, b)]
    pieces.sort()
    mp.dps = 3 * DIGITS
    sols = []
    for a, b in pieces:
        r = mp.findroot(lambda x: _trig_h(x, mp), (a + b) / 2)
        assert a <= r <= b
        # the digits are right: h changes sign (rigorously) within 1e-(DIGITS+5) of r
        iv.dps = 3 * DIGITS
        d = mpmath.mpf(10) ** (-DIGITS - 5)
        h1, h2 = _trig_h(iv.mpf(r - d), iv), _trig_h(iv.mpf(r + d), iv)
        assert (h1.b < 0 < h2.a) or (h2.b < 0 < h1.a)
        sols.append([r, _trig_y(r, mp)])
    # every y(x) is inside [-2, 2] (bound in the .mbx comment), checked here too
    Yr = _trig_y(iv.mpf([lo, hi]), iv)
    assert Yr.a > -2 and Yr.b < 2
    log(f"  {len(pieces)} isolating intervals")
    return sols, {"isolating_intervals": [[str(a), str(b)] for a, b in pieces]}


# ---------------------------------------------------------------------------------------------
# Broyden banded: contraction + Krawczyk, all in mpmath.iv
# ---------------------------------------------------------------------------------------------
def _broyden_J(i, n):
    return [j for j in range(max(0, i - 5), min(n - 1, i + 1) + 1) if j != i]


def _h_inv_bounds(v, lo_side):
    """A point t with h(t) <= v (lo_side) or h(t) >= v (not lo_side), h(t) = 2t + 5t^3."""
    mp.dps = iv.dps + 10
    r = mp.findroot(lambda t: 2 * t + 5 * t**3 - v, mpmath.mpf(0), solver="newton")
    step = mpmath.mpf(10) ** (-iv.dps + 5)
    while True:
        t = r - step if lo_side else r + step
        ht = 2 * iv.mpf(t) + 5 * iv.mpf(t) ** 3
        if (lo_side and ht.b <= v) or (not lo_side and ht.a >= v):
            return t
        step *= 10


def solve_broyden(n=10, log=print):
    iv.dps = 60
    B = [iv.mpf([-1, 1]) for _ in range(n)]
    sweeps = 0
    while sweeps < 2000:
        sweeps += 1
        old = [(b.a, b.b) for b in B]
        for i in range(n):
            S = iv.mpf(0)
            for j in _broyden_J(i, n):
                S += (B[j] + 0.5) ** 2 - 0.25
            V = S - 1
            lo = max(B[i].a, _h_inv_bounds(V.a, True))
            hi = min(B[i].b, _h_inv_bounds(V.b, False))
            if lo > hi:
                raise RuntimeError("empty: no solution")
            B[i] = iv.mpf([lo, hi])
        width = max(mpmath.mpf(b.delta.b) for b in B)
        if all(b.a == o[0] and b.b == o[1] for b, o in zip(B, old)) or width < 1e-45:
            break
    log(f"  contraction: {sweeps} sweeps, width {mpmath.nstr(width, 3)}")
    # Krawczyk on B (inflated a little, it still holds every solution of the domain only if
    # inflated inside the domain; the contraction already proved all solutions are in B)
    mp.dps = iv.dps
    m = [b.mid for b in B]

    def F(x):
        out = []
        for i in range(n):
            s = x[i] * (2 + 5 * x[i] ** 2) + 1
            for j in _broyden_J(i, n):
                s -= x[j] * (1 + x[j])
            out.append(s)
        return out

    def Jac(x):  # entries for interval or point x
        M = [[0] * n for _ in range(n)]
        for i in range(n):
            M[i][i] = 2 + 15 * x[i] ** 2
            for j in _broyden_J(i, n):
                M[i][j] = -(1 + 2 * x[j])
        return M

    Ym = mp.inverse(mp.matrix(Jac([mp.mpf(v) for v in m])))
    Fm = F([iv.mpf(v) for v in m])
    JB = Jac(B)
    K = []
    for i in range(n):
        acc = iv.mpf(m[i])
        for k in range(n):
            acc -= iv.mpf(Ym[i, k]) * Fm[k]
        for j in range(n):
            cij = iv.mpf(1 if i == j else 0)
            for k in range(n):
                cij -= iv.mpf(Ym[i, k]) * JB[k][j]
            acc += cij * (B[j] - m[j])
        K.append(acc)
    inside = all(k.a > b.a and k.b < b.b for k, b in zip(K, B))
    if not inside:
        raise RuntimeError("Krawczyk test failed on the contracted box")
    log("  Krawczyk K(B) in int(B): exactly one solution")
    mp.dps = 3 * DIGITS
    sol = mp.findroot(lambda *x: F(list(x)), [mp.mpf(v) for v in m])
    sol = [sol[i] for i in range(n)]
    assert all(b.a - 1e-50 <= s <= b.b + 1e-50 for s, b in zip(sol, B))
    return [sol], {"contracted_box_width": mpmath.nstr(width, 5), "sweeps": sweeps}


# ---------------------------------------------------------------------------------------------
# Monotone tridiagonal systems: A x + phi(x) = b has exactly one zero; Newton + Krawczyk
# ---------------------------------------------------------------------------------------------
def solve_monotone(n, phi, dphi, b, domain, log=print):
    """The zero of ``F_i = 2 x_i - x_(i-1) - x_(i+1) + phi(i, x_i) - b_i`` (``x_0 = x_(n+1) = 0``).

    ``phi(i, v, ctx)`` / ``dphi(i, v, ctx)`` evaluate with ``ctx`` = ``mp`` or ``iv``.
    """

    def F(x, ctx):
        out = []
        for i in range(n):
            left = x[i - 1] if i > 0 else 0
            right = x[i + 1] if i < n - 1 else 0
            out.append(2 * x[i] - left - right + phi(i, x[i], ctx) - b[i])
        return out

    def J(x, ctx):
        M = [[ctx.mpf(0)] * n for _ in range(n)]
        for i in range(n):
            M[i][i] = 2 + dphi(i, x[i], ctx)
            if i > 0:
                M[i][i - 1] = ctx.mpf(-1)
            if i < n - 1:
                M[i][i + 1] = ctx.mpf(-1)
        return M

    mp.dps = 3 * DIGITS
    x = mp.matrix([mp.mpf(0)] * n)
    for _ in range(200):  # Newton; F is the gradient of a strictly convex function
        step = mp.lu_solve(mp.matrix(J(list(x), mp)), mp.matrix(F(list(x), mp)))
        x -= step
        if mp.norm(step) < mpmath.mpf(10) ** (-3 * DIGITS + 10):
            break
    sol = [x[i] for i in range(n)]
    iv.dps = 3 * DIGITS
    r = mpmath.mpf(10) ** -45
    B = [iv.mpf([v - r, v + r]) for v in sol]
    m = [iv.mpf(v) for v in sol]
    Y = mp.inverse(mp.matrix(J(sol, mp)))
    Fm = F(m, iv)
    if not krawczyk_inside(m, B, Y, Fm, J(B, iv)):
        raise RuntimeError("Krawczyk test failed around the Newton point")
    log("  Krawczyk K(B) in int(B) at radius 1e-45: the (unique) zero is certified")
    assert all(lo < v < hi for v, (lo, hi) in zip(sol, domain))
    return [sol], {"newton_digits": 3 * DIGITS, "krawczyk_radius": "1e-45"}


def _entry_discrete_boundary(n=10):
    def run(log):
        mp.dps = 3 * DIGITS
        h = mpmath.mpf(1) / (n + 1)

        def phi(i, v, ctx):  # h^2 (v + t_i + 1)^3 / 2
            return ctx.mpf(h) ** 2 * (v + (i + 1) * ctx.mpf(h) + 1) ** 3 / 2

        def dphi(i, v, ctx):
            return 3 * ctx.mpf(h) ** 2 * (v + (i + 1) * ctx.mpf(h) + 1) ** 2 / 2

        dom = [(-100, 100)] * n
        sols, info = solve_monotone(n, phi, dphi, [0] * n, dom, log=log)
        names = [f"x[{i}]" for i in range(1, n + 1)]
        return names, dom, sols, "monotone-newton-krawczyk", CITE["discrete-boundary"], info

    return run


def _entry_troesch(n=10, r=10):
    def run(log):
        mp.dps = 3 * DIGITS
        h = mpmath.mpf(1) / (n + 1)

        def phi(i, v, ctx):  # r h^2 sinh(r v)
            e = ctx.exp(r * v)
            return r * ctx.mpf(h) ** 2 * (e - 1 / e) / 2

        def dphi(i, v, ctx):  # r^2 h^2 cosh(r v)
            e = ctx.exp(r * v)
            return r * r * ctx.mpf(h) ** 2 * (e + 1 / e) / 2

        b = [0] * (n - 1) + [1]  # x_(n+1) = 1
        dom = [(-10, 10)] * n
        sols, info = solve_monotone(n, phi, dphi, b, dom, log=log)
        names = [f"x[{i}]" for i in range(1, n + 1)]
        return names, dom, sols, "monotone-newton-krawczyk", CITE["troesch"], info

    return run


# ---------------------------------------------------------------------------------------------
# Driver
# ---------------------------------------------------------------------------------------------
# command-line options (see main)
OPTIONS = {"cross_check": False, "kin2_singular": None}


def _singular_basis(timeout):
    return lambda e, g: lex_basis_singular(e, g, timeout=timeout)


def _same_points(a, b, what):
    assert len(a) == len(b), f"{what}: {len(a)} != {len(b)} solutions"
    tol = mpmath.mpf(10) ** (-DIGITS + 5)
    for p in a:
        close = [
            q for q in b if max(abs(mpmath.mpf(u) - mpmath.mpf(v)) for u, v in zip(p, q)) < tol
        ]
        assert len(close) == 1, f"{what}: solution {p} matched {len(close)} times"


def _entry_poly(builder, citation):
    def run(log):
        eqs, gens, dom = builder()
        sols, info = solve_polynomial(eqs, gens, dom, log=log)
        if OPTIONS["cross_check"]:
            t0 = time.perf_counter()
            other, _ = solve_polynomial(eqs, gens, dom, log=log, lex_basis=_singular_basis(3600))
            _same_points(sols, other, "Singular cross-check")
            info["cross_check"] = (
                "Singular modStd + fglm basis, same isolation: same real solutions "
                f"({time.perf_counter() - t0:.1f} s)"
            )
            log("  Singular cross-check: same solutions")
        return [str(v) for v in gens], dom, sols, "groebner-lex", citation, info

    return run


def _entry_trig(log):
    sols, info = solve_trig_exp(log=log)
    cite = "constructed for this test suite; rigorous 1-D reduction (see the .mbx comment)"
    return ["x", "y"], [(-1.5, 1.5), (-2, 2)], sols, "interval-1d", cite, info


def _entry_broyden(log):
    sols, info = solve_broyden(10, log=log)
    names = [f"x{i}" for i in range(1, 11)]
    return names, [(-1, 1)] * 10, sols, "interval-contraction-krawczyk", CITE["broyden"], info


def _entry_kin2(log):
    """Certified numerics (+ the literature count), or Singular's exact lex basis if asked.

    With ``--kin2-singular SECONDS`` the exact method is tried too (over Q, the 64-solution
    basis with 9-digit decimal coefficients did not finish in 40 min on 2 shared cores);
    the multistart + Krawczyk solutions are then a cross-check.
    """
    eqs, gens, dom = sys_kin2()
    names = [str(v) for v in gens]
    num, num_info = kin2_numeric(log=log)
    exact = None
    timeout = OPTIONS["kin2_singular"]
    if timeout:
        try:
            basis = _singular_basis(timeout)
            exact, info = solve_polynomial(eqs, gens, dom, log=log, lex_basis=basis)
        except subprocess.TimeoutExpired:
            log(f"  Singular did not finish in {timeout} s: numeric method only")
    if exact is not None:
        # same solutions both ways
        assert len(exact) == len(num)
        for p in num:
            assert sum(max(abs(a - b) for a, b in zip(p, q)) < 1e-30 for q in exact) == 1
        info["numeric_cross_check"] = f"{len(num)} Krawczyk-certified multistart solutions agree"
        return names, dom, exact, "groebner-lex (Singular modStd + fglm)", CITE["kin2"], info
    cite = CITE["kin2"] + "; the count (no solution missed) rests on this citation"
    method = "newton-multistart-krawczyk (certified lower bound) + literature count"
    return names, dom, num, method, cite, num_info


SYSTEMS = {
    "circle-line": _entry_poly(sys_circle_line, "constructed: circle and line"),
    "brown-5": _entry_poly(sys_brown, CITE["brown"]),
    "brown-5-vector": _entry_poly(sys_brown_vector, CITE["brown"] + " (vector form)"),
    "discrete-boundary-10": _entry_discrete_boundary(10),
    "troesch-10": _entry_troesch(10),
    "broyden-banded-10": _entry_broyden,
    "katsura-5": _entry_poly(lambda: sys_katsura(5), CITE["katsura"]),
    "katsura-6": _entry_poly(lambda: sys_katsura(6), CITE["katsura"]),
    "eco-6": _entry_poly(lambda: sys_eco(6, (-100, 100)), CITE["eco"]),
    "eco-7": _entry_poly(lambda: sys_eco(7, (-100, 100)), CITE["eco"]),
    "kin2-6r": _entry_kin2,
    "double-root": _entry_poly(sys_double_root, "constructed: tangent line y = 1"),
    "infeasible": _entry_poly(sys_infeasible, "constructed: circle and hyperbola xy = 0.501"),
    "trig-exp": _entry_trig,
}


def _fmt(v) -> str:
    mp.dps = 3 * DIGITS
    v = mpmath.mpf(v)
    if v == 0:
        return "0"
    return mpmath.nstr(v, DIGITS, strip_zeros=False, min_fixed=-5, max_fixed=10)


def dumps(data) -> str:
    """JSON with one line per solution / domain bound pair."""
    text = json.dumps(data, indent=1)
    # collapse innermost lists of scalars onto one line
    return (
        re.sub(
            r"\[\s*((?:\"[^\"]*\"|[-\d.e]+)(?:,\s*(?:\"[^\"]*\"|[-\d.e]+))*)\s*\]",
            lambda m: "[" + re.sub(r",\s+", ", ", m.group(1)) + "]",
            text,
        )
        + "\n"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("systems", nargs="*", help="system names (default: all)")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--dry-run", action="store_true", help="do not write reference.json")
    ap.add_argument(
        "--cross-check",
        action="store_true",
        help="also compute the Groebner bases with Singular (apt-get install singular-ui)",
    )
    ap.add_argument(
        "--kin2-singular",
        type=float,
        metavar="SECONDS",
        help="try the exact method on kin2 with Singular, for at most SECONDS",
    )
    args = ap.parse_args(argv)
    OPTIONS["cross_check"] = args.cross_check
    OPTIONS["kin2_singular"] = args.kin2_singular
    if args.list:
        print("\n".join(SYSTEMS))
        return 0
    names = args.systems or list(SYSTEMS)
    data = json.loads(OUT.read_text()) if OUT.exists() else {}
    for name in names:
        print(f"{name}:", flush=True)
        t0 = time.perf_counter()
        variables, dom, sols, method, cite, info = SYSTEMS[name](lambda s: print(s, flush=True))
        dt = time.perf_counter() - t0
        sols.sort(key=lambda s: [float(v) for v in s])
        data[name] = {
            "file": f"examples/systems/{name}.mbx",
            "variables": variables,
            "domain": [[str(a), str(b)] for a, b in dom],
            "count": len(sols),
            "solutions": [[_fmt(v) for v in s] for s in sols],
            "digits": DIGITS,
            "method": method,
            "citation": cite,
            "details": {k: v for k, v in info.items()},
            "seconds": round(dt, 2),
            "software": f"sympy {sp.__version__}, mpmath {mpmath.__version__}, "
            f"python {sys.version.split()[0]}",
        }
        print(f"  {len(sols)} real solution(s) in the domain, {dt:.1f} s", flush=True)
        if not args.dry_run:
            OUT.write_text(dumps(dict(sorted(data.items()))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
