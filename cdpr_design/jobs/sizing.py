"""The ``size-motors``, ``report`` and ``check`` jobs: motor sizing, the design report, requirement checks."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.common import Progress, output_dir, stage
from cdpr_design.jobs.motion import require_trajectory, trajectory_samples
from cdpr_design.jobs.workspace import run_workspace
from cdpr_design.plots.worker import PictureWorker
from cdpr_design.workspaces.grid import check_step


def write_motor_sizing(out: OutputDir, sizing) -> Path:
    """``motor_sizing.csv``: one row per cable, the contract columns first (cli.md)."""
    from cdpr_design.design.sizing import AxisSizing

    rows = sizing.rows()
    header = list(rows[0].keys()) if rows else list(AxisSizing.CONTRACT)
    return out.write_csv("motor_sizing.csv", header, ([r[k] for k in header] for r in rows))


def write_design_report(out: OutputDir, row: dict, name: str = "design_report.csv") -> Path:
    """``design_report.csv``: one row of the design's headline figures (booleans as 1/0)."""
    header = list(row.keys())
    return out.write_csv(name, header, [[row[k] for k in header]])


class SizingRun(NamedTuple):
    result: object  # design.sizing.SizingResult
    out: OutputDir


def size_motors(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
                motor: str | None = None, step: float | None = None, out: str | Path | None = None,
                overwrite: bool = False, engine: str = "auto") -> SizingRun:
    """The ``size-motors`` command: size motor, gearbox and drum over the task workspace
    (grid ``step`` [m]; duty cycle of spec ``trajectory``, else a standard one) from the
    shipped catalogue extended by the YAML file ``catalogue``; write motor_sizing.csv into ``out``."""
    from cdpr_design.design import sizing as sz
    from cdpr_design.model import spec

    cat = spec.load_catalogue(catalogue)
    samples = trajectory_samples(design, trajectory)
    out_dir = output_dir(design, out, overwrite)
    result = sz.size_motors(design, cat, step=step, samples=samples, safety_factor=safety_factor, motor=motor,
                            engine=engine)
    write_motor_sizing(out_dir, result)
    return SizingRun(result, out_dir)


def evaluate(design, catalogue, trajectory=None, safety_factor: float | None = None,
             motor: str | None = None, step: float | None = None, workspace_result=None,
             progress: Progress | None = None, engine: str = "auto"):
    """Workspace, task box, motor sizing and checks of one design
    (:func:`cdpr_design.design.evaluate.evaluate_full`; ``catalogue``: a loaded motor catalogue,
    ``trajectory``: a spec trajectory's name or its samples, ``step`` [m])."""
    from cdpr_design.design import evaluate as ev

    samples = trajectory if trajectory is None or not isinstance(trajectory, str) else \
        trajectory_samples(design, trajectory)
    with stage(progress, f"evaluate {design.name}") as cb:
        return ev.evaluate_full(design, step=step, catalogue=catalogue, samples=samples,
                                safety_factor=safety_factor, motor=motor,
                                workspace_result=workspace_result, progress=cb, engine=engine)


class CheckRun(NamedTuple):
    evaluation: object  # design.evaluate.Evaluation
    checks: list


def check(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
          motor: str | None = None, step: float | None = None, progress: Progress | None = None,
          engine: str = "auto") -> CheckRun:
    """The ``check`` command: evaluate the design and tabulate its requirements (nothing written);
    ``catalogue``: YAML file extending the shipped motor catalogue."""
    from cdpr_design.design import evaluate as ev
    from cdpr_design.model import spec

    e = evaluate(design, spec.load_catalogue(catalogue), trajectory, safety_factor, motor, step, progress=progress,
                 engine=engine)
    return CheckRun(e, ev.check_table(e.row))


class ReportRun(NamedTuple):
    evaluation: object  # design.evaluate.Evaluation
    checks: list
    out: OutputDir


def report(design, catalogue: Path | None = None, trajectory: str | None = None, safety_factor: float | None = None,
           motor: str | None = None, step: float | None = None, force: bool = False,
           out: str | Path | None = None, overwrite: bool = False, pictures: PictureWorker | None = None,
           engine: str = "auto", progress: Progress | None = None) -> ReportRun:
    """The ``report`` command: the static workspace (:func:`~cdpr_design.jobs.workspace.run_workspace`),
    then motor_sizing.csv, design_report.csv and report.json of the evaluation; ``catalogue``:
    YAML file extending the shipped motor catalogue."""
    from cdpr_design.design import evaluate as ev
    from cdpr_design.model import spec

    from cdpr_design.design import sizing as sz

    # every option checked before the first file is written (the workspace's)
    cat = spec.load_catalogue(catalogue)
    samples = trajectory_samples(design, trajectory)
    sz.check_options(design, cat, safety_factor, motor)
    if step is not None:
        check_step(step, "--step")
    out_dir = output_dir(design, out, overwrite)
    wres = run_workspace(design, out_dir, "static", step, force, pictures=pictures, engine=engine,
                         progress=progress)
    e = evaluate(design, cat, samples, safety_factor, motor, step, wres, progress, engine)
    write_motor_sizing(out_dir, e.sizing)
    write_design_report(out_dir, e.row)
    checks = ev.check_table(e.row)
    out_dir.write_json("report.json", {"report": e.row, "checks": checks, "sizing": e.sizing.summary()})
    return ReportRun(e, checks, out_dir)
