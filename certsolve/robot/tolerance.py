"""Tolerances: a robot known only within intervals, and the interval of every number.

A robot file may say how well its numbers are known::

    "tolerances": [{"path": "wires[*].base[*]", "plus_minus": 0.05},
                   {"path": "wires[*].k", "relative": 0.01},
                   {"path": "platform.mass", "plus_minus": 0.002}]

Each entry selects numbers by a path (:mod:`.paths`, the design spec's grammar) and gives
each of them the interval ``[x - t, x + t]`` (``plus_minus: t``) or
``[x - r |x|, x + r |x|]`` (``relative: r``) around its value ``x`` in the file.  The robots
of the *set* are all robots whose selected numbers lie in their intervals, each number
independently; the other numbers are exact.  Only measured numbers can be toleranced:
anchors, attachments, ``k``, ``K``, ``V``, ``L0``, the mass and the centre of mass (the
tension limits and the stroke are requirements, not measurements).

:func:`widen` computes the intervals with outward rounding (``x ± t`` in binary floating
point), so they hold the decimal intervals the user wrote; :func:`check` refuses what
makes a robot of the set invalid (``k <= 0``, ``L0 <= 0``, a negative mass, ``k <= τ_max``),
naming ``tolerances[i]``.  Both are called by the schema (:mod:`.schema`) and the model
(:meth:`.model.Robot.bounds`), so the intervals the solver uses are the ones validated.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..interval.rounding import down, up
from .paths import PathError, entry_name, parse_path

__all__ = ["TOLERANT_FIELDS", "Entry", "widen", "select", "check"]

#: the fields a tolerance may select
TOLERANT_FIELDS = ("base", "platform", "k", "K", "V", "L0", "mass", "center_of_mass")
#: lower limits of the robot file on toleranced numbers: (bound, strict)
_LOWER = {"k": (0.0, True), "K": (0.0, True), "L0": (0.0, True), "V": (0.0, False)}
_LOWER["mass"] = (0.0, False)

Entry = tuple[str, tuple[int, ...]]


def widen(value: float, plus_minus: float | None, relative: float | None) -> tuple[float, float]:
    """The interval of ``value`` under one tolerance, rounded outward (a zero tolerance
    gives the point ``[value, value]``)."""
    t = plus_minus if plus_minus is not None else abs(value) * float(relative or 0.0)
    if t == 0.0:
        return value, value
    if relative is not None:
        t = float(up(np.float64(t)))
    return float(down(np.float64(value - t))), float(up(np.float64(value + t)))


def select(tolerances: Sequence, m: int, dof: int) -> list[tuple[int, str, list[tuple[int, ...]]]]:
    """``(i, field, entries)`` of each tolerance; raises ``ValueError`` naming
    ``tolerances[i].path`` for a path that does not parse, a field that cannot be
    toleranced, or a number already toleranced by an earlier entry."""
    out = []
    seen: dict[Entry, int] = {}
    for i, tol in enumerate(tolerances):
        where = f"tolerances[{i}].path"
        try:
            field, entries = parse_path(tol.path, m=m, dof=dof)
        except PathError as exc:
            raise ValueError(f"{where}: {exc}") from None
        if field not in TOLERANT_FIELDS:
            raise ValueError(
                f"{where}: {field} is a requirement, not a measured number; tolerances "
                f"apply to {', '.join(TOLERANT_FIELDS)}"
            )
        for e in entries:
            if (field, e) in seen:
                raise ValueError(
                    f"{where}: {entry_name(field, e)} already has a tolerance "
                    f"(tolerances[{seen[(field, e)]}])"
                )
            seen[(field, e)] = i
        out.append((i, field, entries))
    return out


def check(
    tolerances: Sequence,
    m: int,
    dof: int,
    value: Callable[[str, tuple[int, ...]], float | None],
    tau_max: Sequence[float],
) -> dict[Entry, tuple[float, float]]:
    """The interval of every toleranced number, ``{(field, entry): (lo, hi)}``, after
    checking that every robot of the set is valid; ``value(field, entry)`` reads the
    file's number (None where the file does not give it)."""
    out: dict[Entry, tuple[float, float]] = {}
    for i, field, entries in select(tolerances, m, dof):
        tol = tolerances[i]
        for e in entries:
            x = value(field, e)
            name = entry_name(field, e)
            if x is None:
                raise ValueError(f"tolerances[{i}].path: {name} is not given in the file")
            lo, hi = widen(float(x), tol.plus_minus, tol.relative)
            bound, strict = _LOWER.get(field, (-np.inf, False))
            if lo < bound or (strict and lo <= bound):
                rel = ">" if strict else ">="
                raise ValueError(
                    f"tolerances[{i}]: {name} = {x:g} within the tolerance reaches {lo:g} "
                    f"(must be {rel} {bound:g})"
                )
            if field == "k" and lo <= tau_max[e[0]]:
                raise ValueError(
                    f"tolerances[{i}]: {name} = {x:g} within the tolerance reaches {lo:g}, "
                    f"not above tau_max = {tau_max[e[0]]:g} (eq. 5 divides by k - tau)"
                )
            out[(field, e)] = (lo, hi)
    return out
