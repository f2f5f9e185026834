"""The ``cdpr-design`` command line (Typer): the app, its commands and the console-script entry point.

Each command lives in a module of this package (options -> one job or
library call -> a table or JSON); :mod:`cdpr_design.cli.common` holds what
they share, including the exit codes (0 done; 1 a check failed; 2 bad input;
130 interrupted).
"""

from __future__ import annotations

import gc
import importlib
import sys
from typing import Sequence

import typer

from cdpr_design.cli.common import err

#: Every command and the module of this package that registers it, in the order of the help's
#: command list (a test checks this against what the modules register).
COMMANDS = {
    "workspace": "workspace", "pose": "pose", "fk": "pose", "schema": "pose",
    "size-motors": "sizing", "report": "sizing", "check": "sizing", "bridge": "bridge",
    "trajectory": "motion", "simulate": "motion", "compare": "motion", "sweep": "sweep", "optimize": "optimize",
    "certify": "certify",
}


def make_app(argv: Sequence[str] | None = None) -> typer.Typer:
    """The Typer app.  Given the command line ``argv`` (after the program's name) whose first
    word is a command, only that command's module is imported and registered: typer then
    builds that command's options alone, less work at every start than building all
    thirteen.  Else every command (the help's list, an unknown
    command's error)."""
    one = argv is not None and len(argv) > 0 and argv[0] in COMMANDS
    app = typer.Typer(
        add_completion=False,
        no_args_is_help=True,
        rich_markup_mode=None,
        help="Workspace, sizing and simulation explorer for cable-driven parallel robots.",
        context_settings={"help_option_names": ["-h", "--help"]},
    )
    if one:
        app.callback()(_group)  # typer runs a lone command as the program itself: keep the group
    for module in ([COMMANDS[argv[0]]] if one else dict.fromkeys(COMMANDS.values())):
        importlib.import_module(f"cdpr_design.cli.{module}").register(app)
    return app


def _group() -> None:
    """The group's callback when it has one command (:func:`make_app`): nothing to do."""


def __getattr__(name: str):
    """``app``: every command (:func:`make_app`), built on first use (tests, other callers)."""
    if name == "app":
        globals()["app"] = built = make_app()
        return built
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main() -> None:
    """Run the command line on ``sys.argv``: called by :func:`cdpr_design.__main__.main` (the console
    script), which has set up the process first (collection thresholds, BLAS threads, the picture
    worker started before these imports)."""
    from cdpr_design.plots import worker as _picture_worker

    try:
        make_app(sys.argv[1:])()
    except KeyboardInterrupt:
        err.print("interrupted")
        sys.exit(130)
    finally:
        _picture_worker.discard()
        # the command is done: the interpreter's exit then skips its last garbage collections over
        # every object alive (numba's type system and compiled libraries among them)
        gc.freeze()
