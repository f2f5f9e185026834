"""The ``optimize`` job: a design search (optuna study in ``optimize.db``), then optimize.csv,
pareto.csv (several objectives; ``.parquet`` with ``format='parquet'``), best.yaml and optimize.png."""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple, Sequence

from cdpr_design.errors import InputError, WriteError
from cdpr_design.io.columns import check_format, file_name
from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.common import Progress, output_dir, save_pictures, stage
from cdpr_design.jobs.motion import require_trajectory
from cdpr_design.jobs.tables import Timings, write_rows
from cdpr_design.model.limits import MAX_TRIALS, MAX_WORKERS, SEED_LIMIT
from cdpr_design.plots import optimize as optimize_plots

#: Files the job writes besides its tables (``optimize``, ``pareto``) and the study's SQLite file.
OUTPUTS = ("best.yaml", "optimize.png")


class OptimizeRun(NamedTuple):
    summary: dict  # the ``optimize --json`` object
    problem: object  # optimize.Problem
    stats: object  # optimize.RunStats
    trials: list  # optimize.Trial, by number
    best: object  # optimize.Trial or None
    pareto: list  # optimize.Trial (several objectives)
    out: OutputDir


def _check_options(trials: int, workers: int | None, seed: int | None, timeout: float | None,
                   step: float | None) -> int:
    """Validate the numeric options (exit 2 naming the option); the number of workers."""
    if not 1 <= trials <= MAX_TRIALS:
        raise InputError(f"--trials: expected 1 to {MAX_TRIALS:,}, got {trials}")
    workers = 1 if workers is None else workers
    if not 1 <= workers <= MAX_WORKERS:
        raise InputError(f"--workers: expected 1 to {MAX_WORKERS}, got {workers}")
    if seed is not None and not 0 <= seed < SEED_LIMIT:
        raise InputError(f"--seed: expected a whole number from 0 to {SEED_LIMIT - 1}, got {seed}")
    if timeout is not None and not (math.isfinite(timeout) and timeout > 0):
        raise InputError(f"--timeout: expected a positive number of seconds, got {timeout}")
    if step is not None and not (math.isfinite(step) and step > 0):
        raise InputError(f"--step: expected a positive number of metres, got {step}")
    return workers


def best_spec_text(design, problem, best) -> str:
    """``best.yaml``: the base spec with the best trial's values, as YAML, validated first."""
    import yaml

    from cdpr_design.model import spec

    data = problem.space.data(best.params)
    spec.validate(data, design.source)  # a complete trial's spec is valid: a failure here is a bug
    objectives = ", ".join(f"{o.figure} = {v:.6g}" for o, v in zip(problem.objectives, best.values))
    head = [f"# The best design of `cdpr-design optimize` on {design.source or design.name}: trial {best.number}",
            f"# ({objectives}).",
            "# Searched keys: " + ", ".join(f"{k} = {best.params[k]!r}" for k in problem.space.keys)]
    return "\n".join(head) + "\n" + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)


def picture_data(design, problem, rows, best, front, importances) -> dict:
    """What ``optimize.png`` shows (:func:`cdpr_design.plots.optimize.optimize_figure`'s input):
    the trials, the best so far or the Pareto front, the importances."""
    from cdpr_design import optimize as opt

    return {"title": f"{design.name}: search of {', '.join(problem.space.keys)}",
            "objectives": [(o.figure, o.maximize) for o in problem.objectives],
            "trials": [(r.number, r.state, r.values) for r in rows],
            "best": best.number if best is not None else None,
            "pareto": [r.number for r in front],
            "convergence": opt.convergence(problem, rows) if len(problem.objectives) == 1 else [],
            "importances": importances}


def write_outputs(out: OutputDir, design, problem, rows, best, front, importances, picture: bool,
                  format: str = "csv", timings: Timings | None = None) -> list[Path]:
    """optimize.csv, pareto.csv (several objectives; ``format='parquet'``: ``.parquet``), best.yaml
    (when a trial is complete), optimize.png; ``timings`` gets their ``write_s`` and ``pictures_s``."""
    from cdpr_design import optimize as opt

    timings = timings if timings is not None else Timings()
    keys = list(problem.space.keys)
    with out:  # put in place together at the end
        with timings.phase("write_s"):
            paths = [write_rows(out, "optimize", *opt.table(problem, rows), format, design, keys=keys)]
            if len(problem.objectives) > 1:
                paths.append(write_rows(out, "pareto", *opt.table(problem, front), format, design, keys=keys))
            if best is not None:
                paths.append(out.write_text("best.yaml", best_spec_text(design, problem, best)))
        if picture and rows:
            paths += save_pictures(out, [("optimize.png", optimize_plots.optimize_figure,
                                          (picture_data(design, problem, rows, best, front, importances),))],
                                   timings=timings)
    return paths


def _summary(design, problem, stats, rows, best, front, importances, out_dir) -> dict:
    states = [r.state for r in rows]
    return {
        "name": design.name, **problem.describe(),
        "trials_requested": stats.requested, "trials_done": len(rows),
        "complete": states.count("complete"), "infeasible": states.count("infeasible"),
        "failed": states.count("failed"),
        "evaluated_now": stats.evaluated, "resumed": stats.resumed, "requeued_interrupted": stats.requeued,
        "stopped_by_timeout": stats.stopped_by_timeout, "workers": stats.workers,
        "elapsed_s": stats.elapsed_s,
        "trials_per_s": stats.evaluated / stats.elapsed_s if stats.elapsed_s > 0 else None,
        "sampler": "TPE" if len(problem.objectives) == 1 else "multi-objective TPE",
        "best": best.as_dict(problem) if best is not None else None,
        "best_rule": "best value" if len(problem.objectives) == 1 else "knee of the Pareto front",
        "pareto": [r.as_dict(problem) for r in front] if len(problem.objectives) > 1 else None,
        "importances": importances, "files": str(out_dir.path),
    }


@dataclass(frozen=True)
class OptimizeSettings:
    """The options of an ``optimize`` run (docs/cli.md): search ``vary`` (KEY=LO:HI[:log] /
    KEY=a,b,c) for the objectives ``maximize`` / ``minimize`` under the spec's requirements and
    ``require`` (FIGURE>=X / FIGURE<=X); ``trials`` trials in ``workers`` processes from ``seed``
    (``resume`` continues the study in ``out``; ``timeout`` [s] stops starting trials); each trial
    evaluated with ``catalogue``, ``trajectory``, ``safety_factor``, ``motor``, grid ``step`` [m]
    and ``engine``; ``picture`` optimize.png drawn, tables in ``format`` (``csv`` or ``parquet``)
    in ``out`` (``overwrite`` foreign files)."""

    vary: Sequence[str]
    maximize: Sequence[str] | None = None
    minimize: Sequence[str] | None = None
    require: Sequence[str] | None = None
    trials: int = 100
    workers: int | None = None
    seed: int | None = None
    timeout: float | None = None
    resume: bool = False
    catalogue: Path | None = None
    trajectory: str | None = None
    safety_factor: float | None = None
    motor: str | None = None
    step: float | None = None
    picture: bool = True
    out: str | Path | None = None
    overwrite: bool = False
    engine: str = "auto"
    format: str = "csv"


def optimize(design, settings: OptimizeSettings, progress: Progress | None = None,
             log: Callable[[str], None] | None = None) -> OptimizeRun:
    """The ``optimize`` command: the search of ``settings`` (:class:`OptimizeSettings`), then
    optimize.csv, pareto.csv (``format='parquet'``: ``.parquet``), best.yaml and optimize.png
    written; ``log`` receives messages.  The summary's ``timings``: ``sweep_s`` the search,
    ``write_s`` the files, ``pictures_s`` optimize.png."""
    from cdpr_design import batch
    from cdpr_design import optimize as opt
    from cdpr_design.model import spec

    o = settings
    timings = Timings()
    check_format(o.format)
    if o.trajectory is not None and require_trajectory(design, o.trajectory, "--trajectory").type == "csv":
        raise InputError(f"--trajectory {o.trajectory}: a csv trajectory cannot follow the varied design; "
                         "use a square, polyline or circle path")
    options = batch.Options(step=o.step, safety_factor=o.safety_factor, motor=o.motor, trajectory=o.trajectory,
                            catalogue=spec.load_catalogue(o.catalogue), engine=o.engine)
    problem = opt.make_problem(design, o.vary, o.maximize, o.minimize, o.require, options)
    workers = _check_options(o.trials, o.workers, o.seed, o.timeout, o.step)
    out_dir = output_dir(design, o.out, o.overwrite)
    for name in (file_name("optimize", o.format), file_name("pareto", o.format), *OUTPUTS, opt.DB):
        out_dir.target(name)  # refuse foreign files before any work
    opt.study.check_file(out_dir.path, o.resume)  # and an optimize.db that is no study to continue (kept)
    out_dir.wrote(opt.DB)
    with timings.phase("sweep_s"):
        with stage(progress, f"optimize {design.name}") as cb:
            try:
                stats = opt.run(problem, out_dir.path, o.trials, workers=workers, seed=o.seed, timeout=o.timeout,
                                resume=o.resume, progress=cb, log=log)
            except WriteError:
                if not (out_dir.path / opt.DB).exists():  # a new study that could not be written: removed
                    with contextlib.suppress(InputError):
                        out_dir.forget(opt.DB)
                raise
        study = opt.study.load(out_dir.path)
        rows = opt.results.trials(opt.finished(study))
        front = opt.pareto(problem, rows) if len(problem.objectives) > 1 else []
        best = opt.best(problem, rows)
        importances = opt.importances(study, problem)
    write_outputs(out_dir, design, problem, rows, best, front, importances, o.picture, o.format, timings)
    summary = _summary(design, problem, stats, rows, best, front, importances, out_dir)
    summary["timings"] = timings.as_dict()
    return OptimizeRun(summary, problem, stats, rows, best, front, out_dir)
