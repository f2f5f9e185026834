"""``sweep``: batch parameter sweeps over variants of a design."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Optional

import typer

from cdpr_design.cli.common import (CatalogueOpt, Format, FormatOpt, JsonOpt, MotorOpt, OutOpt, OverwriteOpt,
                                    QuietOpt, SafetyOpt, SchedulerOpt, SpecArg, StepOpt, TrajectoryOpt, bars, command,
                                    emit_json, fmt, info, load_design, out_console, summary_table, table,
                                    timings_row)
from cdpr_design.batch.variants import HARD_MAX_VARIANTS, MAX_VARIANTS
from cdpr_design.errors import CheckFailed

if TYPE_CHECKING:
    from rich.table import Table


def best_table(run, top: int) -> Table:
    """The ``top`` variants passing every requirement, ranked."""
    t = table(f"best variants by {run.rank_by} ({'descending' if run.descending else 'ascending'})")
    cols = ["rank", "variant"] + run.plan.keys + [run.rank_by]
    for c in cols:
        t.add_column(c)
    for r in run.best_rows[:top]:
        t.add_row(*[fmt(r[run.best_header.index(c)]) for c in cols])
    return t


def regressions_table(run, baseline: Path) -> Table:
    """Up to 30 figures that regressed against the baseline."""
    t = table(f"regressions against {baseline}")
    for c in ("variant", "figure", "baseline", "now", "change"):
        t.add_column(c)
    for d in run.regressions[:30]:
        t.add_row(str(d.variant), d.column, d.baseline, d.current, d.change)
    return t


def render(design, run, top: int, check_against: Path | None) -> None:
    """The sweep's summary, best variants, failures and regressions on the terminal."""
    st, plan = run.stats, run.plan
    out_console.print(summary_table(
        f"{design.name} — sweep of {', '.join(plan.keys)}",
        [("variants", f"{len(plan):,}"), ("evaluated now", f"{st.evaluated:,}"),
         ("resumed from journal", f"{st.skipped:,}"), ("failed to evaluate", f"{len(run.failed):,}"),
         ("pass every requirement", f"{len(run.best_rows):,}"),
         ("backend", f"{st.backend}, {st.workers} worker(s), {st.chunk} variant(s) per task"),
         ("elapsed [s]", st.elapsed_s),
         timings_row(run.summary["timings"]),
         ("files", str(run.out.path))]))
    if run.best_rows:
        out_console.print(best_table(run, top))
    ie = run.header.index("error")
    for r in run.failed[:5]:
        info(False, f"variant {r[0]}: {r[ie]}")
    if check_against is not None:
        if run.regressions:
            out_console.print(regressions_table(run, check_against))
        else:
            out_console.print(f"no regression against {check_against} "
                              f"({len(run.improvements)} figure(s) better)")


@command
def sweep(
    spec: SpecArg,
    vary: Annotated[Optional[list[str]], typer.Option(
        "--vary", metavar="KEY=VALUES",
        help="A key of the spec by dotted path (effector.mass, frame.upper.0, cables.1.outlet.1, "
             "tension.1) and its values: a,b,c or start:stop:count. Repeat for a full grid. "
             "Given on the command line, these replace the spec's sweep.vary.")] = None,
    workers: Annotated[Optional[int], typer.Option(
        "--workers", help="Worker processes (default sweep.workers, else one per core; 1: in this process).",
        min=1, max=1024)] = None,
    scheduler: SchedulerOpt = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue an interrupted sweep from the journal in --out.")] = False,
    rank_by: Annotated[Optional[str], typer.Option(
        "--rank-by", metavar="FIGURE[:asc|:desc]",
        help="Figure that ranks the variants passing every requirement (default sweep.rank_by, else fraction).")] = None,
    check_against: Annotated[Optional[Path], typer.Option(
        "--check-against", metavar="BASELINE.csv",
        help="Compare with a baseline sweep.csv; exit 1 when a figure regresses.")] = None,
    tolerance: Annotated[float, typer.Option(
        "--tolerance", help="Relative tolerance of --check-against.", min=0.0)] = 1e-6,
    abs_tolerance: Annotated[float, typer.Option(
        "--abs-tolerance", help="Absolute tolerance of --check-against (added to the relative one).", min=0.0)] = 1e-9,
    strict: Annotated[bool, typer.Option(
        "--strict", help="With --check-against: improvements beyond the tolerance fail too.")] = False,
    catalogue: CatalogueOpt = None,
    trajectory: TrajectoryOpt = None,
    safety_factor: SafetyOpt = None,
    motor: MotorOpt = None,
    step: StepOpt = None,
    top: Annotated[int, typer.Option("--top", help="Best variants to list.", min=0)] = 10,
    max_variants: Annotated[int, typer.Option(
        "--max-variants", help="Most variants the sweep may have (the product of the value counts); "
                               f"raise it explicitly for larger sweeps (at most {HARD_MAX_VARIANTS:,}).",
        min=1, max=HARD_MAX_VARIANTS)] = MAX_VARIANTS,
    no_picture: Annotated[bool, typer.Option("--no-picture", help="Do not draw sweep.png.")] = False,
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Batch parameter sweep: sweep.csv (one design_report.csv row per variant), sweep_best.csv, sweep.png."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import sweep as job

    design = load_design(spec)
    settings = job.SweepSettings(vary, workers, scheduler, resume, rank_by, check_against, tolerance, abs_tolerance,
                                 strict, catalogue, trajectory, safety_factor, motor, step, top, not no_picture, out,
                                 overwrite, env.engine(), format.value, max_variants)
    run = job.sweep(design, settings, progress=bars(quiet or json_), log=lambda msg: info(quiet or json_, msg))
    if json_:
        emit_json(run.summary)
    else:
        render(design, run, top, check_against)
    if run.regressions:
        raise CheckFailed("" if json_ else f"{len(run.regressions)} figure(s) regressed against {check_against}")


def register(app: typer.Typer) -> None:
    app.command()(sweep)
