"""Motion pictures: a sampled trajectory (path and axis set-points) and a simulated run.

Each function takes the result objects of :mod:`cdpr_design.motion` and
returns a matplotlib Figure; nothing is written.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.plots._frame import draw_robot, extent, frame_rect, pad_limits
from cdpr_design.plots._style import BLUE, VERMILLION, pyplot

#: The static workspace under a path: light blue (grey elsewhere).
_FEASIBLE = (0.80, 0.88, 0.96)


def trajectory_path_figure(design, samples, workspace_result=None, ax=None):
    """The sampled path over the static workspace map (planar) or the frame (x-y projection).

    Feasible samples in blue, infeasible ones in vermillion; corners marked; the
    robot drawn at the first pose.  ``workspace_result``: a static workspace
    (planar designs) drawn underneath.
    """
    if ax is None:
        fig, ax = pyplot().subplots(figsize=(7.2, 6.4))
        fig.subplots_adjust(left=0.1, right=0.97, bottom=0.08, top=0.9)
    if workspace_result is not None and design.motion.planar:
        _feasible_underlay(ax, workspace_result)
    frame_rect(ax, design)
    draw_robot(ax, design, samples.pose[0])
    p = samples.pose
    ax.plot(p[:, 0], p[:, 1], "-", color=BLUE, lw=1.6, zorder=7, label="path")
    bad = ~samples.feasible
    if bad.any():
        ax.plot(p[bad, 0], p[bad, 1], ".", color=VERMILLION, ms=3, zorder=8, label="infeasible tensions")
    ends = [s.last for s in samples.segments if s.kind != "arc"]
    if ends:
        ax.plot(p[ends, 0], p[ends, 1], "o", mfc="white", mec=BLUE, ms=5, zorder=9, label="waypoints")
    pad_limits(ax, design)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    s = samples.summary()
    ax.set_title(f"{design.name}: trajectory {samples.name} — {s['duration']:.3g} s, peak "
                 f"{s['max_speed']:.3g} m/s, {s['max_acceleration']:.3g} m/s²"
                 + ("" if samples.all_feasible else f"\n{s['infeasible_samples']} infeasible samples"),
                 fontsize=10)
    ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    return ax.figure


def _feasible_underlay(ax, workspace_result) -> None:
    """The feasible cells of a planar workspace in light green, the rest light grey."""
    from matplotlib.colors import ListedColormap

    feas = workspace_result.feasible_map.astype(float)
    ax.imshow(feas.T, origin="lower", extent=extent(workspace_result.map_axes),
              cmap=ListedColormap([(0.88, 0.88, 0.88), _FEASIBLE]), vmin=0, vmax=1,
              interpolation="nearest", aspect="equal", zorder=1)
    ax.plot([], [], "s", color=_FEASIBLE, label="static workspace")


def trajectory_axes_figure(samples):
    """Axis set-points over time [s]: pose, cable lengths, cable speeds, motor angles, tensions."""
    fig, axs = pyplot().subplots(5, 1, figsize=(8, 10.5), sharex=True)
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.05, top=0.95, hspace=0.12)
    t = samples.time
    for j, c in enumerate(samples.coords):
        axs[0].plot(t, samples.pose[:, j], label=c)
    axs[0].set_ylabel("pose [m, rad]")
    for data, ax, lab in ((samples.lengths, axs[1], "length [m]"), (samples.cable_speed, axs[2], "cable speed [m/s]"),
                          (samples.motor_angle, axs[3], "motor angle [rad]"), (samples.tensions, axs[4], "tension [N]")):
        for i, c in enumerate(samples.cable_names):
            ax.plot(t, data[:, i], label=c)
        ax.set_ylabel(lab)
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=4)
    axs[-1].set_xlabel("time [s]")
    fig.suptitle(f"trajectory {samples.name}: set-points every {1000 * samples.cycle_time:g} ms", fontsize=10)
    return fig


def simulation_figure(result):
    """Target against simulated run over time [s]: position [m], position error [mm], tensions [N]."""
    fig, axs = pyplot().subplots(3, 1, figsize=(8, 8.5), sharex=True)
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.06, top=0.93, hspace=0.12)
    t = result.time
    npos = sum(1 for c in result.coords if c in ("x", "y", "z"))
    for j in range(npos):
        c = result.coords[j]
        line, = axs[0].plot(t, result.target_pose[:, j], "--", lw=1.0, label=f"{c} target")
        axs[0].plot(t, result.pose[:, j], "-", color=line.get_color(), lw=1.4, label=c)
    axs[0].set_ylabel("position [m]")
    err_ = np.linalg.norm(result.pose[:, :npos] - result.target_pose[:, :npos], axis=1)
    axs[1].plot(t, 1000 * err_, color=VERMILLION)
    axs[1].set_ylabel("position error [mm]")
    for i, c in enumerate(result.cable_names):
        axs[2].plot(t, result.tensions[:, i], label=c)
    axs[2].set_ylabel("tension [N]")
    axs[2].set_xlabel("time [s]")
    for ax in axs:
        ax.grid(alpha=0.3)
    axs[0].legend(loc="upper right", fontsize=7, ncol=3)
    axs[2].legend(loc="upper right", fontsize=7)
    st = result.settings
    fig.suptitle(f"simulation of {result.name}: delay {1000 * st.get('delay', 0):g} ms, servo bandwidth "
                 f"{st.get('servo_bandwidth', float('nan')):g} rad/s", fontsize=10)
    return fig


#: Colours of the constraints active along a time-optimal profile (time_optimal.CONSTRAINTS order).
_ACTIVE_COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00")


def time_optimal_figure(design, name, timing):
    """The time-optimal profile of trajectory ``name`` (a :class:`~cdpr_design.motion.time_optimal.Timing`):
    path speed s' [m/s] against the position along the path s [m], with the limit curve (the
    largest s' the constraints allow at each s) and the constraint active at each point."""
    from cdpr_design.motion.time_optimal import CONSTRAINTS

    fig, ax = pyplot().subplots(figsize=(8.0, 4.8))
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.12, top=0.84)
    top = max((float(g.speed.max()) for g in timing.segments), default=0.0)
    ceiling = 1.6 * top if top > 0 else 1.0
    above = []
    for k, g in enumerate(timing.segments):
        s = g.start + g.s
        finite = np.isfinite(g.limit) & (g.limit < 1e5)
        if finite.any() and g.limit[finite].min() > ceiling:
            above.append((float(g.limit[finite].min()), float(g.limit[finite].max())))
        ax.plot(s[finite], g.limit[finite], "-", color="0.35", lw=1.6, label="limit curve (max. velocity)")
        for arr, style, lab in ((g.stoppable, ":", "stops at rest by the corner"),
                                (g.reachable, "--", "reached from rest at the corner")):
            if arr is not None:
                ax.plot(s, arr, style, color="0.55", lw=1.0, label=lab)
        ax.plot(s, g.speed, "-", color="k", lw=1.4, label="time-optimal speed")
        for j, cname in enumerate(CONSTRAINTS):
            on = g.active == j
            if on.any():
                ax.plot(s[on], g.speed[on], ".", ms=3, color=_ACTIVE_COLOURS[j],
                        label=f"active: {cname.replace('_', ' ')}")
        if k:
            ax.axvline(g.start, color="0.8", lw=0.8, zorder=0)
    handles, labels = ax.get_legend_handles_labels()
    seen = {}
    for h, lab in zip(handles, labels):
        seen.setdefault(lab, h)
    ax.legend(seen.values(), seen.keys(), fontsize=8, loc="upper right", ncol=2)
    ax.set_ylim(0.0, ceiling)
    ax.set_xlabel("position along the path s [m]")
    ax.set_ylabel("path speed ds/dt [m/s]")
    total = sum(g.duration for g in timing.segments)
    prof = (f", profiled {timing.profiled_duration:.3f} s" if timing.profiled_duration is not None else "")
    note = f"\n{timing.note}" if timing.note else ""
    if above:
        note += (f"\nlimit curve above the chart on {len(above)} segment(s): "
                 f"{min(a for a, _ in above):.3g}–{max(b for _, b in above):.3g} m/s")
    ax.set_title(f"{design.name}: {name} timed as fast as the robot allows — {total:.3f} s{prof}{note}",
                 fontsize=10)
    return fig
