"""Pictures: isotropic-force heat maps (Fig. 9/10 style) and certified pavings.

matplotlib is imported lazily with the non-interactive ``Agg`` backend.  Heat maps draw the
region ``f_min < 0`` (and degenerate poses) in white as in the paper, the contour
``f_min = 0`` (the wrench-feasible workspace boundary), the anchors, a colorbar in newtons
and equal axes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import pyplot
from .certified import CertifiedWorkspace
from .maps import IsotropicMap

__all__ = ["plot_map", "plot_maps", "plot_paving"]


def _plt():
    return pyplot()


def _draw_map(ax, res: IsotropicMap, vmax=None, title=None, cmap="jet", colorbar=True):
    plt = _plt()
    v = np.where(res.values >= 0, res.values, np.nan)
    masked = np.ma.masked_invalid(v)
    cm = plt.get_cmap(cmap).with_extremes(bad="white")
    dx = (res.xs[-1] - res.xs[0]) / max(len(res.xs) - 1, 1) / 2
    dy = (res.ys[-1] - res.ys[0]) / max(len(res.ys) - 1, 1) / 2
    extent = (res.xs[0] - dx, res.xs[-1] + dx, res.ys[0] - dy, res.ys[-1] + dy)
    vmax = vmax if vmax is not None else (float(np.nanmax(v)) if np.isfinite(v).any() else 1.0)
    im = ax.imshow(
        masked,
        origin="lower",
        extent=extent,
        cmap=cm,
        vmin=0.0,
        vmax=vmax,
        interpolation="nearest",
        aspect="equal",
    )
    finite = np.where(np.isfinite(res.values), res.values, -1.0)
    if (finite >= 0).any() and (finite < 0).any() and len(res.xs) > 1 and len(res.ys) > 1:
        ax.contour(res.xs, res.ys, finite, levels=[0.0], colors="k", linewidths=0.8)
    A = res.anchors
    if res.dof == 6:
        ax.plot(A[:, 0], A[:, 1], "k^", ms=6, label="anchors (x, y)")
    else:
        ax.plot(A[:, 0], A[:, 1], "ko", ms=6, label="anchors")
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    pad = 0.05 * max(extent[1] - extent[0], extent[3] - extent[2])
    ax.set_xlim(min(extent[0], A[:, 0].min()) - pad, max(extent[1], A[:, 0].max()) + pad)
    ax.set_ylim(min(extent[2], A[:, 1].min()) - pad, max(extent[3], A[:, 1].max()) + pad)
    if title is None:
        title = f"{res.robot}: maximum isotropic force"
        if res.z is not None:
            title += f" (z = {res.z:g} cm)"
    ax.set_title(title)
    if colorbar:
        plt.colorbar(im, ax=ax, label="maximum isotropic force (N)", shrink=0.85)
    return im


def plot_map(res: IsotropicMap, path=None, vmax=None, title=None, cmap="jet"):
    """One heat map; saved as PNG if ``path`` is given.  Returns the figure."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=120)
    _draw_map(ax, res, vmax=vmax, title=title, cmap=cmap)
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path))
        plt.close(fig)
    return fig


def plot_maps(maps: list[IsotropicMap], path=None, titles=None, shared_scale=True, cmap="jet"):
    """Several maps side by side with one shared colour scale (the paper's Fig. 10)."""
    plt = _plt()
    vmax = max(float(np.nanmax(np.where(m.values >= 0, m.values, np.nan))) for m in maps)
    fig, axes = plt.subplots(1, len(maps), figsize=(4.6 * len(maps) + 1.0, 4.6), dpi=120)
    axes = np.atleast_1d(axes)
    im = None
    for k, (ax, m) in enumerate(zip(axes, maps)):
        im = _draw_map(
            ax,
            m,
            vmax=vmax if shared_scale else None,
            title=None if titles is None else titles[k],
            cmap=cmap,
            colorbar=not shared_scale,
        )
    if shared_scale and im is not None:
        fig.colorbar(im, ax=list(axes), label="maximum isotropic force (N)", shrink=0.85)
    if path is not None:
        fig.savefig(Path(path), bbox_inches="tight")
        plt.close(fig)
    return fig


def plot_paving(ws: CertifiedWorkspace, path=None, title=None, anchors=None, z=None):
    """The paving of a planar box (x, y): inside green, outside grey, boundary orange.

    For dof 6 the picture is the slice ``z = z`` (default: the middle of the box): the boxes
    whose z-range contains it.
    """
    plt = _plt()
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Patch, Rectangle

    fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=120)
    if ws.dof == 6 and z is None:
        z = float(0.5 * (ws.box[2, 0] + ws.box[2, 1]))
    styles = [
        ("outside", "#d9d9d9", "proven f < f_req"),
        ("boundary", "#ff9f1c", "boundary (< eps)"),
        ("pending", "#8ecae6", "not processed"),
        ("inside", "#2a9d8f", "proven f ≥ f_req"),
    ]
    handles = []
    for key, color, label in styles:
        boxes = getattr(ws, key)
        if ws.dof == 6 and len(boxes):
            boxes = boxes[(boxes[:, 2, 0] <= z) & (z <= boxes[:, 2, 1])]
        if len(boxes) == 0:
            continue
        rects = [Rectangle((b[0, 0], b[1, 0]), b[0, 1] - b[0, 0], b[1, 1] - b[1, 0]) for b in boxes]
        pc = PatchCollection(
            rects,
            facecolor=color,
            edgecolor="k" if len(rects) < 3000 else color,
            linewidth=0.15,
        )
        ax.add_collection(pc)
        handles.append(Patch(facecolor=color, edgecolor="k", label=f"{label} ({len(boxes)})"))
    if anchors is not None:
        A = np.asarray(anchors)
        ax.plot(A[:, 0], A[:, 1], "ko", ms=5)
    b = ws.box
    ax.set_xlim(b[0, 0], b[0, 1])
    ax.set_ylim(b[1, 0], b[1, 1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    if title is None:
        title = (
            f"{ws.robot}: f_min ≥ {ws.min_force:g} N, eps {ws.eps:g} cm"
            + (f", slice z = {z:g} cm" if ws.dof == 6 else "")
            + "\n"
            f"inside {ws.inside_measure:.4g} {ws.unit} ({100 * ws.inside_share:.1f} % of the box)"
        )
    ax.set_title(title, fontsize=10)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.12),
        ncol=2,
        fontsize=8,
        frameon=False,
    )
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path))
        plt.close(fig)
    return fig
