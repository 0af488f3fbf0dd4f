"""The maximum isotropic force: at one pose, and vectorised over many poses.

**Definition** (all dofs).  With ``H`` the wrench matrix, force rows ``f`` and moment rows
``m`` (:mod:`.loads`), bias point ``x0 = -w_ext,f`` and required moment ``μ = -w_ext,m``,

    f_min = largest r such that the ball B(x0, r) ⊂ F(μ) = {H_f τ : τ in box, H_m τ = μ},

the largest force that the platform resists **in every direction** while its moment stays
balanced.  For a point platform (dof 2) there are no moment rows, ``F = {H τ}`` is the
paper's operational force polytope and, without load, ``f_min = min_k 1/||v_k||``
(eq. 19) = ``min_k d_k / ||n_k||`` (signed distance from the origin to the facet planes).

**Exact formula used everywhere** (maps, certificates, single poses).  Let ``c_k`` be the
normals of the zonotope ``W = {H τ}`` (:func:`~.polytope.zonotope_facets`, both signs) with
offsets ``d_k``.  ``W = ∩_k {c_k · x ≤ d_k}`` when ``W`` is full-dimensional, so the section
is ``F(μ) = ∩_k {c_k,f · f ≤ d_k - c_k,m · μ}`` and a ball ``B(x0, r)`` lies in it iff
``r ||c_k,f|| ≤ d_k - c_k,f·x0 - c_k,m·μ = d_k + c_k · w_ext`` for every ``k``:

    f_min = min_k (d_k + c_k · w_ext) / ||c_k,f||,

a finite minimum over ``2 C(m, w-1)`` closed-form terms (a term with ``c_k,f = 0`` is
``+inf`` if its numerator is ``≥ 0`` and ``-inf`` otherwise: the required moment alone is
out of reach).  This is exact, not sampled: the section is a polytope and every one of its
facets lies in a facet plane of ``W``; terms of planes that do not touch ``F(μ)`` are larger
than the inscribed radius and do not change the minimum.

* ``f_min ≥ 0``: the bias point is in ``F(μ)`` (the pose is in the wrench-feasible
  workspace) and ``f_min`` is the inscribed radius, status ``"inside"``;
* ``f_min < 0``: the bias point is outside (the pose cannot even balance the load, section
  IV-B of the paper), status ``"outside"``; ``-f_min`` is then the largest violation of a
  facet inequality (a facet-plane distance, not the Euclidean distance to ``F``);
* ``W`` flat (``rank H < w``: fewer wires than wrench components, e.g. the 4-wire
  almost-planar robot with dof 6, or aligned wires): no ball fits, status ``"degenerate"``,
  ``f_min`` is NaN in maps; at a single pose it is reported as 0 if the load can be
  balanced (a linear program) and ``None`` otherwise.

dof 3 uses the same section (force at zero extra moment about the platform origin; no
gravity in the plane, so ``μ = 0`` and ``x0 = 0``); dof 6 the 3-D force section at the
moment required by gravity (MARIONET).  At a single pose the section is also computed
independently as a hull of vertices (:mod:`.section`) and reported with its facets.

Vectorised evaluation (:func:`isotropic_values`): for dof 2 and 3 the ``C(m, w-1)``
generalised cross products are computed directly (:func:`~.polytope.zonotope_facets_t`);
for dof 6 the same facets are obtained in *basis form* from one ``6 × 6`` inverse per pose
(:func:`_index_batch_basis`), about 7 times faster for MARIONET.  Both give the same
values (tested) up to rounding.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from enum import StrEnum
from itertools import combinations
from math import comb
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from ..inputs import check_count, checked
from ..interval.rounding import down
from ..robot import Robot, wrench_matrix
from ..robot.inputs import IsotropicOptions, as_pose
from ..robot.statics import max_margin_tensions
from .ellipse import CentredEllipsoid, largest_centred_ellipsoid
from .krut import krut_polytope
from .loads import external_wrench, force_rows
from .polytope import (
    NORMAL_TOL,
    FlatPolytopeError,
    ForcePolytope,
    hyperplane_shifting,
    zonotope_facets_t,
)
from .section import force_section
from .wedge import basis_groups, wedge_float

__all__ = [
    "IsotropicForceResult",
    "isotropic_force",
    "isotropic_values",
    "set_force_floor",
    "section_index",
    "set_force_bound",
    "INSIDE",
    "OUTSIDE",
    "DEGENERATE",
    "STATUS_NAMES",
    "IsotropicStatus",
]

INSIDE, OUTSIDE, DEGENERATE = 0, 1, 2
#: positions per batch of :func:`set_force_floor`
FLOOR_BATCH = 256


class IsotropicStatus(StrEnum):
    """Where the pose is (module docstring); the int8 codes above name the same cases."""

    INSIDE = "inside"
    OUTSIDE = "outside"
    DEGENERATE = "degenerate"


STATUS_NAMES = {
    INSIDE: IsotropicStatus.INSIDE,
    OUTSIDE: IsotropicStatus.OUTSIDE,
    DEGENERATE: IsotropicStatus.DEGENERATE,
}


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` with ``den = 0`` mapped to ``+inf`` (num ≥ 0) or ``-inf`` (num < 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = num / den
    zero = den == 0
    if np.any(zero):
        r = np.where(zero, np.where(num >= 0, np.inf, -np.inf), r)
    return r


def section_index(
    normals: ArrayLike, offsets: ArrayLike, w_ext: ArrayLike, n_force: int
) -> tuple[float, int]:
    """``min_k (d_k + n_k · w_ext) / ||n_k,f||`` over given facets of ``W``; and the argmin."""
    normals = np.asarray(normals, dtype=float)
    num = np.asarray(offsets, dtype=float) + normals @ np.asarray(w_ext, dtype=float)
    den = np.linalg.norm(normals[:, :n_force], axis=1)
    r = _ratio(num, den)
    k = int(np.argmin(r))
    return float(r[k]), k


def _index_batch(Ht, wt, tau_min, tau_max, nf: int):
    """Core of :func:`isotropic_values`, batch last: ``Ht`` ``(w, m, P)``, ``wt`` ``(w, P)``.

    Returns ``f (P,)``, ``status (P,)`` and the unit force normal of the limiting facet
    ``(nf, P)``.
    """
    P = Ht.shape[-1]
    C, D, dp, dm = zonotope_facets_t(Ht, tau_min, tau_max)
    K = C.shape[1]
    if K == 0:  # fewer wires than w - 1: no facet at all
        return np.full(P, np.nan), np.full(P, DEGENERATE, np.int8), np.full((nf, P), np.nan)
    cw = np.einsum("wkp,wp->kp", C, wt)
    cn = np.sqrt(np.einsum("wkp,wkp->kp", C, C))
    valid = cn > NORMAL_TOL * np.max(cn, axis=0)
    cf = np.sqrt(np.einsum("wkp,wkp->kp", C[:nf], C[:nf]))
    both = np.concatenate([_ratio(dp + cw, cf), _ratio(dm - cw, cf)])  # (2K, P)
    both = np.where(np.concatenate([valid, valid]), both, np.inf)
    k = np.argmin(both, axis=0)
    cols = np.arange(P)
    f = both[k, cols]
    scale = np.max(np.abs(Ht), axis=(0, 1)) + 1.0
    flat = ~np.any(valid[:, None, :] & (np.abs(D) > NORMAL_TOL * scale), axis=(0, 1))
    flat |= np.isnan(f)
    f = np.where(flat, np.nan, f)
    status = np.where(flat, DEGENERATE, np.where(f >= 0, INSIDE, OUTSIDE)).astype(np.int8)
    sign = np.where(k < K, 1.0, -1.0)
    cfk = C[:nf, k % K, cols] * sign
    nrm = np.sqrt(np.sum(cfk * cfk, axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = np.where(nrm > 0, cfk / nrm, np.nan)
    return f, status, direction


def _index_batch_basis(Ht, wt, tau_min, tau_max, nf: int):
    """:func:`_index_batch` in basis form (rigid platforms; same results, fewer operations).

    With ``w`` independent columns ``B0`` and ``Y = H_B0^{-1} H_N``, the normal of the facet
    subset ``S`` is ``λ^T H_B0^{-1}[F]`` (``F = B0 - S``, ``λ`` the generalised cross product of
    ``Y[F, S ∩ N]``), and ``c·h_l`` is ``λ_l`` on ``F``, ``λ·Y[F, l]`` on ``N - S``, 0 on ``S``
    (see :func:`certsolve.force.enclosure._rigid`, which proves the same formula over boxes).
    One ``w × w`` inverse per pose replaces ``C(m, w-1)`` generalised cross products.
    """
    w, m, P = Ht.shape
    H = np.moveaxis(Ht, -1, 0)  # (P, w, m)
    Hn = H / np.maximum(np.linalg.norm(H, axis=1, keepdims=True), 1e-300)
    bases = list(combinations(range(m), w))
    choice = np.zeros(P, dtype=np.int64)
    good = np.abs(np.linalg.det(Hn[:, :, list(bases[0])])) > 1e-3
    if not good.all():
        bad = np.nonzero(~good)[0]
        dets = np.stack([np.abs(np.linalg.det(Hn[bad][:, :, list(b)])) for b in bases])
        dets = np.where(np.isfinite(dets), dets, 0.0)
        choice[bad] = np.argmax(dets, axis=0)
        good[bad] = np.max(dets, axis=0) > 1e-12
    mid = 0.5 * (np.asarray(tau_min, float) + np.asarray(tau_max, float))
    rad = 0.5 * (np.asarray(tau_max, float) - np.asarray(tau_min, float))
    f = np.full(P, np.nan)
    direction = np.full((nf, P), np.nan)
    for ib, b0 in enumerate(bases):
        sel = np.nonzero(good & (choice == ib))[0]
        if sel.size == 0:
            continue
        nn = [i for i in range(m) if i not in b0]
        Hs = H[sel]
        G = np.linalg.inv(Hs[:, :, list(b0)])  # (p, w, w)
        Yt = np.transpose(G @ Hs[:, :, nn], (1, 2, 0))  # (w, e, p)
        zt = np.einsum("pij,pj->ip", G, np.moveaxis(wt[:, sel], 0, 1))  # (w, p)
        Gft = np.transpose(G[:, :, :nf], (2, 1, 0))  # (nf, w, p): force columns of G's rows
        ratios, normals = [], []
        for F, T, R in basis_groups(m, w, tuple(b0)):
            Kt, t = T.shape
            if t == 0:
                lam = np.ones((1, Kt, sel.size))
            else:
                lam = wedge_float(Yt[F.T[:, None, :], T.T[None, :, :]])  # (t+1, Kt, p)
            cols = [np.asarray(b0)[F.T]]
            Ds = [lam]
            if R.shape[1]:
                YFR = Yt[F.T[:, None, :], R.T[None, :, :]]  # (t+1, e-t, Kt, p)
                Ds.append(np.einsum("fkp,frkp->rkp", lam, YFR))
                cols.append(np.asarray(nn)[R.T])
            D = np.concatenate(Ds)  # (e+1, Kt, p)
            c = np.concatenate(cols)[..., None]  # (e+1, Kt, 1)
            lin = np.sum(D * mid[c], axis=0)
            spread = np.sum(np.abs(D) * rad[c], axis=0)
            cw = np.einsum("fkp,fkp->kp", lam, zt[F.T])
            cfv = np.einsum("fkp,nfkp->nkp", lam, Gft[:, F.T])  # (nf, Kt, p)
            cf = np.sqrt(np.sum(cfv * cfv, axis=0))
            lam_n = np.sqrt(np.sum(lam * lam, axis=0))
            ok = lam_n > NORMAL_TOL * np.maximum(1.0, np.max(np.abs(Yt), axis=(0, 1)))
            rp = np.where(ok, _ratio(spread + lin + cw, cf), np.inf)
            rm = np.where(ok, _ratio(spread - lin - cw, cf), np.inf)
            ratios += [rp, rm]
            normals += [cfv, -cfv]
        both = np.concatenate(ratios)  # (2K, p)
        nrm = np.concatenate(normals, axis=1)  # (nf, 2K, p)
        k = np.argmin(both, axis=0)
        cols_p = np.arange(sel.size)
        f[sel] = both[k, cols_p]
        v = nrm[:, k, cols_p]
        vn = np.sqrt(np.sum(v * v, axis=0))
        with np.errstate(invalid="ignore", divide="ignore"):
            direction[:, sel] = np.where(vn > 0, v / vn, np.nan)
    flat = np.isnan(f)
    status = np.where(flat, DEGENERATE, np.where(f >= 0, INSIDE, OUTSIDE)).astype(np.int8)
    return f, status, direction


@overload
def isotropic_values(
    robot: Robot,
    positions: ArrayLike,
    rotations: ArrayLike | None = None,
    external: ArrayLike | None = None,
    chunk: int | None = None,
    return_direction: Literal[False] = False,
) -> tuple[np.ndarray, np.ndarray]: ...


@overload
def isotropic_values(
    robot: Robot,
    positions: ArrayLike,
    rotations: ArrayLike | None = None,
    external: ArrayLike | None = None,
    chunk: int | None = None,
    *,
    return_direction: Literal[True],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def isotropic_values(
    robot: Robot,
    positions: ArrayLike,
    rotations: ArrayLike | None = None,
    external: ArrayLike | None = None,
    chunk: int | None = None,
    return_direction: bool = False,
) -> tuple[np.ndarray, np.ndarray] | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``f_min`` (see the module docstring) for ``P`` poses, without a Python loop per pose.

    ``positions`` ``(P, d)``; ``rotations`` ``(P, d, d)`` or one ``(d, d)`` matrix (identity
    if omitted); ``external`` an optional extra constant wrench ``(w,)``.  Returns
    ``(f_min (P,), status (P,) int8)`` and, if ``return_direction``, the unit force normal
    of the limiting facet ``(P, nf)`` (the weakest disturbance direction is its opposite).
    """
    p = np.asarray(positions, dtype=float)
    if p.ndim == 1:
        p = p[None]
    d = robot.dim
    if p.shape[-1] != d:
        raise ValueError(f"positions: expected {d} coordinates per pose, got {p.shape[-1]}")
    R = np.eye(d) if rotations is None else np.asarray(rotations, dtype=float)
    if R.ndim == 2:
        R = np.broadcast_to(R, (p.shape[0], d, d))
    nf = force_rows(robot)
    P = p.shape[0]
    if chunk is None:  # keep the temporaries of one chunk in cache (~2 MB per array)
        w = robot.wrench_dim
        chunk = (
            4096
            if robot.dof == 6 and robot.m >= 6
            else max(64, (1 << 18) // max(1, comb(robot.m, w - 1) * w * w))
        )
    if chunk < 1:
        raise ValueError("chunk must be at least 1")
    out = np.empty(P)
    status = np.empty(P, dtype=np.int8)
    direction = np.full((P, nf), np.nan) if return_direction else None
    for s in range(0, P, chunk):
        sl = slice(s, min(P, s + chunk))
        H = wrench_matrix(robot, p[sl], R[sl])
        w_ext = external_wrench(robot, R[sl], external)
        # dof 6: one 6x6 inverse per pose beats C(m, 5) 5x5 cross products (~7x for MARIONET)
        core = _index_batch_basis if robot.dof == 6 and robot.m >= 6 else _index_batch
        res = core(np.moveaxis(H, 0, -1), w_ext.T, robot.tau_min, robot.tau_max, nf)
        out[sl], status[sl] = res[0], res[1]
        if direction is not None:
            direction[sl] = res[2].T
    if direction is not None:
        return out, status, direction
    return out, status


@dataclass
class IsotropicForceResult:
    """The maximum isotropic force at one pose, its polytope(s) and how it was obtained."""

    robot: str
    dof: int
    pose: list[float]
    isotropic_force: float | None
    status: IsotropicStatus
    centre: np.ndarray  # bias point x0 = -w_ext,f in force space
    required_moment: np.ndarray | None  # μ = -w_ext,m (None for dof 2)
    external_wrench: np.ndarray
    weakest_direction: np.ndarray | None  # unit disturbance direction resisted least
    algorithm: str
    polytope: ForcePolytope | None  # force polytope (dof 2) or force section F(μ)
    wrench_polytope: ForcePolytope | None  # the full wrench zonotope (dof 3, 6)
    section_check: float | None = None  # inscribed radius from the hull of F(μ) (dof 3, 6)
    feasible: bool | None = None
    ellipse: CentredEllipsoid | None = None  # largest centred ellipse (section IV-C)
    time: float = 0.0
    notes: list[str] = field(default_factory=list)
    #: a robot with tolerances: a certified lower bound of the isotropic force of every
    #: robot of the set (:func:`set_force_bound`); ``isotropic_force`` is the nominal one's
    set_force_lo: float | None = None

    @property
    def inside(self) -> bool:
        return self.status == IsotropicStatus.INSIDE

    def to_dict(self) -> dict:
        def lst(a):
            return None if a is None else [float(t) for t in np.asarray(a).reshape(-1)]

        return {
            "robot": self.robot,
            "dof": self.dof,
            "pose": [float(t) for t in self.pose],
            "isotropic_force": self.isotropic_force,
            "status": str(self.status),
            "inside": self.inside,
            "feasible": self.feasible,
            "centre": lst(self.centre),
            "required_moment": lst(self.required_moment),
            "external_wrench": lst(self.external_wrench),
            "weakest_direction": lst(self.weakest_direction),
            "algorithm": self.algorithm,
            "polytope": None if self.polytope is None else self.polytope.to_dict(),
            "wrench_polytope": (
                None if self.wrench_polytope is None else self.wrench_polytope.to_dict()
            ),
            "section_check": self.section_check,
            "ellipse": None if self.ellipse is None else self.ellipse.to_dict(),
            "units": {"force": "N", "moment": "N*cm", "length": "cm", "angle": "deg"},
            "definition": (
                "radius of the largest ball centred at the bias point -w_ext (force part) "
                "inside the force polytope at the moment required by the load; negative: "
                "the pose cannot balance the load"
            ),
            "time": self.time,
            "notes": list(self.notes),
            **({} if self.set_force_lo is None else {"set_force_lo": self.set_force_lo}),
        }


def isotropic_force(
    robot: Robot,
    pose: Any,
    algorithm: str = "shifting",
    external: ArrayLike | None = None,
    section: bool = True,
    ellipse: bool = False,
) -> IsotropicForceResult:
    """The maximum isotropic force at ``pose`` (a :class:`~certsolve.robot.Pose`, or its
    parameters as a list, tuple, array or text).

    ``algorithm``: ``"shifting"`` (hyperplane shifting, default) or ``"krut"`` (the paper's
    six steps; small ``m`` and ``w`` only).  ``external``: optional extra constant wrench.
    ``section``: for dof 3/6, also compute the force section as a hull of vertices (its
    facets are reported and its inscribed radius is ``section_check``).  The inputs are
    checked as ``POST /v1/isotropic`` and ``certsolve isotropic`` check them
    (:class:`~certsolve.robot.inputs.IsotropicOptions`): a value they refuse raises
    :class:`~certsolve.inputs.InputError` naming it.
    """
    t0 = time.perf_counter()
    pose = as_pose(robot.dof, pose)
    opts = checked(
        IsotropicOptions,
        {"pose": pose.params(robot.dof), "algorithm": algorithm, "external": external},
    )
    check_count(opts.external, robot.wrench_dim, "external", "wrench components")
    pos, rot = pose.position, pose.rotation
    nf = force_rows(robot)
    H = wrench_matrix(robot, pos[None], rot[None])[0]
    w_ext = external_wrench(robot, rot[None], external)[0]
    centre = -w_ext[:nf]
    moment = -w_ext[nf:] if robot.dof != 2 else None
    notes: list[str] = []
    poly_full = None
    status = IsotropicStatus.INSIDE
    value: float | None
    direction = None
    feasible = None
    try:
        if not np.all(np.isfinite(H)):
            raise FlatPolytopeError("a wire has zero length at this pose")
        if algorithm == "krut":
            poly_full = krut_polytope(H, robot.tau_min, robot.tau_max)
        else:
            poly_full = hyperplane_shifting(H, robot.tau_min, robot.tau_max)
        value, k = section_index(poly_full.normals, poly_full.offsets, w_ext, nf)
        nk = poly_full.normals[k, :nf]
        direction = -nk / np.linalg.norm(nk) if np.linalg.norm(nk) > 0 else None
        status = IsotropicStatus.INSIDE if value >= 0 else IsotropicStatus.OUTSIDE
        feasible = value >= 0
    except FlatPolytopeError as exc:
        notes.append(str(exc))
        status = IsotropicStatus.DEGENERATE
        tens = max_margin_tensions(H, w_ext, robot.tau_min, robot.tau_max)
        feasible = bool(tens.feasible)
        value = 0.0 if feasible else None
    poly = None
    section_check = None
    if robot.dof == 2:
        poly = poly_full
    elif section and status != IsotropicStatus.DEGENERATE and moment is not None:
        try:
            poly = force_section(H, robot.tau_min, robot.tau_max, moment, nf)
            section_check = poly.signed_distance(centre)
        except ValueError as exc:
            notes.append(f"force section: {exc}")
    ell = None
    if ellipse and poly is not None and value is not None and value > 0:
        try:
            ell = largest_centred_ellipsoid(poly, centre)
        except ValueError as exc:
            notes.append(f"ellipse: {exc}")
    if value is not None and not np.isfinite(value):
        notes.append("the required moment is out of reach: the section is empty")
        value = None
    set_lo: float | None = None
    if robot.toleranced:
        set_lo = set_force_bound(robot, pos, rot, value or 0.0, external)
        notes.append(
            "robot with tolerances: isotropic_force is the nominal robot's; every robot of "
            + (f"the set has at least {set_lo:.6g} N" if set_lo else "the set: not proven > 0")
        )
    return IsotropicForceResult(
        set_force_lo=set_lo,
        robot=robot.name,
        dof=robot.dof,
        pose=pose.params(robot.dof),
        isotropic_force=value,
        status=status,
        centre=centre,
        required_moment=moment,
        external_wrench=w_ext,
        weakest_direction=direction,
        algorithm="krut2004" if algorithm == "krut" else "hyperplane-shifting",
        polytope=poly,
        wrench_polytope=poly_full if robot.dof != 2 else None,
        section_check=section_check,
        feasible=feasible,
        ellipse=ell,
        time=time.perf_counter() - t0,
        notes=notes,
    )


def set_force_floor(
    robot: Robot,
    positions: ArrayLike,
    rotation: ArrayLike | None = None,
    external: ArrayLike | None = None,
) -> np.ndarray:
    """Certified lower bounds ``(P,)`` of the isotropic force over every robot of a robot's
    set at each of the positions ``(P, d)`` (one orientation ``rotation``), in one batch:
    the slack enclosures at ``F = 0`` with the set's interval arrays
    (:func:`.enclosure.slack_enclosures` with ``norms``) give ``f_min >= min_k g_k / |c_k|``
    where every ``g_k >= 0`` (full rank, every wire usable); NaN where that is not proven
    (``f_min >= 0`` may fail for a robot of the set).  One pass, no bisection: at least
    :func:`set_force_bound`'s bisected bound's quality is not claimed (T-16 at (115, 60,
    118): 6.710 N here, 6.756 N bisected)."""
    from .certified import set_bounds
    from .enclosure import slack_enclosures

    P = np.asarray(positions, dtype=float)
    R = None if rotation is None else np.asarray(rotation, dtype=float)
    params = set_bounds(robot)
    out = np.full(P.shape[0], np.nan)
    for i in range(0, P.shape[0], FLOOR_BATCH):  # batches: ~0.2 MB a point on T-16
        p = P[i : i + FLOOR_BATCH].T
        glo, _, full_rank, wires_ok, norms = slack_enclosures(
            robot, p, p, 0.0, external, rotation=R, params=params, norms=True
        )
        proven = np.all(glo >= 0.0, axis=0) & full_rank & wires_ok
        with np.errstate(divide="ignore", invalid="ignore"):
            floor = down(np.min(glo / norms, axis=0))
        out[i : i + FLOOR_BATCH] = np.where(
            proven & np.isfinite(floor), np.maximum(floor, 0.0), np.nan
        )
    return out


def set_force_bound(
    robot: Robot,
    position: np.ndarray,
    rotation: np.ndarray,
    upper: float,
    external: ArrayLike | None = None,
    steps: int = 30,
) -> float:
    """A certified lower bound of the isotropic force at one pose over every robot of a
    robot's set (:mod:`certsolve.robot.tolerance`): the largest ``F`` of a bisection on
    ``(0, upper]`` for which the slack enclosures with the set's interval arrays
    (:func:`.certified.set_bounds`, :func:`.enclosure.slack_enclosures`: the certified
    workspace's test at a point) prove ``f_min >= F`` for all of them; 0 when none is proven.
    ``upper``: the nominal robot's force (the set's least force is at most that)."""
    from .certified import set_bounds
    from .enclosure import slack_enclosures

    params = set_bounds(robot)
    p = np.asarray(position, dtype=float)[:, None]

    def proven(F: float) -> bool:
        glo, _, full_rank, wires_ok = slack_enclosures(
            robot, p, p, F, external, rotation=rotation, params=params
        )
        return bool(np.all(glo >= 0.0) and full_rank[0] and wires_ok[0])

    lo, hi = 0.0, float(upper)
    if not (hi > 0 and proven(1e-9 * hi)):
        return 0.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if proven(mid) else (lo, mid)
    return lo
