"""Interval arithmetic over numpy arrays, with outward rounding.

An interval array is a pair ``(lo, hi)`` of float64 arrays; every function here is
vectorised over any shape, so a batch of a thousand boxes costs one numpy call per
operation.  Modules:

* :mod:`.rounding`    -- outward rounding (the source of rigour)
* :mod:`.core`        -- set operations: hull, intersection, width, midpoint, inclusion
* :mod:`.arith`       -- ``+ - * /``, powers, ``sqrt``, ``abs``, min/max
* :mod:`.elementary`  -- ``exp``, ``log``, ``sin``, ``cos``
* :mod:`.projections` -- backward (inverse-image) operators for HC4 contraction
* :mod:`.linalg`      -- rigorous midpoint-radius matrix products (Newton, Krawczyk)
* :mod:`.scalar`      -- :class:`Interval`, a small immutable scalar type for users
"""

from . import arith, core, elementary, linalg, projections, rounding
from .scalar import Interval

__all__ = ["arith", "core", "elementary", "linalg", "projections", "rounding", "Interval"]
