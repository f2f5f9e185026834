"""``certify.png``: the paving of a certified workspace in three colours over the frame."""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import frame_rect

#: colour of each status (inside, boundary, outside)
COLOURS = {1: "#4daf4a", 0: "#ffb000", -1: "#d9d9d9"}
NAMES = {1: "inside (proven)", 0: "boundary", -1: "outside (proven)"}
#: slices drawn of a 3D paving (fractions of the box's height)
SLICES = (0.2, 0.5, 0.8)


def _draw(ax, lower, upper, status, axes=(0, 1)) -> None:
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    a, b = axes
    for code in (-1, 1, 0):  # boundary last, on top
        sel = status == code
        lo, hi = lower[sel], upper[sel]
        quads = np.stack([np.c_[lo[:, a], lo[:, b]], np.c_[hi[:, a], lo[:, b]],
                          np.c_[hi[:, a], hi[:, b]], np.c_[lo[:, a], hi[:, b]]], axis=1)
        ax.add_collection(PolyCollection(quads, facecolors=COLOURS[code], edgecolors="none"))
    ax.legend(handles=[Patch(color=COLOURS[c], label=NAMES[c]) for c in (1, 0, -1)], loc="lower right",
              fontsize=8)
    ax.set_aspect("equal")


def certify_figure(result):
    """The paving of a :class:`~cdpr_design.workspaces.certify.CertifyResult`: the boxes in
    three colours over the frame (2D), or the boxes crossing three horizontal slices (3D)."""
    from matplotlib.figure import Figure

    s = result.summary()
    d = result.design
    title = (f"{d.name}: certified {s['kind']} workspace, inner {s['inner_measure']:.4g}, "
             f"outer {s['outer_measure']:.4g} {s['unit']}")
    if len(result.axes) == 2:
        fig = Figure(figsize=(7, 6.5))
        ax = fig.add_subplot()
        _draw(ax, result.lower, result.upper, result.status)
        frame_rect(ax, d)
        lo, hi = np.minimum(d.frame_lower, result.box[0] + (0,)), np.maximum(d.frame_upper, result.box[1] + (0,))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(title, fontsize=9)
        return fig
    fig = Figure(figsize=(5 * len(SLICES), 5))
    zlo, zhi = result.box[0][2], result.box[1][2]
    for i, f in enumerate(SLICES):
        z = zlo + f * (zhi - zlo)
        sel = (result.lower[:, 2] <= z) & (result.upper[:, 2] >= z)
        ax = fig.add_subplot(1, len(SLICES), i + 1)
        _draw(ax, result.lower[sel], result.upper[sel], result.status[sel])
        frame_rect(ax, d)
        ax.set_xlim(min(d.frame_lower[0], result.box[0][0]), max(d.frame_upper[0], result.box[1][0]))
        ax.set_ylim(min(d.frame_lower[1], result.box[0][1]), max(d.frame_upper[1], result.box[1][1]))
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"z = {z:.3g} m", fontsize=9)
    fig.suptitle(title, fontsize=10)
    return fig
