"""The ``sweep`` job: a parameter sweep with its journal, sweep.csv, sweep_best.csv and sweep.png."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple, Sequence

from cdpr_design.errors import InputError, quote
from cdpr_design.io.columns import file_name
from cdpr_design.io.files import OutputDir
from cdpr_design.io.journal import LazyJournal, SweepJournal
from cdpr_design.io.tables import read_csv_table, text_rows
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, write_rows
from cdpr_design.jobs.motion import require_trajectory
from cdpr_design.plots import sweep as sweep_plots


def write_sweep(out: OutputDir, header: list[str], rows: list[list], best_header: list[str],
                best_rows: list[list], keys: Sequence[str], title: str = "",
                rank_by: str | None = None, picture: bool = True, format: str = "csv",
                design=None, timings: Timings | None = None) -> list[Path]:
    """``sweep.csv`` (``format='parquet'``: ``sweep.parquet``), ``sweep_best`` and ``sweep.png``,
    put in place together; the picture is drawn while the tables are written."""
    timings = timings or Timings()
    pending = None
    with out:
        if picture and rows:
            pending = submit_pictures(out, [("sweep.png", sweep_plots.sweep_figure,
                                             (header, rows, keys, title, None, rank_by))], timings=timings)
        with timings.phase("write_s"):
            paths = [write_rows(out, "sweep", header, rows, format, design, keys=list(keys)),
                     write_rows(out, "sweep_best", best_header, best_rows, format, design, keys=list(keys))]
        if pending is not None:
            paths += pending.wait()
    return paths


class SweepRun(NamedTuple):
    summary: dict  # the ``sweep --json`` object
    plan: object  # batch.variants.Plan
    stats: object  # batch.local.RunStats
    header: list
    rows: list
    best_header: list
    best_rows: list
    failed: list  # rows that failed to evaluate
    rank_by: str
    descending: bool
    regressions: list
    improvements: list
    out: OutputDir


def _check_options(design, workers, step, tolerance, abs_tolerance, trajectory) -> int | None:
    """Validate the options against the design; the number of workers (None: one per core)."""
    if workers is None:
        workers = (design.sweep or {}).get("workers")
    if workers is not None and workers < 1:
        raise InputError(f"--workers: expected at least 1, got {workers}")
    if step is not None and not (math.isfinite(step) and step > 0):
        raise InputError(f"--step: expected a positive number of metres, got {step}")
    if not (math.isfinite(tolerance) and tolerance >= 0 and math.isfinite(abs_tolerance) and abs_tolerance >= 0):
        raise InputError("--tolerance / --abs-tolerance: expected non-negative numbers")
    if trajectory is not None and require_trajectory(design, trajectory, "--trajectory").type == "csv":
        raise InputError(f"--trajectory {trajectory}: a csv trajectory cannot be swept (its poses "
                         "do not follow the varied design); use a square, polyline or circle path")
    return workers


def _check_motor(design, catalogue, safety_factor: float | None, motor: str | None) -> None:
    """``--motor`` (every variant's motor) must be in ``catalogue`` and ``--safety-factor`` at least 1,
    before any work.  The spec's own ``winch.motor`` is not checked here: a ``--vary`` may replace
    it, and a motor a variant names is that variant's (unknown: the variant's ``error``)."""
    from cdpr_design.design import sizing as sz

    if motor is not None:
        sz.check_options(design, catalogue, safety_factor, motor)
    elif safety_factor is not None and not (math.isfinite(safety_factor) and safety_factor >= 1):
        raise InputError(f"--safety-factor: expected a number >= 1, got {safety_factor}")


def _read_baseline(check_against: Path | None, plan) -> tuple[list[str], list[list[str]]] | None:
    """The ``--check-against`` baseline (header, rows), refused (exit 2) before any work unless it
    can be compared with a sweep of ``plan`` (:func:`cdpr_design.batch.table.check_baseline`)."""
    from cdpr_design import batch as sw

    if check_against is None:
        return None
    header, rows = read_csv_table(check_against)
    sw.check_baseline(header, rows, plan, str(check_against))
    return header, rows


def _record_problem(rec: dict, plan) -> str | None:
    """What is wrong with a journal record of a sweep of ``plan`` (None: nothing): a variant
    index of the plan, that variant's values, figures by name (numbers, text or null), an
    error text (:func:`cdpr_design.batch.local.record`)."""
    v = rec.get("variant")
    if not isinstance(v, int) or isinstance(v, bool):
        return f"the variant {quote(v)} is not a variant index"
    if not 0 <= v < len(plan):
        return f"variant {v} is not a variant of this sweep (0 to {len(plan) - 1})"
    values = rec.get("values")
    if not isinstance(values, list) or values != list(plan.values(v)):
        return f"the values {quote(values)} are not those of {plan.describe(v)}"
    figures = rec.get("figures")
    if not isinstance(figures, dict) or not all(
            isinstance(x, (int, float, str)) or x is None for x in figures.values()):
        return f"the figures {quote(figures)} are not figure names with numbers, text or null"
    if not isinstance(rec.get("error"), str):
        return f"the error {quote(rec.get('error'))} is not a text"
    return None


def _check_records(journal: SweepJournal, numbered: list[tuple[int, dict]], plan) -> None:
    """Refuse (exit 2, naming the journal's line) a damaged record before anything is written."""
    for line, rec in numbered:
        problem = _record_problem(rec, plan)
        if problem is not None:
            raise InputError(f"--resume: {journal.path} line {line} is damaged: {problem}; delete that line "
                             "(the variant is evaluated again) or run without --resume to start over")


def _kept_records(journal: SweepJournal, meta: dict, plan, resume: bool, log: Callable[[str], None]) -> list[dict]:
    """The journal's finished variants to keep (``resume``), after checking it is this sweep's
    and no record is damaged."""
    numbered = journal.resumed(meta, resume, log, "sweep (other spec, keys, values or options)")
    if numbered is None:
        return []
    _check_records(journal, numbered, plan)
    kept = [rec for _, rec in numbered]
    log(f"resuming: {len(kept)} of {len(plan)} variants already done")
    return kept


def _run_journalled(design, plan, options, out_dir, workers, scheduler, resume, log, progress):
    """Run the variants not in the journal yet, appending each to it; (stats, every record)."""
    from cdpr_design import batch as sw

    journal = SweepJournal(out_dir)
    journal.check_free()  # another sweep writing this folder: refused before any work
    meta = {"journal": "cdpr-design sweep", "version": sw.JOURNAL_VERSION, "name": design.name,
            "keys": plan.keys, "variants": len(plan), "fingerprint": plan.fingerprint(options)}
    kept = _kept_records(journal, meta, plan, resume, log)
    lazy = LazyJournal(journal, meta, kept)
    done = {r["variant"] for r in kept}
    try:
        with stage(progress, f"sweep {design.name}") as cb:
            stats = sw.run(plan, options, workers=workers, scheduler=scheduler, skip=done,
                           on_record=lazy.append, progress=cb)
        lazy.start()
        records = journal.read()[1]  # while the folder's journal is still this sweep's (its lock held)
    finally:
        journal.close()
    return stats, records


@dataclass(frozen=True)
class SweepSettings:
    """The options of a ``sweep`` run (docs/cli.md): ``vary`` KEY=VALUES items (default the spec's
    ``sweep.vary``), ``workers`` processes or a Dask ``scheduler``, ``resume`` the journal in ``out``,
    ``rank_by`` a figure, the baseline ``check_against`` compared within ``tolerance`` (relative)
    plus ``abs_tolerance``, ``strict`` improvements fail too; every variant evaluated with
    ``catalogue``, ``trajectory``, ``safety_factor``, ``motor``, grid ``step`` [m] and ``engine``;
    ``top`` best variants listed, ``picture`` sweep.png drawn, tables in ``format`` (``csv`` or
    ``parquet``) in ``out`` (``overwrite`` foreign files); ``max_variants`` the most variants run
    (default :data:`cdpr_design.batch.variants.MAX_VARIANTS`)."""

    vary: Sequence[str] | None = None
    workers: int | None = None
    scheduler: str | None = None
    resume: bool = False
    rank_by: str | None = None
    check_against: Path | None = None
    tolerance: float = 1e-6
    abs_tolerance: float = 1e-9
    strict: bool = False
    catalogue: Path | None = None
    trajectory: str | None = None
    safety_factor: float | None = None
    motor: str | None = None
    step: float | None = None
    top: int = 10
    picture: bool = True
    out: str | Path | None = None
    overwrite: bool = False
    engine: str = "auto"
    format: str = "csv"
    max_variants: int | None = None


def sweep(design, settings: SweepSettings, progress: Progress | None = None,
          log: Callable[[str], None] | None = None) -> SweepRun:
    """The ``sweep`` command: evaluate every variant of ``settings`` (:class:`SweepSettings`),
    journalled in its ``out`` (``resume`` continues it), then write sweep.csv, sweep_best.csv and
    sweep.png and compare with the baseline ``check_against``; ``log`` receives messages (resuming)."""
    from cdpr_design import batch as sw
    from cdpr_design.model import spec

    o = settings
    section = design.sweep or {}
    plan = sw.make_plan(design, [sw.parse_vary(v) for v in o.vary] if o.vary else sw.vary_from_spec(section),
                        max_variants=o.max_variants or sw.MAX_VARIANTS)
    rank_name, descending = sw.parse_rank(o.rank_by or section.get("rank_by"))
    workers = _check_options(design, o.workers, o.step, o.tolerance, o.abs_tolerance, o.trajectory)
    if o.scheduler:
        sw.check_scheduler(o.scheduler)
    baseline = _read_baseline(o.check_against, plan)
    cat = spec.load_catalogue(o.catalogue)
    _check_motor(design, cat, o.safety_factor, o.motor)
    options = sw.Options(step=o.step, safety_factor=o.safety_factor, motor=o.motor, trajectory=o.trajectory,
                         catalogue=cat, engine=o.engine)
    timings = Timings()
    out_dir = output_dir(design, o.out, o.overwrite)
    for name in (file_name("sweep", o.format), file_name("sweep_best", o.format), "sweep.png", SweepJournal.NAME):
        out_dir.target(name)  # refuse foreign files before any work
    with timings.phase("sweep_s"):
        stats, records = _run_journalled(design, plan, options, out_dir, workers, o.scheduler, o.resume,
                                         log or (lambda msg: None), progress)
        header, rows = sw.table(plan, records)
        bh, brows = sw.best(header, rows, rank_name, descending)
    write_sweep(out_dir, header, rows, bh, brows, plan.keys,
                title=f"{design.name}: sweep of {', '.join(plan.keys)}", rank_by=rank_name, picture=o.picture,
                format=o.format, design=design, timings=timings)
    regressions, improvements = [], []
    if baseline is not None:
        regressions, improvements = sw.compare(header, text_rows(rows), baseline[0], baseline[1], plan.keys,
                                               o.tolerance, o.abs_tolerance, o.strict, str(o.check_against))
    failed = [r for r in rows if r[header.index("error")]]
    summary = {
        "name": design.name, "keys": plan.keys, "variants": len(plan), "evaluated": stats.evaluated,
        "resumed": stats.skipped, "errors": len(failed), "passed": len(brows),
        "rank_by": rank_name, "best": [dict(zip(bh, r)) for r in brows[:o.top]],
        "backend": stats.backend, "workers": stats.workers, "chunk": stats.chunk,
        "elapsed_s": stats.elapsed_s, "files": str(out_dir.path),
    }
    summary["timings"] = timings.as_dict()
    if baseline is not None:
        summary["baseline"] = str(o.check_against)
        summary["regressions"] = [d.as_dict() for d in regressions]
        summary["improvements"] = [d.as_dict() for d in improvements]
    return SweepRun(summary, plan, stats, header, rows, bh, brows, failed, rank_name, descending,
                    regressions, improvements, out_dir)
