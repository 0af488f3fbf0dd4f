"""Minibex, the modelling language of IBEX, read with IBEX's meaning.

::

    Constants
      n = 3;
      c[3] = (0.5; 1; 2);         // vectors: (a; b) column, (a, b) row
      r in [0.1, 0.2];            // an interval constant
    Variables
      x[n] in [-10, 10];          // a vector: x(1) .. x(3), or x[1] .. x[3]
      y;                          // no domain: (-oo, +oo)
      z in [0, +oo];
    function sq(u)
      return u^2;
    end
    Constraints
      for i = 1:n-1;
        x(i) * x(i+1) = c(i);
      end
      sq(y) - x(n) = 0;
      y + z <= 10;                // an extra constraint (contraction only)
      exp(z) - atan2(y, 1) = 2;
    end

The accepted language and its differences from IBEX are documented in ``docs/minibex.md``.
Decimal literals and exact rational arithmetic on them are kept exact, and a constant that
no binary float equals (``0.1``, ``1/3``) becomes its tightest enclosing interval, so the parsed
system contains the written one.  Every error is a :class:`MinibexError` naming the line and
column; :class:`Limits` bounds nesting and size (:data:`LIMITS`, shared by the CLI and HTTP).

:func:`read_minibex` / :func:`load_model` read any text IBEX reads into a :class:`Model`, with
as many equations as written (over- and under-determined systems, inequalities only);
`Model.system` is the :class:`System` the solver takes, and
:func:`parse_minibex` / :func:`load_minibex` go through it.
"""

from __future__ import annotations

from pathlib import Path

from ..system import System
from .lexer import LIMITS, Limits, MinibexError, Token
from .parser import Model, parse
from .values import enclosure

__all__ = [
    "MinibexError",
    "Limits",
    "LIMITS",
    "Model",
    "read_minibex",
    "load_model",
    "parse_minibex",
    "load_minibex",
    "load_system",
    "decimal_enclosure",
]


def read_minibex(text: str, limits: Limits = LIMITS) -> Model:
    """Read Minibex text into a :class:`Model`, square or not (raises :class:`MinibexError`
    only).  `Model.system` is the :class:`System` the solver takes."""
    return parse(text, limits)


def load_model(path, limits: Limits = LIMITS) -> Model:
    """Read a Minibex file into a :class:`Model`, square or not."""
    p = Path(path)
    data = p.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MinibexError(f"{p.name} is not UTF-8 text (byte {exc.start})", 1, 1) from None
    return parse(text, limits)


def parse_minibex(text: str, name: str = "", limits: Limits = LIMITS) -> System:
    """Parse Minibex text into a :class:`System` (raises :class:`MinibexError` only:
    a system with more or fewer equations than variables is refused, naming both counts)."""
    return parse(text, limits).system(name)


def load_minibex(path, limits: Limits = LIMITS) -> System:
    """Parse a Minibex file into a :class:`System` (named after its stem)."""
    return load_model(path, limits).system(Path(path).stem)


def load_system(source, name: str = "", limits: Limits = LIMITS) -> System:
    """A system from Minibex text or a file path (text is recognised by its sections:
    it contains ``Variables``, or a newline).  Raises :class:`MinibexError`, or ``OSError``
    for a file that cannot be read."""
    text = str(source)
    if isinstance(source, Path) or "\n" not in text and "Variables" not in text:
        return load_minibex(source, limits=limits)
    return parse_minibex(text, name=name, limits=limits)


def decimal_enclosure(text: str) -> tuple[float, float]:
    """Tightest float interval containing the exact decimal ``text``.

    Raises ``OverflowError`` for a decimal beyond the float range.
    """
    from fractions import Fraction

    try:
        return enclosure(Fraction(text), Token("NUM", text, 1, 1))
    except MinibexError:
        raise OverflowError(f"{text} is beyond the double-precision range") from None
