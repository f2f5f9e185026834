"""Workspace pictures: capacity-margin map, cable-tension maps, orientation workspace.

Each function takes a :class:`~cdpr_design.workspaces.grid.WorkspaceResult`
and returns a matplotlib Figure; nothing is written.  Planar motions give one
panel (drawn into ``ax`` when one is given), spatial motions a stack of
z-slices on a figure of their own.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import (colour_bar, contourable, draw_robot, extent, fit_width, frame_aspect,
                                      frame_rect, pad_limits, panel_grid, pose_txt, single_panel, slices,
                                      used_panels, z_slices)
from cdpr_design.plots._style import BLUE, VERMILLION, cmap_grey_bad, pyplot
from cdpr_design.plots.solid import draw_boundary, draw_slice_outline

_KIND_TEXT = {"static": "static-equilibrium", "wrench-feasible": "wrench-feasible",
              "wrench-closure": "wrench-closure", "dynamic": "dynamic"}


def _own_figure(ax, what: str) -> None:
    if ax is not None:
        raise ValueError(f"a spatial {what} is drawn as z-slices on a figure of its own (pass ax=None)")


def workspace_figure(result, title_extra: str = "", ax=None):
    """Feasible region shaded by capacity margin [N], with frame, outlets, cables and effector,
    and the boundary between the grid points where the sweep found it (red).

    Planar motions: one panel.  Spatial motions: a stack of z-slices (x-y
    panels), each with the frame's footprint, the outlets and the boundary's outline there.
    """
    d = result.design
    feas = result.feasible_map.astype(bool)
    marg = np.where(feas, result.margin_map, np.nan)
    finite = marg[np.isfinite(marg)]
    vmax = float(finite.max()) if finite.size else 1.0
    vmax = vmax if vmax > 0 else 1.0
    title = _workspace_title(result, title_extra)
    if d.motion.planar:
        return _planar_workspace(result, feas, marg, vmax, title, ax)
    _own_figure(ax, "workspace")
    return _spatial_workspace(result, feas, marg, vmax, title)


def _workspace_title(result, title_extra: str) -> str:
    d = result.design
    unit = "m²" if d.motion.planar else "m³"
    title = (f"{d.name}: {_KIND_TEXT[result.kind]} workspace — {100 * result.fraction:.1f} % of "
             f"{result.poses:,} poses feasible ({result.measure:.3g} {unit})")
    ori = result.orientation_coords()
    if ori:
        title += "\norientation " + ", ".join(
            f"{n} = {np.degrees(v):.3g}°" for n, v in zip(d.motion.rotation_coords, ori))
    f = d.requirements.min_cable_frequency
    if f is not None:  # the tensions' lower bound rises with each cable's length (docs/algorithms.md)
        title += f"\nevery cable's first string mode ≥ {f:g} Hz (requirements.min_cable_frequency)"
    if title_extra:
        title += "\n" + title_extra
    return title


def _planar_workspace(result, feas, marg, vmax, title, ax):
    from matplotlib.patches import Rectangle

    from cdpr_design import workspaces as wsmod

    d = result.design
    rep = wsmod.representative_pose(result)
    if ax is None:
        fig, ax, cax = single_panel(d, title_lines=title.count("\n") + 1)
    else:
        fig, cax = ax.figure, None
    im = ax.imshow(marg.T, origin="lower", extent=extent(result.map_axes), cmap=cmap_grey_bad("viridis"),
                   vmin=0.0, vmax=vmax, interpolation="nearest", aspect="equal", zorder=1)
    if contourable(result.map_axes):  # a grid of one row or column has no outline to draw
        ax.contour(result.map_axes[0], result.map_axes[1], feas.T.astype(float), levels=[0.5],
                   colors="k", linewidths=0.8, zorder=2)
    draw_boundary(ax, result)
    frame_rect(ax, d)
    draw_robot(ax, d, rep)
    if d.requirements.task_box is not None:
        lo, hi = d.requirements.task_box
        ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False,
                               ls="--", lw=1.5, ec=BLUE, zorder=4, label="task box"))
    pad_limits(ax, d)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    colour_bar(fig, im, cax, "capacity margin [N] (grey: infeasible)", ax)
    ax.legend(loc="best", fontsize=8, framealpha=0.9)
    ax.set_title(title, fontsize=10, y=1.0)
    if rep is not None:
        ax.text(0.01, 0.01, "drawn at the pose of largest margin " + pose_txt(d, rep),
                transform=ax.transAxes, fontsize=7, va="bottom", zorder=8,
                bbox=dict(fc="white", ec="none", alpha=0.7))
    return fig


def _spatial_workspace(result, feas, marg, vmax, title):
    d = result.design
    zs = slices(result)
    fig, axs, cax = panel_grid(len(zs), min(3, len(zs)), d, title_lines=title.count("\n") + 1)
    im = z_slices(axs, result, marg, feas, zs, cmap_grey_bad("viridis"), vmax)
    z_axis, eps = result.map_axes[2], 1e-6 * result.grid.step[2]
    for k, ax in used_panels(axs, len(zs)):  # the box's top and bottom faces cut just inside
        draw_slice_outline(ax, result, float(np.clip(z_axis[zs[k]], z_axis[0] + eps, z_axis[-1] - eps)))
    fig.suptitle(title, fontsize=10)
    colour_bar(fig, im, cax, "capacity margin [N] (grey: infeasible)")
    return fig


def tension_figure(result):
    """Tension [N] of each cable over the grid: one panel per cable, shared colour scale.

    Infeasible poses are masked (grey).  Spatial motions show, for every
    cable, the z-slice with the most feasible poses.
    """
    d = result.design
    feas = result.feasible_map.astype(bool)
    T = np.where(feas[None], result.tension_maps, np.nan)
    finite = T[np.isfinite(T)]
    vmin = 0.0
    vmax = float(finite.max()) if finite.size else 1.0
    if vmax <= vmin:
        vmax = vmin + 1.0
    if d.motion.planar:
        img, sub = T, ""
    else:
        iz = int(np.argmax(feas.sum(axis=(0, 1))))
        img = T[:, :, :, iz]
        sub = f" at z = {result.map_axes[2][iz]:.3g} m (slice with the most feasible poses)"
    m = d.m
    fig, axs, cax = panel_grid(m, min(4, m), d, width=3.1)
    cmap = cmap_grey_bad("cividis")
    ext = extent(result.map_axes[:2])
    im = None
    for i, ax in used_panels(axs, d.m):
        im = ax.imshow(img[i].T, origin="lower", extent=ext, cmap=cmap, vmin=vmin, vmax=vmax,
                       interpolation="nearest", aspect="equal")
        frame_rect(ax, d)
        A = d.outlets
        ax.plot(A[i, 0], A[i, 1], "v", ms=9, mfc=VERMILLION, mec="k", zorder=6)
        pad_limits(ax, d)
        c = d.cables[i]
        ax.set_title(f"{c.name}: {c.tension_min:g}–{c.tension_max:g} N", fontsize=9, y=1.0)
    fig.suptitle(f"{d.name}: minimum-norm cable tensions, {result.kind} workspace{sub}", fontsize=10)
    colour_bar(fig, im, cax, "cable tension [N] (grey: infeasible)")
    return fig


def orientation_figure(result, ax=None):
    """Orientation workspace picture: the fraction of the orientation set that is
    feasible (``total``; the total orientation workspace outlined) or the
    orientation range scale s (``range``: the largest feasible box is
    nominal +- s * max) over the grid; a z-slice stack for spatial motions."""
    d = result.design
    om = result.orientation_maps
    val = np.asarray(om.value, float)
    feas = result.feasible_map.astype(bool)
    title, label = _orientation_title(result)
    if d.motion.planar:
        return _planar_orientation(result, val, feas, title, label, ax)
    _own_figure(ax, "orientation workspace")
    return _spatial_orientation(result, val, feas, title, label)


def _orientation_title(result) -> tuple[str, str]:
    """(title, colour-bar label) of :func:`orientation_figure`."""
    d = result.design
    om = result.orientation_maps
    rot = d.motion.rotation_coords
    if om.mode == "total":
        lo, hi = om.orientations.min(axis=0), om.orientations.max(axis=0)
        idx = [i - 3 for i in d.motion.pose_index[d.motion.dim:]]
        box = ", ".join(f"{c} ∈ [{np.degrees(lo[i]):.3g}°, {np.degrees(hi[i]):.3g}°]" for c, i in zip(rot, idx))
        title = (f"{d.name}: total orientation workspace ({result.kind}) — {100 * result.fraction:.1f} % "
                 f"of {result.poses:,} positions feasible for all {len(om.orientations)} orientations\n{box}")
        return title, "fraction of the orientation set feasible"
    mx = ", ".join(f"{c} ± {np.degrees(s):.3g}°" for c, s in zip(rot, om.scale))
    title = (f"{d.name}: orientation range per position ({result.kind}) — largest feasible box "
             f"s × ({mx})")
    return title, "range scale s (grey: nominal orientation infeasible)"


def _planar_orientation(result, val, feas, title, label, ax):
    d = result.design
    if ax is None:
        fig, ax, cax = single_panel(d, title_lines=title.count("\n") + 1)
    else:
        fig, cax = ax.figure, None
    im = ax.imshow(val.T, origin="lower", extent=extent(result.map_axes), cmap=cmap_grey_bad("cividis"),
                   vmin=0.0, vmax=1.0, interpolation="nearest", aspect="equal", zorder=1)
    if result.orientation_maps.mode == "total" and feas.any() and contourable(result.map_axes):
        ax.contour(result.map_axes[0], result.map_axes[1], feas.T.astype(float), levels=[0.5],
                   colors="k", linewidths=0.8, zorder=2)
    draw_boundary(ax, result)
    frame_rect(ax, d)
    ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=7, mfc=VERMILLION, mec="k", zorder=5)
    pad_limits(ax, d)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    colour_bar(fig, im, cax, label, ax)
    ax.set_title(title, fontsize=9, y=1.0)
    return fig


def _spatial_orientation(result, val, feas, title, label):
    zs = slices(result)
    fig, axs, cax = panel_grid(len(zs), min(3, len(zs)), result.design, title_lines=title.count("\n") + 1)
    im = z_slices(axs, result, val, feas, zs, cmap_grey_bad("cividis"), 1.0)
    fig.suptitle(title, fontsize=9)
    colour_bar(fig, im, cax, label)
    return fig


#: Okabe-Ito colours (safe for colour-blind readers): neither, ideal only, model only, both.
_COMPARE = ("#e8e8e8", "#E69F00", "#0072B2", "#009E73")


def cable_model_figure(result, ideal):
    """Where the design's cable model and ideal cables agree: feasible under both, one, or neither.

    ``result`` is the sweep with the design's cable model, ``ideal`` the same
    grid with ideal cables (same map cells).  Planar: one panel; spatial: z-slices.
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    d = result.design
    model = result.extra.get("cable_model", "model")
    a, b = ideal.feasible_map.astype(bool), result.feasible_map.astype(bool)
    code = (a & ~b) * 1.0 + (~a & b) * 2.0 + (a & b) * 3.0
    cmap = ListedColormap(_COMPARE)
    counts = [int(((code == k)).sum()) for k in range(4)]
    labels = [f"neither ({counts[0]:,})", f"ideal only ({counts[1]:,})", f"{model} only ({counts[2]:,})",
              f"both ({counts[3]:,})"]
    handles = [Patch(fc=c, ec="k", lw=0.5, label=lab) for c, lab in zip(_COMPARE, labels)]
    title = (f"{d.name}: feasible poses with {model} and ideal cables "
             f"({_KIND_TEXT[result.kind]}, map cells)")
    if d.motion.planar:
        height = 6.4 * frame_aspect(d) + 1.4
        fig, ax = pyplot().subplots(figsize=(7.5, height))
        fig.subplots_adjust(left=0.09, right=0.97, bottom=0.75 / height, top=1 - 0.55 / height)
        ax.imshow(code.T, origin="lower", extent=extent(result.map_axes), cmap=cmap, vmin=0.0, vmax=3.0,
                  interpolation="nearest", aspect="equal", zorder=1)
        frame_rect(ax, d)
        ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=7, mfc="tab:red", mec="k", zorder=5)
        pad_limits(ax, d)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(handles=handles, loc="lower right", fontsize=8, framealpha=0.9)
        ax.set_title(title, fontsize=10)
        return fig
    zs = slices(result)
    lines = title.count("\n") + 1
    # one more title line: the legend's row, under the title
    fig, axs, _ = panel_grid(len(zs), min(3, len(zs)), d, title_lines=lines + 1, bar=False)
    z_slices(axs, result, code, b, zs, cmap, 3.0)
    height = fig.get_size_inches()[1]
    fig.legend(handles=handles, loc="upper center", ncol=4, fontsize=8,
               bbox_to_anchor=(0.5, 1 - (0.3 * lines + 0.06) / height))
    fig.suptitle(title, fontsize=10)
    fit_width(fig)
    return fig
