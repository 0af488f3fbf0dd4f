"""A quadratic eigenvalue problem: all 10 real eigenpairs of IBEX's Geneig-icse, certified.

``benchmarks/systems/geneig-icse.mbx`` asks for ``(A + λ B + λ² C) x = 0`` with
``x1 + ... + x5 = 1`` through 22 linear and bilinear equations (``λ = x6``, ``λ² = x7``, the
products ``x_j λ``, ``x_j λ²`` as auxiliary variables).  The reference is independent of the
solver: the pencil is written out below from the file's equations (the auxiliary variables
substituted by hand) and its eigenvalues come from scipy's QZ on the companion
linearisation.  With smear bisection alone the search did not finish in 60 s (5 of 10);
the default :class:`~certsolve.solver.bisectors.SmearCurvatureMix` needs a few thousand
boxes.
"""

from pathlib import Path

import numpy as np
import scipy.linalg

from certsolve.expr.minibex import load_minibex
from certsolve.solver import solve

FILE = Path(__file__).resolve().parent.parent / "benchmarks" / "systems" / "geneig-icse.mbx"


def residual(x, lam):
    """The file's five main equations with ``SE(k)`` replaced by their definitions."""
    x1, x2, x3, x4, x5 = x
    l1, l2 = lam, lam * lam
    se = {5: x1 * l1, 6: x2 * l1, 7: x3 * l1, 8: x4 * l1, 9: x5 * l1}
    se |= {10: x1 * l2, 11: x2 * l2, 12: x3 * l2, 13: x4 * l2, 14: x5 * l2}
    se |= {4: -x3 + se[5], 3: 2 * se[8] - se[12], 2: -2 * se[7] + 3 * se[9]}
    se |= {1: 2 * x4 + se[5] + 2 * se[6] + 2 * se[11], 15: 2 * x1 + 2 * se[5] + se[6] + 3 * se[9]}
    s = se
    return np.array([
        10*x1 + 2*x2 + 2*x4 - 2*x5 + s[3] + s[4] + 2*s[6] + s[7] + s[9] - 10*s[10] + 2*s[11]
        + s[13] + 3*s[14],
        9*x2 + 3*x3 - x4 - 2*x5 + s[15] + 2*s[7] + s[8] + 2*s[10] - 11*s[11] + 2*s[12]
        - 2*s[13] + s[14],
        -x1 + 3*x2 + 10*x3 - x5 + s[1] - 2*s[8] - 2*s[9] - s[10] - 12*s[12] - s[13] + s[14],
        2*x1 - x2 + 2*x3 + 12*x4 + x5 + s[2] + s[3] + 2*s[5] + s[6] + s[10] - 2*s[11]
        - 10*s[13] + 2*s[14],
        -2*x1 - 2*x2 + x4 + 10*x5 + s[2] + s[4] + 3*s[6] + 3*s[8] + 3*s[10] + s[11] + s[12]
        + 2*s[13] - 11*s[14],
    ])  # fmt: skip


def eigenpairs():
    """Real eigenvalues of ``A + λ B + λ² C`` and their eigenvectors scaled to sum 1."""
    e = np.eye(5)
    m = {t: np.array([residual(e[j], t) for j in range(5)]).T for t in (0.0, 1.0, -1.0)}
    a, b, c = m[0.0], (m[1.0] - m[-1.0]) / 2, (m[1.0] + m[-1.0]) / 2 - m[0.0]
    z, i = np.zeros((5, 5)), np.eye(5)
    vals, vecs = scipy.linalg.eig(np.block([[z, i], [-a, -b]]), np.block([[i, z], [z, c]]))
    real = np.isfinite(vals) & (np.abs(vals.imag) < 1e-9)
    x = vecs[:5, real].real
    return vals[real].real, (x / x.sum(axis=0)).T


def test_ten_real_eigenpairs_certified():
    lam, vec = eigenpairs()
    assert len(lam) == 10  # the reference itself: 10 real eigenvalues, apart from each other
    assert np.min(np.diff(np.sort(lam))) > 0.05
    res = solve(load_minibex(FILE), timeout=300)
    assert res.status == "complete" and not res.undecided
    assert len(res.solutions) == 10
    assert all(s.certificate == "unique" for s in res.solutions)
    for s in res.solutions:
        lo, hi = np.array(s.box).T
        k = np.argmin(np.abs(lam - s.midpoint[5]))
        assert lo[5] - 1e-9 <= lam[k] <= hi[5] + 1e-9
        assert np.allclose(s.midpoint[:5], vec[k], atol=1e-7)
        assert np.allclose(residual(s.midpoint[:5], s.midpoint[5]), 0.0, atol=1e-8)
    found = {int(np.argmin(np.abs(lam - s.midpoint[5]))) for s in res.solutions}
    assert found == set(range(10))
