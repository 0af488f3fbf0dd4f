"""matplotlib, imported lazily with the non-interactive ``Agg`` backend.

Every picture of certsolve (force maps, pavings, IK sweeps, design pavings) gets
``pyplot`` from :func:`pyplot`, so that importing a command or a library module never
imports matplotlib, and plots work without a display; and each ends with :func:`save`.
"""

from __future__ import annotations

__all__ = ["pyplot", "save"]


def pyplot():
    """``matplotlib.pyplot`` on the ``Agg`` backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path=None, **savefig):
    """Write ``fig`` to ``path`` (the format from its suffix) and close it, if ``path`` is
    given; return ``fig``.  A closed figure is out of pyplot's list, so a long-running
    process (the service drawing pictures) does not collect them."""
    if path is not None:
        from pathlib import Path

        fig.savefig(Path(path), **savefig)
        pyplot().close(fig)
    return fig
