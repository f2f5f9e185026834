"""``optimize``: design search over keys of the spec, one or more objectives, resumable."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Optional

import typer

from cdpr_design.cli.common import (CatalogueOpt, Format, FormatOpt, JsonOpt, MotorOpt, OutOpt, OverwriteOpt,
                                    QuietOpt, SafetyOpt, SpecArg, StepOpt, TrajectoryOpt, bars, command,
                                    emit_json, fmt, info, load_design, out_console, summary_table, table)
from cdpr_design.errors import CheckFailed
from cdpr_design.model.limits import MAX_TRIALS, MAX_WORKERS, SEED_LIMIT

if TYPE_CHECKING:
    from rich.table import Table

_FIGURES = ("task_min_margin, min_margin_figure, task_fraction, task_feasible, fraction, measure, feasible, "
            "min_margin, max_margin, max_tension, peak_tension, peak_tension_<cable>, peak_cable_speed, "
            "peak_motor_torque, rms_motor_torque, peak_motor_speed, torque_margin, speed_margin, "
            "implied_tension_max, task_min_stiffness, task_lowest_frequency, boundary_measure, max_frame_load")


def best_table(run) -> Table:
    """The best trial (one objective) or the Pareto front (several, knee first)."""
    pb = run.problem
    several = len(pb.objectives) > 1
    t = table("Pareto front (★ best.yaml: the knee)" if several else "best trial")
    cols = ["trial"] + pb.space.keys + [o.figure for o in pb.objectives]
    for c in cols:
        t.add_column(c)
    rows = run.pareto if several else [run.best]
    for r in sorted(rows, key=lambda r: r is not run.best)[:15]:
        mark = " ★" if several and r is run.best else ""
        t.add_row(f"{r.number}{mark}", *[fmt(r.params[k]) for k in pb.space.keys], *[fmt(v) for v in r.values])
    return t


def render(design, run) -> None:
    """The search's summary, best trial or front, and a few failures, on the terminal."""
    s, st = run.summary, run.stats
    objectives = ", ".join(f"{o.direction} {o.figure}" for o in run.problem.objectives)
    out_console.print(summary_table(
        f"{design.name} — optimize {', '.join(run.problem.space.keys)}",
        [("objectives", objectives), ("limits", ", ".join(run.problem.constraint_names) or "none"),
         ("evaluates", s["evaluates"]),
         ("trials", f"{s['trials_done']} of {s['trials_requested']} ({s['complete']} complete, "
                    f"{s['infeasible']} infeasible, {s['failed']} failed)"),
         ("evaluated now", f"{st.evaluated} in {st.workers} worker(s)" +
          (f", {st.resumed} resumed" if st.resumed else "")),
         ("elapsed [s]", st.elapsed_s), ("trials/s", s["trials_per_s"]), ("files", str(run.out.path))]))
    if run.best is not None:
        out_console.print(best_table(run))
    for r in [r for r in run.trials if r.state == "failed"][:3]:
        info(False, f"trial {r.number} failed: {r.reason}")


@command
def optimize(
    spec: SpecArg,
    vary: Annotated[Optional[list[str]], typer.Option(
        "--vary", metavar="KEY=LO:HI|KEY=a,b,c",
        help="A key of the spec by dotted path (as for sweep) and its range: LO:HI continuous (integers where "
             "the key is an integer), LO:HI:log on a log scale, a,b,c a choice (e.g. catalogue motors). "
             "Repeat for more keys.")] = None,
    maximize: Annotated[Optional[list[str]], typer.Option(
        "--maximize", metavar="FIGURE", help=f"A figure to maximise (repeatable). Figures: {_FIGURES}.")] = None,
    minimize: Annotated[Optional[list[str]], typer.Option(
        "--minimize", metavar="FIGURE", help="A figure to minimise (repeatable). Maximised objectives come "
                                             "first, then minimised ones.")] = None,
    require: Annotated[Optional[list[str]], typer.Option(
        "--require", metavar="FIGURE>=X|FIGURE<=X",
        help="A limit besides the spec's requirements (repeatable); trials breaking one are infeasible.")] = None,
    trials: Annotated[int, typer.Option("--trials", help="Trials in the study (with --resume: the total).",
                                        min=1, max=MAX_TRIALS)] = 100,
    workers: Annotated[Optional[int], typer.Option(
        "--workers", help="Processes evaluating trials on the shared study (default 1: this process).",
        min=1, max=MAX_WORKERS)] = None,
    seed: Annotated[Optional[int], typer.Option(
        "--seed", help="Sampler seed: with one worker the run is repeatable.", min=0, max=SEED_LIMIT - 1)] = None,
    timeout: Annotated[Optional[float], typer.Option(
        "--timeout", metavar="SEC", help="Start no trial after SEC seconds (--resume continues).",
        min=0.0, max=1e9)] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue the study in --out (interrupted trials are evaluated again).")] = False,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    no_picture: Annotated[bool, typer.Option("--no-picture", help="Do not draw optimize.png.")] = False,
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Design search (optuna): optimize.csv, best.yaml, pareto.csv (several objectives), optimize.png.

    Exit 1 when no trial satisfies every requirement (no best design)."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import optimize as job

    design = load_design(spec)
    settings = job.OptimizeSettings(vary, maximize, minimize, require, trials, workers, seed, timeout, resume,
                                    catalogue, trajectory, safety_factor, motor, step, not no_picture, out,
                                    overwrite, env.engine(), format.value)
    run = job.optimize(design, settings, progress=bars(quiet or json_), log=lambda msg: info(quiet or json_, msg))
    if json_:
        emit_json(run.summary)
    else:
        render(design, run)
    if run.best is None:
        raise CheckFailed("" if json_ else f"no trial of {len(run.trials)} satisfies every requirement "
                                           "(see the reasons in optimize.csv)")


def register(app: typer.Typer) -> None:
    app.command()(optimize)
