"""The ``cdpr-design`` command line (Typer): the app, its commands and the console-script entry point.

Each command lives in a module of this package (options -> one job or
library call -> a table or JSON); :mod:`cdpr_design.cli.common` holds what
they share, including the exit codes (0 done; 1 a check failed; 2 bad input;
130 interrupted).
"""

from __future__ import annotations

import gc
import sys

import typer

from cdpr_design.cli import bridge, motion, optimize, pose, sizing, sweep, workspace
from cdpr_design.cli.common import err

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Workspace, sizing and simulation explorer for cable-driven parallel robots.",
    context_settings={"help_option_names": ["-h", "--help"]},
)

for _module in (workspace, pose, sizing, bridge, motion, sweep, optimize):  # the order of the help's command list
    _module.register(app)


def main() -> None:
    """Console-script entry point (``cdpr_design.__main__.main`` starts the picture worker earlier)."""
    from cdpr_design.cli import env
    from cdpr_design.plots import worker as _picture_worker

    if _picture_worker.wanted(sys.argv[1:]):
        _picture_worker.prestart(enabled=env.picture_worker_enabled())
    try:
        app()
    except KeyboardInterrupt:
        err.print("interrupted")
        sys.exit(130)
    finally:
        _picture_worker.discard()
        # the command is done: the interpreter's exit then skips its last garbage collections over
        # every object alive (numba's type system and compiled libraries: 0.3-0.7 s of a process)
        gc.freeze()
