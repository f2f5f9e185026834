"""The tilt map of an under-constrained design: how far its effector hangs from level.

:func:`tilt_figure` takes a :class:`~cdpr_design.workspaces.grid.WorkspaceResult`
of an under-constrained design (its ``hanging`` maps,
:mod:`cdpr_design.workspaces.hanging`) and returns a matplotlib Figure;
nothing is written.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import (colour_bar, contourable, extent, frame_rect, pad_limits, panel_grid, slices,
                                      z_slices)
from cdpr_design.plots._style import cmap_grey_bad, pyplot

#: Tilt contours drawn on planar maps [deg].
LEVELS = (5, 10, 20, 30, 40, 60)


def _title(result) -> str:
    d, hm = result.design, result.hanging
    worst = result.summary().get("max_tilt")
    if hm.orientation_mode == "free":
        what = "effector.orientation: free — feasibility judged at the hanging pose" + (
            f", tilt limit {hm.tilt_limit:g}°" if hm.tilt_limit is not None else "")
    else:
        what = "effector.orientation: fixed — the analysis holds it; the free body would hang so"
    return (f"{d.name}: tilt of the hanging effector\n{what}\nlargest over the feasible poses "
            + (f"{worst:.3g}°" if worst is not None else "—") + "; grey: it cannot hang there")


def tilt_figure(result, ax=None):
    """Tilt [deg] the effector hangs with over the grid (grey where it cannot hang), the
    feasible region outlined and tilt contours (planar); z-slices for spatial designs."""
    d = result.design
    tilt = np.asarray(result.hanging.tilt, float)
    feas = result.feasible_map.astype(bool)
    finite = tilt[np.isfinite(tilt)]
    vmax = max(float(finite.max()), 1.0) if finite.size else 1.0
    if d.motion.planar:
        return _planar(result, tilt, feas, vmax, ax)
    if ax is not None:
        raise ValueError("a spatial tilt map is drawn as z-slices on a figure of its own (pass ax=None)")
    zs = slices(result)
    title = _title(result)
    fig, axs, cax = panel_grid(len(zs), min(3, len(zs)), d, title_lines=title.count("\n") + 1)
    im = z_slices(axs, result, tilt, feas, zs, cmap_grey_bad("plasma"), vmax)
    fig.suptitle(title, fontsize=9)
    colour_bar(fig, im, cax, "tilt from level [deg] (grey: it cannot hang there)")
    return fig


def _planar(result, tilt, feas, vmax, ax):
    d = result.design
    if ax is None:
        fig, ax = pyplot().subplots(figsize=(7.5, 6.6))
        fig.subplots_adjust(left=0.09, right=0.97, bottom=0.08, top=0.88)
    fig = ax.figure
    x, y = result.map_axes
    im = ax.imshow(tilt.T, origin="lower", extent=extent(result.map_axes), cmap=cmap_grey_bad("plasma"),
                   vmin=0.0, vmax=vmax, interpolation="nearest", aspect="equal", zorder=1)
    if feas.any() and not feas.all() and contourable(result.map_axes):
        ax.contour(x, y, feas.T.astype(float), levels=[0.5], colors="w", linewidths=1.2, zorder=2)
    levels = [v for v in LEVELS if v < vmax]
    if levels and contourable(result.map_axes):
        cs = ax.contour(x, y, np.nan_to_num(tilt, nan=-1.0).T, levels=levels, colors="k", linewidths=0.6,
                        zorder=3)
        ax.clabel(cs, fmt="%g°", fontsize=7)
    frame_rect(ax, d)
    A = d.outlets
    ax.plot(A[:, 0], A[:, 1], "v", ms=9, mfc="tab:red", mec="k", zorder=6)
    pad_limits(ax, d)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    colour_bar(fig, im, None, "tilt from level [deg] (white line: feasible region)", ax)
    ax.set_title(_title(result), fontsize=9)
    return fig
