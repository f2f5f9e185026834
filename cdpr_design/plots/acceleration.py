"""The acceleration map of a workspace sweep (``workspace --accelerations``): ``acceleration_map.png``.

:func:`acceleration_figure` takes a :class:`~cdpr_design.workspaces.grid.WorkspaceResult` whose
``acceleration`` map was kept (:mod:`cdpr_design.workspaces.acceleration`) and returns a
matplotlib Figure; nothing is written.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import colour_bar, contourable, extent, frame_rect, pad_limits, panel_grid
from cdpr_design.plots._style import VERMILLION, cmap_grey_bad

#: Standard gravity [m/s^2], the colour bar's second unit.
G0 = 9.80665


def acceleration_figure(result):
    """The acceleration radius [m/s^2] over the grid (spatial motions: the z-slice with the most
    feasible poses): grey where the effector cannot be held at rest (radius 0), the outline of the
    sweep's feasible region in black."""
    d = result.design
    feas = result.feasible_map.astype(bool)
    radius = np.asarray(result.acceleration, float)
    if d.motion.planar:
        iz, sub = None, ""
    else:
        iz = int(np.argmax(feas.sum(axis=(0, 1))))
        sub = f"z = {result.map_axes[2][iz]:.3g} m, "
    img = radius if iz is None else radius[:, :, iz]
    fimg = feas if iz is None else feas[:, :, iz]
    shown = np.where(img > 0, img, np.nan)
    fig, axs, cax = panel_grid(1, 1, d, width=4.6, title_lines=2)
    ax = axs[0, 0]
    ext = extent(result.map_axes[:2])
    finite = shown[np.isfinite(shown)]
    vmax = float(finite.max()) if finite.size else 1.0
    im = ax.imshow(shown.T, origin="lower", extent=ext, cmap=cmap_grey_bad("viridis"), vmin=0.0,
                   vmax=max(vmax, 1e-12), interpolation="nearest", aspect="equal")
    if contourable(result.map_axes) and fimg.any() and not fimg.all():
        x, y = result.map_axes[:2]
        ax.contour(x, y, fimg.T.astype(float), levels=[0.5], colors="k", linewidths=1.0)
    frame_rect(ax, d)
    ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=7, mfc=VERMILLION, mec="k", zorder=5)
    pad_limits(ax, d)
    inside = img[fimg & np.isfinite(img)]
    rng = (f"{inside.min():.3g} – {inside.max():.3g} m/s² ({inside.min() / G0:.2g} – {inside.max() / G0:.2g} g)"
           if inside.size else "no feasible pose")
    ax.set_title(f"{sub}feasible poses: {rng}", fontsize=9, y=1.0)
    colour_bar(fig, im, cax, "acceleration radius [m/s²]")
    fig.suptitle(f"{d.name}: acceleration from rest in every direction, {result.kind} workspace\n"
                 "(grey: not held at rest; black line: the feasible region)", fontsize=10)
    return fig
