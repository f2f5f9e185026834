"""The ``workspace`` job: sweep the grid, stream ``workspace.csv``, write ``summary.json`` and pictures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cdpr_design.io.files import OutputDir
from cdpr_design.io.tables import format_block
from cdpr_design.jobs.common import Progress, output_dir, save_pictures, stage
from cdpr_design.plots import workspace as wsplots
from cdpr_design.plots.worker import PictureWorker


def workspace_rows(chunk, extra: dict[str, np.ndarray] | None = None) -> str:
    """CSV text of one :class:`~cdpr_design.workspaces.grid.Chunk` (no header)."""
    cols = [chunk.poses[:, j] for j in range(chunk.poses.shape[1])]
    cols.append(chunk.feasible)
    cols.append(chunk.margin)
    cols += [chunk.tensions[:, i] for i in range(chunk.tensions.shape[1])]
    cols += [chunk.lengths[:, i] for i in range(chunk.lengths.shape[1])]
    ints = [chunk.poses.shape[1]]
    for v in (extra or {}).values():
        if v.dtype.kind in "biu":
            ints.append(len(cols))
        cols.append(v)
    return format_block(cols, int_cols=ints)


def workspace(design, out: str | Path | None = None, overwrite: bool = False, **options):
    """The ``workspace`` command: :func:`run_workspace` into the folder ``out``
    (default ``out/<design name>/``; ``overwrite``: replace foreign files).
    Returns (result, output folder)."""
    out_dir = output_dir(design, out, overwrite)
    return run_workspace(design, out_dir, **options), out_dir


def run_workspace(design, out: OutputDir, kind: str = "static", step: float | None = None, force: bool = False,
                  collisions: bool = False, orientations: str | None = None,
                  pictures: PictureWorker | None = None, engine: str = "auto",
                  progress: Progress | None = None):
    """Sweep, stream ``workspace.csv``, write pictures and ``summary.json``; return the result.

    ``step`` [m] overrides the spec's grid step; ``force`` allows grids past
    the size limit.  ``collisions``: intersect feasibility with the
    interference checks (column ``collision_free``); ``orientations``:
    ``total`` or ``range`` orientation workspace (rotational motions; extra
    columns, ``orientation_workspace.png``).  ``pictures``: the worker drawing
    the PNGs (None: in-process); ``engine``: ``auto``, ``numba`` or ``numpy``.
    """
    result = _stream_sweep(design, out, kind, step, force, collisions, orientations, engine, progress)
    out.write_json("summary.json", result.summary())
    save_workspace_pictures(out, result, pictures)
    if result.orientation_maps is not None:
        save_orientation_picture(out, result)
    return result


def _stream_sweep(design, out, kind, step, force, collisions, orientations, engine, progress):
    """The grid sweep, its rows streamed into ``workspace.csv`` (kept only when complete)."""
    from cdpr_design import workspaces as ws

    grid = ws.make_grid(design, step, force)
    header = ws.column_names(design) + ws.extra_columns(design, collisions, orientations)
    files = []  # workspace.csv, opened with the first chunk: options the sweep refuses leave no file

    def csv_file():
        if not files:
            files.append(out.stream("workspace.csv"))
            files[0].write(",".join(header) + "\n")
        return files[0]

    try:
        def on_chunk(chunk):
            csv_file().write(workspace_rows(chunk, extra=ws.chunk_extra(chunk)))

        with stage(progress, f"workspace {design.name}") as cb:
            if orientations:
                result = ws.run_orientations(design, orientations, kind=kind, grid=grid, on_chunk=on_chunk,
                                             progress=cb, force=True, interference=collisions, engine=engine)
            else:
                result = ws.run(design, kind=kind, grid=grid, on_chunk=on_chunk, progress=cb, force=True,
                                interference=collisions, engine=engine)
        csv_file().commit()
    except BaseException:
        if files:
            files[0].abort()
        raise
    return result


def save_workspace_pictures(out: OutputDir, result, worker: PictureWorker | None = None) -> list[Path]:
    """``workspace.png`` and ``tension_map.png`` of a workspace result (drawn by ``worker`` if given)."""
    return save_pictures(out, [("workspace.png", wsplots.workspace_figure, (result,)),
                               ("tension_map.png", wsplots.tension_figure, (result,))], worker)


def save_orientation_picture(out: OutputDir, result) -> Path:
    """``orientation_workspace.png`` of an orientation sweep (:func:`~cdpr_design.plots.workspace.orientation_figure`)."""
    return save_pictures(out, [("orientation_workspace.png", wsplots.orientation_figure, (result,))])[0]
