"""What the jobs write tables with: column units, the tables' metadata, and the timings of a job.

Tables go through :class:`cdpr_design.io.columns.ColumnWriter` (CSV or
Parquet, ``--format``); this module describes them for the Parquet metadata --
the design's name, the table, the grid, each column's unit (from its name,
the conventions of docs/cli.md) -- and times a job's phases for the
``timings`` object of every summary.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from typing import Iterable

from pathlib import Path

from cdpr_design.io.columns import FORMATS, file_name

#: Table formats of ``--format``.
TABLE_FORMATS = tuple(FORMATS)

#: Units of whole column names (docs/cli.md).
_EXACT = {
    "time": "s", "margin": "N", "peak_tension": "N", "static_tension": "N", "min_tension": "N",
    "peak_cable_speed": "m/s", "peak_cable_accel": "m/s^2", "drum_torque": "N m",
    "peak_motor_torque": "N m", "rms_motor_torque": "N m", "peak_motor_speed": "rpm",
    "drum_radius": "m", "reflected_inertia": "kg m^2", "tension_min": "N", "tension_max": "N",
    "implied_tension_max": "N", "implied_tension_rated": "N", "usable_peak_torque": "N m",
    "usable_rated_torque": "N m", "motor_max_speed": "rpm", "min_margin": "N", "max_margin": "N",
    "max_tension": "N", "task_min_margin": "N", "min_margin_figure": "N", "req_min_margin": "N",
    "feasible": "0/1", "collision_free": "0/1", "fits": "0/1", "checks_passed": "0/1",
}
# frame_loads.csv (cdpr_design.workspaces.frame_loads): forces on the frame [N]
_EXACT.update({f"{pre}{name}": "N" for pre in ("", "limit_")
               for name in ["max_force"] + [f"{mm}_f{a}" for a in "xyz" for mm in ("min", "max")]})
#: Units of column-name prefixes, longest first (per-cable and per-coordinate columns).
_PREFIX = sorted([
    ("tension_", "N"), ("outlet_tension_", "N"), ("peak_tension_", "N"), ("length_", "m"),
    ("unstretched_length_", "m"), ("sag_", "m"), ("cable_speed_", "m/s"), ("cable_accel_", "m/s^2"),
    ("motor_angle_", "rad"), ("axis_", "m"), ("lower_", "m"), ("upper_", "m"), ("tilt", "rad"), ("range_", "rad"),
], key=lambda p: -len(p[0]))
_COORD = {"x": "m", "y": "m", "z": "m", "phi": "rad", "rx": "rad", "ry": "rad", "rz": "rad"}


def column_unit(name: str) -> str | None:
    """The unit of a column of the tool's tables, from its name (None: a count, a ratio or text)."""
    if name in _EXACT:
        return _EXACT[name]
    base, _, suffix = name.rpartition("_")
    if name in _COORD or (suffix == "target" and base in _COORD):
        return _COORD[name if name in _COORD else base]
    if suffix in ("vel", "acc") and base in _COORD:
        return _COORD[base] + ("/s" if suffix == "vel" else "/s^2")
    for prefix, unit in _PREFIX:
        if name.startswith(prefix):
            return unit
    return None


def table_metadata(design, table: str, names: Iterable[str], **extra) -> dict:
    """The Parquet metadata of a table: design name, table, units of ``names``, ``extra`` (grid, ...)."""
    units = {n: u for n in names if (u := column_unit(n)) is not None}
    meta = {"name": design.name if design is not None else None, "table": table}
    if design is not None and getattr(design, "source", None):
        meta["spec"] = str(design.source)
    meta.update(extra)
    meta["units"] = units
    return meta


def write_table(out, stem: str, columns: dict, format: str = "csv", design=None, names=None, **meta) -> Path:
    """``stem.csv`` or ``stem.parquet`` of named columns (name -> array or list) in the output folder
    ``out``, with the table's metadata (:func:`table_metadata`; ``meta``: further keys).  ``names``:
    the column order (the header of a table without rows)."""
    names = list(names) if names is not None else list(columns)
    return out.write_columns(file_name(stem, format), columns, names=names,
                             metadata=table_metadata(design, stem, names, **meta))


def write_rows(out, stem: str, header: list[str], rows: list[list], format: str = "csv", design=None,
               **meta) -> Path:
    """:func:`write_table` of a table held as rows (lists of cells in ``header``'s order)."""
    cols = list(zip(*rows)) if rows else [()] * len(header)
    return write_table(out, stem, dict(zip(header, cols)), format, design, names=header, **meta)


def grid_metadata(grid) -> dict:
    """``lower``, ``upper``, ``step`` [m] and ``shape`` of a workspace grid."""
    return {"lower": list(grid.lower), "upper": list(grid.upper), "step": list(grid.step),
            "shape": list(grid.shape)}


class Timings:
    """Wall-clock phases of a job [s], for the ``timings`` object of its summary.

    ``sweep_s``: the computation (grid sweep, evaluation, sampling or
    simulation) without the time its thread spent writing; ``load_s`` (jobs that
    time it apart, ``workspace`` and ``report``): numba's start-up before the sweep,
    loading the kernels from its on-disk cache or compiling them on a machine's
    first run; ``write_s``: formatting
    and writing the tables; ``pictures_s``: drawing the pictures (waiting for
    the picture worker); ``total_s``: the whole job.  Phases may overlap
    (tables are written while the pictures are drawn), so the parts can add up
    to more than ``total_s``.
    """

    def __init__(self):
        self.t0 = time.perf_counter()
        self.sweep_s = self.write_s = self.pictures_s = 0.0
        self.load_s: float | None = None  # measured by the jobs that time numba's start-up apart

    @contextmanager
    def phase(self, name: str):
        """Add the time spent in the ``with`` block to ``name`` (``load_s``, ``sweep_s``, ``write_s``, ``pictures_s``)."""
        t = time.perf_counter()
        try:
            yield
        finally:
            setattr(self, name, (getattr(self, name) or 0.0) + time.perf_counter() - t)

    def as_dict(self) -> dict:
        """``{sweep_s, write_s, pictures_s, total_s}`` (and ``load_s`` when measured), total up to now."""
        out = {} if self.load_s is None else {"load_s": round(self.load_s, 4)}
        return out | {"sweep_s": round(self.sweep_s, 4), "write_s": round(self.write_s, 4),
                      "pictures_s": round(self.pictures_s, 4),
                      "total_s": round(time.perf_counter() - self.t0, 4)}
