"""Rigorous, fast enclosures for inverse kinematics: geometry, ``τ(u)``, ``f``, ``J``, Krawczyk.

The IK equations at a pose are ``f(u) = H τ(u) + w_g = 0`` (Merlet 2007, eqs. 3, 4, 6).
Everything here is evaluated in plain floating point and paired with an *a priori* bound of
the rounding error, in **midpoint-radius** form ``(x̃, e)`` meaning ``|x - x̃| <= e`` where
``x`` is the exact real value of the quantity for the exact (binary) inputs: the pose
``(p, R)`` as given floats, the robot's floats and the float controls ``u``.  The bounds use
the standard model of IEEE-754 round-to-nearest (``fl(a∘b) = (a∘b)(1 + δ)``, ``|δ| <= u =
2**-53``) and Higham's dot-product bound ``|fl(xᵀy) - xᵀy| <= γ_n |x|ᵀ|y|``, ``γ_n = n u /
(1 - n u)`` (any summation order, with or without FMA).  Every bound is computed in
round-to-nearest with a few operations and its constants are padded by ``SAFE = 1 + 2**-20``,
far above the relative error ``(1 + u)**k - 1`` of computing it.  ``tests/test_ik_enclose.py``
checks each enclosure against mpmath at 60 digits.

**Geometry** (per wire, 2-norms, ``β = ||R||_F ||B_i||`` bounds ``|R B_i|`` and ``|R||B_i|``)::

    c = R B_i            ||c̃ - c||   <= γ_3 β
    AB = (A_i - p) - c   ||ÃB - AB|| <= 4u ρ̃ + 8u β                   (two subtractions)
    ρ = ||AB||           |ρ̃ - ρ|    <= e_ρ = 10u ρ̃ + 8u β            (γ_3 dot, sqrt)
    n = AB / ρ           |ñ_k - n_k| <= e_n = (14u ρ̃ + 16u β)(1 + 6u) / (ρ̃ - e_ρ) + 2u
    μ = c × n            |μ̃_k - μ_k| <= e_μ = β ((1 + 4u) e_n + 6u)

(``|a1 b1| + |a2 b2| <= ||a|| ||b||`` bounds the rounding of each cross-product component.)
The columns of ``H`` are ``(n, μ)`` (eq. 4).  Gravity is computed in Python floats with
component-wise bounds.

Why not :mod:`certsolve.interval`?  The same proofs with endpoint interval operations cost
30-70 µs per operation on small arrays (``errstate``, ``nextafter``, NaN handling) and the
whole Algorithm 2 should fit in 0.5 ms; here an operation is one numpy call.  The generic
Krawczyk test is the package's one kernel (:func:`certsolve.interval.linalg.krawczyk_mr`,
re-exported here); :class:`SquareSystem` adds a structured variant that exploits
``J = H_S diag(τ')`` (tests check that they agree).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg.lapack
from numpy.typing import ArrayLike

from ..interval.linalg import UNDERFLOW, U, gamma, krawczyk_mr
from ..robot.model import Robot

__all__ = [
    "SAFE",
    "PoseEnclosure",
    "enclose_pose",
    "float_geometry",
    "tension_mr",
    "tension_range",
    "dtension_range",
    "residual_mr",
    "jacobian_mr",
    "krawczyk_mr",
    "SquareSystem",
    "FreeWires",
    "free_wires",
    "is_elastic",
]

SAFE = 1.0 + 2.0**-20

_dgesv = scipy.linalg.lapack.dgesv

_G3 = gamma(3)


@dataclass(frozen=True)
class _Consts:
    dof: int
    dim: int
    elastic: bool
    A: np.ndarray
    B: np.ndarray
    Bnorm: np.ndarray  # (m,) ||B_i||_2 rounded up
    k: np.ndarray
    K: np.ndarray
    V: np.ndarray
    L0: np.ndarray
    kL0: np.ndarray  # fl(k L0): only used in error bounds (padded)
    kL0K: np.ndarray
    F: list  # weight (Python floats) and its error bounds
    eF: list
    com: list
    wg_const: tuple | None  # (wg, ewg) when the gravity wrench does not depend on the pose
    per_free: dict[bytes, FreeWires]  # SquareSystem constants per set of free wires


def _consts(robot: Robot) -> _Consts:
    """The robot's constants for the bounds of this module, computed once per robot and kept
    with it (:attr:`Robot.derived`)."""
    c = robot.derived.get(__name__)
    if c is None:
        F = [float(robot.mass) * float(g) for g in robot.gravity]
        eF = [2.0 * U * abs(f) for f in F]
        com = [float(x) for x in robot.com]
        w = robot.wrench_dim
        wg_const = None
        if robot.dof == 2 or not any(com) or not any(F):
            wg_const = (
                np.array(F + [0.0] * (w - len(F))),
                np.array(eF + [0.0] * (w - len(F))) * SAFE + UNDERFLOW,
            )
        c = _Consts(
            robot.dof,
            robot.dim,
            robot.is_elastic,
            robot.A,
            robot.B,
            np.sqrt(np.sum(robot.B * robot.B, axis=1)) * (1.0 + 8 * U),
            robot.k,
            robot.K,
            robot.V,
            robot.L0,
            robot.k * robot.L0,
            robot.k * robot.L0 * robot.K,
            F,
            eF,
            com,
            wg_const,
            {},
        )
        robot.derived[__name__] = c
    return c


def is_elastic(robot: Robot) -> bool:
    """Cached :attr:`Robot.is_elastic`."""
    return _consts(robot).elastic


def float_geometry(
    robot: Robot, position: np.ndarray, rotation: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plain floating-point ``(rho, H, w_g)`` for one pose (no error bounds; fast)."""
    enc = enclose_pose(robot, position, rotation, bounds=False)
    return enc.rho, enc.H, enc.wg


@dataclass
class PoseEnclosure:
    """Floating-point geometry at one pose with rigorous error bounds (radii)."""

    rho: np.ndarray  # (m,) wire lengths
    rho_err: np.ndarray | None
    Ht: np.ndarray  # (m, w) wrench matrix, transposed (row i: column H_i)
    Ht_err: np.ndarray | None
    wg: np.ndarray  # (w,) external (gravity) wrench
    wg_err: np.ndarray | None
    W: np.ndarray  # (m,) rho + V
    W_err: np.ndarray | None
    valid: bool = True  # every wire length provably > 0

    @property
    def H(self) -> np.ndarray:
        return self.Ht.T

    @property
    def H_err(self) -> np.ndarray:
        return _bound(self.Ht_err).T


def _bound(err: np.ndarray | None) -> np.ndarray:
    """An error radius of a pose enclosed with its bounds (``enclose_pose(..., bounds=True)``)."""
    if err is None:
        raise ValueError("this pose was enclosed without error bounds (bounds=False)")
    return err


def _xprod(a, ea, b, eb, i, j):
    """``a_i b_j - a_j b_i`` and its error bound (Python floats)."""
    p = a[i] * b[j]
    q = a[j] * b[i]
    err = (
        abs(a[i]) * eb[j] + abs(b[j]) * ea[i] + ea[i] * eb[j]
        + abs(a[j]) * eb[i] + abs(b[i]) * ea[j] + ea[j] * eb[i]
        + 3.0 * U * (abs(p) + abs(q))
    )  # fmt: skip
    return p - q, err * SAFE + UNDERFLOW


def _gravity(cs: _Consts, R):
    """``w_g = (F, (R com) × F)`` in Python floats with component-wise error bounds."""
    if cs.wg_const is not None:
        return cs.wg_const
    F, eF, com = cs.F, cs.eF, cs.com
    k = 2.0 * _G3
    if cs.dof == 6:  # R com and 2 γ_3 |R| |com|, summed in order, unrolled (3 -> 2 µs)
        c0, c1, c2 = com
        cg = []
        ecg = []
        for r0, r1, r2 in R.tolist():
            t0, t1, t2 = r0 * c0, r1 * c1, r2 * c2
            cg.append(0.0 + t0 + t1 + t2)
            ecg.append(k * (0.0 + abs(t0) + abs(t1) + abs(t2)) * SAFE)
    else:
        cg = []
        ecg = []
        for row in R.tolist():  # as above, any size (no generators: ~5 µs)
            s = a = 0.0
            for r, c in zip(row, com, strict=True):
                t = r * c
                s += t
                a += abs(t)
            cg.append(s)
            ecg.append(k * a * SAFE)
    if cs.dof == 3:
        mz, emz = _xprod(cg, ecg, F, eF, 0, 1)
        return np.array(F + [mz]), np.array(eF + [emz])
    m0, e0 = _xprod(cg, ecg, F, eF, 1, 2)
    m1, e1 = _xprod(cg, ecg, F, eF, 2, 0)
    m2, e2 = _xprod(cg, ecg, F, eF, 0, 1)
    return np.array(F + [m0, m1, m2]), np.array(eF + [e0, e1, e2])


# 0-d arrays: an array times one is the same float as times the Python float, faster
_C_RHO = np.array(10.0 * U * SAFE)
_C_BETA = np.array(8.0 * U * SAFE)
_C_N1 = np.array(14.0 * U * SAFE * (1 + 6 * U))
_C_N2 = np.array(16.0 * U * SAFE * (1 + 6 * U))
_C_N3 = np.array(2.0 * U * SAFE)
_C_M1 = np.array((1.0 + 4 * U) * SAFE)
_C_M2 = np.array(6.0 * U * SAFE)
_C_W1 = np.array(1.0 + 4 * U)
_C_W2 = np.array(2.0 * U * SAFE)


def enclose_pose(
    robot: Robot, position: np.ndarray, rotation: ArrayLike, bounds: bool = True
) -> PoseEnclosure:
    """``ρ``, ``H`` and ``w_g`` at the pose with rigorous error bounds (module docstring)."""
    cs = _consts(robot)
    dof = cs.dof
    R = np.asarray(rotation, dtype=float)
    CB = cs.B @ R.T
    AB = (cs.A - position) - CB
    rho = np.sqrt(np.add.reduce(AB * AB, axis=1))  # .sum(axis=1) without its wrapper
    if dof == 6:
        # the rows (n, c × n) of H written in place; c and n doubled, so that (c_1, c_2, c_0)
        # and (c_2, c_0, c_1) are slices (a list index costs ~1 us a use).  H is built
        # transposed, (6, m), where these slices are contiguous blocks of rows (arithmetic on
        # strided (m, 3) column blocks costs three times as much), then copied to C order
        Hw = np.empty((6, AB.shape[0]))
        n = np.divide(AB.T.copy(), rho, out=Hw[:3])
        C2 = np.concatenate((CB.T, CB.T))
        N2 = np.concatenate((n, n))
        np.subtract(C2[1:4] * N2[2:5], C2[2:5] * N2[1:4], out=Hw[3:])
        Ht = Hw.T.copy()
    elif dof == 3:
        n = AB / rho[:, None]
        Ht = np.concatenate([n, (CB[:, 0] * n[:, 1] - CB[:, 1] * n[:, 0])[:, None]], axis=1)
    else:
        Ht = AB / rho[:, None]
    wg, ewg = _gravity(cs, R)
    W = rho + cs.V
    if not bounds:
        return PoseEnclosure(rho, None, Ht, None, wg, None, W, None)
    Rf = math.hypot(*R.ravel().tolist()) * (1.0 + 8 * U)  # hypot: within 1 ulp
    beta = cs.Bnorm * Rf
    erho = _C_RHO * rho + _C_BETA * beta
    rlo = rho - erho
    valid = bool(np.minimum.reduce(rlo) > 0.0)
    if not valid:
        rlo = np.where(rlo > 0.0, rlo, 0.0)
    en = (_C_N1 * rho + _C_N2 * beta) / rlo + _C_N3
    # C order, as Ht: sums of arrays of one layout are 3 times faster than of mixed ones
    Ht_err = np.empty(Ht.shape)
    if dof == 2:
        Ht_err[:] = en[:, None]
    else:
        em = beta * (_C_M1 * en + _C_M2)
        d = cs.dim  # the force columns (n), then the moment columns (μ)
        Ht_err[:, :d] = en[:, None]
        Ht_err[:, d:] = em[:, None]
    eW = erho * _C_W1 + _C_W2 * W
    return PoseEnclosure(rho, erho, Ht, Ht_err, wg, ewg, W, eW, valid)


# -- the elastic model (eq. 6) -----------------------------------------------------------------
def _length_mr(cs: _Consts, enc: PoseEnclosure, u):
    """``L = ρ + V + K u`` (eq. 2) with its error bound; ``u`` broadcasts over wires."""
    Ku = cs.K * u
    L = enc.W + Ku
    eL = _bound(enc.W_err) + (2.0 * U * SAFE) * (np.abs(Ku) + np.abs(L))
    return L, eL


def tension_mr(robot: Robot, enc: PoseEnclosure, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (6) at the float controls ``u`` (shape ``(..., m)``): ``(τ̃, e)`` with ``|τ - τ̃| <= e``.

    ``|τ(L) - τ(L̃)| = k L0 |L - L̃| / (L L̃)``, plus ``γ_3 |τ|`` for ``k (L - L0) / L``.  The
    bound is infinite (or NaN) where ``L`` is not provably positive.
    """
    cs = _consts(robot)
    L, eL = _length_mr(cs, enc, u)
    tau = cs.k * (L - cs.L0) / L
    Llo = L - eL
    e = (cs.kL0 * (1.0 + 4 * U) * SAFE) * eL / (Llo * L) + (2.0 * _G3 * SAFE) * np.abs(tau)
    if not (Llo.min() > 0.0):
        e = np.where(Llo > 0.0, e, np.inf)
    return tau, e


def tension_range(
    robot: Robot, enc: PoseEnclosure, ulo: np.ndarray, uhi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Rigorous bounds of ``τ`` over ``u ∈ [ulo, uhi]`` (eq. 6 increases with ``u``, ``K > 0``)."""
    tlo, elo = tension_mr(robot, enc, ulo)
    thi, ehi = tension_mr(robot, enc, uhi)
    return np.nextafter(tlo - elo, -np.inf), np.nextafter(thi + ehi, np.inf)


def dtension_range(
    robot: Robot, enc: PoseEnclosure, ulo: np.ndarray, uhi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``dτ/du = k L0 K / L²`` over ``u ∈ [ulo, uhi]`` as midpoint-radius ``(c, r)``.

    ``L`` increases with ``u``, so the derivative is largest at ``ulo`` and smallest at ``uhi``.
    """
    cs = _consts(robot)
    Llo, elo = _length_mr(cs, enc, ulo)
    Lhi, ehi = _length_mr(cs, enc, uhi)
    lmin = (Llo - elo) * (1.0 - 8.0 * U)
    lmax = (Lhi + ehi) * (1.0 + 8.0 * U)
    dhi = cs.kL0K / (lmin * lmin) * (1.0 + 16.0 * U)
    dlo = cs.kL0K / (lmax * lmax) * (1.0 - 16.0 * U)
    if not (lmin.min() > 0.0):
        dhi = np.where(lmin > 0.0, dhi, np.inf)
    c = 0.5 * (dlo + dhi)
    r = (0.5 * SAFE) * (dhi - dlo) + (4.0 * U) * c
    return c, r


def residual_mr(
    enc: PoseEnclosure, tau: np.ndarray, tau_err: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``f = H τ + w_g`` for enclosed tensions ``(..., m)``: ``(f̃, e)`` of shape ``(..., w)``.

    ``|Hτ - H̃τ̃| <= E_H |τ̃| + (|H̃| + E_H) e_τ``; rounding ``γ_{m+1} (|H̃||τ̃| + |w̃|)``.
    """
    Ht, eHt = enc.Ht, _bound(enc.Ht_err)
    aHt = np.abs(Ht)
    g = gamma(Ht.shape[0] + 1)
    f = tau @ Ht + enc.wg
    ewg = _bound(enc.wg_err)
    e = np.abs(tau) @ (eHt + g * aHt) + tau_err @ (aHt + eHt) + (ewg + g * np.abs(enc.wg))
    return f, e * SAFE + UNDERFLOW


def jacobian_mr(
    enc: PoseEnclosure, cols: np.ndarray, dc: ArrayLike, dr: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """``J = H[:, cols] diag(dτ/du)`` with the derivative enclosed by ``(dc, dr)`` ``(..., n)``.

    Returns ``(Jc, Jr)`` of shape ``(..., w, n)``.
    """
    Hs = enc.Ht[cols].T
    eHs = _bound(enc.Ht_err)[cols].T
    dc = np.asarray(dc)[..., None, :]
    dr = np.asarray(dr)[..., None, :]
    Jc = Hs * dc
    Jr = np.abs(Hs) * dr + eHs * (np.abs(dc) + dr) + (2.0 * U) * np.abs(Jc)
    return Jc, Jr * SAFE + UNDERFLOW


@dataclass(frozen=True, kw_only=True)
class FreeWires:
    """What :class:`SquareSystem` needs from the robot for one set of free wires ``S``,
    computed once (:func:`free_wires`): the selection (a slice when ``S`` is a run of wires,
    so that taking the columns is a view, not a copy), the identity, the bounds' constants."""

    free: np.ndarray  # (n,) 0-based free wires
    sel: slice | np.ndarray  # the same wires as a slice when contiguous
    eye: np.ndarray  # (n, n) identity
    Kr: np.ndarray  # K_S (1 + 4u): the growth of L over a box of radius r
    Chi: np.ndarray  # k L0 K (1 + 16u) / (1 - 8u)²: τ' = Chi / L² rounded up
    Clo: np.ndarray  # k L0 K (1 - 16u) / (1 + 8u)²: rounded down
    CkL0: np.ndarray  # (m,) k L0 (1 + 4u) SAFE: the bound of τ(L) - τ(L̃)
    kS: np.ndarray  # k_S
    aS: np.ndarray  # k L0 / K over S (eq. 5)
    iKS: np.ndarray  # 1 / K_S
    g: np.ndarray  # γ_n (0-d, as the three below)
    gmS: np.ndarray  # γ_{m+2} SAFE: the rounding of f = H τ + w_g
    kq: np.ndarray  # SAFE (1 + γ_{n+4}): the rounding of the Krawczyk radius
    c0: np.ndarray | None  # the error of w_g in f when w_g does not depend on the pose
    #: (K, k, L0, CkL0, Kr, Chi, Clo) as two rows each, for a batch of two boxes (Algorithm
    #: 2's): a (2, n) array with a (2, n) one costs a third of one with an (n,) broadcast
    two: tuple[np.ndarray, ...]


def free_wires(robot: Robot, free: ArrayLike) -> FreeWires:
    """The :class:`FreeWires` of ``free``, computed once per robot and set of free wires."""
    cs = _consts(robot)
    S = np.asarray(free, dtype=np.int64)
    key = S.tobytes()
    fw = cs.per_free.get(key)
    if fw is None:
        fw = cs.per_free[key] = _free_wires(cs, S)
    return fw


def _free_wires(cs: _Consts, S: np.ndarray) -> FreeWires:
    n = S.size
    run = n > 0 and bool(np.array_equal(S, np.arange(S[0], S[0] + n)))
    Chi = cs.kL0K[S] * ((1.0 + 16.0 * U) / (1.0 - 8.0 * U) ** 2)
    Clo = cs.kL0K[S] * ((1.0 - 16.0 * U) / (1.0 + 8.0 * U) ** 2)
    gmS = gamma(cs.A.shape[0] + 2) * SAFE
    Kr = cs.K[S] * (1.0 + 4.0 * U)
    c0 = None
    if cs.wg_const is not None:
        wg, ewg = cs.wg_const
        c0 = ewg + gmS * np.abs(wg) + UNDERFLOW
    return FreeWires(
        free=S,
        sel=slice(int(S[0]), int(S[0]) + n) if run else S,
        eye=np.eye(n),
        Kr=Kr,
        Chi=Chi,
        Clo=Clo,
        CkL0=cs.kL0 * ((1.0 + 4.0 * U) * SAFE),
        kS=cs.k[S],
        aS=cs.kL0[S] / cs.K[S],
        iKS=1.0 / cs.K[S],
        g=np.array(gamma(n)),
        gmS=np.array(gmS),
        kq=np.array(SAFE * (1.0 + gamma(n + 4))),
        c0=c0,
        two=tuple(
            np.array((x, x))
            for x in (cs.K, cs.k, cs.L0, cs.kL0 * ((1.0 + 4.0 * U) * SAFE), Kr, Chi, Clo)
        ),
    )


# The constants of the per-pose arithmetic below as 0-d arrays: an array times a 0-d array
# is the same float as times the Python float, without the conversion of the scalar (0.21
# against 0.37 us for a (2, 6) product)
_NINF = np.array(-np.inf)
_PINF = np.array(np.inf)
_ZERO = np.array(0.0)
_HALF = np.array(0.5)
_HALF_SAFE = np.array(0.5 * SAFE)
_R4 = np.array(1.0 + 4.0 * U)  # one relative rounding
_A4 = np.array(4.0 * U)
_A4S = np.array(4.0 * U * SAFE)
_A2S = np.array(2.0 * U * SAFE)
_G3S = np.array(2.0 * _G3 * SAFE)
_SAFE = np.array(SAFE)
_TINY = np.array(UNDERFLOW)


class SquareSystem:
    """The square system in the controls of the ``free`` wires, the other wires fixed.

    ``f(u) = H τ(u) + w_g`` has the Jacobian ``J = H_S diag(τ'_S)`` in the free controls
    (``H_S = H[:, free]``, ``w`` columns).  The preconditioner of the Krawczyk operator is
    ``Y = diag(1/d_c) G`` with ``G ≈ H_S⁻¹`` (a float matrix, computed once per pose and shared
    by every box) and ``d_c`` the midpoint of ``τ'`` over the box.  Writing ``G H_S = I + Δ₀``
    with ``|Δ₀| <= Δ = |fl(G H̃_S) - I| + γ_w |G||H̃_S| + |G| E_S``::

        |I - Y J|_ij <= δ_ij d_r,i / d_c,i + Δ_ij (d_c,j + d_r,j) / d_c,i

    so ``(I - Y J)(X - c)`` costs two matrix-vector products per box instead of a batched
    ``w × w`` inverse and three matrix products (:func:`krawczyk_mr`; tests check both
    agree).  ``Y`` is used only through these bounds; any ``Y`` is sound.
    """

    def __init__(
        self,
        robot: Robot,
        enc: PoseEnclosure,
        free: ArrayLike | FreeWires,
    ) -> None:
        self._cs = _consts(robot)
        self.robot = robot
        self.enc = enc
        fw = self.fw = free if isinstance(free, FreeWires) else free_wires(robot, free)
        self.free = fw.free
        sel = fw.sel
        Ht = enc.Ht
        if Ht.shape[1] != fw.free.size:
            raise ValueError("the free wires must make the system square")
        eHt = _bound(enc.Ht_err)
        Hs = Ht[sel].T
        # LAPACK's gesv on (H_S, I), as np.linalg.inv does, without its wrapper (~3 us)
        _, _, G, info = _dgesv(Hs, fw.eye)
        if info > 0:
            raise np.linalg.LinAlgError("Singular matrix")
        # C order, as np.linalg.inv returns it: BLAS takes another path (other floats) for a
        # Fortran-ordered G in G @ x
        self.G = G = np.ascontiguousarray(G)
        self.Gt = G.T
        aG = np.abs(G)
        self.aGt = aG.T
        aHt = np.abs(Ht)
        GH = G @ Hs - fw.eye  # G H_S - I (x - 0 is x: the same floats as the diagonal alone)
        self.DeltaT = ((np.abs(GH) * _R4 + aG @ (fw.g * aHt[sel].T + eHt[sel].T)) * _SAFE + _TINY).T
        self._A1 = eHt + fw.gmS * aHt
        self._A2 = (aHt + eHt) * _SAFE
        c0 = fw.c0
        if c0 is None:
            c0 = _bound(enc.wg_err) + fw.gmS * np.abs(enc.wg) + _TINY
        self._c0 = c0
        #: ``k`` of the free wires (a tension of the square system must stay below it)
        self.k_free = fw.kS
        self._WS = enc.W[sel]

    def controls(self, tau_S: np.ndarray) -> np.ndarray:
        """Eq. (5) for the free wires, in floating point (a candidate, no bound)."""
        fw = self.fw
        return fw.aS / (fw.kS - tau_S) - self._WS * fw.iKS

    def tensions(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Float tensions at ``u`` ``(B, m)`` with error bounds, and ``L``, ``eL`` (eq. 2, 6)."""
        cs, enc, fw = self._cs, self.enc, self.fw
        if u.shape[0] == 2:
            K, k, L0, CkL0 = fw.two[:4]
        else:
            K, k, L0, CkL0 = cs.K, cs.k, cs.L0, fw.CkL0
        Ku = u * K
        L = enc.W + Ku
        eL = _bound(enc.W_err) + _A2S * (np.abs(Ku) + np.abs(L))
        tau = k * (L - L0) / L
        Llo = L - eL
        etau = CkL0 * eL / (Llo * L) + _G3S * np.abs(tau)
        if not (np.minimum.reduce(Llo, axis=None) > 0.0):
            etau = np.where(Llo > 0.0, etau, np.inf)
        return tau, etau, L, eL

    def residual(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Float tensions at ``u`` ``(B, m)`` and the enclosure ``(fc, fr)`` of ``f(u)``."""
        tau, etau, _, _ = self.tensions(u)
        fc = tau @ self.enc.Ht + self.enc.wg
        fr = np.abs(tau) @ self._A1 + etau @ self._A2 + self._c0
        return tau, fc, fr

    def krawczyk(self, u: np.ndarray, rad: np.ndarray) -> tuple[np.ndarray, ...]:
        """Krawczyk test on ``X = [u_S - rad, u_S + rad]`` (``u`` ``(B, m)``, fixed wires exact).

        Returns ``(xlo, xhi, klo, khi, proven, tau, fc)`` over the free wires (``tau``, ``fc``:
        float tensions and residual at ``u``).
        """
        fw = self.fw
        sel = fw.sel
        Kr, Chi, Clo = fw.two[4:] if u.shape[0] == 2 else (fw.Kr, fw.Chi, fw.Clo)
        tau, etau, L, eL = self.tensions(u)
        fc = tau @ self.enc.Ht + self.enc.wg
        fr = np.abs(tau) @ self._A1 + etau @ self._A2 + self._c0
        # the free wires' columns copied: arithmetic on a strided (2, n) view costs three
        # times as much (0.67 against 0.2 us)
        uc = u[:, sel].copy()
        xlo = np.nextafter(uc - rad, _NINF)
        xhi = np.nextafter(uc + rad, _PINF)
        r = np.maximum(xhi - uc, uc - xlo) * _R4
        # τ' = k L0 K / L² over the box: L ∈ L(u_S) ± (eL + K r)
        Ls = L[:, sel].copy()
        eLs = eL[:, sel] + Kr * r
        lo = Ls - eLs
        hi = Ls + eLs
        dhi = Chi / (lo * lo)
        dlo = Clo / (hi * hi)
        if not (np.minimum.reduce(lo, axis=None) > 0.0):
            dhi = np.where(lo > 0.0, dhi, np.inf)
        dc = _HALF * (dlo + dhi)
        dr = _HALF_SAFE * (dhi - dlo) + _A4 * dc
        # K(X) = c - Y f(c) + (I - Y J)(X - c) with Y = diag(1/dc) G:
        # |Y f(c) - bc| + |(I - Y J)(X - c)| <= q / dc + rounding
        q = (fr + fw.g * np.abs(fc)) @ self.aGt + dr * r + ((dc + dr) * r) @ self.DeltaT
        bc = (fc @ self.Gt) / dc
        ce = uc - bc
        rr = fw.kq * (q / dc) + _A4S * (np.abs(uc) + np.abs(bc)) + _TINY
        klo = np.nextafter(ce - rr, _NINF)
        khi = np.nextafter(ce + rr, _PINF)
        proven = np.logical_and.reduce((klo > xlo) & (khi < xhi), axis=1)
        return xlo, xhi, klo, khi, proven, tau, fc
