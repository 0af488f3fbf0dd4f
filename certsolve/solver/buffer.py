"""The box buffer: a stack of boxes stored as two growing ``(capacity, n)`` arrays.

Popping the *last* ``k`` boxes makes the search depth-first at the batch level: the
children of the most recent bisections are processed next, which keeps the buffer small.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BoxStack"]


class BoxStack:
    def __init__(self, n: int, capacity: int = 1024):
        self.n = n
        self._lo = np.empty((capacity, n))
        self._hi = np.empty((capacity, n))
        self._size = 0

    def __len__(self) -> int:
        return self._size

    def push(self, lo: np.ndarray, hi: np.ndarray) -> None:
        k = lo.shape[0]
        if k == 0:
            return
        need = self._size + k
        if need > self._lo.shape[0]:
            cap = max(need, 2 * self._lo.shape[0])
            for name in ("_lo", "_hi"):
                old = getattr(self, name)
                new = np.empty((cap, self.n))
                new[: self._size] = old[: self._size]
                setattr(self, name, new)
        self._lo[self._size : need] = lo
        self._hi[self._size : need] = hi
        self._size = need

    def pop(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        k = min(k, self._size)
        start = self._size - k
        lo = self._lo[start : self._size].copy()
        hi = self._hi[start : self._size].copy()
        self._size = start
        return lo, hi

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of every box in the buffer (for reporting pending boxes)."""
        return self._lo[: self._size].copy(), self._hi[: self._size].copy()
