"""A small immutable scalar interval type, for users, examples and tests.

The solver works on arrays of bounds (see :mod:`.core`); :class:`Interval` wraps the same
functions for one interval so that ``Interval(1, 2) * Interval(-1, 3)`` reads naturally.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import arith, elementary
from .core import midpoint


@dataclass(frozen=True)
class Interval:
    lo: float
    hi: float

    @staticmethod
    def point(x: float) -> Interval:
        return Interval(float(x), float(x))

    @staticmethod
    def _wrap(pair) -> Interval:
        lo, hi = pair
        return Interval(float(lo), float(hi))

    @staticmethod
    def _coerce(x) -> Interval:
        return x if isinstance(x, Interval) else Interval.point(x)

    def _b(self):
        return np.float64(self.lo), np.float64(self.hi)

    # set properties
    @property
    def is_empty(self) -> bool:
        return not self.lo <= self.hi

    @property
    def width(self) -> float:
        return self.hi - self.lo

    @property
    def mid(self) -> float:
        return float(midpoint(np.float64(self.lo), np.float64(self.hi)))

    def __contains__(self, x: float) -> bool:
        return self.lo <= x <= self.hi

    def intersect(self, other: Interval) -> Interval:
        return Interval(max(self.lo, other.lo), min(self.hi, other.hi))

    def hull(self, other: Interval) -> Interval:
        return Interval(min(self.lo, other.lo), max(self.hi, other.hi))

    # arithmetic
    def __add__(self, o: Interval | float) -> Interval:
        return self._wrap(arith.add(*self._b(), *self._coerce(o)._b()))

    __radd__ = __add__

    def __sub__(self, o: Interval | float) -> Interval:
        return self._wrap(arith.sub(*self._b(), *self._coerce(o)._b()))

    def __rsub__(self, o: Interval | float) -> Interval:
        return self._coerce(o) - self

    def __mul__(self, o: Interval | float) -> Interval:
        return self._wrap(arith.mul(*self._b(), *self._coerce(o)._b()))

    __rmul__ = __mul__

    def __truediv__(self, o: Interval | float) -> Interval:
        return self._wrap(arith.div(*self._b(), *self._coerce(o)._b()))

    def __rtruediv__(self, o: Interval | float) -> Interval:
        return self._coerce(o) / self

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __pow__(self, n: int) -> Interval:
        lo, hi = self._b()
        return self._wrap(arith.pow_int(lo, hi, int(n)))

    def sqr(self) -> Interval:
        return self._wrap(arith.sqr(*self._b()))

    def sqrt(self) -> Interval:
        return self._wrap(arith.sqrt(*self._b()))

    def exp(self) -> Interval:
        return self._wrap(elementary.exp(*self._b()))

    def log(self) -> Interval:
        return self._wrap(elementary.log(*self._b()))

    def sin(self) -> Interval:
        return self._wrap(elementary.sin(*self._b()))

    def cos(self) -> Interval:
        return self._wrap(elementary.cos(*self._b()))

    def __repr__(self) -> str:
        return f"[{self.lo!r}, {self.hi!r}]"
