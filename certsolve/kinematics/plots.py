"""Pictures of kinematics results: an IK sweep as in Merlet (2007), Fig. 3.

:func:`plot_sweep` draws every control ``u_j`` against the swept ``u_J`` (top) and the
tensions with their limits (bottom).  Certified points are filled markers, uncertified ones
hollow, infeasible ones (a limit violated) grey crosses.  matplotlib is imported lazily
(:mod:`certsolve.plotting`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import pyplot
from .ik_sweep import IKSweepResult, PointStatus

__all__ = ["plot_sweep"]

_STYLE = {
    PointStatus.CERTIFIED: {"marker": "o", "fill": True},
    PointStatus.UNCERTIFIED: {"marker": "o", "fill": False},
    PointStatus.INFEASIBLE: {"marker": "x", "fill": True},
}


def plot_sweep(res: IKSweepResult, path=None, tau_limits=None, title=None):
    """Controls and tensions along the sweep; saved as PNG if ``path`` is given.

    ``tau_limits``: optional ``(tau_min, tau_max)`` arrays drawn as dashed lines.
    Returns the figure.
    """
    plt = pyplot()
    t = res.values
    U = res.controls()
    T = res.tensions()
    status = np.array([str(p.status) for p in res.points])
    m = U.shape[1]
    fig, (ax_u, ax_t) = plt.subplots(2, 1, figsize=(6.4, 7.2), dpi=120, sharex=True)
    colours = plt.get_cmap("tab10")
    for j in range(m):
        c = colours(j % 10)
        label = f"u_{j + 1}" + (" (swept)" if j + 1 == res.joint else "")
        for ax, Y, name in ((ax_u, U, "u"), (ax_t, T, "tau")):
            ls = ":" if (j + 1 == res.joint and name == "u") else "-"
            ax.plot(t, Y[:, j], ls, color=c, lw=1.2, label=label if name == "u" else None)
            for st, style in _STYLE.items():
                sel = status == str(st)
                if not sel.any():
                    continue
                if st is PointStatus.INFEASIBLE:
                    colour = {"color": "0.5"}
                else:
                    colour = {"facecolors": c if style["fill"] else "none", "edgecolors": c}
                ax.scatter(
                    t[sel], Y[sel, j], s=12, marker=style["marker"], linewidths=0.8, zorder=3,
                    **colour,
                )  # fmt: skip
    if tau_limits is not None:
        lo, hi = (np.asarray(x, dtype=float) for x in tau_limits)
        for v, name in ((np.unique(lo), "tau_min"), (np.unique(hi), "tau_max")):
            for x in v:
                ax_t.axhline(x, color="k", ls="--", lw=0.8)
                ax_t.annotate(
                    f"{name} {x:g} N", (1.0, x), xycoords=("axes fraction", "data"),
                    ha="right", va="bottom", fontsize=7,
                )  # fmt: skip
    counts = res.counts
    ax_u.set_ylabel("controls u_j (cm)")
    ax_t.set_ylabel("tensions τ_j (N)")
    ax_t.set_xlabel(f"u_{res.joint} (cm)")
    ax_u.legend(fontsize=8, ncol=2)
    ax_u.grid(alpha=0.3)
    ax_t.grid(alpha=0.3)
    pose = ", ".join(f"{v:g}" for v in res.pose.params(res.dof))
    if title is None:
        title = (
            f"{res.robot}: IK at pose ({pose}) as u_{res.joint} varies\n"
            f"{counts['certified']} certified (filled), {counts['uncertified']} uncertified "
            f"(hollow), {counts['infeasible']} infeasible (grey x)"
        )
    ax_u.set_title(title, fontsize=9)
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path))
        plt.close(fig)
    return fig
