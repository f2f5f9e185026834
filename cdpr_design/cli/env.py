"""The environment variables the command line reads (and only it: the library takes parameters).

- ``CDPR_DESIGN_PICTURE_WORKER=0``: draw the pictures in-process instead of
  in a helper process (:class:`cdpr_design.plots.worker.PictureWorker`).
- ``CDPR_DESIGN_ENGINE``: ``auto`` (default), ``numba`` or ``numpy``, the
  engine of the workspace sweeps (:data:`cdpr_design.workspaces.engine.ENGINES`).

And two it sets for the libraries below it (:func:`settle_blas_threads`, :func:`use_kernel_cache`).

This module imports nothing heavy: ``python -m cdpr_design`` reads it before
anything else.
"""

from __future__ import annotations

import os

from cdpr_design.errors import InputError

#: Cycles (as a power of two) an idle OpenBLAS thread busy-waits for work before it sleeps.
#: OpenBLAS's default is 28; 4 is its least.
BLAS_THREAD_TIMEOUT = "4"


def settle_blas_threads(environ=os.environ) -> None:
    """Let numpy's and scipy's OpenBLAS threads sleep at once when they have no work
    (``OPENBLAS_THREAD_TIMEOUT``, unless the user set it); call before numpy is imported.

    OpenBLAS starts its threads when it loads and each busy-waits for work
    before it sleeps, and again after every call it shares out (the CPU this
    saves: docs/performance.md).  A command keeps its cores busy with
    its own work (the sweep's threads, the picture worker), so that CPU comes
    out of its wall time.  BLAS still runs on all cores where a call is large
    enough to share out; only the wait is shorter.
    """
    environ.setdefault("OPENBLAS_THREAD_TIMEOUT", BLAS_THREAD_TIMEOUT)


def user_cache(environ=os.environ) -> str:
    """Where the kernels' cache folders go when ``NUMBA_CACHE_DIR`` is not set: the user's cache
    folder (``XDG_CACHE_HOME``, else ``~/.cache``) / ``cdpr-design``."""
    root = environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(root, "cdpr-design")


def use_kernel_cache(environ=os.environ) -> str:
    """Point numba's cache (``NUMBA_CACHE_DIR``) at the kernels' folder for their current sources
    (:func:`cdpr_design.kernels.cache.folder`): under the user's ``NUMBA_CACHE_DIR`` if set, else
    under the user's cache folder.  Call before anything imports numba (it reads the variable
    once); commands this one starts inherit it.  Returns the folder."""
    from cdpr_design.kernels import cache

    chosen = cache.folder(environ.get("NUMBA_CACHE_DIR") or user_cache(environ))
    environ["NUMBA_CACHE_DIR"] = chosen
    return chosen


def picture_worker_enabled(environ=os.environ) -> bool:
    """Whether pictures may be drawn in a helper process (not ``CDPR_DESIGN_PICTURE_WORKER=0``)."""
    return environ.get("CDPR_DESIGN_PICTURE_WORKER", "1").strip() != "0"


def engine(environ=os.environ) -> str:
    """The workspace engine ``CDPR_DESIGN_ENGINE`` asks for (default ``auto``); a bad value is an
    :class:`InputError` naming the variable."""
    from cdpr_design.statics.robot import ENGINES

    value = environ.get("CDPR_DESIGN_ENGINE", "").strip().lower() or "auto"
    if value not in ENGINES:
        raise InputError(f"CDPR_DESIGN_ENGINE: expected one of {', '.join(ENGINES)}, got {value!r}")
    return value
