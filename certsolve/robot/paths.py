"""Paths into a robot file: which numbers a design parameter or a tolerance selects.

One grammar for both (the design spec's parameters, :mod:`.params`, and the robot file's
``tolerances``, :mod:`.tolerance`)::

    wires[W].FIELD[C]      FIELD a vector of the wire: base (A_i), platform (B_i), tau, u
    wires[W].FIELD         FIELD a number of the wire: k, K, V, L0
    platform.mass
    platform.center_of_mass[C]

``W`` and ``C`` are each ``*`` (all), a 0-based index or a comma list of distinct indices
(as the file's arrays and the error messages ``wires[3].tau``).  A path names a set of
*entries*: ``(wire, component)`` for the wire vectors, ``(wire,)`` for the wire numbers,
``()`` for the mass and ``(component,)`` for the centre of mass.  The parser knows the
robot only by its wire count ``m`` and ``dof`` (no model is built), so the schema can
check a file's paths while it validates the file.
"""

from __future__ import annotations

import re

__all__ = ["WIRE_VECTORS", "WIRE_NUMBERS", "PathError", "entry_name", "parse_path"]

#: the vector fields of a wire and their number of components (``None``: the robot's dim)
WIRE_VECTORS: dict[str, int | None] = {"base": None, "platform": None, "tau": 2, "u": 2}
#: the scalar fields of a wire
WIRE_NUMBERS = ("k", "K", "V", "L0")

_WIRE = re.compile(r"^wires\[([^\]]+)\]\.(\w+)(?:\[([^\]]+)\])?$")
_PLATFORM = re.compile(r"^platform\.(mass|center_of_mass)(?:\[([^\]]+)\])?$")
_GRAMMAR = (
    "expected wires[W].base[C], wires[W].platform[C], wires[W].tau[0|1], wires[W].u[0|1], "
    "wires[W].k (K, V, L0), platform.mass or platform.center_of_mass[C] "
    "with W, C = *, an index or a comma list"
)


class PathError(ValueError):
    """A path that does not parse, or selects nothing this robot has."""


def _indices(text: str, n: int, what: str) -> list[int]:
    text = text.replace(" ", "")
    if text == "*":
        return list(range(n))
    try:
        idx = [int(t) for t in text.split(",")]
    except ValueError:
        raise PathError(f"{what} index {text!r}: expected *, an integer or a comma list") from None
    for i in idx:
        if not 0 <= i < n:
            raise PathError(f"{what} index {i}: expected 0..{n - 1}")
    if len(set(idx)) != len(idx):
        raise PathError(f"{what} indices must be distinct")
    return idx


def parse_path(path: str, *, m: int, dof: int) -> tuple[str, list[tuple[int, ...]]]:
    """``path`` -> ``(field, entries)`` for a robot of ``m`` wires and ``dof`` (module
    docstring); raises :class:`PathError` saying what is wrong."""
    text = path.replace(" ", "")
    dim = 3 if dof == 6 else 2
    mp = _PLATFORM.match(text)
    if mp is not None:
        field, comp = mp.group(1), mp.group(2)
        if field == "mass":
            if comp is not None:
                raise PathError(f"path {path!r}: platform.mass is a number, not a vector")
            return "mass", [()]
        if comp is None:
            raise PathError(f"path {path!r}: expected platform.center_of_mass[C]")
        return "center_of_mass", [(c,) for c in _indices(comp, dim, "coordinate")]
    mw = _WIRE.match(text)
    if mw is None:
        raise PathError(f"path {path!r}: {_GRAMMAR}")
    field, comp = mw.group(2), mw.group(3)
    wires = _indices(mw.group(1), m, "wire")
    if field in WIRE_NUMBERS:
        if comp is not None:
            raise PathError(f"path {path!r}: wires[W].{field} is a number, not a vector")
        return field, [(w,) for w in wires]
    if field not in WIRE_VECTORS:
        raise PathError(f"path {path!r}: unknown field {field!r}; {_GRAMMAR}")
    if comp is None:
        raise PathError(f"path {path!r}: wires[W].{field} is a vector: add [C]")
    if field == "platform" and dof == 2:
        raise PathError(f"path {path!r}: a point platform (dof 2) has no attachment coordinates")
    n_comp = WIRE_VECTORS[field] or dim
    what = "coordinate" if WIRE_VECTORS[field] is None else field
    return field, [(w, c) for w in wires for c in _indices(comp, n_comp, what)]


def entry_name(field: str, entry: tuple[int, ...]) -> str:
    """The file's name of one selected number: ``wires[2].base[0]``, ``platform.mass``."""
    if field == "mass":
        return "platform.mass"
    if field == "center_of_mass":
        return f"platform.center_of_mass[{entry[0]}]"
    if field in WIRE_NUMBERS:
        return f"wires[{entry[0]}].{field}"
    return f"wires[{entry[0]}].{field}[{entry[1]}]"
