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
"""

from __future__ import annotations

from pathlib import Path

from ..system import System
from .lexer import LIMITS, Limits, MinibexError, Token
from .parser import parse
from .values import enclosure

__all__ = [
    "MinibexError",
    "Limits",
    "LIMITS",
    "parse_minibex",
    "load_minibex",
    "load_system",
    "decimal_enclosure",
]


def parse_minibex(text: str, name: str = "", limits: Limits = LIMITS) -> System:
    """Parse Minibex text into a :class:`System` (raises :class:`MinibexError` only)."""
    system = parse(text, limits)
    system.name = name
    return system


def load_minibex(path, limits: Limits = LIMITS) -> System:
    """Parse a Minibex file (named after its stem)."""
    p = Path(path)
    data = p.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MinibexError(f"{p.name} is not UTF-8 text (byte {exc.start})", 1, 1) from None
    return parse_minibex(text, name=p.stem, limits=limits)


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
