"""What every command shares: options, loading the spec, number parsing, exit codes, JSON and tables.

Exit status (cli.md): 0 done; 1 the design fails a check it was asked to
pass; 2 bad input (spec, option, file); 130 interrupted.  Only the command
line turns exceptions into exit codes.  ``--json`` prints one JSON object on
stdout; progress and messages go to stderr.
"""

from __future__ import annotations

import errno
import functools
import math
import os
import sys
import warnings
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Optional

import typer

from cdpr_design.errors import CheckFailed, InputError, SpecError, quote
from cdpr_design.io.tables import timing_phases

if TYPE_CHECKING:
    from rich.console import Console
    from rich.table import Table


class _Console:
    """A rich ``Console`` made when first used: a command that prints nothing for a person
    (``--json``: no table, message or progress bar) never imports rich."""

    def __init__(self, **options):
        self._options = options
        self._made = None

    @property
    def made(self) -> Console:
        """The rich ``Console`` itself (made now if it was not yet)."""
        if self._made is None:
            from rich.console import Console

            self._made = Console(**self._options)
        return self._made

    def __getattr__(self, name):  # print, is_terminal, ... of the Console
        return getattr(self.made, name)


def _rich_console(console) -> Console:
    """The rich ``Console`` of :data:`err` or :data:`out_console` (or ``console`` itself, a rich
    ``Console`` put in their place): for rich's own objects that draw on it (progress bars)."""
    return console.made if isinstance(console, _Console) else console


# markup off: messages, names and paths are printed as they are ("[min, max]" stays, "[/x]" is text)
err = _Console(stderr=True, highlight=False, markup=False)
out_console = _Console(highlight=False, markup=False)


def table(title: str, **options) -> Table:
    """A rich table titled ``title``, left-justified as every table the command line prints."""
    from rich.table import Table

    return Table(title=title, title_justify="left", **options)


SpecArg = Annotated[Path, typer.Argument(help="Design spec (YAML).", show_default=False)]
OutOpt = Annotated[Optional[Path], typer.Option("--out", help="Output folder (default out/<design name>/).")]
SchedulerOpt = Annotated[Optional[str], typer.Option(
    "--scheduler", metavar="ADDRESS",
    help="Run on the Dask scheduler at ADDRESS (tcp://host:8786); 'local' starts a LocalCluster "
         "of --workers processes on this machine.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout and nothing else there.")]
QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bars or messages on stderr.")]
OverwriteOpt = Annotated[bool, typer.Option(
    "--overwrite", help="Replace files in --out that cdpr-design did not write.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Allow grids larger than the sane-size limit.")]
#: Grid steps [m]: 1 um (below any robot's accuracy) to 10 km (model.limits.LENGTH); the pose count is limited too.
STEP_RANGE = {"min": 1e-6, "max": 1e4}
StepOpt = Annotated[Optional[float], typer.Option(
    "--step", help="Grid step [m] (overrides workspace.grid.step).", **STEP_RANGE)]
CatalogueOpt = Annotated[Optional[Path], typer.Option(
    "--catalogue", help="Motor catalogue YAML extending the shipped one (same format as cdpr_design/data/motors.yaml).")]
TrajectoryOpt = Annotated[Optional[str], typer.Option(
    "--trajectory", help="Name of a spec trajectory whose duty cycle gives the RMS torque (default: a standard cycle).")]
SafetyOpt = Annotated[Optional[float], typer.Option(
    "--safety-factor", help="Factor >= 1 on required torque and speed (default requirements.safety_factor or 1).",
    min=1.0, max=100.0)]
MotorOpt = Annotated[Optional[str], typer.Option(
    "--motor", help="Evaluate this catalogue motor on every axis instead of the spec's or the smallest that fits.")]


class CableModel(str, Enum):
    ideal = "ideal"
    elastic = "elastic"
    sagging = "sagging"


CableModelOpt = Annotated[Optional[CableModel], typer.Option(
    "--cable-model", help="ideal | elastic | sagging: overrides the spec's cable.model for every cable "
                          "(elastic needs cable.axial_stiffness, sagging also cable.mass_per_length).")]


class Kind(str, Enum):
    static = "static"
    wrench_feasible = "wrench-feasible"
    wrench_closure = "wrench-closure"
    dynamic = "dynamic"


KindOpt = Annotated[Kind, typer.Option("--kind", help="static | wrench-feasible | wrench-closure | dynamic "
                                                      "(every acceleration of requirements.acceleration from rest).")]


class Format(str, Enum):
    csv = "csv"
    parquet = "parquet"


FormatOpt = Annotated[Format, typer.Option(
    "--format", help="Tables as csv (default) or parquet (typed columns, units and the spec in the metadata).")]


def error(message: str, head: str = "error:") -> None:
    """Print ``error: message`` on stderr, the message as plain text (no markup)."""
    from rich.text import Text

    err.print(Text.assemble((head, "bold red"), " ", str(message)), soft_wrap=True)


#: What a file system says when it refuses a write (a full disk or quota, a file-size limit, a
#: read-only or immutable file, a path too long): exit 2 with one line, as bad input, wherever it
#: comes from (the library names the file where it writes; this is the net below it).
FILE_SYSTEM_ERRORS = frozenset({errno.ENOSPC, errno.EFBIG, errno.EDQUOT, errno.EROFS, errno.EIO,
                                errno.ENAMETOOLONG, errno.EACCES, errno.EPERM})


def command(fn):
    """Turn the package's errors into exit codes and messages (no tracebacks for bad input).

    SIGTERM and SIGHUP interrupt the command like Ctrl-C (:mod:`cdpr_design.cli.signals`);
    with ``--quiet`` warnings (numpy's overflow, ...) are not printed either.  Notes the library
    logs (:func:`notes`) are printed on stderr.
    """
    from cdpr_design.cli.signals import interruptible

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            with interruptible(), warnings.catch_warnings(), notes(bool(kwargs.get("quiet") or kwargs.get("json_"))):
                if kwargs.get("quiet"):
                    quiet_warnings()
                return fn(*args, **kwargs)
        except (SpecError, InputError) as exc:
            error(str(exc))
            raise typer.Exit(2) from None
        except OSError as exc:
            if exc.errno not in FILE_SYSTEM_ERRORS:
                raise
            error(f"{exc.filename}: {exc.strerror}" if exc.filename else f"{exc.strerror} (a file of the command)")
            raise typer.Exit(2) from None
        except CheckFailed as exc:
            if str(exc):
                error(str(exc), "check failed:")
            raise typer.Exit(1) from None
        except KeyboardInterrupt:
            err.print("interrupted")
            raise typer.Exit(130) from None

    return wrapper


@contextmanager
def notes(quiet: bool):
    """What the library logs on the ``cdpr_design`` logger (a command waiting for another one that
    is writing into its ``--out``) printed on stderr as notes (:func:`info`; none when ``quiet``)."""
    import logging

    class Note(logging.Handler):
        def emit(self, record):
            info(quiet, record.getMessage())

    logger, handler = logging.getLogger("cdpr_design"), Note()
    logger.addHandler(handler)
    propagate, logger.propagate = logger.propagate, False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate


def quiet_warnings() -> None:
    """No warnings on stderr, in this process and in the worker processes it starts."""
    warnings.simplefilter("ignore")
    os.environ["PYTHONWARNINGS"] = "ignore"


def load_design(path: Path, cable_model: CableModel | None = None):
    """The design of a spec file, with ``--cable-model`` applied when given."""
    from cdpr_design.model import spec

    design = spec.load(path)
    return spec.with_cable_model(design, cable_model.value) if cable_model is not None else design


def parse_numbers(text: str, option: str, count: int | None = None, what: str = "numbers",
                  limit: float = 1e12) -> list[float]:
    """Comma-separated numbers of an option (``--at 0.75,0.75``), each finite and of magnitude at most
    ``limit``; bad text (an empty field too: ``0.75,,0.75`` is a typo, not two numbers) is exit 2."""
    fields = text.replace(" ", "").split(",")
    if "" in fields:
        raise InputError(f"{option}: expected comma-separated numbers, got an empty field in {quote(text)}")
    try:
        vals = [float(v) for v in fields]
    except ValueError:
        raise InputError(f"{option}: expected comma-separated numbers, got {quote(text)}") from None
    if not all(math.isfinite(v) and abs(v) <= limit for v in vals):
        raise InputError(f"{option}: expected finite numbers of magnitude at most {limit:g}, got {quote(text)}")
    if count is not None and len(vals) != count:
        raise InputError(f"{option}: expected {count} {what}, got {len(vals)}")
    return vals


def parse_pose(design, text: str, option: str = "--at") -> list[float]:
    """The pose coordinates [m, rad] of an option, one per motion coordinate."""
    from cdpr_design.model.limits import LENGTH

    coords = design.motion.coords
    return parse_numbers(text, option, len(coords),
                         f"numbers ({','.join(coords)}) for motion {design.motion.name}", limit=LENGTH)


def emit_json(data) -> None:
    """``data`` as one line of JSON on stdout (NaN and infinities as ``null``: always valid JSON)."""
    from cdpr_design.io.tables import json_text

    sys.stdout.write(json_text(data) + "\n")
    sys.stdout.flush()


def show_progress(quiet: bool) -> bool:
    return not quiet and err.is_terminal


#: A stage that has shown nothing for this long shows its description with a moving bar [s].
SILENT_S = 1.5


@contextmanager
def progress_bar(description: str, quiet: bool, min_total: int = 0):
    """Yields a ``progress(done, total)`` callback drawing a rich bar on stderr.

    Off when stderr is not a terminal or with ``--quiet``.  Work smaller than
    ``min_total`` items (that finishes in well under a second) gets no bar
    of its own; a stage still running after :data:`SILENT_S` seconds without
    one (a small sweep that turned out slow, numba compiling the kernels on a
    machine's first run) shows its description with a moving bar, so the
    terminal never looks stuck.
    """
    if not show_progress(quiet):
        yield None
        return
    import threading

    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                  TimeRemainingColumn(), console=_rich_console(err), transient=True) as prog:
        task = None
        lock = threading.Lock()

        def shown(total=None):
            nonlocal task
            with lock:
                if task is None:
                    task = prog.add_task(description, total=total)
                return task

        timer = threading.Timer(SILENT_S, shown)
        timer.daemon = True
        timer.start()

        def cb(done, total):
            if total < min_total:
                return
            prog.update(shown(total), total=total, completed=done)

        try:
            yield cb
        finally:
            timer.cancel()


def bars(quiet: bool, min_total: int = 0):
    """The ``progress`` of a job (:mod:`cdpr_design.jobs.common`): a :func:`progress_bar` per stage."""
    return lambda description: progress_bar(description, quiet, min_total)


def info(quiet: bool, msg: str) -> None:
    """A message on stderr unless ``quiet`` (plain text: no markup)."""
    if not quiet:
        err.print(msg, soft_wrap=True)


def fmt(v, digits=4):
    """A table cell: floats with ``digits`` significant digits, None and non-finite as a dash."""
    if v is None:
        return "—"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "—"
        return f"{v + 0.0:.{digits}g}"  # + 0.0: no "-0" on screen either
    return str(v)


def summary_table(title: str, rows: list[tuple[str, object]]) -> Table:
    """A two-column table of (name, value) rows."""
    t = table(title, show_header=False)
    t.add_column("", style="bold")
    t.add_column("")
    for k, v in rows:
        t.add_row(k, fmt(v))  # the consoles print without markup: values and paths as they are
    return t


def timings_row(timings: dict) -> tuple[str, str]:
    """(``load/sweep/write/pictures/total [s]``, ``0.9/0.42/0.08/0.61/1.9``): a summary's
    ``timings`` as a row of :func:`summary_table` (``load`` only where measured)."""
    phases = timing_phases(timings)
    return ("/".join(k for k, _ in phases) + " [s]", "/".join(f"{v:.3g}" for _, v in phases))
