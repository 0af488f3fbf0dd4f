"""Design parameters: named paths into a robot file, and the robot as an affine map of them.

A design parameter changes some numbers of the robot file.  It is written as

    {"name": "base_half_width", "path": "wires[*].base[0]", "mode": "half-width",
     "range": [60, 140]}

**Paths** select numbers of the file: ``wires[W].FIELD[C]`` with ``FIELD`` one of ``base``
(anchor ``A_i``), ``platform`` (attachment ``B_i``) or ``tau`` (``[τ_min, τ_max]``: index 0
or 1), and ``W``, ``C`` each ``*`` (all), an index or a comma list of indices (0-based, as
the file's arrays and the error messages ``wires[3].tau``).

**Modes** say how the value ``θ`` of the parameter gives the selected numbers ``x``:

* ``"set"`` (default): every selected number is ``θ`` (e.g. ``wires[*].tau[1]``: the upper
  tension limit of every wire);
* ``"half-width"``: the selected coordinates are scaled about a centre ``c`` (per axis; by
  default the middle of their range in the file, or ``centre`` if given) by one common
  factor, so that ``θ`` is the largest ``|x - c|``: ``x(θ) = c + (x_file - c) θ / h`` with
  ``h = max |x_file - c|``.  ``wires[*].base[0]`` is the half-width of the base frame in
  x, ``wires[*].platform[*]`` the half-size of the platform (its shape kept).

Why paths and two modes: a path says exactly which numbers of the file move, and the two
modes cover the usual design questions (a size, a limit) while keeping every robot array
an **affine** function of the parameters,

    A(θ) = A_c + Σ_p θ_p A_p,   B(θ) = …,   τ_min(θ) = …,   τ_max(θ) = …,

so that a box of parameters maps to interval arrays by outward-rounded interval arithmetic
(:meth:`AffineRobot.bounds`), which the force enclosures take directly
(:func:`certsolve.force.enclosure.slack_enclosures`).  Two parameters may not move the
same number.  Only anchors, attachments and tension limits can be parameters: the other
fields do not enter the force index.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import product

import numpy as np
from numpy.typing import ArrayLike

from ..interval import arith
from ..interval.rounding import up
from . import paths
from .model import Robot
from .schema import RobotFileError, RobotSource, load_robot_spec

__all__ = ["ParameterDef", "RobotBounds", "AffineRobot", "parse_path", "MODES"]

MODES = ("set", "half-width")
_FIELDS = {"base": "A", "platform": "B", "tau": "tau"}


@dataclass(frozen=True, kw_only=True)
class ParameterDef:
    """One design parameter (module docstring); ``range`` is ``(lo, hi)``."""

    name: str
    path: str
    range: tuple[float, float]
    mode: str = "set"
    centre: tuple[float, ...] | None = None


@dataclass(frozen=True, kw_only=True)
class RobotBounds:
    """Interval robot arrays over a batch of ``n`` boxes of ``k`` parameters (batch last).

    Every array is a pair ``(lo, hi)``: ``A``, ``B`` ``(m, d, n)``, ``tau_min``, ``tau_max``
    ``(m, n)`` enclose the arrays of every robot of each box; ``*_mid`` enclose those of the
    robot at the box's centre ``θ_mid``; ``radius`` ``(k, n)`` bounds ``|θ - θ_mid|`` over the
    box; ``dA``, ``dB`` ``(k, m, d)`` and ``dtau_min``, ``dtau_max`` ``(k, m)`` are the exact
    derivatives of the arrays in each parameter (they are affine).  A proof made with these
    holds for every robot of the box.  ``k = 0`` for a fixed robot (:meth:`point`).
    ``mass`` (floats) and ``com`` (``(d,)`` arrays) are the intervals of the mass and the
    centre of mass (platform frame), shared by the batch; they are not parameters (the
    weight's wrench is multilinear in them: :meth:`weight_corners`).
    """

    A: tuple[np.ndarray, np.ndarray]
    B: tuple[np.ndarray, np.ndarray]
    tau_min: tuple[np.ndarray, np.ndarray]
    tau_max: tuple[np.ndarray, np.ndarray]
    A_mid: tuple[np.ndarray, np.ndarray]
    B_mid: tuple[np.ndarray, np.ndarray]
    tau_min_mid: tuple[np.ndarray, np.ndarray]
    tau_max_mid: tuple[np.ndarray, np.ndarray]
    radius: np.ndarray
    dA: np.ndarray
    dB: np.ndarray
    dtau_min: np.ndarray
    dtau_max: np.ndarray
    mass: tuple[float, float]
    com: tuple[np.ndarray, np.ndarray]

    @property
    def k(self) -> int:
        """Number of parameters (slope dimensions added to the pose's)."""
        return self.radius.shape[0]

    @classmethod
    def point(cls, robot: Robot) -> RobotBounds:
        """The robot's own float arrays as thin intervals (a batch of one, no parameter)."""

        def thin(a):
            a = np.asarray(a, dtype=float)[..., None]
            return a, a

        A, B, tn, tx = thin(robot.A), thin(robot.B), thin(robot.tau_min), thin(robot.tau_max)
        m, d = robot.A.shape
        return cls(
            A=A, B=B, tau_min=tn, tau_max=tx, A_mid=A, B_mid=B, tau_min_mid=tn, tau_max_mid=tx,
            radius=np.zeros((0, 1)), dA=np.zeros((0, m, d)), dB=np.zeros((0, m, d)),
            dtau_min=np.zeros((0, m)), dtau_max=np.zeros((0, m)),
            mass=(robot.mass, robot.mass), com=(robot.com, robot.com),
        )  # fmt: skip

    def weight_corners(self) -> tuple[np.ndarray, np.ndarray]:
        """The corners ``(masses (V,), coms (V, d))`` of the box of the mass and the centre of
        mass: each toleranced number at both ends, the exact ones once (``V = 1`` for an
        exact weight: the nominal numbers).  The weight's wrench ``(m g, (R c) × (m g))`` is
        multilinear in ``(m, c)``, so a quantity affine in it lies, for every robot of the
        box, between its least and greatest value at the corners."""
        lo = np.r_[self.mass[0], self.com[0]]
        hi = np.r_[self.mass[1], self.com[1]]
        ends = [np.unique([a, b]) for a, b in zip(lo, hi, strict=True)]
        corners = np.array(list(product(*ends)), dtype=float)
        return corners[:, 0], corners[:, 1:]

    @classmethod
    def of_tolerances(cls, robot: Robot) -> RobotBounds:
        """The robot set of a file with tolerances (:meth:`.Robot.bounds`) as a batch of one
        box of parameters: one parameter per toleranced anchor or attachment coordinate,
        ``A = A_c + Σ_l θ_l e_l`` (an affine map like the design's ``set`` parameters),
        ``θ_l`` over its interval; the tension limits are exact; the mass and the centre of
        mass are their intervals.  A proof made with these holds for every robot of the set
        (the numbers the force index reads: anchors, attachments, tension limits, mass and
        centre of mass)."""
        b = robot.bounds()
        base = cls.point(robot)
        m, d = robot.A.shape
        slopes: dict[str, list[np.ndarray]] = {"A": [], "B": []}
        radius, pairs, mids = [], {}, {}
        for name in ("A", "B"):
            lo, hi = b.A if name == "A" else b.B
            for i, c in zip(*np.nonzero(lo != hi), strict=True):
                e = np.zeros((m, d))
                e[i, c] = 1.0
                for other in slopes:
                    slopes[other].append(e if other == name else np.zeros((m, d)))
                mid = 0.5 * lo[i, c] + 0.5 * hi[i, c]
                radius.append(max(float(up(hi[i, c] - mid)), float(up(mid - lo[i, c]))))
            mid = np.minimum(np.maximum(0.5 * lo + 0.5 * hi, lo), hi)
            pairs[name] = (lo[..., None], hi[..., None])
            mids[name] = (mid[..., None], mid[..., None])
        k = len(radius)
        return replace(
            base,
            A=pairs["A"], B=pairs["B"], A_mid=mids["A"], B_mid=mids["B"],
            radius=np.array(radius).reshape(k, 1),
            dA=np.array(slopes["A"]).reshape(k, m, d), dB=np.array(slopes["B"]).reshape(k, m, d),
            dtau_min=np.zeros((k, m)), dtau_max=np.zeros((k, m)),
            mass=b.mass, com=b.com,
        )  # fmt: skip

    def take(self, idx: np.ndarray | slice) -> RobotBounds:
        """The boxes ``idx`` of the batch (a batch of one is shared by every box)."""
        if self.radius.shape[-1] == 1:
            return self

        def sel(p):
            return p[0][..., idx], p[1][..., idx]

        return replace(
            self,
            **{f: sel(getattr(self, f)) for f in _PAIRS},
            radius=self.radius[:, idx],
        )


_PAIRS = ("A", "B", "tau_min", "tau_max", "A_mid", "B_mid", "tau_min_mid", "tau_max_mid")


def parse_path(path: str, robot: Robot) -> tuple[str, list[tuple]]:
    """``wires[W].FIELD[C]`` -> ``(field, [array index, ...])`` with field ``A``/``B``/``tau``.

    The grammar is :mod:`.paths`' (shared with the tolerances); a design parameter may set
    only anchors, attachments and tension limits.  Array indices are ``(wire, coordinate)``
    for ``A`` and ``B`` and ``(wire, 0|1)`` for ``tau`` (0: ``τ_min``, 1: ``τ_max``).
    """
    field, entries = paths.parse_path(path, m=robot.m, dof=robot.dof)
    if field not in _FIELDS:
        raise ValueError(
            f"path {path!r}: a design parameter sets wires[W].base[C], wires[W].platform[C] "
            "or wires[W].tau[0|1] (the other fields do not enter the force index)"
        )
    return _FIELDS[field], entries


class AffineRobot:
    """A robot file whose arrays are affine in the design parameters (module docstring).

    ``source``: anything :meth:`Robot.load` accepts; ``params``: :class:`ParameterDef` list.
    Raises ``ValueError`` naming ``parameters[i]`` for a bad path, mode, range or an invalid
    robot at a corner of the parameter box.
    """

    def __init__(self, source: RobotSource, params: list[ParameterDef]) -> None:
        self.spec = load_robot_spec(source)
        self.robot = Robot.from_spec(self.spec)
        self.params = list(params)
        robot = self.robot
        k = len(params)
        base = {
            "A": robot.A.copy(),
            "B": robot.B.copy(),
            "tau": np.stack([robot.tau_min, robot.tau_max], axis=1),
        }
        self._const = {f: a.copy() for f, a in base.items()}
        self._coef = {f: np.zeros((k,) + a.shape) for f, a in base.items()}
        owner: dict[tuple, int] = {}
        self._targets = []
        for p, prm in enumerate(params):
            where = f"parameters[{p}]"
            lo, hi = (float(v) for v in prm.range)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise ValueError(f"{where}.range: need finite lo < hi")
            try:
                field, entries = parse_path(prm.path, robot)
            except ValueError as exc:
                raise ValueError(f"{where}.path: {exc}") from None
            for e in entries:
                if e + (field,) in owner:
                    other = params[owner[e + (field,)]].name
                    raise ValueError(
                        f"{where}.path: {field_name(field, e)} is already set by parameter "
                        f"{other!r}"
                    )
                owner[e + (field,)] = p
            self._targets.append((field, entries))
            self._apply(p, prm, field, entries, base[field], where)
        self._check_corners()

    def _apply(self, p, prm, field, entries, values, where):
        rows = np.array([e[0] for e in entries])
        cols = np.array([e[1] for e in entries])
        if prm.mode == "set":
            if prm.centre is not None:
                raise ValueError(f"{where}.centre: only with mode 'half-width'")
            self._const[field][rows, cols] = 0.0
            self._coef[field][p][rows, cols] = 1.0
            return
        if prm.mode != "half-width":
            raise ValueError(f"{where}.mode: expected one of {', '.join(MODES)}")
        if field == "tau":
            raise ValueError(f"{where}.mode: 'half-width' scales coordinates, not tensions")
        x = values[rows, cols]
        comps = sorted(set(cols.tolist()))
        centre = np.zeros(values.shape[1])
        if prm.centre is not None:
            if len(prm.centre) != values.shape[1]:
                raise ValueError(f"{where}.centre: expected {values.shape[1]} coordinates")
            centre[:] = prm.centre
        else:
            for c in comps:
                xc = x[cols == c]
                centre[c] = 0.5 * (xc.min() + xc.max())
        h = float(np.max(np.abs(x - centre[cols])))
        if not h > 0:
            raise ValueError(f"{where}: the selected coordinates all sit at the centre")
        self._const[field][rows, cols] = centre[cols]
        self._coef[field][p][rows, cols] = (x - centre[cols]) / h

    def _check_corners(self) -> None:
        """Every robot at a corner of the parameter box is a valid robot file (the arrays are
        affine, so the limits checked by the schema hold inside if they hold at corners,
        except ``τ_min ≤ τ_max`` which is checked on the whole box)."""
        lo, hi = self.box[:, 0], self.box[:, 1]
        for corner in product(*zip(lo, hi)):
            try:
                load_robot_spec(self.spec_at(np.array(corner)))
            except RobotFileError as exc:
                vals = ", ".join(f"{p.name} = {v:g}" for p, v in zip(self.params, corner))
                why = str(exc).replace("\n", "; ")
                raise ValueError(f"parameters: the robot with {vals} is invalid: {why}") from None
        b = self.bounds(lo[None], hi[None])
        if np.any(b.tau_min[1] > b.tau_max[0]):
            raise ValueError("parameters: tau_min may exceed tau_max inside the ranges")

    # -- facts --------------------------------------------------------------------------
    @property
    def names(self) -> list[str]:
        return [p.name for p in self.params]

    @property
    def box(self) -> np.ndarray:
        """``(k, 2)`` the parameter ranges."""
        return np.array([[float(v) for v in p.range] for p in self.params])

    def values(self, theta: ArrayLike) -> dict[str, np.ndarray]:
        """Float arrays ``A``, ``B``, ``tau`` at the parameter values ``theta`` ``(k,)``."""
        t = np.asarray(theta, dtype=float)
        return {f: self._const[f] + np.tensordot(t, self._coef[f], axes=1) for f in self._const}

    def spec_at(self, theta: ArrayLike) -> dict:
        """The robot file (a dict) at ``theta``: the selected numbers replaced."""
        vals = self.values(theta)
        data = self.spec.model_dump(mode="json", exclude_none=True)
        for field, entries in self._targets:
            for w, c in entries:
                v = float(vals[field][w, c])
                key = {"A": "base", "B": "platform", "tau": "tau"}[field]
                wire = data["wires"][w]
                if key == "platform" and "platform" not in wire:
                    wire["platform"] = [0.0] * self.robot.dim
                arr = list(wire[key])
                arr[c] = v
                wire[key] = arr
        return data

    def robot_at(self, theta: ArrayLike) -> Robot:
        return Robot.load(self.spec_at(theta))

    def bounds(self, lo: ArrayLike, hi: ArrayLike) -> RobotBounds:
        """Interval arrays over parameter boxes ``[lo, hi]`` ``(n, k)`` (outward rounded)."""
        lo = np.asarray(lo, dtype=float)
        hi = np.asarray(hi, dtype=float)
        mid = np.minimum(np.maximum(0.5 * lo + 0.5 * hi, lo), hi)
        radius = np.maximum(up(hi - mid), up(mid - lo)).T  # (k, n)
        box = self._enclose(lo, hi)
        at_mid = self._enclose(mid, mid)
        dtau = self._coef["tau"]  # (k, m, 2)
        return RobotBounds(
            A=box["A"],
            B=box["B"],
            tau_min=(box["tau"][0][:, 0], box["tau"][1][:, 0]),
            tau_max=(box["tau"][0][:, 1], box["tau"][1][:, 1]),
            A_mid=at_mid["A"],
            B_mid=at_mid["B"],
            tau_min_mid=(at_mid["tau"][0][:, 0], at_mid["tau"][1][:, 0]),
            tau_max_mid=(at_mid["tau"][0][:, 1], at_mid["tau"][1][:, 1]),
            radius=radius,
            dA=self._coef["A"],
            dB=self._coef["B"],
            dtau_min=dtau[..., 0],
            dtau_max=dtau[..., 1],
            mass=(self.robot.mass, self.robot.mass),
            com=(self.robot.com, self.robot.com),
        )

    def _enclose(self, lo, hi) -> dict:
        """``const + Σ_p [lo_p, hi_p] coef_p`` per field, batch last: ``(..., n)`` pairs."""
        out = {}
        for f, const in self._const.items():
            clo = np.broadcast_to(const[..., None], const.shape + (lo.shape[0],))
            acc = (clo, clo)
            for p in range(lo.shape[1]):
                g = self._coef[f][p]
                if not np.any(g):
                    continue
                shape = (1,) * g.ndim + (-1,)
                term = arith.scale(lo[:, p].reshape(shape), hi[:, p].reshape(shape), g[..., None])
                zero = (g == 0)[..., None]
                term = (np.where(zero, 0.0, term[0]), np.where(zero, 0.0, term[1]))
                acc = arith.add(*acc, *term)
            out[f] = acc
        return out


def field_name(field: str, entry: tuple) -> str:
    return paths.entry_name({"A": "base", "B": "platform", "tau": "tau"}[field], entry)
