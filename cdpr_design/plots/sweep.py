"""The picture of a parameter sweep: headline figures against the varied keys.

:func:`sweep_figure` takes the sweep table (header and rows, as
:func:`cdpr_design.batch.table.table` gives them) and returns a matplotlib
Figure; nothing is written.
"""

from __future__ import annotations

import math
import textwrap
from typing import Sequence

import numpy as np

from cdpr_design.plots._frame import used_panels
from cdpr_design.plots._style import FAIL, PASS, cmap_grey_bad, pyplot

_FIG_LABELS = {
    "fraction": "feasible fraction", "min_margin_figure": "capacity margin [N]\n(task box)",
    "peak_tension": "peak tension [N]", "peak_motor_torque": "peak motor torque [N m]",
    "torque_margin": "torque margin (≥ 1 passes)", "speed_margin": "speed margin (≥ 1 passes)",
    "measure": "feasible measure [m² or m³]", "task_min_margin": "task min margin [N]",
    "peak_cable_speed": "peak cable speed [m/s]", "rms_motor_torque": "RMS motor torque [N m]",
    "peak_motor_speed": "peak motor speed [rpm]", "max_tension": "largest tension [N]",
    "min_margin": "least margin [N]", "max_margin": "largest margin [N]",
}
#: Units of varied spec keys, by their last named part (docs/spec-format.md).
_KEY_UNITS = {
    "mass": "kg", "tension": "N", "outlet": "m", "attachment": "m", "upper": "m", "lower": "m", "size": "m",
    "step": "m", "diameter": "m", "drum_radius": "m", "radius": "m", "inertia": "kg m²", "gravity": "m/s²",
    "max_speed": "m/s", "max_acceleration": "m/s²", "min_margin": "N", "drum_inertia": "kg m²",
    "axial_stiffness": "N", "orientation": "rad", "external_wrench": "N, N m",
}


def key_label(key: str) -> str:
    """An axis label for a varied spec key: the key and its unit (``effector.mass [kg]``)."""
    parts = [p for p in key.replace("[", ".").replace("]", "").split(".") if p and not p.isdigit()]
    unit = next((_KEY_UNITS[p] for p in reversed(parts) if p in _KEY_UNITS), "")
    return f"{key} [{unit}]" if unit else key


def _axis_values(header, rows, key):
    """Values of column ``key`` as numbers, or (for text) indices into the returned labels."""
    j = header.index(key)
    vals = [r[j] for r in rows]
    try:
        num = [float(v) for v in vals]
        return num, None
    except (TypeError, ValueError):
        labels = []
        for v in vals:
            s = str(v)
            if s not in labels:
                labels.append(s)
        return [labels.index(str(v)) for v in vals], labels


def _figure_column(header, rows, name):
    """Column ``name`` as floats (empty or non-numeric cells NaN); None when absent."""
    if name not in header:
        return None
    j = header.index(name)
    out = []
    for r in rows:
        v = r[j]
        try:
            x = float(v) if v not in (None, "") else math.nan
        except (TypeError, ValueError):
            x = math.nan
        out.append(x)
    return np.array(out, dtype=float)


def _passing(header, rows):
    """Which variants evaluated without error and pass every requirement."""
    ip = header.index("checks_passed") if "checks_passed" in header else None
    ie = header.index("error")
    return np.array([(not r[ie]) and ip is not None and r[ip] in (True, 1, "1") for r in rows], dtype=bool)


def sweep_figure(header: list[str], rows: list[list], keys: Sequence[str], title: str = "",
                 figures: Sequence[str] | None = None, rank_by: str | None = None):
    """Headline figures against the varied keys.

    One key: each figure against it (line plots, passing variants green,
    failing red crosses, failed evaluations as gaps).  Two keys: a heat map
    per figure (failing cells marked ×).  More: a parallel-coordinates view of
    the varied keys and the figures, lines coloured by ``rank_by``, variants
    failing a requirement in grey.  No figure at all (every variant failed to
    evaluate): a panel saying so, with the first error.
    """
    from cdpr_design import batch as sw

    figs = [f for f in (figures or sw.HEADLINE) if f in header]
    if not figs:
        figs = [h for h in header if h not in keys and h not in ("variant", "error")][:1]
    ok = _passing(header, rows)
    if not figs:
        fig = _no_figures(header, rows)
    elif len(keys) == 1:
        fig = _line_panels(header, rows, keys[0], figs, ok)
    elif len(keys) == 2:
        fig = _heat_maps(header, rows, keys, figs, ok)
    else:
        fig = _parallel_coordinates(header, rows, keys, figs, ok, rank_by)
    npass = int(ok.sum())
    fig.suptitle((title + "\n" if title else "") +
                 f"{len(rows)} variants, {npass} pass every requirement", fontsize=10)
    return fig


def _no_figures(header, rows):
    """No figure to draw: a panel naming the variants that failed to evaluate and the first error."""
    ie = header.index("error")
    errors = [str(r[ie]) for r in rows if r[ie]]
    text = f"nothing to draw: {len(errors)} of {len(rows)} variants failed to evaluate"
    if errors:
        text += "\n\nfirst error:\n" + "\n".join(textwrap.wrap(textwrap.shorten(errors[0], 300), 70))
    fig, ax = pyplot().subplots(figsize=(6.4, 3.2))
    fig.subplots_adjust(left=0.05, right=0.95, bottom=0.05, top=0.8)
    ax.axis("off")
    ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=8, color=FAIL, transform=ax.transAxes)
    return fig


def _panels(n: int, width: float, height: float, **adjust):
    """A figure of ``n`` panels, up to 3 a row, each ``width`` x ``height`` [in]."""
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    fig, axs = pyplot().subplots(nrow, ncol, figsize=(width * ncol, height * nrow + 0.7), squeeze=False)
    fig.subplots_adjust(**adjust)
    return fig, axs


def _line_panels(header, rows, key, figs, ok):
    """One key: each figure against it."""
    x, labels = _axis_values(header, rows, key)
    x = np.array(x, dtype=float)
    order = np.argsort(x, kind="stable")
    fig, axs = _panels(len(figs), 4.3, 3.4, left=0.08, right=0.98, bottom=0.12, top=0.86, wspace=0.35, hspace=0.5)
    for k, ax in used_panels(axs, len(figs)):
        y = _figure_column(header, rows, figs[k])
        ax.plot(x[order], y[order], "-", color="0.5", lw=1.0, zorder=1)
        ax.plot(x[ok], y[ok], "o", ms=4, color=PASS, label="passes", zorder=2)
        ax.plot(x[~ok], y[~ok], "x", ms=5, color=FAIL, label="fails a requirement", zorder=2)
        ax.set_ylabel(_FIG_LABELS.get(figs[k], figs[k]), fontsize=8)
        ax.set_xlabel(key_label(key), fontsize=8)
        ax.tick_params(labelsize=7)
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels, rotation=30, fontsize=7)
        ax.grid(alpha=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    return fig


def _heat_maps(header, rows, keys, figs, ok):
    """Two keys: a heat map per figure, the first key upwards, failing cells marked ×."""
    x, xl = _axis_values(header, rows, keys[1])
    y, yl = _axis_values(header, rows, keys[0])
    xs, ys = sorted(set(x)), sorted(set(y))
    xi = {v: i for i, v in enumerate(xs)}
    yi = {v: i for i, v in enumerate(ys)}
    fig, axs = _panels(len(figs), 4.6, 3.9, left=0.08, right=0.97, bottom=0.1, top=0.86, wspace=0.45, hspace=0.5)
    for k, ax in used_panels(axs, len(figs)):
        col = _figure_column(header, rows, figs[k])
        img = np.full((len(ys), len(xs)), np.nan)
        fail = np.zeros_like(img, dtype=bool)
        for r in range(len(rows)):
            img[yi[y[r]], xi[x[r]]] = col[r]
            fail[yi[y[r]], xi[x[r]]] = not ok[r]
        im = ax.imshow(np.ma.masked_invalid(img), origin="lower", aspect="auto", cmap=cmap_grey_bad("viridis"),
                       interpolation="nearest")
        fy, fx = np.nonzero(fail)
        ax.plot(fx, fy, "x", color=FAIL, ms=5, mew=1.2, label="fails a requirement")
        for axis, vals, lab in ((ax.set_xticks, xs, xl), (ax.set_yticks, ys, yl)):
            step = max(1, math.ceil(len(vals) / 8))
            pos = list(range(0, len(vals), step))
            axis(pos, [(lab[int(vals[p])] if lab is not None else f"{vals[p]:.4g}") for p in pos], fontsize=7)
        ax.set_xlabel(key_label(keys[1]), fontsize=8)
        ax.set_ylabel(key_label(keys[0]), fontsize=8)
        label = _FIG_LABELS.get(figs[k], figs[k]).replace("\n", " ")
        ax.set_title(label, fontsize=9)
        cb = fig.colorbar(im, ax=ax, shrink=0.85)
        cb.set_label(label, fontsize=8)
        cb.ax.tick_params(labelsize=7)
        ax.set_xlim(-0.5, len(xs) - 0.5)
        ax.set_ylim(-0.5, len(ys) - 0.5)
    return fig


def _normalised_columns(header, rows, keys, cols):
    """Each column scaled to [0, 1], and its (low, high, labels) for the axis texts."""
    data, ticks = [], []
    for c in cols:
        if c in keys:
            v, lab = _axis_values(header, rows, c)
            v = np.array(v, dtype=float)
        else:
            v, lab = _figure_column(header, rows, c), None
        lo, hi = np.nanmin(v) if np.isfinite(v).any() else 0.0, np.nanmax(v) if np.isfinite(v).any() else 1.0
        span = hi - lo if hi > lo else 1.0
        data.append((v - lo) / span)
        ticks.append((lo, hi, lab))
    return np.array(data), ticks


def _parallel_coordinates(header, rows, keys, figs, ok, rank_by):
    """More keys: one line per variant through the keys and figures, coloured by ``rank_by``."""
    cols = list(keys) + figs
    data, ticks = _normalised_columns(header, rows, keys, cols)
    fig, ax = pyplot().subplots(figsize=(max(8.0, 1.4 * len(cols)), 5.2))
    fig.subplots_adjust(left=0.06, right=0.9, bottom=0.2, top=0.86)
    rank = _figure_column(header, rows, rank_by) if rank_by else None
    cmap = pyplot().get_cmap("viridis")
    xs = np.arange(len(cols))
    good = rank[ok] if rank is not None else np.array([])
    rlo = np.nanmin(good) if np.isfinite(good).any() else 0.0
    rhi = np.nanmax(good) if np.isfinite(good).any() else 1.0
    for r in np.argsort(ok, kind="stable"):  # failing first, passing on top
        yv = data[:, r]
        if ok[r] and rank is not None and np.isfinite(rank[r]):
            colr = cmap((rank[r] - rlo) / (rhi - rlo) if rhi > rlo else 0.5)
            ax.plot(xs, yv, "-", color=colr, lw=1.2, alpha=0.9, zorder=3)
        else:
            ax.plot(xs, yv, "-", color="0.75" if not ok[r] else PASS, lw=0.8, alpha=0.6, zorder=2)
    _parallel_axes(ax, ticks, cols, keys)
    if rank is not None and rank_by:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        sm = ScalarMappable(norm=Normalize(rlo, rhi if rhi > rlo else rlo + 1), cmap=cmap)
        fig.colorbar(sm, ax=ax, shrink=0.8, label=f"{rank_by} (variants passing every requirement; grey: failing)")
    return fig


def _parallel_axes(ax, ticks, cols, keys) -> None:
    """The vertical axes of the parallel-coordinates view with their end values and names."""
    for k, (lo, hi, lab) in enumerate(ticks):
        ax.axvline(k, color="k", lw=0.8, zorder=1)
        top = lab[-1] if lab is not None else f"{hi:.4g}"
        bottom = lab[0] if lab is not None else f"{lo:.4g}"
        ax.text(k, 1.03, top, ha="center", fontsize=7)
        ax.text(k, -0.06, bottom, ha="center", va="top", fontsize=7)
    ax.set_xticks(np.arange(len(cols)), [key_label(c) if c in keys else _FIG_LABELS.get(c, c).replace("\n", " ")
                                         for c in cols],
                  rotation=25, ha="right", fontsize=8)
    ax.set_yticks([])
    ax.set_ylim(-0.1, 1.1)
    ax.set_xlim(-0.3, len(cols) - 0.7)
    for s in ("top", "right", "left"):
        ax.spines[s].set_visible(False)
