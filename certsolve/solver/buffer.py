"""The box buffer: a stack of boxes stored as two growing ``(capacity, n)`` arrays.

Popping the *last* ``k`` boxes makes the search depth-first at the batch level: the
children of the most recent bisections are processed next, which keeps the buffer small.

**Hints.**  Beside each box the buffer may keep a row of small integers that a contractor
left for the box's next contraction: the polytope hull's optimal LP active sets
(:mod:`.relaxation`), which the halves of a bisected box inherit and start from.  A hint
only changes where a contractor's work starts, never what it proves, so a box may lose its
hint wherever keeping it would cost more than it saves (the pieces of a box minus a unicity
box, a buffer that keeps none such as the certified design's queue: ``-1`` rows, "no
hint"); the search driver carries them to worker tasks and back, and into checkpoints.
The hints' width is set by the first push that brings some; a push of another width is
taken without them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["HINT_DTYPE", "BoxStack", "no_hints", "stacked_hints"]

#: the hints' integer type (the hull's active sets index at most ``8n`` constraints)
HINT_DTYPE = np.int16


def no_hints(k: int, width: int) -> np.ndarray:
    """``k`` rows of "no hint"."""
    return np.full((k, width), -1, dtype=HINT_DTYPE)


def stacked_hints(parts: list[tuple[int, np.ndarray | None]]) -> np.ndarray | None:
    """The hints of consecutive groups of ``k`` boxes, ``(k, hints or None)``: ``-1``
    rows for a group without (``None`` when no group has any; a group of another width
    than the first is taken without)."""
    width = next((h.shape[1] for _, h in parts if h is not None), None)
    if width is None:
        return None
    return np.concatenate(
        [h if h is not None and h.shape[1] == width else no_hints(k, width) for k, h in parts]
    )


class BoxStack:
    def __init__(self, n: int, capacity: int = 1024):
        self.n = n
        self._lo = np.empty((capacity, n))
        self._hi = np.empty((capacity, n))
        self._hints: np.ndarray | None = None  # (capacity, width) once a push brings hints
        self._size = 0

    def __len__(self) -> int:
        return self._size

    def push(self, lo: np.ndarray, hi: np.ndarray, hints: np.ndarray | None = None) -> None:
        k = lo.shape[0]
        if k == 0:
            return
        need = self._size + k
        if need > self._lo.shape[0]:
            cap = max(need, 2 * self._lo.shape[0])
            for name in ("_lo", "_hi", "_hints"):
                old = getattr(self, name)
                if old is not None:
                    new = np.empty((cap, old.shape[1]), dtype=old.dtype)
                    new[: self._size] = old[: self._size]
                    setattr(self, name, new)
        self._lo[self._size : need] = lo
        self._hi[self._size : need] = hi
        if hints is not None and self._hints is None:
            self._hints = no_hints(self._lo.shape[0], hints.shape[1])
        if self._hints is not None:
            fits = hints is not None and hints.shape[1] == self._hints.shape[1]
            self._hints[self._size : need] = hints if fits else -1
        self._size = need

    def pop(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi, _ = self.pop_hinted(k)
        return lo, hi

    def pop_hinted(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """The last ``k`` boxes and their hints (``None``: the buffer holds none)."""
        k = min(k, self._size)
        start = self._size - k
        lo = self._lo[start : self._size].copy()
        hi = self._hi[start : self._size].copy()
        hints = None if self._hints is None else self._hints[start : self._size].copy()
        self._size = start
        return lo, hi, hints

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of every box in the buffer (for reporting pending boxes)."""
        lo, hi = self.view()
        return lo.copy(), hi.copy()

    def view(self) -> tuple[np.ndarray, np.ndarray]:
        """Every box in the buffer, as read-only views: valid until the next push or pop
        (for reading a few rows without copying the whole buffer)."""
        lo, hi = self._lo[: self._size], self._hi[: self._size]
        lo, hi = lo.view(), hi.view()
        lo.flags.writeable = hi.flags.writeable = False
        return lo, hi

    def hints(self) -> np.ndarray | None:
        """A copy of every box's hints (``None``: the buffer holds none)."""
        return None if self._hints is None else self._hints[: self._size].copy()
