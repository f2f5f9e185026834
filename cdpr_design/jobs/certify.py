"""The ``certify`` job: pave the workspace with proven boxes, write ``boxes.csv`` (or
``.parquet``), ``certify.png`` and ``summary.json``."""

from __future__ import annotations

from pathlib import Path

from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, table_metadata
from cdpr_design.plots.certify import certify_figure
from cdpr_design.plots.worker import PictureWorker

#: the files the job writes besides its table
FILES = ("certify.png", "summary.json")


def certify(design, out: str | Path | None = None, overwrite: bool = False, **options):
    """The ``certify`` command: :func:`run_certify` into the folder ``out`` (default
    ``out/<design name>/``; ``overwrite``: replace foreign files).  Returns (result, folder)."""
    out_dir = output_dir(design, out, overwrite)
    return run_certify(design, out_dir, **options), out_dir


def run_certify(design, out: OutputDir, kind: str = "static", resolution: float | None = None, box=None,
                min_margin: float | None = None, max_boxes: int | None = None, time_limit: float | None = None,
                format: str = "csv", pictures: PictureWorker | None = None, progress: Progress | None = None,
                timings: Timings | None = None):
    """Certify (:func:`cdpr_design.workspaces.certify.certify`, the options are its own), then
    write the boxes, the picture and ``summary.json`` (with the ``timings``: ``load_s`` the
    kernels' load or compile, ``sweep_s`` the branch-and-prune)."""
    from cdpr_design.workspaces import certify as cert

    timings = timings or Timings()
    cert.check_certifiable(design, kind)
    for name in FILES:
        out.target(name)  # a foreign file of that name: refused before any work
    limits = {} if max_boxes is None else {"max_boxes": max_boxes}
    with timings.phase("load_s"), stage(progress, "loading the kernels (a first run compiles them)"):
        cert.warm_up(design, kind)
    with timings.phase("sweep_s"), stage(progress, f"certify {design.name}") as cb:
        result = cert.certify(design, kind, resolution, box, min_margin, time_limit=time_limit,
                              progress=None if cb is None else (lambda done, todo: cb(done, done + todo)),
                              **limits)
    pending = submit_pictures(out, [("certify.png", certify_figure, (result,))], pictures, timings)
    cols = result.columns()
    meta = table_metadata(design, "boxes", cols, kind=kind, resolution=result.resolution,
                          orientation=[float(v) for v in design.default_orientation_full()])
    with timings.phase("write_s"):
        writer = out.table("boxes", format, metadata=meta, names=list(cols))
        try:
            writer.write(cols)
            writer.close()
        except BaseException:
            writer.abort()
            raise
    pending.wait()
    result.extra["timings"] = timings.as_dict()
    out.write_json("summary.json", result.summary())
    return result
