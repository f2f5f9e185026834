"""The picture of a design search (``optimize.png``): convergence or Pareto front, and importances.

:func:`optimize_figure` takes plain data (see its docstring; the ``optimize``
job builds it from the study) and returns a matplotlib Figure; nothing is
written.
"""

from __future__ import annotations

import itertools
from typing import Sequence

import numpy as np

from cdpr_design.plots._style import pyplot

_LABELS = {
    "task_min_margin": "task min margin [N]", "min_margin_figure": "capacity margin [N]",
    "min_margin": "workspace min margin [N]", "max_margin": "max margin [N]", "fraction": "feasible fraction",
    "measure": "feasible measure [m², m³]", "peak_tension": "peak tension [N]",
    "peak_motor_torque": "peak motor torque [N m]", "rms_motor_torque": "RMS motor torque [N m]",
    "peak_motor_speed": "peak motor speed [rpm]", "peak_cable_speed": "peak cable speed [m/s]",
    "torque_margin": "torque margin", "speed_margin": "speed margin", "max_tension": "max tension [N]",
}


def _label(figure: str, maximize: bool) -> str:
    return f"{_LABELS.get(figure, figure)} ({'max' if maximize else 'min'})"


def optimize_figure(data: dict):
    """Convergence (one objective) or the Pareto front (several), with the keys' importances.

    ``data``: ``title``; ``objectives``: [(figure, maximize)]; ``trials``: [(number,
    state, values or None)] with state complete / infeasible / failed; ``best``:
    the best trial's number or None; ``pareto``: numbers of the front (several
    objectives); ``convergence``: best complete value after each trial (one
    objective); ``importances``: {figure: {key: importance}} (may be empty).
    """
    objectives = data["objectives"]
    imp = data.get("importances") or {}
    pairs = list(itertools.combinations(range(len(objectives)), 2))[:3] if len(objectives) > 1 else [None]
    n = len(pairs) + (1 if imp else 0)
    ratios = [1.0] * len(pairs) + ([0.6] if imp else [])
    fig, axs = pyplot().subplots(1, n, figsize=(5.0 * sum(ratios), 4.2), squeeze=False,
                                 gridspec_kw={"width_ratios": ratios})
    fig.subplots_adjust(left=0.09 if n == 1 else 0.07, right=0.97, bottom=0.14, top=0.83, wspace=0.45)
    axs = axs[0]
    if len(objectives) == 1:
        _convergence(axs[0], data)
    else:
        for ax, (i, j) in zip(axs, pairs):
            _front(ax, data, i, j)
    if imp:
        _importances(axs[-1], imp, objectives)
    states = [t[1] for t in data["trials"]]
    fig.suptitle((data.get("title", "") + "\n" if data.get("title") else "") +
                 f"{len(states)} trials: {states.count('complete')} complete, "
                 f"{states.count('infeasible')} infeasible, {states.count('failed')} failed", fontsize=10)
    return fig


def _convergence(ax, data: dict) -> None:
    """Each trial's value (complete green, infeasible red ×) and the best complete value so far."""
    figure, maximize = data["objectives"][0]
    trials = data["trials"]
    for state, style in (("infeasible", dict(marker="x", color="tab:red", ms=4, ls="", label="infeasible")),
                         ("complete", dict(marker="o", color="tab:green", ms=3.5, ls="", label="complete"))):
        pts = [(t[0], t[2][0]) for t in trials if t[1] == state and t[2] is not None]
        if pts:
            ax.plot(*zip(*pts), alpha=0.75, **style)
    conv = data.get("convergence") or []
    xs = [t[0] for t, c in zip(trials, conv) if c is not None]
    ys = [c for c in conv if c is not None]
    if xs:
        ax.step(xs, ys, where="post", color="k", lw=1.5, label="best so far")
    best = data.get("best")
    for t in trials:
        if t[0] == best:
            ax.plot([t[0]], [t[2][0]], marker="*", ms=13, color="gold", mec="k", ls="", label=f"best (trial {best})")
    failed = [t[0] for t in trials if t[1] == "failed"]
    if failed:
        ax.plot(failed, [0.0] * len(failed), "|", color="0.4", ms=8, transform=ax.get_xaxis_transform(),
                label="failed")
    ax.set_xlabel("trial", fontsize=8)
    ax.set_ylabel(_label(figure, maximize), fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _front(ax, data: dict, i: int, j: int) -> None:
    """Objectives i and j of every trial with values: the front joined, dominated grey, infeasible ×."""
    objectives = data["objectives"]
    front = set(data.get("pareto") or ())
    trials = [t for t in data["trials"] if t[2] is not None]
    groups = (("infeasible", lambda t: t[1] == "infeasible", dict(marker="x", color="tab:red", ms=4, alpha=0.5)),
              ("dominated", lambda t: t[1] == "complete" and t[0] not in front,
               dict(marker="o", color="0.7", ms=4, alpha=0.7)),
              ("Pareto front", lambda t: t[0] in front, dict(marker="o", color="tab:blue", ms=5)))
    for label, keep, style in groups:
        pts = [(t[2][i], t[2][j]) for t in trials if keep(t)]
        if pts:
            if label == "Pareto front":
                pts.sort()
                ax.plot(*zip(*pts), "-", color="tab:blue", lw=1, alpha=0.6)
            ax.plot(*zip(*pts), ls="", label=label, **style)
    best = data.get("best")
    for t in trials:
        if t[0] == best:
            ax.plot([t[2][i]], [t[2][j]], marker="*", ms=14, color="gold", mec="k", ls="",
                    label=f"best.yaml (knee, trial {best})")
    ax.set_xlabel(_label(*objectives[i]), fontsize=8)
    ax.set_ylabel(_label(*objectives[j]), fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _importances(ax, imp: dict, objectives: Sequence) -> None:
    """Horizontal bars: each key's importance for each objective."""
    figs = [f for f, _ in objectives if f in imp]
    keys = sorted({k for f in figs for k in imp[f]}, key=lambda k: -max(imp[f].get(k, 0.0) for f in figs))
    h = 0.8 / max(1, len(figs))
    y = np.arange(len(keys))
    for n, f in enumerate(figs):
        ax.barh(y + n * h - 0.4 + h / 2, [imp[f].get(k, 0.0) for k in keys], height=h, label=_LABELS.get(f, f))
    ax.set_yticks(y, keys, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("importance (PED-ANOVA)", fontsize=8)
    ax.set_xlim(0, max(1e-9, max((v for f in figs for v in imp[f].values()), default=1.0)) * 1.1)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3, axis="x")
    if len(figs) > 1:
        ax.legend(fontsize=7)
    ax.set_title("which keys matter", fontsize=9)

