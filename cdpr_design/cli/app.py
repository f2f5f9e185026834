"""The ``cdpr-design`` command line (Typer). Options, printing and exit codes; no math.

Exit status (cli.md): 0 done; 1 the design fails a check it was asked to
pass; 2 bad input (spec, option, file); 130 interrupted.  Only this module
turns exceptions into exit codes.  ``--json`` prints one JSON object on
stdout; progress and messages go to stderr.
"""

from __future__ import annotations

import functools
import json
import math
import sys
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from rich.table import Table

from cdpr_design.errors import CheckFailed, InputError, SpecError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Workspace, sizing and simulation explorer for cable-driven parallel robots.",
    context_settings={"help_option_names": ["-h", "--help"]},
)

err = Console(stderr=True, highlight=False)
out_console = Console(highlight=False)

# ----------------------------------------------------------------------------
# Shared options and helpers (every command uses these)
# ----------------------------------------------------------------------------

SpecArg = Annotated[Path, typer.Argument(help="Design spec (YAML).", show_default=False)]
OutOpt = Annotated[Optional[Path], typer.Option("--out", help="Output folder (default out/<design name>/).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout and nothing else there.")]
QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bars or messages on stderr.")]
OverwriteOpt = Annotated[bool, typer.Option(
    "--overwrite", help="Replace files in --out that cdpr-design did not write.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Allow grids larger than the sane-size limit.")]


class Kind(str, Enum):
    static = "static"
    wrench_feasible = "wrench-feasible"
    wrench_closure = "wrench-closure"


KindOpt = Annotated[Kind, typer.Option("--kind", help="static | wrench-feasible | wrench-closure.")]


class Objective(str, Enum):
    min_norm = "min-norm"
    min_max = "min-max"
    min_sum = "min-sum"


ObjectiveOpt = Annotated[Objective, typer.Option(
    "--objective", help="Tension objective: min-norm (2-norm, exact kernel), min-max (inf-norm) "
                        "or min-sum (1-norm), both with cvxpy.")]
WeightsOpt = Annotated[Optional[str], typer.Option(
    "--weights", help="Per-cable weights of the objective, comma-separated positive numbers.")]


class Orientations(str, Enum):
    total = "total"
    range = "range"


def command(fn):
    """Turn the package's errors into exit codes and messages (no tracebacks for bad input)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except (SpecError, InputError) as exc:
            err.print(f"[bold red]error:[/] {exc}", markup=True, soft_wrap=True)
            raise typer.Exit(2) from None
        except CheckFailed as exc:
            if str(exc):
                err.print(f"[bold red]check failed:[/] {exc}", markup=True, soft_wrap=True)
            raise typer.Exit(1) from None
        except KeyboardInterrupt:
            err.print("interrupted")
            raise typer.Exit(130) from None

    return wrapper


def load_design(path: Path):
    from cdpr_design.model import spec

    return spec.load(path)


def output_dir(design, out: Path | None, overwrite: bool = False):
    from cdpr_design.jobs.report import OutputDir

    return OutputDir(out if out is not None else Path("out") / design.name, overwrite=overwrite)


def parse_numbers(text: str, option: str, count: int | None = None, what: str = "numbers") -> list[float]:
    """Comma-separated numbers of an option (``--at 0.75,0.75``); bad text is exit 2."""
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise InputError(f"{option}: expected comma-separated numbers, got {text!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"{option}: expected finite numbers, got {text!r}")
    if count is not None and len(vals) != count:
        raise InputError(f"{option}: expected {count} {what}, got {len(vals)}")
    return vals


def parse_pose(design, text: str, option: str = "--at") -> list[float]:
    coords = design.motion.coords
    return parse_numbers(text, option, len(coords),
                         f"numbers ({','.join(coords)}) for motion {design.motion.name}")


def emit_json(data) -> None:
    from cdpr_design.jobs.report import _json_default

    sys.stdout.write(json.dumps(data, default=_json_default) + "\n")
    sys.stdout.flush()


def show_progress(quiet: bool) -> bool:
    return not quiet and err.is_terminal


@contextmanager
def progress_bar(description: str, quiet: bool, min_total: int = 0):
    """Yields a ``progress(done, total)`` callback drawing a rich bar on stderr.

    Off when stderr is not a terminal, with ``--quiet``, or for work smaller
    than ``min_total`` items (that finishes in well under a second).
    """
    if not show_progress(quiet):
        yield None
        return
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                  TimeRemainingColumn(), console=err, transient=True) as prog:
        task = None

        def cb(done, total):
            nonlocal task
            if total < min_total:
                return
            if task is None:
                task = prog.add_task(description, total=total)
            prog.update(task, completed=done)

        yield cb


def info(quiet: bool, msg: str) -> None:
    if not quiet:
        err.print(msg, soft_wrap=True)


def _fmt(v, digits=4):
    if v is None:
        return "—"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "—"
        return f"{v:.{digits}g}"
    return str(v)


def summary_table(title: str, rows: list[tuple[str, object]]) -> Table:
    t = Table(title=title, show_header=False, title_justify="left")
    t.add_column("", style="bold")
    t.add_column("")
    for k, v in rows:
        t.add_row(k, _fmt(v))
    return t


# ----------------------------------------------------------------------------
# workspace
# ----------------------------------------------------------------------------


def run_workspace(design, out_dir, kind: str, step, force: bool, quiet: bool,
                  collisions: bool = False, orientations: str | None = None, pictures=None):
    """Sweep, stream ``workspace.csv``, write pictures and ``summary.json``; return the result.

    ``collisions``: intersect feasibility with the interference checks (column
    ``collision_free``); ``orientations``: ``total`` or ``range`` orientation
    workspace (rotational motions; extra columns, ``orientation_workspace.png``).
    """
    from cdpr_design.jobs import report
    from cdpr_design import workspaces as ws

    grid = ws.make_grid(design, step, force)
    header = report.workspace_header(design) + ws.extra_columns(design, collisions, orientations)
    csv_file = out_dir.stream("workspace.csv")
    try:
        csv_file.write(",".join(header) + "\n")

        def on_chunk(chunk):
            csv_file.write(report.workspace_rows(chunk, extra=ws.chunk_extra(chunk)))

        with progress_bar(f"workspace {design.name}", quiet, min_total=500_000) as cb:
            if orientations:
                result = ws.run_orientations(design, orientations, kind=kind, grid=grid, on_chunk=on_chunk,
                                             progress=cb, force=True, interference=collisions)
            else:
                result = ws.run(design, kind=kind, grid=grid, on_chunk=on_chunk, progress=cb, force=True,
                                interference=collisions)
        csv_file.commit()
    except BaseException:
        csv_file.abort()
        raise
    out_dir.write_json("summary.json", result.summary())
    report.save_workspace_pictures(out_dir, result, pictures)
    if getattr(result, "orientation_maps", None) is not None:
        report.save_orientation_picture(out_dir, result)
    return result


@app.command()
@command
def workspace(
    spec: SpecArg,
    kind: KindOpt = Kind.static,
    step: Annotated[Optional[float], typer.Option("--step", help="Grid step [m] (overrides workspace.grid.step).")] = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    force: ForceOpt = False,
    overwrite: OverwriteOpt = False,
    collisions: Annotated[bool, typer.Option(
        "--collisions", help="Also check cable-cable, cable-effector and effector-frame interference; "
                             "feasible = statics feasible and collision free (column collision_free).")] = False,
    orientations: Annotated[Optional[Orientations], typer.Option(
        "--orientations", help="total: feasible for every orientation of workspace.orientation_set; "
                               "range: largest feasible orientation range per position "
                               "(workspace.orientation_range). 1R2T and 3R3T.")] = None,
):
    """Grid sweep of the workspace: workspace.csv, workspace.png, tension_map.png, summary.json."""
    from cdpr_design.plots import worker as _picture_worker

    with _picture_worker.take() as pictures:  # matplotlib's import overlaps the spec and the sweep
        design = load_design(spec)
        out_dir = output_dir(design, out, overwrite)
        result = run_workspace(design, out_dir, kind.value, step, force, quiet or json_, collisions,
                               orientations.value if orientations is not None else None, pictures)
    s = result.summary()
    if json_:
        emit_json(s)
        return
    unit = "m²" if design.motion.planar else "m³"
    out_console.print(summary_table(
        f"{design.name} — {s['kind']} workspace",
        [("poses", f"{s['poses']:,}"), ("feasible", f"{s['feasible']:,}"),
         ("fraction", f"{100 * s['fraction']:.2f} %"), ("measure", f"{s['measure']:.4g} {unit}"),
         ("min margin \\[N]", s["min_margin"]), ("max margin \\[N]", s["max_margin"]),
         ("max tension \\[N]", s["max_tension"]), ("elapsed \\[s]", s["elapsed_s"])]
        + ([("collision free", f"{s['collision_free']:,}"),
            ("feasible before interference", f"{s['feasible_statics']:,}")] if "collision_free" in s else [])
        + ([("orientations", f"{s['orientation_mode']} ({s['orientation_count']} samples)")]
           if "orientation_mode" in s else [])
        + [("files", str(out_dir.path))]))


# ----------------------------------------------------------------------------
# pose and fk
# ----------------------------------------------------------------------------


def pose_data(design, result) -> dict:
    """The ``pose --json`` object (cli.md keys)."""
    import numpy as np

    names = design.cable_names
    return {
        "pose": [float(v) for v in result.pose],
        "lengths": {c: float(v) for c, v in zip(names, result.lengths)},
        "tensions": {c: (float(v) if np.isfinite(v) else None) for c, v in zip(names, result.tensions)},
        "feasible": bool(result.feasible),
        "margin": float(result.margin) if np.isfinite(result.margin) else None,
        "structure_matrix": [[float(x) for x in row] for row in result.W],
        "collisions": [list(p) for p in getattr(result, "collisions", [])],
    }


def _reobjective(design, result, objective: str, weights):
    """Tensions of a pose result for another objective or weights (tension.py)."""
    import numpy as np

    from cdpr_design.statics import tension as T

    if not np.all(np.isfinite(result.tensions)):
        return result
    tmin, tmax = design.tension_min, design.tension_max
    if objective == "min-norm":
        t = T.min_norm(result.W, result.wrench, tmin, tmax, weights=weights)
    else:
        t = T.solve_cvxpy(result.W, result.wrench, tmin, tmax, objective, weights)
    result.tensions = np.full(design.m, np.nan) if t is None else t
    return result


@app.command()
@command
def pose(
    spec: SpecArg,
    at: Annotated[str, typer.Option("--at", help="Pose coordinates, comma-separated (e.g. 0.75,0.75).")],
    kind: KindOpt = Kind.static,
    objective: ObjectiveOpt = Objective.min_norm,
    weights: WeightsOpt = None,
    json_: JsonOpt = False,
):
    """One pose: cable lengths, tensions, feasibility, margin, structure matrix."""
    from cdpr_design import workspaces as ws

    design = load_design(spec)
    p = parse_pose(design, at)
    c = None
    if weights is not None:
        c = parse_numbers(weights, "--weights", design.m, "weights (one per cable)")
        if any(v <= 0 for v in c):
            raise InputError(f"--weights: expected positive numbers, got {weights!r}")
    from cdpr_design.statics import pose as sp

    result = sp.evaluate_pose(design, p, kind.value)
    if objective is not Objective.min_norm or c is not None:
        result = _reobjective(design, result, objective.value, c)
    data = pose_data(design, result)
    data["objective"] = objective.value
    if json_:
        emit_json(data)
        return
    t = Table(title=f"{design.name} at ({at}) — {'feasible' if data['feasible'] else 'infeasible'}, "
                    f"margin {_fmt(data['margin'])} N", title_justify="left")
    for col in ("cable", "length [m]", "tension [N]", "bounds [N]"):
        t.add_column(col)
    for c in design.cables:
        t.add_row(c.name, _fmt(data["lengths"][c.name], 6), _fmt(data["tensions"][c.name], 6),
                  f"{c.tension_min:g} – {c.tension_max:g}")
    out_console.print(t)
    if data["collisions"]:
        out_console.print("collisions: " + ", ".join(" – ".join(p) for p in data["collisions"]))


@app.command()
@command
def fk(
    spec: SpecArg,
    lengths: Annotated[str, typer.Option("--lengths", help="Cable lengths [m], comma-separated, in cable order.")],
    guess: Annotated[Optional[str], typer.Option("--guess", help="Starting pose for the numerical solver.")] = None,
    json_: JsonOpt = False,
):
    """Forward kinematics: the pose for given cable lengths."""
    from cdpr_design.statics import kinematics as kin

    design = load_design(spec)
    L = parse_numbers(lengths, "--lengths", design.m, "cable lengths (one per cable)")
    if any(v < 0 for v in L):
        raise InputError("--lengths: cable lengths must be non-negative")
    g = parse_pose(design, guess, "--guess") if guess is not None else None
    res = kin.forward_kinematics(design, L, guess=g)
    data = {"pose": [float(v) for v in res.pose], "residual": float(res.residual), "method": res.method}
    if json_:
        emit_json(data)
        return
    out_console.print(summary_table(
        f"{design.name} — forward kinematics ({res.method})",
        [(c, float(v)) for c, v in zip(design.motion.coords, res.pose)] + [("residual \\[m]", res.residual)]))


# ----------------------------------------------------------------------------
# schema
# ----------------------------------------------------------------------------


@app.command()
@command
def schema():
    """Print the JSON Schema of the spec format (for editors' YAML validation)."""
    from cdpr_design.model import spec as spec_mod

    sys.stdout.write(spec_mod.schema_text() + "\n")


def main() -> None:
    """Console-script entry point (``cdpr_design.__main__.main`` starts the picture worker earlier)."""
    from cdpr_design.plots import worker as _picture_worker

    if _picture_worker.wanted(sys.argv[1:]):
        _picture_worker.prestart()
    try:
        app()
    except KeyboardInterrupt:
        err.print("interrupted")
        sys.exit(130)
    finally:
        _picture_worker.discard()


# ----------------------------------------------------------------------------
# size-motors, report, check
# ----------------------------------------------------------------------------

CatalogueOpt = Annotated[Optional[Path], typer.Option(
    "--catalogue", help="Motor catalogue YAML extending the shipped one (same format as cdpr_design/data/motors.yaml).")]
TrajectoryOpt = Annotated[Optional[str], typer.Option(
    "--trajectory", help="Name of a spec trajectory whose duty cycle gives the RMS torque (default: a standard cycle).")]
SafetyOpt = Annotated[Optional[float], typer.Option(
    "--safety-factor", help="Factor >= 1 on required torque and speed (default requirements.safety_factor or 1).")]
MotorOpt = Annotated[Optional[str], typer.Option(
    "--motor", help="Evaluate this catalogue motor on every axis instead of the spec's or the smallest that fits.")]
StepOpt = Annotated[Optional[float], typer.Option("--step", help="Grid step [m] (overrides workspace.grid.step).")]


def load_catalogue_opt(path: Path | None):
    from cdpr_design.model import spec

    return spec.load_catalogue(path)


def trajectory_samples(design, name: str | None):
    """Sample the spec trajectory ``name`` (None: no trajectory); bad names are exit 2."""
    if name is None:
        return None
    import numpy as np

    from cdpr_design.motion import trajectory as tr

    traj = design.trajectories.get(name)
    if traj is None:
        known = ", ".join(design.trajectories) or "none"
        raise InputError(f"--trajectory: no trajectory named {name!r} in the spec (known: {known})")
    poses = None
    if traj.type == "csv":
        p = Path(traj.file)
        if not p.is_absolute() and design.source:
            p = Path(design.source).resolve().parent / p
        try:
            try:
                poses = np.loadtxt(p, delimiter=",", ndmin=2)
            except ValueError:
                poses = np.loadtxt(p, delimiter=",", ndmin=2, skiprows=1)
        except (OSError, ValueError) as exc:
            raise InputError(f"trajectories.{name}.file: cannot read poses from {p}: {exc}") from None
    try:
        return tr.sample(design, name, csv_poses=poses)
    except (KeyError, ValueError) as exc:
        raise InputError(f"trajectories.{name}: {exc}") from None


def sizing_table(design, result) -> Table:
    t = Table(title=f"{design.name} — motor sizing ({result.envelope.poses:,} {result.envelope.source} poses, "
                    f"safety factor {result.safety_factor:g})", title_justify="left")
    cols = [("cable", "cable"), ("T \\[N]", "peak_tension"), ("τ pk", "peak_motor_torque"),
            ("τ rms", "rms_motor_torque"), ("rpm", "peak_motor_speed"),
            ("motor", "motor"), ("τ mrg", "torque_margin"), ("n mrg", "speed_margin"),
            ("T lim \\[N]", "implied_tension_max")]
    for head, key in cols:
        t.add_column(head, no_wrap=key in ("motor", "cable"))
    for row in result.rows():
        cells = []
        for _, key in cols:
            v = row[key]
            cells.append((v or "none fits") if key == "motor" else _fmt(v, 3))
        t.add_row(*cells)
    r0 = result.axes[0] if result.axes else None
    if r0 is not None:
        t.caption = (f"drum radius {r0.drum_radius:g} m, gear ratio {r0.gear_ratio:g} (cable {r0.cable}); "
                     "T: peak tension; τ [N m] at the motor; margins ≥ 1 pass; T lim = τ_peak i η / r")
    return t


@app.command("size-motors")
@command
def size_motors(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Motor, gearbox and drum sizing over the task workspace: motor_sizing.csv."""
    from cdpr_design.jobs import report
    from cdpr_design.design import sizing as sz

    design = load_design(spec)
    cat = load_catalogue_opt(catalogue)
    samples = trajectory_samples(design, trajectory)
    out_dir = output_dir(design, out, overwrite)
    result = sz.size_motors(design, cat, step=step, samples=samples, safety_factor=safety_factor, motor=motor)
    report.write_motor_sizing(out_dir, result)
    if json_:
        emit_json(result.summary())
        return
    out_console.print(sizing_table(design, result))
    info(quiet, f"duty cycle: {result.cycle}")
    for note in result.notes:
        info(quiet, f"note: {note}")
    info(quiet, f"wrote {out_dir.path / 'motor_sizing.csv'}")


def _evaluate(design, step, catalogue, trajectory, safety_factor, motor, quiet, workspace_result=None):
    from cdpr_design.design import evaluate as ev

    cat = load_catalogue_opt(catalogue)
    samples = trajectory_samples(design, trajectory)
    with progress_bar(f"evaluate {design.name}", quiet, min_total=500_000) as cb:
        return ev.evaluate_full(design, step=step, catalogue=cat, samples=samples,
                                safety_factor=safety_factor, motor=motor,
                                workspace_result=workspace_result, progress=cb)


def checks_table(design, rows: list[dict]) -> Table:
    t = Table(title=f"{design.name} — requirements", title_justify="left")
    for col in ("requirement", "figure", "limit", "result"):
        t.add_column(col)
    for r in rows:
        t.add_row(r["requirement"], r["figure"], r["limit"], "pass" if r["passed"] else "FAIL")
    return t


@app.command()
@command
def report(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    force: ForceOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Every artefact for one design (workspace, motor sizing) plus design_report.csv."""
    from cdpr_design.design import evaluate as ev
    from cdpr_design.jobs import report as rep

    from cdpr_design.plots import worker as _picture_worker

    with _picture_worker.take() as pictures:  # matplotlib's import overlaps the spec and the sweep
        design = load_design(spec)
        load_catalogue_opt(catalogue)  # bad catalogue: exit 2 before any work
        if trajectory is not None and trajectory not in design.trajectories:
            trajectory_samples(design, trajectory)  # unknown name: exit 2 before any work
        out_dir = output_dir(design, out, overwrite)
        wres = run_workspace(design, out_dir, "static", step, force, quiet or json_, pictures=pictures)
    e = _evaluate(design, step, catalogue, trajectory, safety_factor, motor, quiet or json_, wres)
    rep.write_motor_sizing(out_dir, e.sizing)
    rep.write_design_report(out_dir, e.row)
    checks = ev.check_table(e.row)
    out_dir.write_json("report.json", {"report": e.row, "checks": checks, "sizing": e.sizing.summary()})
    if json_:
        emit_json({**e.row, "checks": checks})
        return
    out_console.print(sizing_table(design, e.sizing))
    if checks:
        out_console.print(checks_table(design, checks))
    info(quiet, f"wrote workspace.csv, workspace.png, tension_map.png, summary.json, motor_sizing.csv, "
                f"design_report.csv, report.json to {out_dir.path}")


@app.command()
@command
def check(
    spec: SpecArg,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
):
    """Test the spec's requirements: one line per requirement; exit 0 all pass, 1 otherwise."""
    from cdpr_design.design import evaluate as ev

    design = load_design(spec)
    e = _evaluate(design, step, catalogue, trajectory, safety_factor, motor, quiet or json_)
    checks = ev.check_table(e.row)
    passed = e.passed
    if json_:
        emit_json({"name": design.name, "passed": passed, "checks": checks, "figures": e.row})
    else:
        if checks:
            out_console.print(checks_table(design, checks))
        else:
            out_console.print(f"{design.name}: the spec's requirements section asks for nothing to check")
    if not passed:
        failed = [c["requirement"] for c in checks if not c["passed"]]
        raise CheckFailed("" if json_ else f"{design.name}: {', '.join(failed)}")


# ----------------------------------------------------------------------------
# bridge (the paper's loop A: PLC <-> simulated robot over ADS)
# ----------------------------------------------------------------------------

#: Exit status of ``bridge`` when the PLC stops answering (the run's log is kept).
EXIT_PLC_LOST = 3


@app.command()
@command
def bridge(
    spec: SpecArg,
    test_plc: Annotated[Optional[str], typer.Option(
        "--test-plc", metavar="TRAJECTORY",
        help="Start a built-in test PLC on 127.0.0.1 that plays this spec trajectory as set-points.")] = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", help="Stop after this many seconds (default: the test trajectory + 0.5 s; "
        "else until Ctrl-C).")] = None,
    cycle_time: Annotated[Optional[float], typer.Option(
        "--cycle-time", help="Gateway cycle [s] (default plc.cycle_time).")] = None,
    timeout: Annotated[Optional[float], typer.Option(
        "--timeout", help="Timeout of each ADS request [s] (default max(5 cycles, 50 ms)).")] = None,
    reconnect: Annotated[int, typer.Option(
        "--reconnect", help="Reconnection attempts when the PLC stops answering, with back-off "
        "0.1 s doubling to 2 s (default 0: stop).")] = 0,
    local_net_id: Annotated[Optional[str], typer.Option(
        "--local-net-id", help="AMS net id of this computer (the route the PLC knows it by).")] = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Gateway PLC <-> simulated robot over ADS: bridge.csv (simulation.csv columns), bridge.json.

    Exit status: 0 done; 2 bad input (spec, option, a PLC symbol missing or
    mistyped: named); 3 the PLC cannot be reached or stopped answering (an
    addition to the common 0/1/2/130: the log written so far is kept);
    130 interrupted (Ctrl-C; the log is complete).
    """
    import signal

    from cdpr_design.plc import bridge as br
    from cdpr_design.plc.ads import AdsTransport
    from cdpr_design.plc.delay import axis_delays
    from cdpr_design.plc.rows import RowMaker, csv_header
    from cdpr_design.plc.symbols import PlcLayout
    from cdpr_design.plc.testplc import LOOPBACK, TEST_LOCAL_NET_ID, TEST_PLC_NET_ID, TestPlc
    from cdpr_design.plc.transport import PlcLinkError
    from cdpr_design.jobs.report import fmt

    design = load_design(spec)
    if design.plc is None:
        raise InputError(f"{spec}: plc: the spec has no plc: section (bridge needs its symbols)")
    dt = float(cycle_time if cycle_time is not None else design.plc.cycle_time)
    if not (math.isfinite(dt) and 1e-4 <= dt <= 10):
        raise InputError(f"--cycle-time: expected 0.0001 to 10 s, got {dt}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise InputError(f"--duration: expected a positive number of seconds, got {duration}")
    if reconnect < 0:
        raise InputError(f"--reconnect: expected a count >= 0, got {reconnect}")
    tmo = float(timeout) if timeout is not None else max(5 * dt, 0.05)
    if not (math.isfinite(tmo) and tmo > 0):
        raise InputError(f"--timeout: expected a positive number of seconds, got {timeout}")
    layout = PlcLayout.from_design(design)
    loud = not quiet  # link status (lost, reconnecting) goes to stderr unless --quiet
    quiet = quiet or json_
    plc = None
    if test_plc is not None:
        if test_plc not in design.trajectories:
            known = ", ".join(design.trajectories) or "none"
            raise InputError(f"--test-plc: no trajectory named {test_plc!r} in the spec (known: {known})")
        samples = trajectory_samples(design, test_plc)
        if duration is None:
            duration = samples.duration + 0.5
        host, net_id, port = LOOPBACK, TEST_PLC_NET_ID, design.plc.port
        local = local_net_id or TEST_LOCAL_NET_ID
    else:
        host = design.plc.host or ".".join(design.plc.ams_net_id.split(".")[:4])
        net_id, port, local = design.plc.ams_net_id, design.plc.port, local_net_id
    out_dir = output_dir(design, out, overwrite)
    out_dir.target("bridge.csv")
    out_dir.target("bridge.json")

    stop = {"flag": False}

    def on_sigint(signum, frame):
        if stop["flag"]:
            raise KeyboardInterrupt
        stop["flag"] = True

    old_handler = signal.signal(signal.SIGINT, on_sigint)
    transport = AdsTransport(layout, net_id, port, host, timeout=tmo, local_net_id=local)
    log = None
    res = None
    plc_log = None
    try:
        if test_plc is not None:
            info(quiet, f"test PLC on {LOOPBACK} playing {test_plc!r} ({samples.duration:.3g} s)")
            try:
                plc = TestPlc(layout, samples.time, samples.lengths,
                              task_cycle=max(samples.cycle_time, 1e-3)).start()
            except PlcLinkError as exc:
                err.print(f"[bold red]error:[/] {exc}", markup=True, soft_wrap=True)
                raise typer.Exit(EXIT_PLC_LOST) from None
        wait = 0.1
        for attempt in range(reconnect + 1):
            try:
                transport.connect()
                break
            except PlcLinkError as exc:
                if attempt == reconnect or stop["flag"]:
                    err.print(f"[bold red]error:[/] {exc}", markup=True, soft_wrap=True)
                    raise typer.Exit(EXIT_PLC_LOST) from None
                info(quiet, f"{exc}; retrying in {wait:.2g} s")
                import time as _time

                _time.sleep(wait)
                wait = min(2 * wait, 2.0)
        try:
            sp0 = transport.read_setpoints()
        except PlcLinkError as exc:
            err.print(f"[bold red]error:[/] {exc}", markup=True, soft_wrap=True)
            raise typer.Exit(EXIT_PLC_LOST) from None
        sim = br.make_simulator(design, dt, sp0)
        rows = RowMaker(design)
        log = out_dir.stream("bridge.csv")
        log.write(",".join(csv_header(design)) + "\n")
        last_flush = [0.0]

        def on_row(sp, state):
            log.write(",".join(fmt(v) for v in rows.values(sp, state)) + "\n")
            now = state.time
            if now - last_flush[0] >= 0.1:
                log.flush()
                last_flush[0] = now

        info(quiet, f"bridge running: {net_id}:{port} at {host}, cycle {dt * 1e3:.3g} ms"
             + (f", {duration:.3g} s" if duration else ", Ctrl-C to stop"))
        res = br.run(transport, sim, cycle_time=dt, duration=duration, on_row=on_row,
                     should_stop=lambda: stop["flag"], reconnect=reconnect,
                     on_status=lambda msg: info(not loud, msg))
        if stop["flag"] and res.stopped == "stop":
            res.stopped = "interrupted"
    except KeyboardInterrupt:
        if res is None:
            raise
    finally:
        signal.signal(signal.SIGINT, old_handler)
        transport.close()
        if log is not None:
            log.commit()  # every row is whole: what was logged is kept, also on failure
        if plc is not None:
            if res is not None:
                plc_log = plc.log()
            plc.stop()
    summary = res.summary()
    summary["delay"] = res.delay(design.cable_names)  # set-point read -> motion written (PLC view)
    summary["delay_model"] = rows.delay()  # bridge.csv: model time (what compare reports)
    if plc_log is not None and plc_log.shape[0] > 8:
        m = design.m
        summary["plc_delay"] = axis_delays(design.cable_names, plc_log[:, 0],
                                           plc_log[:, 1: 1 + m], plc_log[:, 1 + m: 1 + 2 * m])
    summary["name"] = design.name
    summary["test_plc"] = test_plc
    out_dir.write_json("bridge.json", summary)
    if json_:
        emit_json(summary)
    else:
        lat = summary["latency"]
        out_console.print(summary_table(
            f"{design.name} — bridge ({summary['stopped']})",
            [("cycles", summary["cycles"]), ("overruns", summary["overruns"]),
             ("cycle time \\[ms]", dt * 1e3),
             ("round trip mean / p99 / max \\[ms]",
              " / ".join(_fmt(None if v is None else v * 1e3) for v in
                         (lat["mean"], lat["p99"], lat["max"]))),
             ("delay \\[ms]", ", ".join(f"{k}: {_fmt(None if v is None else v * 1e3)}"
                                      for k, v in summary["delay"].items())),
             ("files", str(out_dir.path))]))
    if res.stopped == "interrupted":
        err.print("interrupted")
        raise typer.Exit(130)
    if res.stopped == "plc_lost":
        err.print(f"[bold red]error:[/] PLC lost: {res.error}", markup=True, soft_wrap=True)
        raise typer.Exit(EXIT_PLC_LOST)


# ----------------------------------------------------------------------------
# trajectory, simulate, compare (the paper's Tables 1 and 2)
# ----------------------------------------------------------------------------

CycleOpt = Annotated[Optional[float], typer.Option(
    "--cycle-time", help="Sample period [s] (default: the trajectory's cycle_time, else 0.001).")]


def _sample_named(design, name: str, cycle_time: float | None, hold_end: float = 0.0):
    """Sample spec trajectory ``name`` (reading a csv path's poses); bad names/files are exit 2."""
    from cdpr_design.jobs import report
    from cdpr_design.motion import trajectory as tr

    traj = design.trajectories.get(name)
    if traj is None:
        known = ", ".join(design.trajectories) or "none"
        raise InputError(f"NAME: no trajectory named {name!r} in the spec (known: {known})")
    if cycle_time is not None and not (math.isfinite(cycle_time) and 1e-5 <= cycle_time <= 1.0):
        raise InputError(f"--cycle-time: expected 1e-5 to 1 s, got {cycle_time}")
    poses = None
    if traj.type == "csv":
        p = Path(traj.file)
        if not p.is_absolute() and design.source:
            p = Path(design.source).resolve().parent / p
        poses = report.read_poses(p, design, f"trajectories.{name}.file")
    try:
        return tr.sample(design, name, cycle_time, csv_poses=poses, hold_end=hold_end)
    except (KeyError, ValueError) as exc:
        raise InputError(f"trajectories.{name}: {exc}") from None


def _path_map(design):
    """A static workspace map for the path picture (planar designs; coarse enough to be quick)."""
    if not design.motion.planar:
        return None
    from cdpr_design import workspaces as ws

    g = design.workspace.grid
    ext = max(h - l for l, h in zip(g.lower, g.upper))
    step = max(max(g.step), ext / 200.0)
    try:
        return ws.run(design, kind="static", step=step)
    except Exception:  # noqa: BLE001 - the picture is drawn without the map
        return None


@app.command("trajectory")
@command
def trajectory_cmd(
    spec: SpecArg,
    name: Annotated[str, typer.Argument(help="Name of a path in the spec's trajectories: section.")],
    cycle_time: CycleOpt = None,
    check: Annotated[bool, typer.Option(
        "--check", help="Exit 1 when a sample's tensions leave the cable bounds.")] = False,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Sample a spec path at a fixed cycle: trajectory.csv, trajectory.png, trajectory_axes.png, trajectory.json."""
    from cdpr_design.jobs import report

    design = load_design(spec)
    samples = _sample_named(design, name, cycle_time)
    out_dir = output_dir(design, out, overwrite)
    report.write_columns(out_dir, "trajectory.csv", samples.columns())
    s = samples.summary()
    out_dir.write_json("trajectory.json", s)
    report.save_figures(out_dir, {
        "trajectory.png": report.trajectory_path_figure(design, samples, _path_map(design)),
        "trajectory_axes.png": report.trajectory_axes_figure(samples),
    })
    if json_:
        emit_json(s)
    else:
        out_console.print(summary_table(
            f"{design.name} — trajectory {name}",
            [("samples", f"{s['samples']:,}"), ("cycle time \\[ms]", 1e3 * s["cycle_time"]),
             ("duration \\[s]", s["duration"]), ("peak speed \\[m/s]", s["max_speed"]),
             ("peak acceleration \\[m/s²]", s["max_acceleration"]),
             ("tension range \\[N]", ", ".join(f"{c}: {_fmt(s['min_tension'][c])}–{_fmt(s['max_tension'][c])}"
                                             for c in samples.cable_names)),
             ("feasible", "yes" if s["feasible"] else f"no ({s['infeasible_samples']} samples)"),
             ("files", str(out_dir.path))]))
    if check and not s["feasible"]:
        raise CheckFailed(f"trajectory {name}: {s['infeasible_samples']} samples with tensions outside the bounds")


def segments_table(title: str, segments: list[dict]) -> Table:
    """The paper's Table 2 layout: mean target and mean actual position per straight segment."""
    t = Table(title=title, title_justify="left")
    for head in ("segment", "axis", "mean target \\[mm]", "mean actual \\[mm]", "error \\[mm]", "error \\[%]"):
        t.add_column(head, justify="right")
    for r in segments:
        t.add_row(str(r["segment"]), r["axis"], f"{1e3 * r['mean_target']:.3f}", f"{1e3 * r['mean_actual']:.3f}",
                  f"{1e3 * r['error']:+.3f}", f"{r['error_pct']:.3f}")
    return t


def delay_text(delay: dict) -> str:
    return ", ".join(f"{k}: {_fmt(None if v is None else 1e3 * v)}" for k, v in delay.items())


@app.command()
@command
def simulate(
    spec: SpecArg,
    name: Annotated[str, typer.Argument(help="Name of a path in the spec's trajectories: section.")],
    delay: Annotated[float, typer.Option(
        "--delay", help="Transport delay of the set-points [s] (the paper's ADS path: 0.11-0.15).")] = 0.0,
    servo_bandwidth: Annotated[float, typer.Option(
        "--servo-bandwidth", help="Position-loop bandwidth of each winch axis [rad/s].")] = 300.0,
    feedforward: Annotated[bool, typer.Option(
        "--feedforward/--no-feedforward", help="Velocity feed-forward in the axis position loop.")] = True,
    compensate_stretch: Annotated[bool, typer.Option(
        "--stretch-compensation/--no-stretch-compensation",
        help="Take up each cable's expected elastic stretch T/k in the command.")] = True,
    cable_damping: Annotated[float, typer.Option(
        "--cable-damping", help="Damping ratio of the axial cable mode.")] = 0.7,
    timestep: Annotated[float, typer.Option("--timestep", help="Physics step [s].")] = 5e-4,
    hold: Annotated[Optional[float], typer.Option(
        "--hold", help="Time [s] to keep the last set-point at the end (default 0.5 s + the delay).")] = None,
    cycle_time: CycleOpt = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Run a spec path on the MuJoCo model of the robot: simulation.csv, simulation.json, simulation.png."""
    from cdpr_design.jobs import report
    from cdpr_design.motion import simulation as sim

    design = load_design(spec)
    checks = [("--delay", delay, 0.0, 10.0), ("--servo-bandwidth", servo_bandwidth, 1e-3, 1e6),
              ("--cable-damping", cable_damping, 0.0, 100.0), ("--timestep", timestep, 1e-6, 0.01)]
    for opt, v, lo, hi in checks:
        if not (math.isfinite(v) and lo <= v <= hi) or (opt in ("--servo-bandwidth", "--timestep") and v <= 0):
            raise InputError(f"{opt}: expected a number in [{lo:g}, {hi:g}], got {v}")
    if hold is not None and not (math.isfinite(hold) and 0 <= hold <= 60):
        raise InputError(f"--hold: expected 0 to 60 s, got {hold}")
    samples = _sample_named(design, name, cycle_time, hold_end=(0.5 + delay) if hold is None else hold)
    if samples.cycle_time < timestep:
        raise InputError(f"--timestep: {timestep} s is longer than the cycle time {samples.cycle_time} s")
    out_dir = output_dir(design, out, overwrite)
    out_dir.target("simulation.csv")
    with progress_bar(f"simulate {name}", quiet or json_, min_total=2000) as cb:
        try:
            result = sim.simulate(design, samples, timestep=timestep, servo_bandwidth=servo_bandwidth,
                                  delay=delay, cable_damping=cable_damping, feedforward=feedforward,
                                  compensate_stretch=compensate_stretch, progress=cb)
        except sim.SimulationError as exc:
            raise InputError(f"--timestep / --servo-bandwidth / --cable-damping: {exc}") from None
    report.write_columns(out_dir, "simulation.csv", result.columns())
    s = result.summary()
    s["trajectory_feasible"] = samples.all_feasible
    out_dir.write_json("simulation.json", s)
    report.save_figures(out_dir, {"simulation.png": report.simulation_figure(result)})
    if json_:
        emit_json(s)
        return
    out_console.print(summary_table(
        f"{design.name} — simulation of {name} (delay {1e3 * delay:g} ms)",
        [("samples", f"{s['samples']:,}"), ("RMS position error \\[mm]", 1e3 * s["rms_error"]),
         ("max position error \\[mm]", 1e3 * s["max_error"]), ("delay \\[ms]", delay_text(s["delay"])),
         ("tension range \\[N]", ", ".join(f"{c}: {_fmt(s['min_tension'][c])}–{_fmt(s['max_tension'][c])}"
                                         for c in result.cable_names)),
         ("files", str(out_dir.path))]))
    if s["segments"]:
        out_console.print(segments_table("straight segments (the paper's Table 2)", s["segments"]))
    if not samples.all_feasible:
        info(quiet, "note: the trajectory's tensions leave the cable bounds somewhere (see trajectory --check)")


@app.command()
@command
def compare(
    target: Annotated[Path, typer.Argument(help="CSV log of the target run (set-points or a reference).")],
    actual: Annotated[Path, typer.Argument(help="CSV log of the actual run (simulation, prototype scope export).")],
    columns: Annotated[Optional[str], typer.Option(
        "--columns", help="Comma-separated columns to compare (default: every column in both).")] = None,
    rename: Annotated[Optional[list[str]], typer.Option(
        "--map", help="TARGET_COL=ACTUAL_COL: compare differently named columns (repeatable).")] = None,
    max_delay: Annotated[Optional[float], typer.Option(
        "--max-delay", help="Largest delay searched [s] (default: half the record).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Folder for comparison.json (default: nothing written).")] = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Compare two logs of the same motion: delay per column, position errors, per-segment table."""
    from cdpr_design.motion import compare as cmp
    from cdpr_design.jobs import report

    t_t, tgt = report.read_log(target, "TARGET")
    t_a, act = report.read_log(actual, "ACTUAL")
    for item in rename or []:
        if item.count("=") != 1 or not all(item.split("=")):
            raise InputError(f"--map: expected TARGET_COL=ACTUAL_COL, got {item!r}")
        a, b = item.split("=")
        if b not in act:
            raise InputError(f"--map: ACTUAL has no column {b!r}")
        act[a] = act.pop(b)
    if columns is not None:
        cols = [c.strip() for c in columns.split(",") if c.strip()]
        for c in cols:
            for what, d in (("TARGET", tgt), ("ACTUAL", act)):
                if c not in d:
                    raise InputError(f"--columns: {what} has no numeric column {c!r}")
    else:
        cols = [c for c in tgt if c in act and c not in ("segment", "feasible")]
        if not cols:
            raise InputError(f"TARGET and ACTUAL have no value column in common "
                             f"(TARGET: {', '.join(tgt)}; ACTUAL: {', '.join(act)}); use --map")
    if max_delay is not None and not (math.isfinite(max_delay) and max_delay > 0):
        raise InputError(f"--max-delay: expected a positive number of seconds, got {max_delay}")
    try:
        res = cmp.compare(t_t, tgt, t_a, act, columns=cols, max_delay=max_delay)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    s = res.to_json()
    s["target"], s["actual"] = str(target), str(actual)
    if out is not None:
        from cdpr_design.jobs.report import OutputDir

        OutputDir(out, overwrite=overwrite).write_json("comparison.json", s)
    if json_:
        emit_json(s)
        return
    t = Table(title=f"compare {target.name} → {actual.name}", title_justify="left")
    for head in ("column", "delay \\[ms]", "mean error", "RMS error", "max error"):
        t.add_column(head, justify="right")
    for c in cols:
        st = s["columns"][c]
        t.add_row(c, _fmt(None if s["delay"][c] is None else 1e3 * s["delay"][c]), _fmt(st["mean"]),
                  _fmt(st["rms"]), _fmt(st["max"]))
    out_console.print(t)
    pos = res.position_columns
    if pos:
        out_console.print(summary_table("position error (" + ",".join(pos) + ")",
                                        [("RMS \\[mm]", 1e3 * res.rms_error), ("max \\[mm]", 1e3 * res.max_error)]))
    if s["segments"]:
        out_console.print(segments_table("straight segments (the paper's Table 2)", s["segments"]))


# ----------------------------------------------------------------------------
# sweep (batch parameter sweeps)
# ----------------------------------------------------------------------------


@app.command()
@command
def sweep(
    spec: SpecArg,
    vary: Annotated[Optional[list[str]], typer.Option(
        "--vary", metavar="KEY=VALUES",
        help="A key of the spec by dotted path (effector.mass, frame.upper.0, cables.1.outlet.1, "
             "tension.1) and its values: a,b,c or start:stop:count. Repeat for a full grid. "
             "Given on the command line, these replace the spec's sweep.vary.")] = None,
    workers: Annotated[Optional[int], typer.Option(
        "--workers", help="Worker processes (default sweep.workers, else one per core; 1: in this process).")] = None,
    scheduler: Annotated[Optional[str], typer.Option(
        "--scheduler", metavar="ADDRESS",
        help="Run on the Dask scheduler at ADDRESS (tcp://host:8786); 'local' starts a LocalCluster "
             "of --workers processes on this machine.")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue an interrupted sweep from the journal in --out.")] = False,
    rank_by: Annotated[Optional[str], typer.Option(
        "--rank-by", metavar="FIGURE[:asc|:desc]",
        help="Figure that ranks the variants passing every requirement (default sweep.rank_by, else fraction).")] = None,
    check_against: Annotated[Optional[Path], typer.Option(
        "--check-against", metavar="BASELINE.csv",
        help="Compare with a baseline sweep.csv; exit 1 when a figure regresses.")] = None,
    tolerance: Annotated[float, typer.Option(
        "--tolerance", help="Relative tolerance of --check-against.")] = 1e-6,
    abs_tolerance: Annotated[float, typer.Option(
        "--abs-tolerance", help="Absolute tolerance of --check-against (added to the relative one).")] = 1e-9,
    strict: Annotated[bool, typer.Option(
        "--strict", help="With --check-against: improvements beyond the tolerance fail too.")] = False,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    top: Annotated[int, typer.Option("--top", help="Best variants to list.")] = 10,
    no_picture: Annotated[bool, typer.Option("--no-picture", help="Do not draw sweep.png.")] = False,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Batch parameter sweep: sweep.csv (one design_report.csv row per variant), sweep_best.csv, sweep.png."""
    from cdpr_design.jobs import report as rep
    from cdpr_design.batch import sweep as sw

    design = load_design(spec)
    section = design.sweep or {}
    axes = [sw.parse_vary(v) for v in vary] if vary else sw.vary_from_spec(section)
    plan = sw.make_plan(design, axes)
    rank_name, descending = sw.parse_rank(rank_by or section.get("rank_by"))
    if workers is None:
        workers = section.get("workers")
    if workers is not None and workers < 1:
        raise InputError(f"--workers: expected at least 1, got {workers}")
    if step is not None and not (math.isfinite(step) and step > 0):
        raise InputError(f"--step: expected a positive number of metres, got {step}")
    if not (math.isfinite(tolerance) and tolerance >= 0 and math.isfinite(abs_tolerance) and abs_tolerance >= 0):
        raise InputError("--tolerance / --abs-tolerance: expected non-negative numbers")
    if trajectory is not None:
        traj = design.trajectories.get(trajectory)
        if traj is None:
            known = ", ".join(design.trajectories) or "none"
            raise InputError(f"--trajectory: no trajectory named {trajectory!r} in the spec (known: {known})")
        if traj.type == "csv":
            raise InputError(f"--trajectory {trajectory}: a csv trajectory cannot be swept (its poses "
                             "do not follow the varied design); use a square, polyline or circle path")
    baseline = rep.read_csv_table(check_against) if check_against is not None else None
    cat = load_catalogue_opt(catalogue)
    options = sw.Options(step=step, safety_factor=safety_factor, motor=motor, trajectory=trajectory,
                         catalogue=cat)
    out_dir = output_dir(design, out, overwrite)
    for name in ("sweep.csv", "sweep_best.csv", "sweep.png"):
        out_dir.target(name)  # refuse foreign files before any work
    journal = rep.SweepJournal(out_dir)
    meta = {"journal": "cdpr-design sweep", "version": sw.JOURNAL_VERSION, "name": design.name,
            "keys": plan.keys, "variants": len(plan), "fingerprint": plan.fingerprint(options)}
    kept: list[dict] = []
    quiet = quiet or json_
    if resume:
        old_meta, old = journal.read()
        if old_meta is None:
            info(quiet, f"--resume: no journal in {out_dir.path}; starting the sweep")
        elif old_meta.get("fingerprint") != meta["fingerprint"]:
            raise InputError(f"--resume: the journal in {out_dir.path} is from another sweep (other spec, "
                             "keys, values or options); run without --resume to start over")
        else:
            kept = [r for r in old if 0 <= int(r["variant"]) < len(plan)]
            info(quiet, f"resuming: {len(kept)} of {len(plan)} variants already done")
    journal.start(meta, kept)
    done = {int(r["variant"]) for r in kept}
    try:
        with progress_bar(f"sweep {design.name}", quiet) as cb:
            stats = sw.run(plan, options, workers=workers, scheduler=scheduler, skip=done,
                           on_record=journal.append, progress=cb)
    finally:
        journal.close()
    _, records = journal.read()
    header, rows = sw.table(plan, records)
    bh, brows = sw.best(header, rows, rank_name, descending)
    rep.write_sweep(out_dir, header, rows, bh, brows, plan.keys,
                    title=f"{design.name}: sweep of {', '.join(plan.keys)}", rank_by=rank_name,
                    picture=not no_picture)
    regressions, improvements = [], []
    if baseline is not None:
        text_rows = [[rep.fmt(v) for v in r] for r in rows]
        regressions, improvements = sw.compare(header, text_rows, baseline[0], baseline[1], plan.keys,
                                               tolerance, abs_tolerance, strict)
    ie = header.index("error")
    failed = [r for r in rows if r[ie]]
    summary = {
        "name": design.name, "keys": plan.keys, "variants": len(plan), "evaluated": stats.evaluated,
        "resumed": stats.skipped, "errors": len(failed), "passed": len(brows),
        "rank_by": rank_name, "best": [dict(zip(bh, r)) for r in brows[:top]],
        "backend": stats.backend, "workers": stats.workers, "chunk": stats.chunk,
        "elapsed_s": stats.elapsed_s, "files": str(out_dir.path),
    }
    if baseline is not None:
        summary["baseline"] = str(check_against)
        summary["regressions"] = [d.as_dict() for d in regressions]
        summary["improvements"] = [d.as_dict() for d in improvements]
    if json_:
        emit_json(summary)
    else:
        out_console.print(summary_table(
            f"{design.name} — sweep of {', '.join(plan.keys)}",
            [("variants", f"{len(plan):,}"), ("evaluated now", f"{stats.evaluated:,}"),
             ("resumed from journal", f"{stats.skipped:,}"), ("failed to evaluate", f"{len(failed):,}"),
             ("pass every requirement", f"{len(brows):,}"),
             ("backend", f"{stats.backend}, {stats.workers} worker(s), {stats.chunk} variant(s) per task"),
             ("elapsed \\[s]", stats.elapsed_s), ("files", str(out_dir.path))]))
        if brows:
            t = Table(title=f"best variants by {rank_name} ({'descending' if descending else 'ascending'})",
                      title_justify="left")
            cols = ["rank", "variant"] + plan.keys + [rank_name]
            for c in cols:
                t.add_column(c)
            for r in brows[:top]:
                t.add_row(*[_fmt(r[bh.index(c)]) for c in cols])
            out_console.print(t)
        for r in failed[:5]:
            info(False, f"variant {r[0]}: {r[ie]}")
        if baseline is not None:
            if regressions:
                t = Table(title=f"regressions against {check_against}", title_justify="left")
                for c in ("variant", "figure", "baseline", "now", "change"):
                    t.add_column(c)
                for d in regressions[:30]:
                    t.add_row(str(d.variant), d.column, d.baseline, d.current, d.change)
                out_console.print(t)
            else:
                out_console.print(f"no regression against {check_against} "
                                  f"({len(improvements)} figure(s) better)")
    if regressions:
        raise CheckFailed("" if json_ else f"{len(regressions)} figure(s) regressed against {check_against}")
