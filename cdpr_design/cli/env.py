"""The environment variables the command line reads (and only it: the library takes parameters).

- ``CDPR_DESIGN_PICTURE_WORKER=0``: draw the pictures in-process instead of
  in a helper process (:class:`cdpr_design.plots.worker.PictureWorker`).
- ``CDPR_DESIGN_ENGINE``: ``auto`` (default), ``numba`` or ``numpy``, the
  engine of the workspace sweeps (:data:`cdpr_design.workspaces.engine.ENGINES`).

This module imports nothing heavy: ``python -m cdpr_design`` reads it before
anything else.
"""

from __future__ import annotations

import os

from cdpr_design.errors import InputError

def picture_worker_enabled(environ=os.environ) -> bool:
    """Whether pictures may be drawn in a helper process (not ``CDPR_DESIGN_PICTURE_WORKER=0``)."""
    return environ.get("CDPR_DESIGN_PICTURE_WORKER", "1").strip() != "0"


def engine(environ=os.environ) -> str:
    """The workspace engine ``CDPR_DESIGN_ENGINE`` asks for (default ``auto``); a bad value is an
    :class:`InputError` naming the variable."""
    from cdpr_design.workspaces.engine import ENGINES

    value = environ.get("CDPR_DESIGN_ENGINE", "").strip().lower() or "auto"
    if value not in ENGINES:
        raise InputError(f"CDPR_DESIGN_ENGINE: expected one of {', '.join(ENGINES)}, got {value!r}")
    return value
