"""The Gauss–Seidel kernel (:func:`certsolve.interval.linalg.gauss_seidel`) against the
plain sweep it replaces, and against solutions.

The kernel computes the parts of the sweep that do not depend on the component once for all
components; the plain form below redoes them at every component (one row of ``M`` copied, its
diagonal zeroed, the pivot rounded and divided with the general interval division).  Both are
run on the linearisations of random boxes of the reference systems, at batch sizes on both
sides of the rounding rule's size threshold, and must give the same floats.  A box around a
known solution must keep it.
"""

from pathlib import Path

import numpy as np
import pytest

from certsolve.expr.compiled import CompiledSystem
from certsolve.expr.minibex import load_minibex
from certsolve.interval import arith
from certsolve.interval.linalg import U, gamma, gauss_seidel, mr_from_bounds
from certsolve.interval.rounding import down, up
from certsolve.solver.newton import linearize

SYSTEMS = Path(__file__).resolve().parent.parent / "examples" / "systems"


def plain_sweep(lin):
    """The sweep component by component, every step computed where it is used."""
    lo, hi, c = lin.lo.copy(), lin.hi.copy(), lin.c
    B, n = lo.shape
    empty = np.zeros(B, dtype=bool)
    with np.errstate(all="ignore"):
        dlo, dhi = down(lo - c), up(hi - c)
        g = 1.0 + 2.0 * gamma(n + 4)
        dc, dr = mr_from_bounds(dlo, dhi)
        for i in range(n):
            mc, mr = lin.Mc[:, i, :].copy(), lin.Mr[:, i, :].copy()
            piv_c, piv_r = mc[:, i].copy(), mr[:, i].copy()
            mc[:, i] = 0.0
            mr[:, i] = 0.0
            sc = np.einsum("bj,bj->b", mc, dc)
            amc, adc = np.abs(mc), np.abs(dc)
            sr = (
                np.einsum("bj,bj->b", amc, adc) * gamma(n)
                + np.einsum("bj,bj->b", amc, dr)
                + np.einsum("bj,bj->b", mr, adc + dr)
            )
            sr = sr * g + n * 2.0**-1000
            tc = lin.bc[:, i] + sc
            tr = up(up(lin.br[:, i] + sr) + np.abs(tc) * (2 * U))
            tlo, thi = down(tc - tr), up(tc + tr)
            plo, phi = down(piv_c - piv_r), up(piv_c + piv_r)
            usable = lin.ok & ((plo > 0.0) | (phi < 0.0))
            qlo, qhi = arith.div(tlo, thi, plo, phi)
            nlo, nhi = arith.sub(c[:, i], c[:, i], qlo, qhi)
            new_lo = np.where(usable, np.fmax(lo[:, i], nlo), lo[:, i])
            new_hi = np.where(usable, np.fmin(hi[:, i], nhi), hi[:, i])
            empty |= ~(new_lo <= new_hi)
            lo[:, i], hi[:, i] = new_lo, new_hi
            dlo[:, i], dhi[:, i] = down(new_lo - c[:, i]), up(new_hi - c[:, i])
            dc[:, i], dr[:, i] = mr_from_bounds(dlo[:, i], dhi[:, i], size=dlo.size)
    return lo, hi, empty


def random_boxes(domain, B, rng, scale):
    """``B`` boxes inside the (clipped) domain, of widths ``scale`` of it."""
    dom = np.clip(np.asarray(domain, dtype=float), -100.0, 100.0)
    w = (dom[:, 1] - dom[:, 0]) * scale
    lo = dom[:, 0] + rng.random((B, dom.shape[0])) * (dom[:, 1] - dom[:, 0] - w)
    return lo, lo + w


@pytest.mark.parametrize(
    "name", ["katsura-5", "eco-6", "brown-5", "trig-exp", "broyden-banded-10", "kin2-6r"]
)
@pytest.mark.parametrize("B", [1, 7, 600])
def test_same_floats_as_the_plain_sweep(name, B):
    system = load_minibex(SYSTEMS / f"{name}.mbx")
    csys = CompiledSystem(system)
    rng = np.random.default_rng(B)
    for scale in (1e-6, 1e-3, 1 / 16):
        lin = linearize(csys, *random_boxes(system.domain, B, rng, scale))
        got = gauss_seidel(lin.c, lin.lo, lin.hi, lin.Mc, lin.Mr, lin.bc, lin.br, lin.ok)
        want = plain_sweep(lin)
        for a, b in zip(got, want):
            assert np.array_equal(a, b, equal_nan=True)
    # the cases the test is about occurred: some rows contracted, some pivots held 0
    assert np.any(got[0] > lin.lo) or np.any(want[2])


def test_keeps_a_solution_and_skips_pivots_with_zero():
    rng = np.random.default_rng(3)
    B, n = 200, 6
    # M = Y J around a point solution x* of M (x - c) + b = 0: b = -M (x* - c)
    xs = rng.standard_normal((B, n))
    lo, hi = xs - rng.random((B, n)), xs + rng.random((B, n))
    c = 0.5 * lo + 0.5 * hi
    Mc = np.eye(n) + 0.2 * rng.standard_normal((B, n, n))
    Mr = 0.01 * rng.random((B, n, n))
    Mr[:20, 0, 0] = 10.0  # pivot M_00 holds 0: component 0 left as it is
    bc = -np.einsum("bij,bj->bi", Mc, xs - c)
    br = np.full((B, n), 1e-12)
    ok = np.ones(B, dtype=bool)
    ok[-5:] = False
    nlo, nhi, empty = gauss_seidel(c, lo, hi, Mc, Mr, bc, br, ok)
    assert not empty.any()
    assert np.all((nlo <= xs) & (xs <= nhi))
    assert np.all((lo <= nlo) & (nhi <= hi))
    assert np.array_equal(nlo[-5:], lo[-5:]) and np.array_equal(nhi[-5:], hi[-5:])
    assert np.array_equal(nlo[:20, 0], lo[:20, 0])
    assert np.all(np.any(nhi[20:-5] - nlo[20:-5] < hi[20:-5] - lo[20:-5], axis=1))


@pytest.mark.parametrize("n", [3, 24, 40])
def test_one_box_gives_the_floats_of_a_batch(n):
    """One box takes a scalar path (Python floats, one ``einsum`` per component): each row
    of a batch must get the same floats alone, pivots holding 0, unusable rows, infinite
    and NaN entries included."""
    rng = np.random.default_rng(n)
    B = 12
    xs = rng.standard_normal((B, n))
    lo, hi = xs - rng.random((B, n)) * 10.0 ** rng.integers(-9, 1, (B, 1)), xs + rng.random((B, n))
    c = 0.5 * lo + 0.5 * hi
    Mc = np.eye(n) + (0.5 / n) * rng.standard_normal((B, n, n))
    Mr = 1e-3 * rng.random((B, n, n))
    Mr[0, 1, 1] = 10.0  # a pivot holding 0
    Mc[1, 2, 0] = np.inf
    Mc[2, 0, 3 % n] = np.nan
    bc = -np.einsum("bij,bj->bi", Mc, xs - c) + 1e-3 * rng.standard_normal((B, n))
    br = np.full((B, n), 1e-12)
    ok = np.ones(B, dtype=bool)
    ok[3] = False
    whole = gauss_seidel(c, lo, hi, Mc, Mr, bc, br, ok)
    narrowed = 0
    for k in range(B):
        one = gauss_seidel(c[k : k + 1], lo[k : k + 1], hi[k : k + 1], Mc[k : k + 1],
                           Mr[k : k + 1], bc[k : k + 1], br[k : k + 1], ok[k : k + 1])  # fmt: skip
        for a, b in zip(one, whole):
            assert np.array_equal(a[0], b[k], equal_nan=True)
        narrowed += int(np.any((one[0] > lo[k]) | (one[1] < hi[k])))
    assert narrowed >= B // 2  # the sweeps did contract
