"""Local minima of the potential energy: where a robot at rest can be, found fast in floats.

The elastic wires of MARIONET (Merlet 2007, eqs. 1, 2, 6) store the energy
``E_i = k_i (L_i - L0_i ln L_i)`` with ``L_i = ρ_i + V_i + K_i u_i``: its derivative with
respect to ``ρ_i`` is the tension ``τ_i = k_i (L_i - L0_i) / L_i``.  A slack wire
(``L_i < L0_i``) pulls nothing: ``E_i`` is then constant.  With the weight ``W = m g``
acting at the centre of mass ``G``, the potential energy of a pose ``(p, R)`` is

    U(p, R) = Σ_i E_i(ρ_i(p, R)) - W · G(p, R),   ρ_i = |A_i - p - R b_i|,  G = p + R c,

and the equilibrium equations (eq. 3) are ``∇U = 0``.  A *stable* equilibrium -- the pose a
robot at rest is in -- is a local minimum of ``U``.  Its gradient, for a small rotation
``δω`` of the platform about ``p`` in world axes (``δB_i = δω × r_i``, ``r_i = R b_i``):

    ∂U/∂p = Σ_i τ_i n_i - W,   ∂U/∂ω = Σ_i τ_i r_i × n_i - (R c) × W,   n_i = (B_i - A_i)/ρ_i.

:func:`energy_minima` runs a damped Newton descent on ``U`` from many starting
orientations at once (every numpy call takes the whole batch of starts; the Hessian is
the central difference of the exact gradient), and keeps the converged points whose
Hessian is positive definite, whose tensions lie within the limits and whose attachments
lie in the domain.  Nothing here is a proof: these are *seeds*, searched first by the
certified forward kinematics (:mod:`.seeding`), which proves each pose and its stability.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..robot.elastic import tension
from ..robot.geometry import gravity_wrench, wire_geometry, wrenches
from ..robot.model import Robot

__all__ = ["EnergyMinimum", "energy_minima", "start_orientations"]


@dataclass(frozen=True, kw_only=True)
class EnergyMinimum:
    """A float local minimum of ``U``: position, rotation, tensions, smallest eigenvalue of
    the Hessian (in ``(p, ω)`` coordinates) and the gradient's norm there."""

    position: np.ndarray
    rotation: np.ndarray
    tau: np.ndarray
    eig_min: float
    gradient: float


def _skew(w: np.ndarray) -> np.ndarray:
    """``[w]×`` for a batch ``(S, 3)``."""
    z = np.zeros(w.shape[0])
    return np.stack(
        [
            np.stack([z, -w[:, 2], w[:, 1]], axis=-1),
            np.stack([w[:, 2], z, -w[:, 0]], axis=-1),
            np.stack([-w[:, 1], w[:, 0], z], axis=-1),
        ],
        axis=1,
    )


def _rotation_of(w: np.ndarray) -> np.ndarray:
    """``exp([w]×)`` (Rodrigues) for a batch ``(S, 3)``."""
    t = np.linalg.norm(w, axis=1)[:, None, None]
    K = _skew(w)
    small = t < 1e-12
    ts = np.where(small, 1.0, t)
    a = np.where(small, 1.0, np.sin(ts) / ts)
    b = np.where(small, 0.5, (1.0 - np.cos(ts)) / ts**2)
    return np.eye(3) + a * K + b * (K @ K)


def start_orientations(count: int) -> np.ndarray:
    """``count`` rotations spread over SO(3), the identity first (deterministic: unit
    quaternions from a Halton sequence through Shoemake's map)."""

    def halton(i: int, base: int) -> float:
        f, r = 1.0, 0.0
        while i > 0:
            f /= base
            r += f * (i % base)
            i //= base
        return r

    out = [np.eye(3)]
    for i in range(1, count):
        u1, u2, u3 = halton(i, 2), halton(i, 3), halton(i, 5)
        a, b = np.sqrt(1 - u1), np.sqrt(u1)
        w, x = a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2)
        y, z = b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)
        out.append(
            np.array(
                [
                    [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
                ]
            )
        )
    return np.array(out)


class _Energy:
    """``U`` and ``∇U`` of one robot at one control vector, for batches of poses."""

    def __init__(self, robot: Robot, u: np.ndarray):
        self.r = robot
        self.u = u

    def value(self, p, R) -> np.ndarray:
        r = self.r
        rho = wire_geometry(r, p, R)[0]
        L = np.maximum(rho + r.V + r.K * self.u, r.L0)  # slack: E stays at its value at L0
        E = r.k * (L - r.L0 * np.log(L))
        G = p + R @ r.com
        return E.sum(axis=1) - G @ r.weight

    def gradient(self, p, R) -> np.ndarray:
        """``∇U = -(H τ + w_g)``: the net wrench on the platform (eq. 3), negated, with the
        tension of a slack wire 0."""
        rho, n, CB = wire_geometry(self.r, p, R)
        t = np.maximum(tension(self.r, rho, self.u), 0.0)
        H = wrenches(n, CB, self.r.dof)
        return -(np.einsum("swm,sm->sw", H, t) + gravity_wrench(self.r, R))

    def moved(self, p, R, step):
        return p + step[:, :3], _rotation_of(step[:, 3:]) @ R

    def hessian(self, p, R, h: float = 1e-6) -> np.ndarray:
        """Central differences of the exact gradient in ``(p, ω)``; symmetrised."""
        S = p.shape[0]
        H = np.empty((S, 6, 6))
        for j in range(6):  # 6 batched gradient pairs, each over every start
            e = np.zeros((S, 6))
            e[:, j] = h
            gp = self.gradient(*self.moved(p, R, e))
            gm = self.gradient(*self.moved(p, R, -e))
            H[:, :, j] = (gp - gm) / (2 * h)
        return 0.5 * (H + H.transpose(0, 2, 1))


def energy_minima(
    robot: Robot,
    u,
    *,
    starts: int = 48,
    iterations: int = 80,
    tol: float = 1e-9,
) -> list[EnergyMinimum]:
    """Local minima of ``U`` at control ``u`` from ``starts`` orientations (the robot's
    domain centre as the start position), distinct, with the tensions within the limits
    and the attachments in the domain; most stable (smallest energy) first.

    A damped Newton descent: ``(H + λ I) δ = -∇U`` with ``λ`` making the matrix positive
    definite, then halving ``δ`` until ``U`` decreases.  Spatial robots only (dof 6).
    """
    if robot.dof != 6:
        raise ValueError("energy_minima: spatial (dof 6) robots only")
    u = np.asarray(u, dtype=float).ravel()
    en = _Energy(robot, u)
    R = start_orientations(starts)
    p = np.tile(robot.domain.mean(axis=1), (starts, 1))
    U = en.value(p, R)
    scale = np.linalg.norm(robot.weight) + float(np.max(robot.tau_max)) + 1.0
    act = np.arange(starts)  # the starts still descending
    for _ in range(iterations):
        g = en.gradient(p[act], R[act])
        moving = np.linalg.norm(g, axis=1) > tol * scale
        act, g = act[moving], g[moving]
        if not act.size:
            break
        H = en.hessian(p[act], R[act])
        lam = np.maximum(0.0, -np.linalg.eigvalsh(H)[:, 0]) * 1.1 + 1e-9 * scale
        step = -np.linalg.solve(H + lam[:, None, None] * np.eye(6), g[..., None])[..., 0]
        step[:, 3:] = np.clip(step[:, 3:], -0.5, 0.5)  # at most ~30° a turn
        alpha = np.ones(act.size)
        for _ in range(30):  # backtracking, the whole batch at once
            pn, Rn = en.moved(p[act], R[act], alpha[:, None] * step)
            Un = en.value(pn, Rn)
            bad = ~(Un <= U[act])
            if not bad.any():
                break
            alpha = np.where(bad, 0.5 * alpha, alpha)
        ok = Un <= U[act]
        p[act[ok]], R[act[ok]], U[act[ok]] = pn[ok], Rn[ok], Un[ok]
        act = act[ok]  # a start that cannot descend any more has stopped
    g = np.linalg.norm(en.gradient(p, R), axis=1)
    eig = np.linalg.eigvalsh(en.hessian(p, R))[:, 0]
    rho, _, CB = wire_geometry(robot, p, R)
    B = p[:, None, :] + CB
    tau = tension(robot, rho, u)
    dom = robot.domain
    inside = np.all((B >= dom[:, 0]) & (B <= dom[:, 1]), axis=(1, 2))
    taut = np.all((tau >= robot.tau_min) & (tau <= robot.tau_max), axis=1)
    keep = (g <= 1e-6 * scale) & (eig > 0.0) & inside & taut
    out: list[EnergyMinimum] = []
    for s in np.flatnonzero(keep)[np.argsort(U[keep])]:
        if any(
            np.linalg.norm(m.position - p[s]) < 1e-4 and np.linalg.norm(m.rotation - R[s]) < 1e-4
            for m in out
        ):
            continue
        out.append(
            EnergyMinimum(
                position=p[s].copy(),
                rotation=R[s].copy(),
                tau=tau[s].copy(),
                eig_min=float(eig[s]),
                gradient=float(g[s]),
            )
        )
    return out
