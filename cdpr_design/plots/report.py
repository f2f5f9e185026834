"""``report.html``: one self-contained, interactive page of a design's results.

:func:`report_html` returns the page as text (nothing is written): the
design's name and summary table, an interactive workspace figure (planar: a
heat map of the capacity margin with the boundary between the grid points;
spatial: that boundary as a surface to turn, the feasible poses as 3-D points
a click away), the cable-tension map, the loads on the frame, the
motor-sizing table and the requirement checks.
Hovering a cell or point shows its pose, margin and tensions.

The page needs no network: plotly's JavaScript is inlined once, and each
figure's JSON sits in a ``<script type="application/json">`` block that a
few lines of inline script hand to ``Plotly.newPlot``.  Maps larger than
:data:`MAX_CELLS` (planar) or :data:`MAX_POINTS` (spatial) are shown every
k-th grid cell per axis, so the page stays a few megabytes.
"""

from __future__ import annotations

import html
import json

import numpy as np

from cdpr_design.io.tables import timing_phases

#: Largest planar map shown cell by cell in the page (cells).
MAX_CELLS = 90_000
#: Largest number of feasible poses drawn as 3-D points.
MAX_POINTS = 40_000
#: Height of the workspace figure [px] (the tension grid's follows from its rows).
FIGURE_HEIGHT = 640
#: Colour-blind-safe continuous scales (perceptually uniform).
MARGIN_SCALE, TENSION_SCALE = "Viridis", "Cividis"
_GREY = "rgb(217,217,217)"

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.pass { color: #1a7f37; font-weight: bold; } .fail { color: #b00020; font-weight: bold; }
.figure { width: 100%; } .note { color: #555; font-size: 0.85em; }
"""

_BOOT = """
for (const el of document.querySelectorAll('script[type="application/json"][data-figure]')) {
  const fig = JSON.parse(el.textContent);
  Plotly.newPlot(el.dataset.figure, fig.data, fig.layout, {responsive: true, displaylogo: false});
}
"""


def report_html(result=None, sizing=None, checks=None, summary: dict | None = None, title: str | None = None) -> str:
    """The page: ``result`` a workspace result (:class:`~cdpr_design.workspaces.grid.WorkspaceResult`),
    ``sizing`` a :class:`~cdpr_design.design.sizing.SizingResult`, ``checks`` the rows of
    :func:`~cdpr_design.design.evaluate.check_table`, ``summary`` the figures to tabulate
    (default ``result.summary()``).  Any of them may be None (its section is left out)."""
    from plotly.offline import get_plotlyjs

    d = result.design if result is not None else None
    name = title or (d.name if d is not None else (summary or {}).get("name", "design"))
    parts = [f"<h1>{_esc(name)}</h1>"]
    if d is not None:
        parts.append(f"<p>{_esc(d.motion.name)} motion, {d.m} cables, {result.kind} workspace.</p>")
    summary = summary if summary is not None else (result.summary() if result is not None else None)
    if summary:
        parts += ["<h2>Summary</h2>", _summary_table(summary)]
    figures = []
    if result is not None:
        figures = [("workspace", "Workspace", workspace_plotly(result)),
                   ("tensions", "Cable tensions", tension_plotly(result))]
        for fid, heading, (fig, note) in figures:
            parts += [f"<h2>{heading}</h2>",
                      f'<div id="{fid}" class="figure" style="height: {fig["layout"]["height"]}px"></div>',
                      f'<p class="note">{_esc(note)}</p>']
    if result is not None and getattr(result, "frame_loads", None) is not None:
        parts += ["<h2>Loads on the frame</h2>", frame_load_table(result)]
    if sizing is not None:
        parts += ["<h2>Motor sizing</h2>", _sizing_table(sizing)]
    if checks is not None:
        parts += ["<h2>Requirement checks</h2>", _checks_table(checks)]
    data = "".join(f'<script type="application/json" data-figure="{fid}">{_json(fig)}</script>\n'
                   for fid, _, (fig, _) in figures)
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{_esc(name)} — cdpr-design report</title>\n<style>{_STYLE}</style>\n"
            f"<script type=\"text/javascript\">{get_plotlyjs()}</script>\n</head>\n<body>\n"
            + "\n".join(parts) + "\n" + data + f"<script>{_BOOT}</script>\n</body>\n</html>\n")


# ----------------------------------------------------------------------------
# Figures (plotly figure dicts; numbers as plain lists)
# ----------------------------------------------------------------------------


def workspace_plotly(result) -> tuple[dict, str]:
    """(figure, note): margin heat map (planar) or feasible 3-D points (spatial)."""
    if result.design.motion.planar:
        return _planar_workspace(result)
    return _spatial_workspace(result)


def _stride(shape, limit: int) -> int:
    """Smallest k such that every k-th cell per axis keeps at most ``limit`` cells."""
    k = 1
    while np.prod([(s + k - 1) // k for s in shape]) > limit:
        k += 1
    return k


def _hover(d, coords: list[str]) -> str:
    """Hover text: the pose coordinates, the margin and each cable's tension."""
    spatial = len(coords) == 3  # 3-D points: customdata = [margin, tensions...]; heat maps: z is the margin
    lines = [f"{c} = %{{{'xyz'[i]}:.4g}} m" for i, c in enumerate(coords)]
    lines.append("margin = %{customdata[0]:.4g} N" if spatial else "margin = %{z:.4g} N")
    lines += [f"T {c} = %{{customdata[{i + spatial}]:.4g}} N" for i, c in enumerate(d.cable_names)]
    return "<br>".join(lines) + "<extra></extra>"


def _planar_workspace(result) -> tuple[dict, str]:
    d = result.design
    k = _stride(result.margin_map.shape, MAX_CELLS)
    x, y = (ax[::k] for ax in result.map_axes[:2])
    feas = result.feasible_map[::k, ::k].astype(bool).T
    marg = result.margin_map[::k, ::k].T.astype(float)
    ten = np.moveaxis(result.tension_maps[:, ::k, ::k], 0, -1).transpose(1, 0, 2)
    hover = _hover(d, list(d.motion.coords[:2]))
    traces = [
        {"type": "heatmap", "x": x, "y": y, "z": np.where(feas, np.nan, marg), "name": "infeasible",
         "colorscale": [[0, _GREY], [1, _GREY]], "showscale": False, "customdata": ten, "hovertemplate": hover},
        {"type": "heatmap", "x": x, "y": y, "z": np.where(feas, marg, np.nan), "name": "feasible",
         "colorscale": MARGIN_SCALE, "zmin": 0.0, "customdata": ten, "hovertemplate": hover,
         "colorbar": {"title": {"text": "capacity margin [N]"}}},
        _outlets(d, planar=True),
    ] + _boundary_lines(result)
    layout = {"title": {"text": _title(result)}, "xaxis": {"title": {"text": "x [m]"}},
              "yaxis": {"title": {"text": "y [m]"}, "scaleanchor": "x", "scaleratio": 1},
              "shapes": [_frame_shape(d)], "legend": {"orientation": "h"}, "height": FIGURE_HEIGHT}
    note = "Grey: infeasible poses (negative margin). Hover a cell for its pose, margin and tensions."
    if k > 1:
        note += f" Every {k}th grid cell per axis is shown."
    return {"data": traces, "layout": layout}, note


def _spatial_workspace(result) -> tuple[dict, str]:
    d = result.design
    shape = result.feasible_map.shape
    k = max(1, _stride(shape, MAX_POINTS))
    while k > 1 and np.count_nonzero(result.feasible_map[::k - 1, ::k - 1, ::k - 1]) <= MAX_POINTS:
        k -= 1  # feasible points are fewer than cells: the finest stride that fits
    feas = result.feasible_map[::k, ::k, ::k].astype(bool)
    axes = [ax[::k] for ax in result.map_axes[:3]]
    idx = np.nonzero(feas)
    pts = [axes[j][idx[j]] for j in range(3)]
    marg = result.margin_map[::k, ::k, ::k][idx].astype(float)
    ten = np.stack([t[::k, ::k, ::k][idx] for t in result.tension_maps], axis=1)
    hover_data = np.concatenate([marg[:, None], ten], axis=1)  # margin, then each cable's tension
    traces = [
        {"type": "scatter3d", "mode": "markers", "x": pts[0], "y": pts[1], "z": pts[2], "name": "feasible poses",
         "marker": {"size": 2.5, "color": marg, "colorscale": MARGIN_SCALE, "cmin": 0.0,
                    "colorbar": {"title": {"text": "capacity margin [N]"}}},
         "customdata": hover_data, "hovertemplate": _hover(d, ["x", "y", "z"])},
        _outlets(d, planar=False),
        _frame_edges(d),
    ]
    mesh = _boundary_mesh(result)
    if mesh is not None:  # the surface first; the points a click away in the legend
        traces[0]["visible"] = "legendonly"
        traces.insert(0, mesh)
    scene = {"xaxis": {"title": {"text": "x [m]"}}, "yaxis": {"title": {"text": "y [m]"}},
             "zaxis": {"title": {"text": "z [m]"}}, "aspectmode": "data",
             # the camera far enough that the whole frame, its tick labels and titles stay in the view
             "camera": {"eye": {"x": 1.7, "y": 1.7, "z": 1.1}}}
    layout = {"title": {"text": _title(result)}, "scene": scene, "legend": {"orientation": "h"},
              "height": FIGURE_HEIGHT, "margin": {"l": 10, "r": 10, "t": 60, "b": 10}}
    note = (f"{idx[0].size:,} feasible poses" + (f" (every {k}th grid cell per axis)" if k > 1 else "")
            + (", shown by clicking them in the legend, and the workspace's boundary (workspace.stl)"
               if mesh is not None else " drawn")
            + ". Drag to turn, scroll to zoom; hover a point for its pose, margin and tensions.")
    return {"data": traces, "layout": layout}, note


def _boundary_lines(result) -> list[dict]:
    """The planar boundary's loops as one line trace (gaps between loops), or none."""
    b = getattr(result, "boundary", None)
    if b is None or not b.loops:
        return []
    xs: list = []
    ys: list = []
    for lp in b.loops:
        xs += list(lp[:, 0]) + [float(lp[0, 0]), None]
        ys += list(lp[:, 1]) + [float(lp[0, 1]), None]
    return [{"type": "scatter", "mode": "lines", "x": xs, "y": ys, "name": "boundary between grid points",
             "line": {"color": "#D55E00", "width": 2}, "hoverinfo": "skip"}]


def _boundary_mesh(result) -> dict | None:
    """The spatial boundary (the closed mesh of workspace.stl) as a mesh trace, or None."""
    b = getattr(result, "boundary", None)
    if b is None or len(b.faces) == 0:
        return None
    v, f = b.vertices, b.faces
    return {"type": "mesh3d", "x": v[:, 0], "y": v[:, 1], "z": v[:, 2], "i": f[:, 0], "j": f[:, 1], "k": f[:, 2],
            "name": "workspace boundary", "color": "#56B4E9", "opacity": 0.55, "flatshading": True,
            "showlegend": True, "hoverinfo": "skip"}


def tension_plotly(result) -> tuple[dict, str]:
    """(figure, note): each cable's minimum-norm tension over the grid (spatial: the z-slice with
    the most feasible poses), one panel per cable on a shared scale."""
    d = result.design
    feas = result.feasible_map.astype(bool)
    T = np.where(feas[None], result.tension_maps, np.nan)
    note = "Blank: infeasible poses."
    title = f"{d.name}: minimum-norm cable tensions [N]"
    if not d.motion.planar:
        iz = int(np.argmax(feas.sum(axis=(0, 1))))
        T = T[..., iz]
        z = f"{result.map_axes[2][iz]:.3g}"
        title += f" in the slice z = {z} m"
        note = f"The z = {z} m slice (the one with the most feasible poses). " + note
    k = _stride(T.shape[1:], MAX_CELLS // max(1, d.m))
    x, y = (ax[::k] for ax in result.map_axes[:2])
    finite = T[np.isfinite(T)]
    top = float(finite.max()) if finite.size else 1.0
    ncol = min(4, d.m)
    nrow = -(-d.m // ncol)
    # heights in pixels: each row of panels, the room between rows (the upper row's tick labels and
    # x title, then the lower row's panel titles), the margins above and below the grid
    row_px, between_px, top_px, bottom_px = 300, 100, 90, 60
    plot_px = nrow * row_px + (nrow - 1) * between_px
    traces, layout = [], {"title": {"text": title},
                          "coloraxis": {"colorscale": TENSION_SCALE, "cmin": 0.0, "cmax": top,
                                        "colorbar": {"title": {"text": "tension [N]"}}},
                          "annotations": [], "margin": {"t": top_px, "b": bottom_px},
                          "height": plot_px + top_px + bottom_px}
    gap = 0.06
    for i, c in enumerate(d.cable_names):
        r, col = divmod(i, ncol)
        n = i + 1
        xa, ya = f"x{n if n > 1 else ''}", f"y{n if n > 1 else ''}"
        dom_x = [col / ncol + gap / 2, (col + 1) / ncol - gap / 2]
        upper = 1 - r * (row_px + between_px) / plot_px
        dom_y = [max(0.0, upper - row_px / plot_px), upper]
        traces.append({"type": "heatmap", "x": x, "y": y, "z": T[i, ::k, ::k].T.astype(float), "xaxis": xa,
                       "yaxis": ya, "coloraxis": "coloraxis", "name": c,
                       "hovertemplate": f"x = %{{x:.4g}} m<br>y = %{{y:.4g}} m<br>T {c} = %{{z:.4g}} N<extra></extra>"})
        layout[f"xaxis{n if n > 1 else ''}"] = {"domain": dom_x, "anchor": ya, "title": {"text": "x [m]"}}
        layout[f"yaxis{n if n > 1 else ''}"] = {"domain": dom_y, "anchor": xa, "title": {"text": "y [m]"},
                                                "scaleanchor": xa, "scaleratio": 1}
        layout["annotations"].append({"text": f"{c}: {d.cables[i].tension_min:g}–{d.cables[i].tension_max:g} N",
                                      "xref": "paper", "yref": "paper", "x": sum(dom_x) / 2, "y": dom_y[1],
                                      "yanchor": "bottom", "showarrow": False})
    return {"data": traces, "layout": layout}, note


def _title(result) -> str:
    unit = "m²" if result.design.motion.planar else "m³"
    return (f"{result.design.name}: {result.kind} workspace — {100 * result.fraction:.1f} % of "
            f"{result.poses:,} poses feasible ({result.measure:.3g} {unit})")


def _outlets(d, planar: bool) -> dict:
    A = d.outlets
    tr = {"mode": "markers+text", "name": "outlets", "text": d.cable_names, "textposition": "top center",
          "hovertemplate": "outlet %{text}<extra></extra>", "x": A[:, 0], "y": A[:, 1],
          "marker": {"symbol": "triangle-down" if planar else "diamond", "size": 11 if planar else 5,
                     "color": "rgb(213,94,0)", "line": {"color": "black", "width": 1}}}
    if planar:
        return {"type": "scatter", **tr}
    return {"type": "scatter3d", **tr, "z": A[:, 2]}


def _frame_shape(d) -> dict:
    lo, hi = d.frame_lower, d.frame_upper
    return {"type": "rect", "x0": lo[0], "y0": lo[1], "x1": hi[0], "y1": hi[1], "line": {"color": "black"}}


def _frame_edges(d) -> dict:
    """The frame's box as 3-D line segments."""
    lo, hi = np.asarray(d.frame_lower, float), np.asarray(d.frame_upper, float)
    xs, ys, zs = [], [], []
    corners = [(a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1)]
    for p in corners:
        for q in corners:
            if p < q and sum(u != v for u, v in zip(p, q)) == 1:
                for pt in (p, q):
                    v = np.where(np.array(pt) == 1, hi, lo)
                    xs.append(v[0]), ys.append(v[1]), zs.append(v[2])
                xs.append(None), ys.append(None), zs.append(None)
    return {"type": "scatter3d", "mode": "lines", "name": "frame", "x": xs, "y": ys, "z": zs,
            "line": {"color": "black", "width": 2}, "hoverinfo": "skip"}


# ----------------------------------------------------------------------------
# Tables
# ----------------------------------------------------------------------------

_SUMMARY_ROWS = [("poses", "grid poses", ""), ("feasible", "feasible poses", ""), ("fraction", "feasible fraction", ""),
                 ("measure", "measure", "measure_unit"),
                 ("boundary_measure", "inside the boundary between grid points", "measure_unit"),
                 ("min_margin", "least margin", "N"),
                 ("max_margin", "largest margin", "N"), ("max_tension", "largest tension", "N"),
                 ("elapsed_s", "sweep time", "s")]


#: Units as the page writes them (the summary's plain-text ones).
_UNITS = {"m^2": "m²", "m^3": "m³"}


def _summary_table(s: dict) -> str:
    def unit_of(key):
        u = s.get(key, key)
        return _esc(_UNITS.get(u, u))

    rows = [(label, _cell(s[key]) + (" " + unit_of(unit) if unit and s[key] is not None else ""))
            for key, label, unit in _SUMMARY_ROWS if key in s]
    if "grid" in s:
        g = s["grid"]
        rows.append(("grid", " × ".join(str(v) for v in g["shape"]) + f", step {', '.join(_cell(v) for v in g['step'])} m"))
    if "timings" in s:
        phases = timing_phases(s["timings"])
        rows.append((" / ".join(k for k, _ in phases), " / ".join(_cell(v) for _, v in phases) + " s"))
    return _table(["", ""], rows, header=False)


_SIZING_COLS = [("cable", "cable"), ("peak_tension", "peak tension [N]"), ("peak_cable_speed", "cable speed [m/s]"),
                ("peak_motor_torque", "peak torque [N m]"), ("rms_motor_torque", "RMS torque [N m]"),
                ("peak_motor_speed", "speed [rpm]"), ("motor", "motor"), ("torque_margin", "torque margin"),
                ("speed_margin", "speed margin"), ("fits", "fits")]


def _sizing_table(sizing) -> str:
    rows = sizing.rows()
    body = [[_cell(r.get(k)) if k != "fits" else _verdict(bool(r.get(k))) for k, _ in _SIZING_COLS] for r in rows]
    note = f'<p class="note">Duty cycle: {_esc(sizing.cycle)}; safety factor {sizing.safety_factor:g}.</p>'
    return _table([h for _, h in _SIZING_COLS], body) + note


def frame_load_table(result) -> str:
    """``frame_loads.csv`` as an HTML table (N), with the total force and moment's envelope."""
    d = result.design
    cols = result.frame_loads.rows(d.cable_names)
    names = [n for n in cols if n != "cable"]
    body = [[_esc(c)] + [_cell(cols[n][i]) for n in names] for i, c in enumerate(cols["cable"])]
    s = result.frame_loads.summary(d.cable_names)
    note = (f'<p class="note">Forces [N] on the frame at each outlet over the {s["poses"]:,} feasible poses, '
            "with the sweep's tensions; <code>limit_</code>: each cable at its upper tension bound along every "
            "direction it takes. Total force up to " + _cell(s["total_force"]["max_magnitude"]) + " N, moment "
            "about the frame's origin up to " + _cell(s["total_moment"]["max_magnitude"]) + " N m.</p>")
    return _table(["cable"] + names, body) + note


def _checks_table(checks: list[dict]) -> str:
    if not checks:
        return "<p>The spec's requirements section asks for nothing to check.</p>"
    body = [[_esc(c["requirement"]), _esc(c["figure"]), _esc(c["limit"]), _verdict(c["passed"])] for c in checks]
    return _table(["requirement", "figure", "limit", "result"], body)


def _table(head, rows, header: bool = True) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{_esc(h)}</th>" for h in head) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{c}</td>" if i or not header else f"<td>{c}</td>"
                                    for i, c in enumerate(r)) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _verdict(passed) -> str:
    return '<span class="pass">pass</span>' if passed else '<span class="fail">FAIL</span>'


def _cell(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return "—" if not np.isfinite(v) else f"{float(v):.4g}"
    if isinstance(v, (int, np.integer)):
        return f"{int(v):,}"
    return _esc(str(v))


def _esc(text) -> str:
    return html.escape(str(text), quote=True)


def _json(fig: dict) -> str:
    """Figure JSON for a ``<script>`` block: NaN as null, ``</`` escaped."""
    return json.dumps(fig, default=_plain, allow_nan=False, separators=(",", ":")).replace("</", "<\\/")


def _plain(o):
    if isinstance(o, np.ndarray):
        return _finite_list(_compact(o))
    if isinstance(o, np.generic):
        v = o.item()
        return v if not isinstance(v, float) or np.isfinite(v) else None
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _compact(a: np.ndarray) -> np.ndarray:
    """Floats rounded to at least 6 significant digits of the array's largest value (shorter JSON)."""
    if a.dtype.kind != "f" or not a.size:
        return a
    a = a.astype(np.float64)
    finite = np.abs(a[np.isfinite(a)])
    top = float(finite.max()) if finite.size else 0.0
    decimals = 9 if top == 0.0 else int(min(9, max(0, 6 - np.ceil(np.log10(top)))))
    return np.round(a, decimals)


def _finite_list(a: np.ndarray):
    if a.dtype.kind == "f":
        a = a.astype(np.float64)
        return np.where(np.isfinite(a), a, None).tolist() if not np.isfinite(a).all() else a.tolist()
    return a.tolist()
