"""Contraction by a square sub-system whose solution is known to be unique (parametric Krawczyk).

Some systems contain a square sub-system ``f_S(x_V, x_R) = 0`` (equations ``S``, as many
variables ``V``; ``R`` the other variables) that has, for every fixed ``x_R``, *at most one*
solution ``x_V`` in a known region ``D_V`` -- a fact about the model that the caller
asserts (forward kinematics of elastic wire robots: for a fixed orientation of the
platform the translational equilibrium is the unique minimum of a strictly convex energy,
see :mod:`certsolve.kinematics.fk_systems`).  Then, for a box ``X = X_V × X_R``:

1. float Newton on ``f_S`` in ``x_V`` with ``x_R = mid X_R`` gives ``x̃_V``;
2. around it a box ``T ⊆ D_V`` is tried with the *parametric* Krawczyk operator

       K(T) = x̃_V - Y f_S(x̃_V, X_R) + (I - Y J_SV(T × X_R)) (T - x̃_V),

   and ``K(T) ⊂ int T`` proves that for every ``x_R ∈ X_R`` the sub-system has exactly one
   solution in ``T``, and that it lies in ``K(T)``;
3. by the asserted uniqueness in ``D_V`` that solution is the only one anywhere in ``D_V``,
   so every solution of the whole system in ``X`` has ``x_V ∈ K(T)``: ``X_V ← X_V ∩ K(T)``
   (empty: no solution in ``X``).

Unlike interval Newton on ``X`` itself, this contracts boxes that are wide in ``V`` (``T``
is chosen small, around the solution for the mid parameters) as long as ``X_R`` is narrow
enough for ``T`` to hold the solution for all parameters.  Nothing is removed without the
proof of step 2; boxes where it fails are returned unchanged.
"""

from __future__ import annotations

import numpy as np

from ..expr.compiled import CompiledSystem
from .newton import batched_inverse, krawczyk, linearization_from_bounds

__all__ = ["UniqueSubsystem"]


class UniqueSubsystem:
    """Parametric Krawczyk contraction of ``X_V`` (see the module docstring).

    Parameters
    ----------
    equations, variables:
        the square sub-system ``S``, ``V`` (index arrays into the system's equations and
        variables).
    region:
        callable returning ``(lo, hi)`` of ``D_V`` (shape ``(|V|,)``, infinite bounds
        allowed) at contraction time -- the region in which the caller guarantees at most
        one solution for every fixed value of the other variables.
    scales:
        ``T`` radii tried, as multiples of the first-order spread of the solution over
        ``X_R``.
    """

    def __init__(
        self,
        csys: CompiledSystem,
        equations,
        variables,
        region,
        newton_iterations: int = 6,
        scales: tuple[float, ...] = (1.5, 4.0),
    ):
        self.csys = csys
        self.S = np.asarray(equations, dtype=np.int64)
        self.V = np.asarray(variables, dtype=np.int64)
        if self.S.shape != self.V.shape:
            raise ValueError("the sub-system must be square")
        self.region = region
        self.newton_iterations = newton_iterations
        self.scales = scales

    def _newton(self, x):
        """Float Newton on ``f_S`` in ``x_V`` (other components fixed); points and a mask."""
        S, V = self.S, self.V
        x = x.copy()
        ok = np.ones(x.shape[0], dtype=bool)
        for _ in range(self.newton_iterations):
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                break
            f, J = self.csys.eval_fj_float(x[idx])
            Y, good = batched_inverse(J[:, S][:, :, V])
            with np.errstate(all="ignore"):
                step = np.einsum("bij,bj->bi", np.where(good[:, None, None], Y, 0.0), f[:, S])
                xv = x[idx][:, V] - step
            good &= np.all(np.isfinite(xv), axis=1)
            x[idx[good][:, None], V[None, :]] = xv[good]
            ok[idx[~good]] = False
        return x, ok

    def contract(self, lo, hi):
        """Returns ``(lo, hi, empty)``; unproven boxes come back unchanged."""
        S, V = self.S, self.V
        B = lo.shape[0]
        lo = lo.copy()
        hi = hi.copy()
        empty = np.zeros(B, dtype=bool)
        if B == 0:
            return lo, hi, empty
        dlo, dhi = self.region()
        x, ok = self._newton(0.5 * lo + 0.5 * hi)
        xv = x[:, V]
        ok &= np.all((xv > dlo) & (xv < dhi), axis=1)
        idx = np.flatnonzero(ok)
        if idx.size == 0:
            return lo, hi, empty
        xv = xv[idx]
        # f_S at (x̃_V, X_R): the V components degenerate
        plo, phi = lo[idx].copy(), hi[idx].copy()
        plo[:, V] = xv
        phi[:, V] = xv
        flo, fhi = self.csys.eval_f(plo, phi)
        flo, fhi = flo[:, S], fhi[:, S]
        # first-order spread of the solution over X_R: |Y| rad f + |Y mid f|
        _, Jp = self.csys.eval_fj_float(x[idx])
        Y, good = batched_inverse(Jp[:, S][:, :, V])
        with np.errstate(all="ignore"):
            fm = 0.5 * flo + 0.5 * fhi
            fr = 0.5 * (fhi - flo)
            spread = np.einsum("bij,bj->bi", np.abs(Y), fr) + np.abs(np.einsum("bij,bj->bi", Y, fm))
        good &= np.all(np.isfinite(spread), axis=1)
        spread = np.where(good[:, None], spread, 0.0)
        todo = np.flatnonzero(good)
        floor = 1e-9 * (1.0 + np.abs(xv))
        for s in self.scales:
            if todo.size == 0:
                break
            r = s * spread[todo] + floor[todo]
            tlo = np.maximum(xv[todo] - r, dlo)
            thi = np.minimum(xv[todo] + r, dhi)
            rows = idx[todo]
            blo, bhi = lo[rows].copy(), hi[rows].copy()
            blo[:, V] = tlo
            bhi[:, V] = thi
            _, _, jlo, jhi, defined = self.csys.eval_fj(blo, bhi, check_domain=True)
            lin = linearization_from_bounds(
                tlo,
                thi,
                xv[todo],
                flo[todo],
                fhi[todo],
                jlo[:, S][:, :, V],
                jhi[:, S][:, :, V],
                defined,
            )
            klo, khi, proven = krawczyk(lin)
            if np.any(proven):
                p = rows[proven]
                nlo = np.fmax(lo[p][:, V], klo[proven])
                nhi = np.fmin(hi[p][:, V], khi[proven])
                empty[p] = np.any(~(nlo <= nhi), axis=1)
                lo[p[:, None], V[None, :]] = nlo
                hi[p[:, None], V[None, :]] = nhi
            todo = todo[~proven]
        return lo, hi, empty

