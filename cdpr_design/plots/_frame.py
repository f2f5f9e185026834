"""Drawing helpers shared by the figures: the frame, the robot, image extents, slices."""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._style import ORANGE, VERMILLION


def frame_rect(ax, design, **kw) -> None:
    """The frame's x-y footprint as a rectangle outline."""
    from matplotlib.patches import Rectangle

    lo, hi = design.frame_lower, design.frame_upper
    ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False,
                           lw=2.0, ec=kw.get("ec", "0.15"), zorder=3))


def draw_robot(ax, design, pose, proj=(0, 1)) -> None:
    """Outlets, cables and the effector box at ``pose`` (motion coords [m, rad]), projected."""
    from matplotlib.patches import Polygon

    from cdpr_design.statics import kinematics as kin

    a, b = proj
    A = design.outlets
    ax.plot(A[:, a], A[:, b], "v", ms=9, mfc=VERMILLION, mec="k", zorder=6, label="outlets")
    for i, c in enumerate(design.cables):
        ax.annotate(c.name, (A[i, a], A[i, b]), textcoords="offset points", xytext=(4, 6),
                    fontsize=8, zorder=7)
    if pose is None:
        return
    geo = kin.cable_geometry(design, pose)
    for i in range(design.m):
        ax.plot([A[i, a], geo.anchors[i, a]], [A[i, b], geo.anchors[i, b]], "-", color="k",
                lw=1.2, zorder=5)
    R = kin.pose_rotation(design, pose)
    full = design.full_pose(pose)
    hx, hy = design.effector.size[a] / 2, design.effector.size[b] / 2
    corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    pts3 = np.zeros((4, 3))
    pts3[:, a], pts3[:, b] = corners[:, 0], corners[:, 1]
    world = full[:3] + pts3 @ R.T
    ax.add_patch(Polygon(world[:, [a, b]], closed=True, fc=ORANGE, ec="k", lw=1.0,
                         alpha=0.9, zorder=6, label="effector"))


def extent(axes2) -> list[float]:
    """``imshow`` extent [m] of a map over the grid axes (x, y): cell edges, not centres."""
    x, y = axes2
    dx = (x[1] - x[0]) if x.size > 1 else 1.0
    dy = (y[1] - y[0]) if y.size > 1 else 1.0
    return [x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2]


def contourable(axes2) -> bool:
    """Whether a map over the grid axes (x, y) can take a contour line (two samples on each axis at least)."""
    return all(np.asarray(a).size >= 2 for a in axes2[:2])


def slices(result, nmax: int = 6) -> list[int]:
    """z-slice indices to show for a spatial result: evenly spread, up to nmax."""
    nz = result.feasible_map.shape[2]
    if nz <= nmax:
        return list(range(nz))
    return sorted({int(round(v)) for v in np.linspace(0, nz - 1, nmax)})


def pose_txt(d, pose) -> str:
    """``(x = 0.75, y = 0.75)``: a pose in the motion's coordinates."""
    return "(" + ", ".join(f"{n} = {v:.3g}" for n, v in zip(d.motion.coords, pose)) + ")"


def frame_aspect(d) -> float:
    """Height / width of the frame's x-y footprint (panel shape of the pictures)."""
    lo, hi = np.array(d.frame_lower), np.array(d.frame_upper)
    return float(np.clip((hi[1] - lo[1]) / (hi[0] - lo[0]), 0.3, 3.0))


#: Room around a map panel [in]: left (tick labels, y label), below (tick labels, x label),
#: above (the panel's title), and to the right of the panels for the colour bar.
_LEFT, _BELOW, _ABOVE, _BAR = 0.75, 0.55, 0.32, 1.15


def panel_grid(n: int, ncol: int, aspect: float, width: float = 3.4, title_lines: int = 1,
               panel_title_lines: int = 1):
    """A figure of ``n`` equal-aspect map panels, ``ncol`` a row, sized to its content.

    Each panel's axes are ``width`` [in] wide and ``aspect`` x ``width`` high
    (the frame's shape); the figure adds fixed room for tick and axis labels,
    ``panel_title_lines`` of panel title, ``title_lines`` of figure title and a colour bar on the
    right (its own axes, so the panels keep their size), placed by
    arithmetic: no white bands between or around the panels, and no layout
    engine to run at drawing time.  Returns (figure, axes (nrow, ncol), colour-bar axes).
    """
    import math

    from cdpr_design.plots._style import pyplot

    nrow = math.ceil(n / ncol)
    height = width * aspect
    top = 0.3 * title_lines + 0.12
    above = _ABOVE * panel_title_lines
    W = ncol * (width + _LEFT) + _BAR
    H = top + nrow * (above + height + _BELOW)
    fig, axs = pyplot().subplots(nrow, ncol, squeeze=False, figsize=(W, H))
    fig.subplots_adjust(left=_LEFT / W, right=1 - _BAR / W, bottom=_BELOW / H, top=1 - (top + above) / H,
                        wspace=_LEFT / width, hspace=(above + _BELOW) / height)
    span = 1 - (top + above + _BELOW) / H  # the panels' height, as a fraction of the figure's
    cax = fig.add_axes((1 - 0.85 * _BAR / W, _BELOW / H + 0.1 * span, 0.16 / W, 0.8 * span))
    return fig, axs, cax


def single_panel(aspect: float, width: float = 5.8, title_lines: int = 1):
    """:func:`panel_grid` of one panel (a planar map) whose title has ``title_lines``:
    (figure, axes, colour-bar axes)."""
    fig, axs, cax = panel_grid(1, 1, aspect, width, title_lines=0, panel_title_lines=title_lines)
    return fig, axs[0, 0], cax


def pad_limits(ax, d) -> None:
    """Axis limits: the frame's footprint plus a 6 % margin."""
    lo, hi = np.array(d.frame_lower), np.array(d.frame_upper)
    pad = 0.06 * (hi - lo)
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])



def used_panels(axs, n: int):
    """(k, ax) of the first ``n`` panels of a grid of axes; the others are hidden, in turn."""
    for k, ax in enumerate(axs.flat):
        if k >= n:
            ax.axis("off")
        else:
            yield k, ax


def z_slices(axs, result, values, feas, zs, cmap, vmax: float):
    """One x-y panel per z-slice index in ``zs``: ``values`` [nx, ny, nz] shaded, the frame's
    footprint, the outlets and the feasible share in the title.  Returns the last image."""
    d = result.design
    ext = extent(result.map_axes[:2])
    z_axis = result.map_axes[2]
    im = None
    for k, ax in used_panels(axs, len(zs)):
        iz = zs[k]
        im = ax.imshow(values[:, :, iz].T, origin="lower", extent=ext, cmap=cmap, vmin=0.0, vmax=vmax,
                       interpolation="nearest", aspect="equal")
        frac = feas[:, :, iz].mean() if feas[:, :, iz].size else 0.0
        frame_rect(ax, d)
        A = d.outlets
        ax.plot(A[:, 0], A[:, 1], "v", ms=6, mfc=VERMILLION, mec="k")
        pad_limits(ax, d)
        ax.set_title(f"z = {z_axis[iz]:.3g} m  ({100 * frac:.0f} % feasible)", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    return im
