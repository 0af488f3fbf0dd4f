"""The robots of the two papers, built programmatically (``examples/robots/*.json``).

MARIONET (Merlet 2007, Table I; lengths in cm): k = 383 N, K = 2, mass 0.02 kg,
u ∈ [-20, 20] cm.  The paper does not give ``V`` and ``L0``; we choose them so that ``u = 0``
in the middle of the workspace:

1. the *middle* is the level pose (no rotation) with the largest tension margin for
   ``τ ∈ [0, 10]`` N -- the pose deepest inside the wrench-feasible workspace, found by a
   5 cm grid search refined with Nelder-Mead and rounded to the cm: ``(111, 58, 107)`` cm
   for the main design (margin 3.85 N), ``(115, 60, 118)`` cm for the T-platform (4.26 N).
   (The centre of the paper's search box, ``(95, 70, 85)``, needs slightly negative tensions
   in wires 1 and 2 with the platform level, so it is not a valid reference pose.)
2. take ``V = 100`` cm for every wire (the fixed length between the opening A and F);
3. compute the max-margin tension distribution ``τ*`` at that pose, with gravity
   (:func:`~certsolve.robot.statics.max_margin_tensions`);
4. set ``L0_i = (ρ_i + V)(1 - τ*_i / k)`` -- eq. (1) with ``u = 0`` -- rounded to 1e-3 cm.

At that pose the commanded ``u`` is then 0 up to the rounding (|u| < 1e-3 cm), and the
strokes ``[-20, 20]`` are centred on the middle of the workspace.  The same recipe gives the
almost-planar and planar robots (centre of their anchor rectangle).

Krut et al. (2004): planar point robots with ``n`` motors on a circle of radius
``l = 1000 mm = 100 cm``, tensions in ``[50, 500]`` N; 3 motors at 30°, 150°, 270°; for ``n``
motors the angles are ``θ_i = 90° - 180°/n + i·360°/n`` (the same rule gives 30°, 150°,
270° for n = 3; a square with axis-parallel sides for n = 4).
"""

from __future__ import annotations

import numpy as np

from .geometry import gravity_wrench, rotation_2d, wire_geometry, wrench_matrix
from .model import Robot
from .schema import RobotSpec
from .statics import max_margin_tensions

__all__ = [
    "MARIONET_A",
    "MARIONET_B",
    "MARIONET_T_B",
    "marionet",
    "marionet_t",
    "almost_planar",
    "planar",
    "krut_planar",
    "random_marionet",
    "all_presets",
]

MARIONET_A = [
    [0, 60, 0],
    [180, 120, 0],
    [180, 0, 0],
    [20, 0, 180],
    [20, 120, 180],
    [180, 120, 180],
    [180, 0, 180],
]
MARIONET_B = [
    [-10, -5, 0],
    [10, -5, 0],
    [0, 10, 0],
    [-5, -10, 10],
    [-5, 10, 10],
    [5, 10, 10],
    [5, -10, 10],
]
# T-platform (values in parentheses in Table I): wires 1,4,5 at B1; 2,6 at B2; 3,7 at B3
MARIONET_T_B = [
    [-10, 0, 0],
    [10, 10, 0],
    [10, -10, 0],
    [-10, 0, 0],
    [-10, 0, 0],
    [10, 10, 0],
    [10, -10, 0],
]
PAPER_DOMAIN = [[30, 160], [30, 110], [0, 170]]  # search ranges of Merlet (2007), section III
MARIONET_MIDDLE = [111.0, 58.0, 107.0]  # see the module docstring
MARIONET_T_MIDDLE = [115.0, 60.0, 118.0]

_K_WIRE = 383.0
_K_PULLEY = 2.0
_V = 100.0
_MASS = 0.02
_G = [0.0, 0.0, -9.81]


def _calibrate(spec: dict, position, rotation) -> dict:
    """Set every wire's L0 so that u = 0 at the given pose (see module docstring)."""
    probe = dict(spec)
    probe["wires"] = [dict(w, L0=1.0) for w in spec["wires"]]
    robot = Robot.from_spec(RobotSpec.model_validate(probe))
    H = wrench_matrix(robot, position, rotation)[0]
    wg = gravity_wrench(robot, rotation)[0]
    td = max_margin_tensions(H, wg, robot.tau_min, robot.tau_max)
    if not td.feasible:
        raise RuntimeError(f"{spec['name']}: calibration pose is not wrench-feasible")
    rho = wire_geometry(robot, position, rotation)[0][0]
    wires = []
    for w, r, t in zip(spec["wires"], rho, td.tau, strict=True):
        L0 = (r + w["V"]) * (1.0 - t / w["k"])
        wires.append(dict(w, L0=round(float(L0), 3)))
    return dict(spec, wires=wires)


def _elastic_wire(A, B, tau=(0.0, 10.0)):
    return {
        "base": [float(v) for v in A],
        "platform": [float(v) for v in B],
        "k": _K_WIRE,
        "K": _K_PULLEY,
        "V": _V,
        "L0": 0.0,
        "tau": list(tau),
        "u": [-20.0, 20.0],
    }


def marionet(tau_max: float = 10.0) -> dict:
    """MARIONET, main design of Table I."""
    spec = {
        "name": "marionet",
        "dof": 6,
        "gravity": _G,
        "platform": {"mass": _MASS, "center_of_mass": [0.0, 0.0, 5.0]},
        "wires": [_elastic_wire(a, b, (0.0, tau_max)) for a, b in zip(MARIONET_A, MARIONET_B)],
        "domain": {"points": PAPER_DOMAIN},
    }
    return _calibrate(spec, MARIONET_MIDDLE, np.eye(3))


def marionet_t(tau_max: float = 10.0) -> dict:
    """The T-platform design of Table I (values in parentheses)."""
    spec = {
        "name": "marionet-t",
        "dof": 6,
        "gravity": _G,
        "platform": {"mass": _MASS, "center_of_mass": [0.0, 0.0, 0.0]},
        "wires": [_elastic_wire(a, b, (0.0, tau_max)) for a, b in zip(MARIONET_A, MARIONET_T_B)],
        "domain": {"points": PAPER_DOMAIN},
    }
    return _calibrate(spec, MARIONET_T_MIDDLE, np.eye(3))


_PLANAR_A = [[0, 0], [180, 0], [180, 120], [0, 120]]
_PLANAR_B = [[-10, -5], [10, -5], [10, 5], [-10, 5]]
_PLANAR_CENTRE = [90.0, 60.0]


def almost_planar(tau_max: float = 10.0) -> dict:
    """4 wires from the corners of a horizontal 180 × 120 cm rectangle (z = 0) to a
    20 × 10 cm platform; gravity makes the platform hang slightly below the plane."""
    spec = {
        "name": "almost-planar",
        "dof": 6,
        "gravity": _G,
        "platform": {"mass": _MASS, "center_of_mass": [0.0, 0.0, 0.0]},
        "wires": [
            _elastic_wire(a + [0], b + [0], (0.0, tau_max)) for a, b in zip(_PLANAR_A, _PLANAR_B)
        ],
        "domain": {"points": [[0, 180], [0, 120], [-10, 10]]},
    }
    # calibrate with the platform slightly below the plane so gravity can be balanced
    return _calibrate(spec, _PLANAR_CENTRE + [-1.0], np.eye(3))


def planar(tau_max: float = 10.0) -> dict:
    """The planar 3-dof counterpart of :func:`almost_planar` (no gravity in the plane)."""
    spec = {
        "name": "planar",
        "dof": 3,
        "platform": {"mass": _MASS},
        "wires": [_elastic_wire(a, b, (0.0, tau_max)) for a, b in zip(_PLANAR_A, _PLANAR_B)],
        "domain": {"points": [[0, 180], [0, 120]]},
    }
    return _calibrate(spec, _PLANAR_CENTRE, rotation_2d(0.0))


def krut_planar(
    n: int = 3, radius: float = 100.0, tau: tuple[float, float] = (50.0, 500.0)
) -> dict:
    """Krut et al. (2004): n motors on a circle of radius 1000 mm (100 cm), point platform."""
    theta = np.radians(90.0 - 180.0 / n + 360.0 * np.arange(n) / n)
    wires = [
        {"base": [float(radius * np.cos(t)), float(radius * np.sin(t))], "tau": list(tau)}
        for t in theta
    ]
    return {"name": f"krut-{n}", "dof": 2, "wires": wires}


def random_marionet(kind: str = "general", seed: int = 0, spread: float = 15.0) -> dict:
    """A perturbed MARIONET design, for benchmarks and tests on robots nobody tuned.

    The anchors of Table I move by up to ``spread`` cm along each axis (z kept in [0, 180]);
    ``kind="general"`` moves the seven attachments by up to 3 cm, ``kind="T"`` keeps the
    T-platform's three attachment points (moved by up to 3 cm in its plane).  ``V`` and
    ``L0`` follow the same recipe as :func:`marionet` (u = 0 at the max-margin middle of the
    workspace), so every control vector in the strokes is a sensible command.  Raises
    ``RuntimeError`` if the middle pose is not wrench-feasible for the drawn anchors.
    """
    if kind not in ("general", "T"):
        raise ValueError("kind must be 'general' or 'T'")
    rng = np.random.default_rng(seed)
    A = np.array(MARIONET_A, dtype=float) + rng.uniform(-spread, spread, (7, 3))
    A[:, 2] = np.clip(A[:, 2], 0.0, 180.0)
    if kind == "general":
        B = np.array(MARIONET_B, dtype=float) + rng.uniform(-3.0, 3.0, (7, 3))
        com, middle = [0.0, 0.0, 5.0], MARIONET_MIDDLE
    else:
        shift = rng.uniform(-3.0, 3.0, (3, 3)) * np.array([1.0, 1.0, 0.0])
        group = [0, 1, 2, 0, 0, 1, 2]  # the T-platform's wires per attachment point
        B = np.array(MARIONET_T_B, dtype=float) + shift[group]
        com, middle = [0.0, 0.0, 0.0], MARIONET_T_MIDDLE
    spec = {
        "name": f"random-{kind}-{seed}",
        "dof": 6,
        "gravity": _G,
        "platform": {"mass": _MASS, "center_of_mass": com},
        "wires": [_elastic_wire(a, b) for a, b in zip(A, B, strict=True)],
        "domain": {"points": PAPER_DOMAIN},
    }
    return _calibrate(spec, middle, np.eye(3))


def marionet_t_tolerances() -> dict:
    """The T-platform robot known within tolerances (docs/tolerances.md): anchors measured
    to ±0.05 cm (±0.5 mm) and every wire's ``k`` within ±1 %."""
    spec = marionet_t()
    spec["name"] = "marionet-t-tol"
    spec["tolerances"] = [
        {"path": "wires[*].base[*]", "plus_minus": 0.05},
        {"path": "wires[*].k", "relative": 0.01},
    ]
    return spec


def all_presets() -> dict[str, dict]:
    """File name -> robot dict, for ``examples/robots``."""
    out = {
        "marionet.json": marionet(),
        "marionet-t.json": marionet_t(),
        "marionet-t-tol.json": marionet_t_tolerances(),
        "almost-planar.json": almost_planar(),
        "planar.json": planar(),
    }
    for n in (3, 4, 5, 6):
        out[f"krut-{n}.json"] = krut_planar(n)
    return out
