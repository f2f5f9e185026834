"""The ``workspace`` job: sweep the grid, stream ``workspace.csv`` (or ``.parquet``), write
``summary.json``, the pictures and, if asked, ``report.html``."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.solid import solid_names, write_solid
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, grid_metadata, table_metadata
from cdpr_design.plots import workspace as wsplots
from cdpr_design.plots.hanging import tilt_figure
from cdpr_design.plots.solid import frame_load_figure
from cdpr_design.plots.acceleration import acceleration_figure
from cdpr_design.plots.stiffness import stiffness_figure
from cdpr_design.plots.report import report_html
from cdpr_design.plots.worker import PictureWorker
from cdpr_design.statics.robot import Analysis, resolve


def workspace_columns(design, chunk) -> dict:
    """The ``workspace.csv`` columns of one :class:`~cdpr_design.workspaces.grid.Chunk`, in order:
    the contract's (pose coordinates, ``feasible`` as bool, ``margin``, tensions, lengths), then
    the extra columns the sweep plan declared (0/1 flags held as uint8 become bool)."""
    from cdpr_design import workspaces as ws

    names = ws.column_names(design)
    k, m = chunk.poses.shape[1], chunk.tensions.shape[1]
    arrays = ([chunk.poses[:, j] for j in range(k)] + [chunk.feasible.astype(bool), chunk.margin]
              + [chunk.tensions[:, i] for i in range(m)] + [chunk.lengths[:, i] for i in range(m)])
    cols = dict(zip(names, arrays))
    for name, v in chunk.extra.items():
        v = np.asarray(v)
        cols[name] = v.astype(bool) if v.dtype == np.uint8 else v
    return cols


@dataclass(frozen=True)
class WorkspaceSettings:
    """The options of a ``workspace`` run (docs/cli.md): the ``analysis``
    (:class:`~cdpr_design.statics.robot.Analysis`: ``kind``, ``collisions``, ``orientations``,
    ``max_tilt`` [deg], ``engine``, ``stiffness``, ``accelerations``; see
    :func:`cdpr_design.workspaces.run`), the grid ``step`` [m] overriding the spec's, ``force``
    grids past the size limit, the table ``format`` (``csv`` or ``parquet``) and ``html``
    (``report.html`` too)."""

    analysis: Analysis = Analysis()
    step: float | None = None
    force: bool = False
    format: str = "csv"
    html: bool = False


def workspace(design, settings: WorkspaceSettings = WorkspaceSettings(), out: str | Path | None = None,
              overwrite: bool = False, *, pictures: PictureWorker | None = None,
              progress: Progress | None = None):
    """The ``workspace`` command: :func:`run_workspace` into the folder ``out``
    (default ``out/<design name>/``; ``overwrite``: replace foreign files).
    Returns (result, output folder).  The files are put in place together when all are written
    (:class:`~cdpr_design.io.files.OutputDir`): a failure leaves the folder's earlier files whole."""
    out_dir = output_dir(design, out, overwrite)
    with out_dir:
        result = run_workspace(design, out_dir, settings, pictures=pictures, progress=progress)
    return result, out_dir


def run_workspace(design, out: OutputDir, settings: WorkspaceSettings = WorkspaceSettings(),
                  pictures: PictureWorker | None = None, progress: Progress | None = None,
                  timings: Timings | None = None):
    """Sweep, stream ``workspace.csv`` (``settings.format='parquet'``: ``workspace.parquet``),
    write the pictures, ``summary.json`` and (``settings.html``) ``report.html``; return the result.

    What is swept is ``settings`` (:class:`WorkspaceSettings`): its analysis decides the columns
    (``collisions``: ``collision_free``; ``orientations``: the orientation workspace's columns
    and ``orientation_workspace.png``; a free under-constrained effector: ``tilt_map.png``;
    ``stiffness``: ``min_stiffness`` [N/m], ``lowest_frequency`` [Hz] and
    ``stiffness_map.png``; ``accelerations``: ``acceleration_radius`` [m/s^2] and
    ``acceleration_map.png``); with sagging cables the grid is swept again with ideal cables
    for ``cable_models.png``.  ``pictures``: the worker drawing the PNGs (None: in-process).
    The table is written by a thread while the sweep goes on and the pictures are drawn;
    ``result.summary()['timings']`` gives the phases (``timings``: a running
    :class:`~cdpr_design.jobs.tables.Timings` to add them to).
    """
    timings = timings or Timings()
    result, pending = start_workspace(design, out, settings, pictures, progress, timings)
    finish_workspace(out, result, pending, timings)
    return result


def start_workspace(design, out: OutputDir, settings: WorkspaceSettings = WorkspaceSettings(),
                    pictures: PictureWorker | None = None, progress: Progress | None = None,
                    timings: Timings | None = None):
    """:func:`run_workspace` up to the pictures: the table is written and the pictures are being
    drawn.  Returns (result, pending pictures); :func:`finish_workspace` waits for them, so a
    caller can do more work (``report``'s evaluation) while they are drawn."""
    from cdpr_design import workspaces as ws

    o = settings
    timings = timings if timings is not None else Timings()
    grid = ws.make_grid(design, o.step, o.force)
    p = ws.plan(resolve(design, o.analysis), grid, solid=True)
    meta = table_metadata(design, "workspace", p.columns, kind=o.analysis.kind, grid=grid_metadata(grid),
                          orientation=[float(v) for v in (design.workspace.orientation or [])])
    files = output_names(p, o.html, o.format)
    for name in files:
        out.target(name)  # a foreign file of that name: refused before any work
    writer = out.table("workspace", o.format, metadata=meta, names=p.columns, background=True,
                       compiled=p.robot.engine == "numba")  # the kernels loaded: their formatter costs no start-up
    try:
        result = _sweep(p, progress, writer, timings)
        with timings.phase("write_s"):
            write_solid(out, result, o.format)
        pics = workspace_pictures(result, p.pictures) + ([("report.html", report_html, (result,))] if o.html else [])
        pending = submit_pictures(out, pics, pictures, timings)
        writer.close()
    except BaseException:
        writer.abort()
        raise
    timings.write_s += writer.busy_s
    return result, pending


def output_names(p, html: bool = False, format: str = "csv") -> list[str]:
    """Every file :func:`start_workspace` writes besides its table, known before the sweep: the
    pictures the sweep plan ``p`` declares, ``summary.json``, with ``html`` ``report.html``, and
    (a plan made with ``solid``) the boundary's and the frame loads' files (tables in ``format``)."""
    pics = p.pictures
    return (pics[:2] + ["summary.json"] + pics[2:] + (["report.html"] if html else [])
            + (solid_names(p.robot.design, format) if p.solid else []))


def finish_workspace(out: OutputDir, result, pending, timings: Timings) -> None:
    """Wait for the pictures of :func:`start_workspace`, then write ``summary.json`` with the timings."""
    pending.wait()
    result.extra["timings"] = timings.as_dict() | {"boundary_s": round(result.boundary.elapsed_s, 4)}
    out.write_json("summary.json", result.summary())


#: What the load stage says while it runs (shown once it has taken a while).
LOAD_HINT = "a first run compiles them: up to a minute"


def _sweep(p, progress, writer, timings):
    """The sweep plan ``p`` run, each chunk handed to ``writer`` (a background ColumnWriter)."""
    from cdpr_design import workspaces as ws

    waited = 0.0
    design = p.robot.design

    def on_chunk(chunk):
        nonlocal waited
        t = time.perf_counter()
        writer.write(workspace_columns(design, chunk))
        waited += time.perf_counter() - t

    # numba's start-up, apart from the sweep's time (a machine's first run compiles the kernels)
    with timings.phase("load_s"), stage(progress, f"loading the kernels ({LOAD_HINT})"):
        ws.warm_up(p)
        writer.warm_up()
    t0 = time.perf_counter()
    with stage(progress, f"workspace {design.name}") as cb:
        result = p.run(on_chunk, cb)
    timings.sweep_s += time.perf_counter() - t0 - waited
    return result


#: The figure function of each picture a sweep plan may declare (``cable_models.png`` apart:
#: it sweeps the grid again, :func:`cable_model_picture`).
FIGURES = {"workspace.png": wsplots.workspace_figure, "tension_map.png": wsplots.tension_figure,
           "tilt_map.png": tilt_figure, "orientation_workspace.png": wsplots.orientation_figure,
           "stiffness_map.png": stiffness_figure, "frame_loads.png": frame_load_figure,
           "acceleration_map.png": acceleration_figure}


def workspace_pictures(result, names: list[str] | None = None) -> list:
    """The pictures ``names`` (default: those the sweep's plan declared, ``result.pictures``) as
    (file, figure function, arguments); ``cable_models.png`` sweeps the grid again with ideal cables."""
    names = result.pictures if names is None else names
    return [cable_model_picture(result) if n == "cable_models.png" else (n, FIGURES[n], (result,))
            for n in names]


def cable_model_picture(result) -> tuple:
    """``cable_models.png`` of a sagging sweep: the same grid swept with ideal cables, compared
    with ``result`` (:func:`~cdpr_design.plots.workspace.cable_model_figure`)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.model.spec import with_cable_model

    robot = result.robot
    collisions = bool(robot.analysis.collisions) if robot is not None else False
    engine = robot.engine if robot is not None else "auto"
    # only the feasible cells are compared: no hanging tilt of a held under-constrained effector
    ideal = ws.run(with_cable_model(result.design, "ideal"), Analysis(kind=result.kind, collisions=collisions,
                                                                     engine=engine),
                   grid=result.grid, orientation=result.orientation, force=True, tilt=False)
    return ("cable_models.png", wsplots.cable_model_figure, (result, ideal))
