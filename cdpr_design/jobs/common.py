"""What every job shares: its output folder, progress stages and pictures written to PNG files.

Progress: a job that reports progress takes ``progress``, a callable that,
given the description of a stage (``"workspace planar2"``), returns a context
manager yielding a callback ``cb(done, total)`` (or None: no reporting).  The
command line passes one drawing progress bars; None reports nothing.
"""

from __future__ import annotations

import time
from contextlib import nullcontext
from pathlib import Path
from typing import Callable, ContextManager, Optional, Sequence

from cdpr_design.io.files import OutputDir
from cdpr_design.plots.worker import PictureWorker

Callback = Callable[[int, int], None]
Progress = Callable[[str], ContextManager[Optional[Callback]]]
#: A picture to draw: (file name, figure function of cdpr_design.plots, its arguments).
Picture = tuple[str, Callable, tuple]


def output_dir(design, out: str | Path | None = None, overwrite: bool = False) -> OutputDir:
    """The output folder ``out`` (default ``out/<design name>/``), created if missing."""
    return OutputDir(out if out is not None else Path("out") / design.name, overwrite=overwrite)


def stage(progress: Progress | None, description: str) -> ContextManager[Optional[Callback]]:
    """The context of one stage of a job: ``with stage(progress, "...") as cb:``."""
    return progress(description) if progress is not None else nullcontext(None)


def submit_pictures(out: OutputDir, pictures: Sequence[Picture], worker: PictureWorker | None = None,
                    timings=None) -> "PendingPictures":
    """Start drawing the pictures (in ``worker``'s child if given, while the caller goes on);
    :meth:`PendingPictures.wait` writes the PNGs.  Every name is checked against ``out``
    (foreign files) before anything is drawn.  ``timings``: a :class:`~cdpr_design.jobs.tables.Timings`
    whose ``pictures_s`` gets the time from here until the files are written."""
    for name, _, _ in pictures:
        out.target(name)
    return PendingPictures(out, (worker or PictureWorker(enabled=False)).submit(list(pictures)), timings)


class PendingPictures:
    """Pictures being drawn (:func:`submit_pictures`)."""

    def __init__(self, out: OutputDir, pending, timings=None):
        self.out, self.pending, self.timings = out, pending, timings
        self.t0 = time.perf_counter()

    def wait(self) -> list[Path]:
        """Wait for the PNGs and write them atomically; their paths."""
        paths = [self.out.write_bytes(name, data) for name, data in self.pending.result()]
        if self.timings is not None:
            self.timings.pictures_s += time.perf_counter() - self.t0
        return paths


def save_pictures(out: OutputDir, pictures: Sequence[Picture], worker: PictureWorker | None = None,
                  timings=None) -> list[Path]:
    """Draw each picture (in ``worker`` if given, else in-process) and write the PNGs atomically."""
    return submit_pictures(out, pictures, worker, timings).wait()
