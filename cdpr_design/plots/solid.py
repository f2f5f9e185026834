"""Pictures of the workspace's boundary and of the loads on the frame.

:func:`draw_boundary` and :func:`draw_slice_outline` draw the boundary between the grid points
(:mod:`cdpr_design.workspaces.boundary`) over the workspace pictures; :func:`frame_load_figure`
is ``frame_loads.png`` (:mod:`cdpr_design.workspaces.frame_loads`).  Nothing is written.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import frame_rect, pad_limits
from cdpr_design.plots._style import BLUE, ORANGE, VERMILLION, pyplot

#: The boundary's line in the workspace pictures.
BOUNDARY_STYLE = dict(color=VERMILLION, lw=1.3, zorder=5)


def draw_boundary(ax, result) -> None:
    """The planar boundary's loops of ``result`` (a sweep planned with ``solid``) on ``ax``."""
    b = getattr(result, "boundary", None)
    if b is None or not b.loops:
        return
    for k, lp in enumerate(b.loops):
        closed = np.vstack([lp, lp[:1]])
        ax.plot(closed[:, 0], closed[:, 1], label="boundary between grid points" if k == 0 else None,
                **BOUNDARY_STYLE)


def slice_segments(vertices: np.ndarray, faces: np.ndarray, z: float) -> np.ndarray:
    """Where the plane at height ``z`` [m] cuts a triangle mesh: segments (s, 2, 2), their x, y [m]
    (a triangle with a vertex exactly on the plane is cut as if it lay a hair above it)."""
    if len(faces) == 0:
        return np.zeros((0, 2, 2))
    tri = vertices[faces]  # (F, 3, 3)
    above = tri[:, :, 2] > z
    count = above.sum(axis=1)
    cut = (count == 1) | (count == 2)
    tri, above = tri[cut], above[cut]
    segs = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        crosses = above[:, a] != above[:, b]
        pa, pb = tri[:, a], tri[:, b]
        # only an edge that crosses has ends at two heights: t of the others (0 / 0 or x / 0 on an
        # edge level with the plane or not reaching it) is never formed
        dz = pb[:, 2] - pa[:, 2]
        t = np.divide(z - pa[:, 2], dz, out=np.zeros_like(dz), where=crosses)
        p = pa[:, :2] + t[:, None] * (pb[:, :2] - pa[:, :2])
        segs.append(np.where(crosses[:, None], p, np.nan))
    pts = np.stack(segs, axis=1)  # (F', 3, 2): two of the three edges cross
    ok = ~np.isnan(pts[:, :, 0])
    return np.stack([pts[ok].reshape(-1, 2, 2)[:, 0], pts[ok].reshape(-1, 2, 2)[:, 1]], axis=1)


def draw_slice_outline(ax, result, z: float) -> None:
    """The spatial boundary's outline at height ``z`` [m] on ``ax`` (a sweep planned with ``solid``)."""
    from matplotlib.collections import LineCollection

    b = getattr(result, "boundary", None)
    if b is None or len(b.faces) == 0:
        return
    segs = slice_segments(b.vertices, b.faces, z)
    if len(segs):
        ax.add_collection(LineCollection(segs, colors=BOUNDARY_STYLE["color"], linewidths=BOUNDARY_STYLE["lw"],
                                         zorder=BOUNDARY_STYLE["zorder"]))


def frame_load_figure(result):
    """``frame_loads.png``: each outlet's force envelope over the feasible poses.

    Left (planar: the frame itself; spatial: its x-y footprint): at each outlet, the cable's
    force components' ranges drawn as a box from (min fx, min fy) to (max fx, max fy) off the
    outlet, scaled to the frame, an arrow to its middle and the cable's name there.  Right: per cable
    the largest force with the sweep's tensions and the largest the tension bounds allow.
    """
    d = result.design
    table = result.frame_loads
    names = d.cable_names
    cols = table.rows(names)
    fig = pyplot().figure(figsize=(10.5, 4.9))
    # the panels' two-line titles end below the figure's title (top 0.83 + two lines of 9 pt)
    ax = fig.add_axes([0.06, 0.11, 0.5, 0.72])
    bx = fig.add_axes([0.66, 0.11, 0.31, 0.72])
    frame_rect(ax, d)
    A = d.outlets
    ax.plot(A[:, 0], A[:, 1], "v", ms=8, mfc=VERMILLION, mec="k", zorder=6, label="outlets")
    lo, hi = np.array(d.frame_lower[:2], float), np.array(d.frame_upper[:2], float)
    span = float(np.max(hi - lo))
    peak = np.nanmax(np.abs([cols[f"{s}_f{a}"] for s in ("min", "max") for a in "xy"])) if table.poses else np.nan
    scale = 0.18 * span / peak if np.isfinite(peak) and peak > 0 else 0.0
    for i, c in enumerate(names):
        if not np.isfinite(cols["max_force"][i]):
            continue
        x0, y0 = A[i, 0], A[i, 1]
        fx = (cols["min_fx"][i], cols["max_fx"][i])
        fy = (cols["min_fy"][i], cols["max_fy"][i])
        xs = [x0 + scale * fx[0], x0 + scale * fx[1], x0 + scale * fx[1], x0 + scale * fx[0], x0 + scale * fx[0]]
        ys = [y0 + scale * fy[0], y0 + scale * fy[0], y0 + scale * fy[1], y0 + scale * fy[1], y0 + scale * fy[0]]
        ax.fill(xs, ys, color=BLUE, alpha=0.25, lw=0, zorder=3)
        ax.plot(xs, ys, color=BLUE, lw=1.0, zorder=4)
        # the force at the pose of largest tension points towards the workspace: an arrow to the box's centre
        cx, cy = np.mean(fx), np.mean(fy)
        ax.annotate("", xy=(x0 + scale * cx, y0 + scale * cy), xytext=(x0, y0),
                    arrowprops=dict(arrowstyle="->", color="k", lw=1.0), zorder=5)
        ax.text(x0 + scale * cx, y0 + scale * cy, c, fontsize=8, ha="center", va="center", zorder=7,
                bbox=dict(fc="white", ec="none", alpha=0.7, pad=1))
    pad_limits(ax, d)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"force ranges on the frame at each outlet\n(boxes: min..max of fx, fy; "
                 f"{1 / scale:.3g} N per m of drawing)" if scale else "no feasible pose: no load",
                 fontsize=9)
    y = np.arange(len(names))
    bx.barh(y + 0.2, np.nan_to_num(cols["limit_max_force"]), height=0.38, color=ORANGE,
            label="at the tension bounds")
    bx.barh(y - 0.2, np.nan_to_num(cols["max_force"]), height=0.38, color=BLUE, label="with the sweep's tensions")
    bx.set_yticks(y, names)
    bx.invert_yaxis()
    bx.set_xlabel("largest force on the frame [N]")
    bx.legend(loc="lower right", fontsize=8)
    total = table.summary(names)
    tf = total["total_force"]["max_magnitude"]
    tm = total["total_moment"]["max_magnitude"]
    bx.set_title("per cable, over the feasible poses" + (f"\ntotal ≤ {tf:.3g} N, moment ≤ {tm:.3g} N m"
                                                          if tf is not None else ""), fontsize=9)
    fig.suptitle(f"{d.name}: loads on the frame ({total['poses']:,} feasible poses)", fontsize=10, y=0.985)
    return fig
