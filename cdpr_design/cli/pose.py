"""``pose``, ``fk`` and ``schema``: one pose of a design, forward kinematics, the spec's JSON Schema."""

from __future__ import annotations

import sys
from enum import Enum
from typing import Annotated, Optional

import typer
from rich.table import Table

from cdpr_design.cli.common import (JsonOpt, Kind, KindOpt, QuietOpt, SpecArg, command, emit_json, fmt, load_design,
                                    out_console, parse_numbers, parse_pose, summary_table)
from cdpr_design.errors import InputError
from cdpr_design.model.limits import LENGTH
from cdpr_design.statics.reach import require_reached


class Objective(str, Enum):
    min_norm = "min-norm"
    min_max = "min-max"
    min_sum = "min-sum"


ObjectiveOpt = Annotated[Objective, typer.Option(
    "--objective", help="Tension objective: min-norm (2-norm, exact kernel), min-max (inf-norm) "
                        "or min-sum (1-norm), both with cvxpy.")]
WeightsOpt = Annotated[Optional[str], typer.Option(
    "--weights", help="Per-cable weights of the objective, comma-separated positive numbers.")]


def parse_weights(design, text: str | None) -> list[float] | None:
    """``--weights``: one positive number per cable (None: unweighted)."""
    if text is None:
        return None
    c = parse_numbers(text, "--weights", design.m, "weights (one per cable)")
    if any(v <= 0 for v in c):
        raise InputError(f"--weights: expected positive numbers, got {text!r}")
    return c


@command
def pose(
    spec: SpecArg,
    at: Annotated[str, typer.Option("--at", help="Pose coordinates, comma-separated (e.g. 0.75,0.75).")],
    kind: KindOpt = Kind.static,
    objective: ObjectiveOpt = Objective.min_norm,
    weights: WeightsOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
):
    """One pose: cable lengths, tensions, feasibility, margin, structure matrix."""
    from cdpr_design.jobs import pose as job
    from cdpr_design.statics.pose import evaluate_pose

    design = load_design(spec)
    p = parse_pose(design, at)
    c = parse_weights(design, weights)
    result = evaluate_pose(design, p, kind.value, objective.value, c)
    data = job.pose_data(design, result)
    data["objective"] = objective.value
    if json_:
        emit_json(data)
        return
    t = Table(title=f"{design.name} at ({at}) — {'feasible' if data['feasible'] else 'infeasible'}, "
                    f"margin {fmt(data['margin'])} N", title_justify="left")
    for col in ("cable", "length [m]", "tension [N]", "bounds [N]"):
        t.add_column(col)
    for cable in design.cables:
        t.add_row(cable.name, fmt(data["lengths"][cable.name], 6), fmt(data["tensions"][cable.name], 6),
                  f"{cable.tension_min:g} – {cable.tension_max:g}")
    out_console.print(t)
    if data["collisions"]:
        out_console.print("collisions: " + ", ".join(" – ".join(p) for p in data["collisions"]))


@command
def fk(
    spec: SpecArg,
    lengths: Annotated[str, typer.Option("--lengths", help="Cable lengths [m], comma-separated, in cable order.")],
    guess: Annotated[Optional[str], typer.Option("--guess", help="Starting pose for the numerical solver.")] = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
):
    """Forward kinematics: the pose for given cable lengths."""
    from cdpr_design.statics import kinematics as kin

    design = load_design(spec)
    L = parse_numbers(lengths, "--lengths", design.m, "cable lengths (one per cable)", limit=LENGTH)
    if any(v < 0 for v in L):
        raise InputError("--lengths: cable lengths must be non-negative")
    g = parse_pose(design, guess, "--guess") if guess is not None else None
    res = kin.forward_kinematics(design, L, guess=g)
    require_reached(res.residual, L)  # lengths no pose has: exit 2 with the residual, never a pose
    data = {"pose": [float(v) for v in res.pose], "residual": float(res.residual), "method": res.method}
    if json_:
        emit_json(data)
        return
    out_console.print(summary_table(
        f"{design.name} — forward kinematics ({res.method})",
        [(c, float(v)) for c, v in zip(design.motion.coords, res.pose)] + [("residual [m]", res.residual)]))


@command
def schema(
    json_: Annotated[bool, typer.Option("--json", help="Print the schema as one line of JSON.")] = False,
    quiet: QuietOpt = False,
):
    """Print the JSON Schema of the spec format (for editors' YAML validation)."""
    from cdpr_design.model import spec as spec_mod

    if json_:
        emit_json(spec_mod.json_schema())
        return
    sys.stdout.write(spec_mod.schema_text() + "\n")


def register(app: typer.Typer) -> None:
    app.command()(pose)
    app.command()(fk)
    app.command()(schema)
