"""The stiffness map of a workspace sweep (``workspace --stiffness``): ``stiffness_map.png``.

:func:`stiffness_figure` takes a :class:`~cdpr_design.workspaces.grid.WorkspaceResult` whose
``stiffness`` maps were kept (:mod:`cdpr_design.workspaces.stiffness`) and returns a
matplotlib Figure; nothing is written.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import colour_bar, extent, frame_rect, pad_limits, panel_grid, used_panels
from cdpr_design.plots._style import VERMILLION, cmap_grey_bad

#: (map, panel title, colour-bar label, scale) of the two panels.
PANELS = (("min_stiffness", "least stiffness", "kN/m", 1e-3),
          ("lowest_frequency", "lowest natural frequency", "Hz", 1.0))


def stiffness_figure(result):
    """The least stiffness [kN/m] and the lowest natural frequency [Hz] over the grid, one panel
    each (spatial motions: the z-slice with the most feasible poses); infeasible poses grey."""
    d = result.design
    feas = result.feasible_map.astype(bool)
    if d.motion.planar:
        iz, sub = None, ""
    else:
        iz = int(np.argmax(feas.sum(axis=(0, 1))))
        sub = f" at z = {result.map_axes[2][iz]:.3g} m (slice with the most feasible poses)"
    fig, axs, _ = panel_grid(2, 2, d, width=3.4, bar=False)
    ext = extent(result.map_axes[:2])
    for k, ax in used_panels(axs, 2):
        name, title, label, scale = PANELS[k]
        v = np.where(feas, np.asarray(result.stiffness[name], float), np.nan) * scale
        img = v if iz is None else v[:, :, iz]
        finite = img[np.isfinite(img)]
        vmax = float(finite.max()) if finite.size else 1.0
        im = ax.imshow(img.T, origin="lower", extent=ext, cmap=cmap_grey_bad("viridis"), vmin=0.0,
                       vmax=max(vmax, 1e-12), interpolation="nearest", aspect="equal")
        frame_rect(ax, d)
        ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=7, mfc=VERMILLION, mec="k", zorder=5)
        pad_limits(ax, d)
        least = f"{finite.min():.3g}" if finite.size else "—"
        ax.set_title(f"{title} [{label}]: least {least}", fontsize=9, y=1.0)
        colour_bar(fig, im, None, "", ax)  # the unit is in the panel's title
    fig.suptitle(f"{d.name}: stiffness and vibration, {result.kind} workspace (grey: infeasible)\n{sub.strip()}",
                 fontsize=10)
    return fig
