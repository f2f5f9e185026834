"""What ``optimize`` optimises and requires: figures of the design report, their directions, limits.

A FIGURE is a number of the ``report`` command's ``design_report.csv`` row
(:func:`cdpr_design.design.evaluate.evaluate`): :data:`FIGURES` and, per cable,
``peak_tension_<cable>``.  ``--maximize`` / ``--minimize`` name the objectives
(maximised ones first, then minimised ones, each in the order given);
``--require FIGURE>=X`` / ``FIGURE<=X`` add limits.  The spec's own
``requirements:`` (task box, min_margin, min_fraction, motors) are limits
too.

A trial whose limits all hold is *feasible*.  Each limit is handed to the
sampler as a violation (> 0 violated, <= 0 held; optuna's constrained TPE and
NSGA-II rank infeasible trials by the summed violation), in the limit's own
unit: N for margins, a fraction, poses outside the task box, motor margin
short of 1.  A limit whose figure is undefined for the variant counts as
violated by :data:`UNDEFINED`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Sequence

from cdpr_design.batch.table import HIGHER_IS_BETTER, LOWER_IS_BETTER
from cdpr_design.design.evaluate import CHECKS
from cdpr_design.errors import InputError, quote

#: Numeric figures of design_report.csv an objective or a limit may name (with ``peak_tension_<cable>``).
FIGURES = tuple(sorted(f for f in HIGHER_IS_BETTER | LOWER_IS_BETTER
                       if not f.startswith("check") and f != "checks_passed"))
#: Figures that exist only when the spec has a ``requirements.task_box``.
TASK_FIGURES = frozenset({"task_feasible", "task_fraction", "task_min_margin", "task_min_stiffness",
                          "task_lowest_frequency"})
#: The violation of a limit whose figure is undefined (a NaN cannot be handed to the sampler).
UNDEFINED = 1e9

#: Why a figure can be undefined for a variant (failed trials say so).
_UNDEFINED_WHY = {
    "task_min_margin": "a task pose has a rank-deficient structure matrix",
    "min_margin": "no pose of the workspace is feasible",
    "min_margin_figure": "a task pose has a rank-deficient structure matrix, or no pose is feasible",
    "max_margin": "no pose of the workspace is feasible",
    "max_tension": "no pose of the workspace is feasible",
    "speed_margin": "no axis turns (no max_speed)",
    "task_min_stiffness": "no task pose is feasible, or the stiffness is not defined there",
    "task_lowest_frequency": "no task pose is feasible, or its equilibrium is unstable",
    "max_frame_load": "no pose of the workspace is feasible",
}


@dataclass(frozen=True)
class Objective:
    figure: str
    maximize: bool

    @property
    def direction(self) -> str:
        return "maximize" if self.maximize else "minimize"


@dataclass(frozen=True)
class Limit:
    """``figure >= bound`` (``at_least``) or ``figure <= bound``."""

    figure: str
    at_least: bool
    bound: float

    def text(self) -> str:
        return f"{self.figure}{'>=' if self.at_least else '<='}{self.bound:g}"

    def violation(self, value) -> float:
        v = number(value)
        if v is None:
            return UNDEFINED
        return self.bound - v if self.at_least else v - self.bound


def number(v) -> float | None:
    """A finite float, or None (None, NaN, inf, text)."""
    if v is None or isinstance(v, (str, bool)):
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def known_figures(design) -> list[str]:
    """The figures an objective or a limit may name for this design."""
    return list(FIGURES) + [f"peak_tension_{c.name}" for c in design.cables]


def check_figure(design, name: str, option: str) -> str:
    """``name`` if it is a numeric figure for this design; else exit 2 naming ``option``."""
    name = name.strip()
    if name not in known_figures(design):
        raise InputError(f"{option} {quote(name)}: not a numeric figure of design_report.csv; one of "
                         f"{', '.join(FIGURES)}, peak_tension_<cable>")
    if name in TASK_FIGURES and design.requirements.task_box is None:
        raise InputError(f"{option} {name}: the spec has no requirements.task_box, so {name} is not computed")
    return name


def make_objectives(design, maximize: Sequence[str] | None, minimize: Sequence[str] | None) -> list[Objective]:
    """The objectives of ``--maximize`` and ``--minimize`` (maximised first); exit 2 if none, or a bad
    or repeated figure."""
    out = [Objective(check_figure(design, f, "--maximize"), True) for f in maximize or ()]
    out += [Objective(check_figure(design, f, "--minimize"), False) for f in minimize or ()]
    if not out:
        raise InputError("--maximize / --minimize: give at least one objective (a figure such as task_min_margin)")
    seen = set()
    for o in out:
        if o.figure in seen:
            raise InputError(f"--{o.direction} {o.figure}: the figure is already an objective")
        seen.add(o.figure)
    return out


_LIMIT = re.compile(r"^\s*([A-Za-z_][\w.-]*)\s*(>=|<=)\s*(\S+)\s*$")


def parse_limit(design, text: str) -> Limit:
    """One ``--require FIGURE>=X`` / ``FIGURE<=X``; exit 2 naming ``--require``."""
    m = _LIMIT.match(text)
    if not m:
        raise InputError(f"--require {quote(text)}: expected FIGURE>=X or FIGURE<=X (e.g. torque_margin>=1)")
    name = check_figure(design, m.group(1), "--require")
    try:
        bound = float(m.group(3))
    except ValueError:
        raise InputError(f"--require {quote(text)}: expected a number after {m.group(2)}, "
                         f"got {quote(m.group(3))}") from None
    if not math.isfinite(bound):
        raise InputError(f"--require {quote(text)}: expected a finite number")
    return Limit(name, m.group(2) == ">=", bound)


def spec_checks(design, motor: str | None = None) -> list[str]:
    """The spec's requirements that are checked (``check_<name>`` of the report row)."""
    from cdpr_design.design.evaluate import motors_asked

    req = design.requirements
    asked = {"task_box": req.task_box is not None, "min_margin": req.min_margin is not None,
             "min_fraction": req.min_fraction is not None, "motors": motors_asked(design, motor),
             "min_stiffness": req.min_stiffness is not None and req.task_box is not None,
             "min_frequency": req.min_frequency is not None and req.task_box is not None,
             "max_frame_load": req.max_frame_load is not None}
    return [c for c in CHECKS + ("min_stiffness", "min_frequency", "max_frame_load") if asked[c]]


#: The figures behind each spec check (columns of optimize.csv).
CHECK_FIGURES = {"task_box": ("task_feasible", "task_poses"), "min_margin": ("min_margin_figure",),
                 "min_fraction": ("fraction",), "motors": ("torque_margin", "speed_margin"),
                 "min_stiffness": ("task_min_stiffness",), "min_frequency": ("task_lowest_frequency",),
                 "max_frame_load": ("max_frame_load",)}


def check_violation(name: str, row: dict) -> tuple[float, str]:
    """A spec check's violation (> 0: failed) and what failed, from a report row."""
    passed = row.get(f"check_{name}")
    if name == "task_box":
        bad = (row.get("task_poses") or 0) - (row.get("task_feasible") or 0)
        v = float(bad) if not passed else 0.0
        return v, f"task_box ({bad} of {row.get('task_poses')} task poses infeasible)"
    if name == "min_margin":
        f = number(row.get("min_margin_figure"))
        v = UNDEFINED if f is None else row["req_min_margin"] - f
        return v, f"min_margin ({'undefined' if f is None else f'{f:.4g} N'} < {row['req_min_margin']:g} N)"
    if name in ("min_stiffness", "min_frequency"):
        figure = "task_min_stiffness" if name == "min_stiffness" else "task_lowest_frequency"
        f, limit = number(row.get(figure)), row[f"req_{name}"]
        unit = "N/m" if name == "min_stiffness" else "Hz"
        v = UNDEFINED if f is None else limit - f
        return v, f"{name} ({'undefined' if f is None else f'{f:.4g} {unit}'} < {limit:g} {unit})"
    if name == "max_frame_load":
        f, limit = number(row.get("max_frame_load")), row["req_max_frame_load"]
        v = UNDEFINED if f is None else f - limit
        return v, f"max_frame_load ({'undefined' if f is None else f'{f:.4g} N'} > {limit:g} N)"
    if name == "min_fraction":
        f = number(row.get("fraction"))
        v = UNDEFINED if f is None else row["req_min_fraction"] - f
        return v, f"min_fraction ({'undefined' if f is None else f'{f:.4g}'} < {row['req_min_fraction']:g})"
    margins = [number(row.get(k)) for k in ("torque_margin", "speed_margin")]
    least = min((m for m in margins if m is not None), default=0.0)
    v = 1.0 - least
    # the check's own verdict decides (a motor may fit on margins but be named wrongly, ...)
    v = min(v, 0.0) if passed else max(v, 1e-9)
    return v, f"motors ({row.get('motor') or 'none fits'}: least margin {least:.4g} < 1)"


def figures_needed(objectives: Sequence[Objective], limits: Sequence[Limit]) -> frozenset:
    """The report figures a trial must compute (the spec's checks add theirs, see
    :func:`cdpr_design.design.evaluate.parts_needed`)."""
    return frozenset([o.figure for o in objectives] + [lim.figure for lim in limits])


def undefined_reason(figure: str) -> str:
    why = _UNDEFINED_WHY.get(figure)
    return f"{figure} is undefined for this variant" + (f" ({why})" if why else "")
