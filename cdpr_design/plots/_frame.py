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


#: Room around the map panels [in]: left of them (tick labels, y label), below them (tick labels,
#: x label), above each (its title), to their right for the colour bar, and between two
#: panels (only the outer ones carry tick and axis labels: :func:`_outer_ticks`).
_LEFT, _BELOW, _ABOVE, _BAR, _GAP = 0.62, 0.5, 0.26, 1.0, 0.14
#: Room to the right of the panels [in] when there is no colour bar.
_RIGHT = 0.15


def panel_grid(n: int, ncol: int, design, width: float = 3.4, title_lines: int = 1,
               panel_title_lines: int = 1, bar: bool = True):
    """A figure of ``n`` equal-aspect map panels of ``design``'s frame, ``ncol`` a row, sized to
    its content.

    Each panel's axes are ``width`` [in] wide and :func:`frame_aspect` x ``width``
    high; the figure adds fixed room for tick and axis labels,
    ``panel_title_lines`` of panel title, ``title_lines`` of figure title and (``bar``) a colour
    bar on the right (its own axes, so the panels keep their size), placed by
    arithmetic: no white bands between or around the panels, and no layout
    engine to run at drawing time.  Every panel shows the same x-y range
    (:func:`pad_limits`), so only the outer ones carry tick and axis labels
    (:func:`_outer_ticks`); panels beyond ``n`` are hidden.
    Returns (figure, axes (nrow, ncol), colour-bar axes or None without ``bar``).
    """
    import math

    from cdpr_design.plots._style import pyplot

    nrow = math.ceil(n / ncol)
    height = width * frame_aspect(design)
    top = 0.3 * title_lines + 0.12
    above = _ABOVE * panel_title_lines + 0.04
    right = _BAR if bar else _RIGHT
    W = _LEFT + ncol * width + (ncol - 1) * _GAP + right
    H = top + nrow * (above + height) + (nrow - 1) * _GAP + _BELOW
    fig, axs = pyplot().subplots(nrow, ncol, squeeze=False, figsize=(W, H))
    fig.subplots_adjust(left=_LEFT / W, right=1 - right / W, bottom=_BELOW / H, top=1 - (top + above) / H,
                        wspace=_GAP / width, hspace=(above + _GAP) / height)
    span = 1 - (top + above + _BELOW) / H  # the panels' height, as a fraction of the figure's
    cax = fig.add_axes((1 - 0.8 * _BAR / W, _BELOW / H + 0.1 * span, 0.16 / W, 0.8 * span)) if bar else None
    for _, ax in used_panels(axs, n):
        ax.set_aspect("equal")  # as the maps are drawn (imshow)
        pad_limits(ax, design)
    _outer_ticks(axs, n)
    return fig, axs, cax


def _outer_ticks(axs, n: int, xlabel: str = "x [m]", ylabel: str = "y [m]") -> None:
    """Ticks for the first ``n`` panels of a grid (row by row), all of one size and x-y range.

    The lowest used panel of each column carries the x tick labels and
    ``xlabel``, the left column the y tick labels and ``ylabel``, at the places
    matplotlib's default locator picks for the panel (those within the limits).
    The other panels get tick marks at the same places, drawn as one line of
    markers a side instead of matplotlib's ticks: each of those is two lines, a
    grid line and two texts, made, laid out and drawn one by one, most of a
    picture's time when every panel had its own.
    """
    from matplotlib.ticker import FixedLocator, NullLocator

    ref = axs.flat[0]
    ref.apply_aspect()  # the panel's drawn size: the locator's number of ticks depends on it
    ticks = [_in_view(ref.xaxis.get_majorticklocs(), ref.get_xlim()),
             _in_view(ref.yaxis.get_majorticklocs(), ref.get_ylim())]
    ncol = axs.shape[1]
    for k, ax in enumerate(axs.flat[:n]):
        outer = (k + ncol >= n, k % ncol == 0)  # (no used panel below, the left column)
        for i, (axis, label) in enumerate(((ax.xaxis, xlabel), (ax.yaxis, ylabel))):
            if outer[i]:
                axis.set_major_locator(FixedLocator(ticks[i]))
                axis.set_label_text(label)
            else:
                axis.set_major_locator(NullLocator())
                _tick_marks(ax, ticks[i], "xy"[i])


def _in_view(locs, lims) -> np.ndarray:
    """The tick positions ``locs`` within the axis limits ``lims`` (the others are never drawn)."""
    lo, hi = sorted(lims)
    tol = 1e-9 * (hi - lo)
    locs = np.asarray(locs, float)
    return locs[(locs >= lo - tol) & (locs <= hi + tol)]


def _tick_marks(ax, locs, which: str) -> None:
    """Tick marks (no labels) at ``locs`` [data units] on the bottom (``which="x"``) or left
    (``"y"``) side of ``ax``, drawn like matplotlib's major ticks: one line of markers."""
    import matplotlib as mpl
    from matplotlib.lines import Line2D
    from matplotlib.markers import TICKDOWN, TICKLEFT

    rc = mpl.rcParams
    zero = np.zeros(len(locs))
    xy, transform, marker = (((locs, zero), ax.get_xaxis_transform(), TICKDOWN) if which == "x"
                             else ((zero, locs), ax.get_yaxis_transform(), TICKLEFT))
    ax.add_line(Line2D(*xy, transform=transform, linestyle="none", marker=marker, clip_on=False,
                       markersize=rc[f"{which}tick.major.size"], markeredgewidth=rc[f"{which}tick.major.width"],
                       color=rc[f"{which}tick.color"], zorder=2.5))


#: Room kept between the outermost text and the figure's left and right edges [in].
_EDGE = 0.06


def colour_bar(fig, im, cax, label: str, ax=None) -> None:
    """The colour bar of ``im``, labelled ``label``: in ``cax`` (:func:`panel_grid`'s), then
    :func:`fit_width`; without ``cax``, beside ``ax`` (a caller's axes, in a figure laid out
    by the caller)."""
    if cax is None:
        fig.colorbar(im, ax=ax, shrink=0.85, label=label)
        return
    fig.colorbar(im, cax=cax, label=label)
    fit_width(fig, cax)


def fit_width(fig, cax=None) -> None:
    """Widen a :func:`panel_grid` figure where its texts would pass the left or right edge.

    :func:`panel_grid` leaves fixed room for the left column's y tick labels
    and label and for the colour bar ``cax`` with its tick labels and label;
    where they need more (long tick labels, a minus sign, the descenders of a
    label at the edge) the figure grows on that side by what they need, every
    axes keeping its size and place in inches.  The figure's own texts and
    legends (a suptitle, a legend row over the panels) stay where they are as a
    fraction of its width (centred, as drawn here); where one is wider than the
    figure with that room (the title over a single panel), the figure grows by
    the difference, half on either side.  Measured on the figure's renderer;
    call it once all of them are set.  It measures the first panel of the left
    column with a y label (every one carries the same ticks and label at the
    same x: :func:`_outer_ticks`) and the colour bar's y axis and frame (nothing
    else of it reaches further right), so the other panels' y axes are laid out
    once, when drawn, and not also here."""
    renderer = fig.canvas.get_renderer()
    width, height = fig.get_size_inches()
    first = next((ax for ax in fig.axes if ax is not cax and ax.get_visible() and ax.axison and ax.get_ylabel()),
                 None)
    box = first.yaxis.get_tightbbox(renderer) if first is not None else None
    left = max(_EDGE - box.x0 / fig.dpi, 0.0) if box is not None else 0.0
    right = 0.0
    if cax is not None:
        x1 = max(cax.yaxis.get_tightbbox(renderer).x1, cax.get_window_extent(renderer).x1)
        right = max(x1 / fig.dpi + _EDGE - width, 0.0)
    spare = _figure_text_width(fig, renderer, width) - (width + left + right)
    if spare > 0.0:
        left, right = left + spare / 2, right + spare / 2
    if left == 0.0 and right == 0.0:
        return
    new = width + left + right
    for ax in fig.axes:
        x0, y0, w, h = ax.get_position(original=True).bounds
        ax.set_position(((x0 * width + left) / new, y0, w * width / new, h))
        ax.set_in_layout(True)  # set_position takes the axes out of any later layout engine's hands
    fig.set_size_inches(new, height)


def _figure_text_width(fig, renderer, width: float) -> float:
    """The figure width [in] its own texts and legends need to keep :data:`_EDGE` from both edges,
    each staying centred where it is now as a fraction of the width (0 without any)."""
    need = 0.0
    for artist in (*fig.texts, *fig.legends):
        if not artist.get_visible():
            continue
        box = artist.get_window_extent(renderer)
        x0, x1 = box.x0 / fig.dpi, box.x1 / fig.dpi
        at = min(max(0.5 * (x0 + x1) / width, 0.05), 0.95)  # its centre, as a fraction of the width
        half = 0.5 * (x1 - x0) + _EDGE
        need = max(need, half / at, half / (1.0 - at))
    return need


def single_panel(design, width: float = 5.8, title_lines: int = 1):
    """:func:`panel_grid` of one panel (a planar map of ``design``) whose title has
    ``title_lines``: (figure, axes, colour-bar axes)."""
    fig, axs, cax = panel_grid(1, 1, design, width, title_lines=0, panel_title_lines=title_lines)
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
    footprint, the outlets and the feasible share in the title (ticks and axis labels: :func:`panel_grid`).
    Returns the last image."""
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
        ax.set_title(f"z = {z_axis[iz]:.3g} m  ({100 * frac:.0f} % feasible)", fontsize=9, y=1.0)
    return im
