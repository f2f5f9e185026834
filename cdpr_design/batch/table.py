"""A sweep's rows as tables: ``sweep.csv``, the best variants, regression checks against a baseline."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable, Collection, Iterable, Sequence

from cdpr_design.batch.variants import Plan, short
from cdpr_design.errors import InputError, quote
from cdpr_design.io.tables import text_rows


#: Figures where a larger value is better (ranking, regression checks).
HIGHER_IS_BETTER = frozenset({
    "feasible", "fraction", "measure", "min_margin", "max_margin", "task_feasible",
    "task_fraction", "task_min_margin", "torque_margin", "speed_margin",
    "implied_tension_max", "min_margin_figure", "checks_passed",
    "check_task_box", "check_min_margin", "check_min_fraction", "check_motors",
    "task_min_stiffness", "task_lowest_frequency", "check_min_stiffness", "check_min_frequency",
    "boundary_measure", "check_max_frame_load",
})


#: Figures where a smaller value is better.
LOWER_IS_BETTER = frozenset({
    "max_tension", "peak_tension", "peak_cable_speed", "peak_motor_torque",
    "rms_motor_torque", "peak_motor_speed", "max_frame_load",
})


#: Every figure name of an :func:`~cdpr_design.design.evaluate.evaluate` row apart from
#: the per-cable ones (``peak_tension_<cable>``, ``motor_<cable>``).
KNOWN_FIGURES = HIGHER_IS_BETTER | LOWER_IS_BETTER | frozenset({
    "name", "motion", "cables", "kind", "poses", "task_poses", "sizing_poses", "motor",
    "tension_max", "drum_radius", "gear_ratio", "safety_factor", "duty_cycle",
    "req_min_margin", "req_min_fraction", "req_min_stiffness", "req_min_frequency",
    "boundary_surface", "req_max_frame_load",
})


#: Figures that are numbers (a ``sweep.csv`` cell of theirs is a finite number or empty) besides
#: those with a direction; ``drum_radius`` and ``gear_ratio`` are text (``0.03;0.036``).
NUMERIC_FIGURES = HIGHER_IS_BETTER | LOWER_IS_BETTER | frozenset({
    "cables", "poses", "task_poses", "sizing_poses", "tension_max", "safety_factor",
    "req_min_margin", "req_min_fraction", "req_min_stiffness", "req_min_frequency",
    "boundary_surface", "req_max_frame_load",
})


#: Figures drawn in the sweep pictures (when present).
HEADLINE = ("fraction", "min_margin_figure", "peak_tension", "peak_motor_torque",
            "torque_margin", "speed_margin")


def table(plan: Plan, records: Iterable[dict]) -> tuple[list[str], list[list]]:
    """``sweep.csv`` as (header, rows): variant, the varied keys, the figures, ``error``.

    Rows are sorted by variant index (a variant recorded twice keeps its
    first record); the figure columns are those of the rows in index order,
    by first appearance, so the table does not depend on completion order.
    """
    by_index: dict[int, dict] = {}
    for r in records:
        by_index.setdefault(int(r["variant"]), r)
    ordered = [by_index[i] for i in sorted(by_index)]
    keys = plan.keys
    figs: dict[str, None] = {}
    for r in ordered:
        for k in r["figures"]:
            if k not in keys and k not in ("variant", "error"):
                figs.setdefault(k, None)
    header = ["variant"] + keys + list(figs) + ["error"]
    rows = []
    for r in ordered:
        f = r["figures"]
        rows.append([r["variant"]] + list(r["values"]) + [f.get(k) for k in figs] + [r["error"]])
    return header, rows


def parse_rank(text: str | None) -> tuple[str, bool]:
    """``--rank-by FIGURE[:asc|:desc]`` -> (figure, descending).

    Default direction: descending for figures where more is better, ascending
    for tensions, torques and speeds.
    """
    text = (text or "fraction").strip()
    name, _, direction = text.partition(":")
    name = name.strip()
    if direction not in ("", "asc", "desc"):
        raise InputError(f"--rank-by {quote(text)}: expected FIGURE, FIGURE:asc or FIGURE:desc")
    if not (name in KNOWN_FIGURES or name.startswith(("peak_tension_", "motor_"))):
        known = ", ".join(sorted(f for f in HIGHER_IS_BETTER | LOWER_IS_BETTER if not f.startswith("check_"))
                          + ["check_<requirement>"])
        raise InputError(f"--rank-by {quote(name)}: not a figure of design_report.csv (numbers: {known})")
    if direction:
        return name, direction == "desc"
    return name, not (name in LOWER_IS_BETTER or name.startswith("peak_tension_"))


def _num(v) -> float | None:
    if v is None or v == "":
        return None
    if isinstance(v, bool):
        return float(v)
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def best(header: list[str], rows: list[list], rank_by: str, descending: bool) -> tuple[list[str], list[list]]:
    """The variants that pass every requirement, ranked by ``rank_by`` (missing figures last).

    Returns (header, rows) with a ``rank`` column first.
    """
    if rank_by not in header:
        return ["rank"] + header, []
    ip = header.index("checks_passed") if "checks_passed" in header else None
    ie = header.index("error")
    ir = header.index(rank_by)
    passing = [r for r in rows if not r[ie] and ip is not None and r[ip] in (True, 1, "1")]

    def key(r):
        v = _num(r[ir])
        if v is None:
            return (1, 0.0, r[0])
        return (0, -v if descending else v, r[0])

    ranked = sorted(passing, key=key)
    return ["rank"] + header, [[k + 1] + r for k, r in enumerate(ranked)]


@dataclass
class Difference:
    """One figure of one variant that moved against the baseline."""

    variant: int
    column: str
    baseline: str
    current: str
    change: str  # "worse", "better", "changed", "missing"

    def as_dict(self) -> dict:
        return {"variant": self.variant, "column": self.column, "baseline": self.baseline,
                "current": self.current, "change": self.change}


def _direction(column: str) -> int:
    if column in HIGHER_IS_BETTER:
        return 1
    if column in LOWER_IS_BETTER or column.startswith("peak_tension_"):
        return -1
    return 0


def check_baseline(base_header: list[str], base_rows: list[list[str]], plan: Plan,
                   source: str = "the baseline") -> None:
    """Refuse a baseline ``sweep.csv`` (cells as CSV text) that cannot be compared with a sweep of
    ``plan``, before any variant is evaluated: what :func:`compare` refuses, checked against the
    plan's variants and varied values.

    Raises
    ------
    InputError
        Naming ``source`` (the file) and the row, variant and column at fault.
    """
    n = len(plan)

    def key_cells(i: int) -> list[str] | None:
        return text_rows([plan.values(i)])[0] if 0 <= i < n else None

    _check_baseline(base_header, base_rows, plan.keys, key_cells, range(n), source)


def _check_baseline(base_header: list[str], base_rows: list[list[str]], keys: Sequence[str],
                    key_cells: Callable[[int], list[str] | None], variants: Collection[int], source: str) -> None:
    """A baseline that can be compared: a sweep table of the same keys holding each of ``variants``
    exactly once, with the varied values ``key_cells(variant)`` gives (None: no such variant here)
    and numbers (or empty cells) where figures are numbers.  InputError otherwise."""
    where = f"--check-against {source}"
    _check_baseline_header(base_header, keys, where)
    if not base_rows:
        raise InputError(f"{where}: no variant rows, only a header (a baseline holds every variant of the sweep)")
    col = {c: j for j, c in enumerate(base_header)}
    seen: dict[int, int] = {}
    for k, row in enumerate(base_rows, 1):
        v = _check_baseline_row(base_header, row, k, col, keys, key_cells, where)
        if v in seen:
            raise InputError(f"{where}: variant {v} is in rows {seen[v]} and {k} (each variant once)")
        seen[v] = k
    if len(seen) < len(variants):
        missing = [str(v) for v in variants if v not in seen]
        shown = ", ".join(missing[:5]) + (f" and {len(missing) - 5} more" if len(missing) > 5 else "")
        raise InputError(f"{where}: no row for variant {shown} (it is from another sweep, or rows were lost)")


def _check_baseline_header(base_header: list[str], keys: Sequence[str], where: str) -> None:
    """The header of a sweep table of ``keys``: ``variant``, the keys, no column twice."""
    if "variant" not in base_header:
        raise InputError(f"{where}: the baseline has no 'variant' column (not a sweep.csv)")
    twice = next((c for j, c in enumerate(base_header) if c in base_header[:j]), None)
    if twice is not None:
        raise InputError(f"{where}: the column {quote(twice)} is in the header twice")
    missing_keys = [short(k) for k in keys if k not in base_header]
    if missing_keys:
        raise InputError(f"{where}: the baseline does not vary {', '.join(missing_keys)} "
                         "(it is from another sweep)")


_VARIANT = re.compile(r"^[0-9]+$")


def _check_baseline_row(base_header: list[str], row: list[str], k: int, col: dict, keys: Sequence[str],
                        key_cells: Callable[[int], list[str] | None], where: str) -> int:
    """Row ``k`` (1-based, after the header) of a baseline: its variant, after checking its cells."""
    if len(row) != len(base_header):
        raise InputError(f"{where}: row {k} has {len(row)} cells, the header {len(base_header)}")
    text = row[col["variant"]].strip()
    if not (_VARIANT.match(text) and len(text) < 10):
        raise InputError(f"{where}: row {k}: the variant {quote(text)} is not a variant index (a whole number)")
    v = int(text)
    cells = key_cells(v)
    if cells is None:
        raise InputError(f"{where}: row {k}: variant {v} is not a variant of this sweep (it is from another sweep)")
    for key, now in zip(keys, cells):
        if not _same_value(row[col[key]], now):
            raise InputError(f"{where}: row {k}: variant {v} has {short(key)}={quote(row[col[key]])} in the "
                             f"baseline, {short(now)} here (it is from another sweep)")
    for name, cell in zip(base_header, row):
        if name in NUMERIC_FIGURES or name.startswith("peak_tension_"):
            problem = _number_problem(cell)
            if problem:
                raise InputError(f"{where}: row {k} (variant {v}), column {short(name)}: {quote(cell)} {problem}")
    return v


def _number_problem(cell: str) -> str | None:
    """What is wrong with a baseline cell of a numeric figure (None: a number, or empty as
    ``sweep.csv`` leaves a figure it has not got)."""
    if not cell.strip():
        return None
    try:
        x = float(cell)
    except ValueError:
        return "is not a number"
    return None if math.isfinite(x) else "is not a finite number (sweep.csv leaves a missing figure empty)"


def _same_value(base: str, now: str) -> bool:
    """Whether a varied value of the baseline (CSV text) is this sweep's (CSV text)."""
    a, b = _num(base), _num(now)
    return (a is not None and b is not None and math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)) or base == now


def compare(header: list[str], rows: list[list[str]], base_header: list[str], base_rows: list[list[str]],
            keys: Sequence[str], tolerance: float = 1e-6, abs_tolerance: float = 1e-9,
            strict: bool = False, source: str = "the baseline") -> tuple[list[Difference], list[Difference]]:
    """Compare a sweep table with a baseline table (cells as CSV text).

    Variants are matched by index, and their varied values must agree.  A
    number differs when |current - baseline| > tolerance * max(|baseline|,
    |current|) + abs_tolerance.  For figures with a known direction a
    difference is ``worse`` or ``better``; for the others (counts, names) any
    difference is ``changed``.  A variant that fails now and did not fail in
    the baseline is ``worse``; a baseline column missing now is ``missing``.

    Returns
    -------
    regressions, improvements : lists of :class:`Difference`
        Regressions are ``worse``, ``changed`` and ``missing`` (and, with
        ``strict``, ``better`` too).

    Raises
    ------
    InputError
        The baseline (``source``, for the message) is not a sweep table, or it is
        from another sweep (other varied keys or values, variants this sweep does
        not have or it lacks), or it is damaged (a variant twice, a numeric figure
        that is neither a finite number nor empty): see :func:`check_baseline`.
    """
    cur = {int(r[0]): r for r in rows}
    bi = {c: j for j, c in enumerate(base_header)}
    ci = {c: j for j, c in enumerate(header)}

    def key_cells(i: int) -> list[str] | None:
        return [cur[i][ci[k]] for k in keys] if i in cur else None

    _check_baseline(base_header, base_rows, keys, key_cells, cur, source)
    worse: list[Difference] = []
    better: list[Difference] = []
    for br in base_rows:
        v = br[bi["variant"]].strip()
        r = cur[int(v)]
        for col in base_header:
            if col in keys or col == "variant":
                continue
            old = br[bi[col]]
            if col not in ci:
                worse.append(Difference(int(v), col, old, "", "missing"))
                continue
            new = r[ci[col]]
            if old == new:
                continue
            if col == "error":
                d = Difference(int(v), col, old, new, "worse" if new and not old else
                               ("better" if old and not new else "changed"))
                (better if d.change == "better" else worse).append(d)
                continue
            a, b = _num(old), _num(new)
            direction = _direction(col)
            if a is not None and b is not None:
                if abs(b - a) <= tolerance * max(abs(a), abs(b)) + abs_tolerance:
                    continue
                if direction == 0:
                    change = "changed"
                else:
                    change = "better" if (b - a) * direction > 0 else "worse"
            elif direction != 0 and a is None and b is not None:
                change = "better"
            elif direction != 0 and a is not None and b is None:
                change = "worse"
            else:
                change = "changed"
            d = Difference(int(v), col, old, new, change)
            if change == "better":
                better.append(d)
                if strict:
                    worse.append(d)
            else:
                worse.append(d)
    return worse, better
