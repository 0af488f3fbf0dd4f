"""matplotlib, imported lazily with the non-interactive ``Agg`` backend.

Every picture of certsolve (force maps, pavings, IK sweeps, design pavings) gets
``pyplot`` from :func:`pyplot`, so that importing a command or a library module never
imports matplotlib, and plots work without a display.
"""

from __future__ import annotations

__all__ = ["pyplot"]


def pyplot():
    """``matplotlib.pyplot`` on the ``Agg`` backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
