"""``certify``: the workspace paved with proven boxes (interval analysis)."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from cdpr_design.cli.common import (CableModelOpt, Format, FormatOpt, JsonOpt, Kind, KindOpt, OutOpt, OverwriteOpt,
                                    QuietOpt, SchedulerOpt, SpecArg, bars, command, emit_json, info, load_design,
                                    out_console, summary_table, timings_row)

ResolutionOpt = Annotated[Optional[float], typer.Option(
    "--resolution", help="Finest box edge [m]: undecided boxes are bisected down to it, then called boundary "
                         "(default: the spec's grid step).")]


@command
def certify(
    spec: SpecArg,
    kind: KindOpt = Kind.static,
    resolution: ResolutionOpt = None,
    min_margin: Annotated[Optional[float], typer.Option(
        "--min-margin", help="Prove a capacity margin of at least this many newtons (inside) instead of "
                             "feasibility.")] = None,
    max_boxes: Annotated[Optional[int], typer.Option(
        "--max-boxes", help="Stop bisecting after this many boxes (the rest are boundary).")] = None,
    time_limit: Annotated[Optional[float], typer.Option(
        "--time-limit", help="Stop bisecting after this many seconds (the rest are boundary).")] = None,
    workers: Annotated[Optional[int], typer.Option(
        "--workers", help="Worker processes classifying each level's boxes (default: this process, its kernels "
                          "on every core; with --scheduler local: one per core). The boxes are the same.",
        min=1, max=1024)] = None,
    scheduler: SchedulerOpt = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue an interrupted (or --max-boxes / --time-limit stopped) paving from the "
                         "journal in --out.")] = False,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
    cable_model: CableModelOpt = None,
    format: FormatOpt = Format.csv,
):
    """Certified workspace by interval analysis: boxes.csv, certify.png, summary.json."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import certify as job
    from cdpr_design.plots import worker as _picture_worker

    with _picture_worker.take(enabled=env.picture_worker_enabled()) as pictures:
        design = load_design(spec, cable_model)
        settings = job.CertifySettings(kind=kind.value, resolution=resolution, min_margin=min_margin,
                                       max_boxes=max_boxes, time_limit=time_limit, format=format.value,
                                       workers=workers, scheduler=scheduler, resume=resume)
        result, out_dir = job.certify(design, settings, out, overwrite, pictures=pictures,
                                      progress=bars(quiet or json_), log=lambda msg: info(quiet or json_, msg))
    s = result.summary()
    if json_:
        emit_json(s)
        return
    c = s["counts"]
    out_console.print(summary_table(
        f"{design.name} — certified {s['kind']} workspace",
        [("inner measure", f"{s['inner_measure']:.6g} {s['unit']}"),
         ("outer measure", f"{s['outer_measure']:.6g} {s['unit']}"),
         ("boundary measure", f"{s['boundary_measure']:.4g} {s['unit']} "
                              f"({100 * s['boundary_fraction']:.3g} % of the box)"),
         ("boxes", f"inside {c['inside']:,}, boundary {c['boundary']:,}, outside {c['outside']:,}"),
         ("resolution [m]", s["resolution"])]
        + ([("min margin [N]", s["min_margin"])] if s["min_margin"] else [])
        + ([("stopped early", s["truncated"])] if s["truncated"] else [])
        + ([("too small to halve", f"{s['unsplit_boxes']:,} boundary boxes: --resolution is below the "
                                   "floating-point spacing of the box's coordinates")] if s["unsplit_boxes"] else [])
        + [timings_row(s["timings"]), ("files", str(out_dir.path))]))


def register(app: typer.Typer) -> None:
    app.command()(certify)
