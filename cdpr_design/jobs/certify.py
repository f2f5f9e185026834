"""The ``certify`` job: pave the workspace with proven boxes, write ``boxes.csv`` (or
``.parquet``), ``certify.png`` and ``summary.json``."""

from __future__ import annotations

import base64
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.io.columns import file_name
from cdpr_design.io.files import OutputDir
from cdpr_design.io.journal import CertifyJournal, LazyJournal
from cdpr_design.jobs.common import Progress, output_dir, stage, submit_pictures
from cdpr_design.jobs.tables import Timings, table_metadata
from cdpr_design.plots.certify import certify_figure
from cdpr_design.plots.worker import PictureWorker

#: the files the job writes besides its table
FILES = ("certify.png", "summary.json")


@dataclass(frozen=True)
class CertifySettings:
    """The options of a ``certify`` run (docs/cli.md): the ``kind``, the finest box edge
    ``resolution`` [m], the ``box`` (lower, upper) [m] paved, the ``min_margin`` [N] proven, the
    ``max_boxes`` and ``time_limit`` [s] that stop the bisection
    (:func:`cdpr_design.workspaces.certify.certify`), the table ``format`` (``csv`` or
    ``parquet``), ``workers``, ``scheduler`` and ``resume`` (:func:`run_certify`)."""

    kind: str = "static"
    resolution: float | None = None
    box: tuple | None = None
    min_margin: float | None = None
    max_boxes: int | None = None
    time_limit: float | None = None
    format: str = "csv"
    workers: int | None = None
    scheduler: str | None = None
    resume: bool = False


def certify(design, settings: CertifySettings, out: str | Path | None = None, overwrite: bool = False, *,
            pictures: PictureWorker | None = None, progress: Progress | None = None,
            log: Callable[[str], None] | None = None):
    """The ``certify`` command: :func:`run_certify` into the folder ``out`` (default
    ``out/<design name>/``; ``overwrite``: replace foreign files).  Returns (result, folder).
    The files are put in place together when all are written
    (:class:`~cdpr_design.io.files.OutputDir`): a failure leaves the folder's earlier files whole."""
    out_dir = output_dir(design, out, overwrite)
    with out_dir:
        result = run_certify(design, out_dir, settings, pictures=pictures, progress=progress, log=log)
    return result, out_dir


def run_certify(design, out: OutputDir, settings: CertifySettings, pictures: PictureWorker | None = None,
                progress: Progress | None = None, timings: Timings | None = None,
                log: Callable[[str], None] | None = None):
    """Certify (:func:`cdpr_design.workspaces.certify.certify` with the options of ``settings``),
    then write the boxes, the picture and ``summary.json`` (with the ``timings``: ``load_s`` the
    kernels' load or compile, ``sweep_s`` the branch-and-prune).

    ``workers`` processes (None or 1: in this process, the kernels on every core) or the Dask
    ``scheduler`` (``"local"``: a LocalCluster of ``workers`` processes, None: one per core; or an
    address) classify each level's boxes (:mod:`cdpr_design.batch.certify`):
    the boxes are the same whatever they are.  Every level classified is journalled in
    ``certify.journal.jsonl``; ``resume`` replays the journal's levels of the same paving
    (an interrupted or ``max_boxes``-stopped run) and classifies only the rest."""
    from cdpr_design import batch
    from cdpr_design.batch import certify as parallel_certify
    from cdpr_design.workspaces import certify as cert

    timings = timings or Timings()
    kind, resolution, box, min_margin = settings.kind, settings.resolution, settings.box, settings.min_margin
    max_boxes, time_limit, format = settings.max_boxes, settings.time_limit, settings.format
    workers, scheduler, resume = settings.workers, settings.scheduler, settings.resume
    robot = cert.check_certifiable(design, kind)
    if scheduler:
        batch.check_scheduler(scheduler)
    classifier = parallel_certify.classifier(1 if workers is None and not scheduler else workers, scheduler)
    for name in FILES + (CertifyJournal.NAME, file_name("boxes", format)):
        out.target(name)  # a foreign file of that name: refused before any work
    journal = CertifyJournal(out)
    journal.check_free()  # another certify writing this folder: refused before any work
    meta = {"journal": "cdpr-design certify", "name": design.name,
            "fingerprint": fingerprint(robot, kind, resolution, box, min_margin)}
    kept = kept_levels(journal, meta, resume, log or (lambda msg: None))
    lazy = LazyJournal(journal, meta, kept)
    limits = {} if max_boxes is None else {"max_boxes": max_boxes}
    with timings.phase("load_s"), stage(progress, "loading the kernels (a first run compiles them)"):
        cert.warm_up(robot)
    try:
        with timings.phase("sweep_s"), stage(progress, f"certify {design.name}") as cb:
            result = cert.certify(robot, resolution, box, min_margin, time_limit=time_limit,
                                  progress=None if cb is None else (lambda done, todo: cb(done, done + todo)),
                                  classifier=classifier, replay=[decode(r) for r in kept],
                                  on_level=lambda k, st: lazy.append(level_record(k, st)), **limits)
        lazy.start()
    finally:
        journal.close()
    pending = submit_pictures(out, [("certify.png", certify_figure, (result,))], pictures, timings)
    cols = result.columns()
    meta = table_metadata(design, "boxes", cols, kind=kind, resolution=result.resolution,
                          orientation=[float(v) for v in design.default_orientation_full()])
    with timings.phase("write_s"):
        writer = out.table("boxes", format, metadata=meta, names=list(cols), compiled=True)  # the kernels run
        try:
            writer.write(cols)
            writer.close()
        except BaseException:
            writer.abort()
            raise
    pending.wait()
    result.extra["timings"] = timings.as_dict()
    out.write_json("summary.json", result.summary())
    return result


def fingerprint(robot, kind: str, resolution, box, min_margin) -> str:
    """A hash of everything that decides the boxes (the spec, the resolved robot's cable model, the
    options; not the limits, which only stop a paving earlier): a journal is resumed only by its
    own paving."""
    from cdpr_design import __version__

    blob = json.dumps({"spec": robot.design.raw, "cable_model": robot.cables.name, "kind": kind,
                       "resolution": resolution, "box": box, "min_margin": min_margin, "version": __version__},
                      sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def level_record(level: int, status: np.ndarray) -> dict:
    """A journal line: one level's status codes (int8, base64 of their bytes)."""
    st = np.ascontiguousarray(status, np.int8)
    return {"level": int(level), "boxes": int(st.size), "status": base64.b64encode(st.tobytes()).decode("ascii")}


def decode(rec: dict) -> np.ndarray:
    """The status codes of a journal line (:func:`level_record`)."""
    return np.frombuffer(base64.b64decode(rec["status"]), np.int8)


def kept_levels(journal: CertifyJournal, meta: dict, resume: bool, log: Callable[[str], None]) -> list[dict]:
    """The journal's levels to replay (``resume``), after checking it is this paving's and whole:
    levels 0, 1, ... in order, each with its count of codes -1, 0 or 1 (a damaged line is refused,
    exit 2, naming it)."""
    numbered = journal.resumed(meta, resume, log, "paving (other spec or options)")
    if numbered is None:
        return []
    kept = []
    for line, rec in numbered:
        try:
            st = decode(rec)
            ok = rec["level"] == len(kept) and rec["boxes"] == st.size and np.all(np.abs(st) <= 1)
        except (KeyError, TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(f"--resume: {journal.path} line {line} is damaged; delete it and the lines after it "
                             "(those levels are classified again) or run without --resume to start over")
        kept.append(rec)
    log(f"resuming: {len(kept)} level(s) of boxes already classified")
    return kept


#: boxes of the task box's longest edge that ``check --certify`` bisects down to
TASK_DIVISIONS = 256


def certify_task(design, kind: str = "static", resolution: float | None = None, max_boxes: int | None = None) -> dict:
    """The ``certified`` requirement of ``check``: prove every position of
    ``requirements.task_box`` feasible at the fixed orientation (with ``requirements.min_margin``
    when it is positive).  A row of the checks table (``requirement``, ``figure``, ``limit``,
    ``passed``) plus, when it fails, ``unproven_box`` (the first box not proven inside:
    ``lower``, ``upper`` [m] and ``status``) and ``witness`` (a pose of it found infeasible by
    the pose evaluation, with its tensions [N] and margin [N], or None)."""
    from cdpr_design.errors import InputError
    from cdpr_design.workspaces import certify as cert

    task = design.requirements.task_box
    if task is None:
        raise InputError("requirements.certified / --certify: the spec gives no requirements.task_box to certify")
    lo, hi = (tuple(float(v) for v in c) for c in task)
    res = resolution if resolution is not None else max(max(b - a for a, b in zip(lo, hi)) / TASK_DIVISIONS, 1e-6)
    mu = design.requirements.min_margin
    mu = mu if mu is not None and mu > 0 else None
    r = cert.certify(cert.check_certifiable(design, kind), res, (lo, hi), mu, max_boxes=max_boxes)
    counts = r.counts()
    row = {"requirement": "certified", "figure": f"{100 * r.fraction(1):.4g} % "
           f"proven ({counts['inside']} inside, {counts['boundary']} boundary, {counts['outside']} outside)",
           "limit": "whole task box" + (f", margin >= {mu:g} N" if mu else ""), "passed": counts["inside"] == r.status.size}
    if not row["passed"]:
        order = np.argsort(r.status, kind="stable")  # outside (-1) first, then boundary
        k = int(order[0])
        row["unproven_box"] = {"lower": r.lower[k].tolist(), "upper": r.upper[k].tolist(),
                               "status": cert.STATUS[int(r.status[k])]}
        row["witness"] = witness(design, kind, r.lower[k], r.upper[k], mu or 0.0)
    return row


def witness(design, kind: str, lower, upper, min_margin: float = 0.0) -> dict | None:
    """A pose of the box [lower, upper] [m] that fails (infeasible, or its margin below
    ``min_margin`` [N]) by the pose evaluation: its centre or a corner; None if all pass."""
    import itertools

    from cdpr_design.statics.kinematics import pose_at
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.pose import evaluate_pose

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    points = [0.5 * (lower + upper)] + [np.array(c) for c in itertools.product(*zip(lower, upper))]
    ori = design.default_orientation_full()
    robot = resolve(design, Analysis(command="statics", kind=kind))
    for p in points:
        pose = pose_at(design, np.pad(p, (0, 3 - p.size)), ori)
        e = evaluate_pose(robot, pose)
        if not e.feasible or not (e.margin >= min_margin):
            return {"pose": [float(v) for v in pose], "feasible": bool(e.feasible),
                    "margin": None if not np.isfinite(e.margin) else float(e.margin),
                    "tensions": [None if not np.isfinite(t) else float(t) for t in e.tensions]}
    return None
