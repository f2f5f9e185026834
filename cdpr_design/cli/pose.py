"""``pose``, ``fk`` and ``schema``: one pose of a design, forward kinematics, the spec's JSON Schema."""

from __future__ import annotations

import sys
from enum import Enum
from typing import Annotated, Optional

import typer

from cdpr_design.cli.common import (CableModelOpt, JsonOpt, Kind, KindOpt, QuietOpt, SpecArg, command,
                                    emit_json, fmt, load_design, out_console, parse_numbers, parse_pose,
                                    summary_table, table)
from cdpr_design.errors import InputError
from cdpr_design.model.limits import LENGTH


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
    at: Annotated[str, typer.Option("--at", help="Pose coordinates, comma-separated (e.g. 0.75,0.75); "
                                                 "the position only when effector.orientation is free.")],
    kind: KindOpt = Kind.static,
    objective: ObjectiveOpt = Objective.min_norm,
    weights: WeightsOpt = None,
    json_: JsonOpt = False,
    cable_model: CableModelOpt = None,
    quiet: QuietOpt = False,
):
    """One pose: cable lengths, tensions, feasibility, margin, structure matrix (and the hanging tilt)."""
    from cdpr_design.jobs import hanging as hjob
    from cdpr_design.jobs import pose as job
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.pose import evaluate_pose

    design = load_design(spec, cable_model)
    robot = resolve(design, Analysis(command="pose", kind=kind.value, objective=objective.value,
                                     weights=weights is not None))
    if robot.orientation.free:
        coords = design.motion.position_coords
        position = parse_numbers(at, "--at", len(coords), f"numbers ({','.join(coords)}): effector.orientation "
                                 "is free, so the position alone is commanded and the orientation hangs")
        data = hjob.free_pose_data(robot, position)  # with its stiffness keys
        stiffness = {}
        accelerations = job.acceleration_data(robot)
    else:
        p = parse_pose(design, at)
        c = parse_weights(design, weights)
        result = evaluate_pose(robot, p, c)
        data = job.pose_data(design, result)
        state = result.cable_state
        stiffness = job.stiffness_data(design, p, result.tensions, feasible=result.feasible,
                                       unstretched=None if state is None else state.unstretched_lengths)
        accelerations = job.acceleration_data(robot, p)
        if robot.underconstrained and robot.cables.rigid and not robot.outlets.pulleys:
            data.update(hjob.hanging_fields(design, p[: design.motion.dim]))
    data["objective"] = objective.value
    data.update(stiffness)
    data.update(accelerations)
    if json_:
        emit_json(data)
        return
    _pose_table(design, at, data)


def _pose_table(design, at: str, data: dict) -> None:
    verdict = "feasible" if data["feasible"] else "infeasible"
    if "reason" in data and not data["feasible"]:
        verdict += f" ({data['reason']})"
    t = table(f"{design.name} at ({at}) — {verdict}, margin {fmt(data['margin'])} N")
    model = data.get("cable_model")
    extra = [("outlet tension [N]", "outlet_tensions"), ("unstretched [m]", "unstretched_lengths"),
             ("sag [m]", "sag")] if model else []
    for col in ("cable", "length [m]", "tension [N]") + tuple(c for c, _ in extra) + ("bounds [N]",):
        t.add_column(col)
    for cable in design.cables:
        t.add_row(cable.name, fmt(data["lengths"][cable.name], 6), fmt(data["tensions"][cable.name], 6),
                  *(fmt(data[k][cable.name], 6) for _, k in extra),
                  f"{cable.tension_min:g} – {cable.tension_max:g}")
    out_console.print(t)
    if model:
        out_console.print(f"cable model: {model} (tensions at the effector end; status {data['cable_status']})")
    if data.get("effector_orientation") == "free" and data["orientation"] is not None:
        out_console.print(f"hangs with orientation {fmt(data['orientation'])}, tilt {fmt(data['tilt'])}°")
        if all(v is None for v in data["tensions"].values()):
            # infeasible (tilted too far, or a tension out of bounds): the tensions it still hangs with
            out_console.print("and tensions [N] " + ", ".join(f"{c} {fmt(v, 6)}"
                                                              for c, v in data["hanging_tensions"].items()))
    elif "hanging" in data and data["hanging"] is None:
        out_console.print("hanging: no tilt — a weightless effector (effector.mass 0 or zero gravity) hangs in no "
                          "particular orientation")
    elif "hanging" in data:
        h = data["hanging"]
        out_console.print(f"hanging: the free body would tilt by {fmt(h['tilt'])}° here"
                          + ("" if h["feasible"] else f" — it cannot hang here: {h['reason']}")
                          + " (effector.orientation: fixed holds it at the commanded orientation)")
    if data.get("acceleration_radius") is not None:
        axes = ", ".join(f"{c} {fmt(lo)} to {fmt(hi)}" for c, (lo, hi) in zip(design.motion.position_coords,
                                                                              data["axis_accelerations"]))
        out_console.print(f"acceleration from rest: {fmt(data['acceleration_radius'])} m/s² in every direction; "
                          f"along the axes [m/s²]: {axes}")
    if data["collisions"]:
        out_console.print("collisions: " + ", ".join(" – ".join(p) for p in data["collisions"]))


@command
def fk(
    spec: SpecArg,
    lengths: Annotated[str, typer.Option("--lengths", help="Cable lengths [m], comma-separated, in cable order.")],
    guess: Annotated[Optional[str], typer.Option(
        "--guess", help="A pose whose orientation also starts the search (rotational motions; the starting "
                        "pose of the kinematic solve with swivel pulleys).")] = None,
    json_: JsonOpt = False,
    cable_model: CableModelOpt = None,
    quiet: QuietOpt = False,
):
    """Where the effector rests for given cable lengths (geometrico-static forward problem; unstretched
    lengths with elastic or sagging cables)."""
    from cdpr_design.jobs import hanging as hjob
    from cdpr_design.jobs import pose as job

    from cdpr_design.statics.robot import Analysis, resolve

    design = load_design(spec, cable_model)
    robot = resolve(design, Analysis(command="fk"))  # refused combinations: exit 2 with the reason
    L = parse_numbers(lengths, "--lengths", design.m, "cable lengths (one per cable)", limit=LENGTH)
    if any(v < 0 for v in L):
        raise InputError("--lengths: cable lengths must be non-negative")
    g = parse_pose(design, guess, "--guess") if guess is not None else None
    if not robot.cables.rigid:
        data = job.cable_fk_data(robot, L, g)  # --lengths are unstretched lengths
        if json_:
            emit_json(data)
            return
        out_console.print(summary_table(
            f"{design.name} — forward kinematics ({data['method']})",
            [(c, float(v)) for c, v in zip(design.motion.coords, data["pose"])]
            + ([("tilt [deg]", data["tilt"])] if "tilt" in data else []) + [("residual [m]", data["residual"])]
            + [(f"tension {c} [N]", v) for c, v in data.get("tensions", {}).items()]
            + [("within tension bounds", "yes" if data["within_bounds"] else "no")]))
        return
    data = hjob.fk_data(robot, L, guess=g)
    if json_:
        emit_json(data)
        return
    rows = [(c, v) for c, v in zip(design.motion.coords, data["pose"])]
    if data["tensions"] is not None:
        rows += [("tilt [deg]", data["tilt"])] + [(f"tension {c} [N]", v) for c, v in data["tensions"].items()]
        rows += [("slack", ", ".join(data["slack"]) or "none"), ("stable", str(data["stable"])),
                 ("other stable equilibria", str(len(data["equilibria"])))]
    rows += [("residual [m]", data["residual"])]
    out_console.print(summary_table(f"{design.name} — where it rests ({data['method']})", rows))


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
