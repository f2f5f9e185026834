"""``workspace``: the grid sweep of a design's workspace."""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Optional

import typer

from cdpr_design.cli.common import (CableModelOpt, ForceOpt, Format, FormatOpt, JsonOpt, Kind, KindOpt, OutOpt,
                                    OverwriteOpt, QuietOpt, SpecArg, StepOpt, bars, command, emit_json, fmt, load_design,
                                    out_console, summary_table, timings_row)


class Orientations(str, Enum):
    total = "total"
    range = "range"


@command
def workspace(
    spec: SpecArg,
    kind: KindOpt = Kind.static,
    step: StepOpt = None,
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
    max_tilt: Annotated[Optional[float], typer.Option(
        "--max-tilt", help="Largest tilt [deg] a feasible pose may hang with (under-constrained designs with "
                           "effector.orientation: free; default requirements.max_tilt).", min=0.0, max=180.0)] = None,
    cable_model: CableModelOpt = None,
    stiffness: Annotated[bool, typer.Option(
        "--stiffness", help="Also the least stiffness [N/m] and the lowest natural frequency [Hz] of every "
                            "feasible pose (elastic cables, or ideal ones with axial_stiffness): columns "
                            "min_stiffness and lowest_frequency, stiffness_map.png.")] = False,
    accelerations: Annotated[bool, typer.Option(
        "--accelerations", help="Also the acceleration radius [m/s^2] of every pose: the largest translational "
                                "acceleration reachable from rest in every direction (column "
                                "acceleration_radius, acceleration_map.png).")] = False,
    format: FormatOpt = Format.csv,
    html: Annotated[bool, typer.Option(
        "--html", help="Also write report.html: the interactive workspace, tension map and summary in one "
                       "file that opens offline.")] = False,
):
    """Grid sweep of the workspace: workspace.csv, workspace.png, tension_map.png, summary.json."""
    from cdpr_design.cli import env
    from cdpr_design.jobs import workspace as job
    from cdpr_design.plots import worker as _picture_worker
    from cdpr_design.statics.robot import Analysis

    with _picture_worker.take(enabled=env.picture_worker_enabled()) as pictures:  # matplotlib's import overlaps the spec and the sweep
        design = load_design(spec, cable_model)
        analysis = Analysis(kind=kind.value, collisions=collisions,
                            orientations=orientations.value if orientations is not None else None,
                            max_tilt=max_tilt, engine=env.engine(), stiffness=stiffness, accelerations=accelerations)
        settings = job.WorkspaceSettings(analysis, step=step, force=force, format=format.value, html=html)
        result, out_dir = job.workspace(design, settings, out, overwrite, pictures=pictures,
                                        progress=bars(quiet or json_, min_total=500_000))
    s = result.summary()
    if json_:
        emit_json(s)
        return
    unit = "m²" if design.motion.planar else "m³"
    out_console.print(summary_table(
        f"{design.name} — {s['kind']} workspace",
        [("poses", f"{s['poses']:,}"), ("feasible", f"{s['feasible']:,}"),
         ("fraction", f"{100 * s['fraction']:.2f} %"), ("measure", f"{s['measure']:.4g} {unit}"),
         ("inside the boundary", f"{s['boundary_measure']:.4g} {unit}"),
         ("largest force on the frame [N]", s["frame_loads"]["max_force"]),
         ("min margin [N]", s["min_margin"]), ("max margin [N]", s["max_margin"]),
         ("max tension [N]", s["max_tension"]), ("elapsed [s]", s["elapsed_s"]),
         timings_row(s["timings"])]
        + ([("collision free", f"{s['collision_free']:,}"),
            ("feasible before interference", f"{s['feasible_statics']:,}")] if "collision_free" in s else [])
        + ([("orientations", f"{s['orientation_mode']} ({s['orientation_count']} samples)")]
           if "orientation_mode" in s else [])
        + ([("effector orientation", s["effector_orientation"])] if "effector_orientation" in s else [])
        + ([("hangs at", f"{s['hangs']:,} positions"), ("max tilt (feasible) [deg]", s["max_tilt"])]
           if "hangs" in s else [])
        + ([("cable model", s["cable_model"])] if "cable_model" in s else [])
        + ([("least stiffness [N/m]", s["min_stiffness"]), ("lowest frequency [Hz]", s["lowest_frequency"])]
           if "lowest_frequency" in s else [])
        + ([("acceleration radius [m/s²]", f"{fmt(s['min_acceleration_radius'])} – "
                                           f"{fmt(s['max_acceleration_radius'])} (feasible poses)")]
           if "min_acceleration_radius" in s else [])
        + ([("cable status", ", ".join(f"{k} {v:,}" for k, v in s["cable_status"].items() if v))]
           if "cable_status" in s else [])
        + [("files", str(out_dir.path))]))


def register(app: typer.Typer) -> None:
    app.command()(workspace)
