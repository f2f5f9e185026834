"""Batch parameter sweeps over copies of a design (``cdpr-design sweep``).

A sweep varies keys of the spec, given by dotted paths into the validated
spec data (``effector.mass``, ``frame.upper.0``, ``cables.1.outlet.1``,
``tension.1``, ``winch.drum_radius``; a cable may also be named:
``cables.c2.outlet.0``).  Several keys make a full grid, the last key
varying fastest; variant ``i`` is the i-th point of that grid (0-based).

Every variant is rebuilt with :func:`cdpr_design.model.spec.from_dict` (so the spec
rules apply to it) and evaluated by :func:`cdpr_design.design.evaluate.evaluate`, the
code behind ``report``'s ``design_report.csv``: a sweep row *is* the report
row of that variant.

This module is the core: it never touches files.  Rows leave it through an
``on_record`` callback (the command line appends them to a journal and
writes ``sweep.csv``); a resumed sweep passes the variant indices already
done in ``skip``.

Execution backends
------------------
- in-process (``workers=1``);
- a process pool (``workers > 1``, default one per core).  Workers are
  started with ``spawn``: the kernels run numba's parallel layer, which here is
  GNU OpenMP, and a ``fork`` after an OpenMP parallel region can deadlock the
  child (numba's documentation, "threading layers": the GNU OpenMP runtime is
  not fork-safe); ``spawn`` is safe whatever the parent ran before.  Workers
  load the kernels from numba's on-disk cache (``cache=True``).
- Dask distributed (``scheduler=ADDRESS`` or ``"local"`` for a
  :class:`distributed.LocalCluster`).

Parallelism is across variants: each worker runs numba's kernels on one
thread (``numba.set_num_threads(1)``), which also avoids oversubscribing the
cores.  Results do not depend on the thread count (each pose is computed on
its own; the reductions are min / max / counts).  Variants travel in chunks
(ten or more per task for Dask, whose per-task overhead is a few ms) so that
scheduling overhead stays small.
"""

from __future__ import annotations

import hashlib
import importlib
import itertools
import json
import math
import os
import pickle
import re
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Sequence

from cdpr_design.errors import InputError, SpecError

#: Figures where a larger value is better (ranking, regression checks).
HIGHER_IS_BETTER = frozenset({
    "feasible", "fraction", "measure", "min_margin", "max_margin", "task_feasible",
    "task_fraction", "task_min_margin", "torque_margin", "speed_margin",
    "implied_tension_max", "min_margin_figure", "checks_passed",
    "check_task_box", "check_min_margin", "check_min_fraction", "check_motors",
})
#: Figures where a smaller value is better.
LOWER_IS_BETTER = frozenset({
    "max_tension", "peak_tension", "peak_cable_speed", "peak_motor_torque",
    "rms_motor_torque", "peak_motor_speed",
})
#: Every figure name of an :func:`~cdpr_design.design.evaluate.evaluate` row apart from
#: the per-cable ones (``peak_tension_<cable>``, ``motor_<cable>``).
KNOWN_FIGURES = HIGHER_IS_BETTER | LOWER_IS_BETTER | frozenset({
    "name", "motion", "cables", "kind", "poses", "task_poses", "sizing_poses", "motor",
    "tension_max", "drum_radius", "gear_ratio", "safety_factor", "duty_cycle",
    "req_min_margin", "req_min_fraction",
})
#: Figures drawn in the sweep pictures (when present).
HEADLINE = ("fraction", "min_margin_figure", "peak_tension", "peak_motor_torque",
            "torque_margin", "speed_margin")

JOURNAL_VERSION = 1


# ----------------------------------------------------------------------------
# Definitions: VALUES, key paths, the grid of variants
# ----------------------------------------------------------------------------

_INT = re.compile(r"^[+-]?\d+$")


def _scalar(text: str):
    """``"2"`` -> 2, ``"0.5"`` -> 0.5, anything else stays text (a motor name)."""
    t = text.strip()
    if _INT.match(t):
        return int(t)
    try:
        v = float(t)
    except ValueError:
        return t
    if not math.isfinite(v):
        raise ValueError(f"expected finite numbers, got {t!r}")
    return v


def _tidy(v: float) -> float:
    """A linspace value rounded to 12 significant digits (0.30000000000000004 -> 0.3)."""
    return float(f"{v:.12g}")


def parse_values(text: str) -> tuple:
    """Parse VALUES: ``a,b,c`` (numbers or names) or ``start:stop:count`` (inclusive linspace).

    Raises
    ------
    ValueError
        With a message saying what was expected.
    """
    text = text.strip()
    if not text:
        raise ValueError("expected values: a,b,c or start:stop:count")
    if ":" in text and "," not in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"expected start:stop:count, got {text!r}")
        try:
            start, stop = float(parts[0]), float(parts[1])
        except ValueError:
            raise ValueError(f"expected numbers in start:stop:count, got {text!r}") from None
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise ValueError(f"expected finite start and stop, got {text!r}")
        if not _INT.match(parts[2].strip()) or int(parts[2]) < 1:
            raise ValueError(f"expected a whole count >= 1 in start:stop:count, got {parts[2]!r}")
        n = int(parts[2])
        if n == 1:
            return (_tidy(start),)
        return tuple(_tidy(start + (stop - start) * k / (n - 1)) for k in range(n))
    items = [s for s in text.split(",")]
    if any(not s.strip() for s in items):
        raise ValueError(f"expected comma-separated values without empty entries, got {text!r}")
    return tuple(_scalar(s) for s in items)


def parse_vary(option: str) -> tuple[str, tuple]:
    """One ``--vary KEY=VALUES`` option: (key, values).

    Raises
    ------
    InputError
        Bad syntax (exit 2), naming the option.
    """
    key, sep, values = option.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InputError(f"--vary {option!r}: expected KEY=VALUES (e.g. effector.mass=0.5,1,2 or "
                         "frame.upper.0=1.2:2.0:5)")
    try:
        return key, parse_values(values)
    except ValueError as exc:
        raise InputError(f"--vary {key}: {exc}") from None


def vary_from_spec(section: dict | None) -> list[tuple[str, tuple]]:
    """The ``sweep.vary`` mapping of a spec: a list of (key, values).

    A value may be a list (each entry one value, lists allowed for vector
    keys), a VALUES string (``"0.5:2:4"``, ``"a,b"``) or a single scalar.
    """
    vary = (section or {}).get("vary") or {}
    out = []
    problems = []
    for key, v in vary.items():
        where = f"sweep.vary.{key}"
        if isinstance(v, str):
            try:
                out.append((str(key), parse_values(v)))
            except ValueError as exc:
                problems.append((where, str(exc)))
        elif isinstance(v, list):
            if not v:
                problems.append((where, "expected at least one value"))
            else:
                out.append((str(key), tuple(v)))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out.append((str(key), (v,)))
        else:
            problems.append((where, f"expected a list of values or 'start:stop:count', got {v!r}"))
    if problems:
        raise SpecError(problems)
    return out


def parse_path(key: str) -> tuple:
    """``cables.1.outlet.1`` or ``cables[1].outlet[1]`` -> ("cables", 1, "outlet", 1)."""
    text = re.sub(r"\[(\w+)\]", r".\1", key.strip())
    parts = text.split(".")
    if not text or any(p == "" for p in parts):
        raise ValueError(f"expected a dotted key path such as effector.mass, got {key!r}")
    return tuple(int(p) if _INT.match(p) else p for p in parts)


def _locate(container, part, trail: str):
    """The index or key ``part`` addresses in ``container`` (lists: an index or a cable name)."""
    if isinstance(container, dict):
        if isinstance(part, int):
            part = str(part)
        return part
    if isinstance(container, list):
        if isinstance(part, int):
            if not -len(container) <= part < len(container):
                raise ValueError(f"{trail}: index {part} is out of range (the spec has {len(container)} entries)")
            return part % len(container)
        for i, item in enumerate(container):
            if isinstance(item, dict) and item.get("name") == part:
                return i
        raise ValueError(f"{trail}: no entry named {part!r}")
    raise ValueError(f"{trail} is a value ({container!r}), not a section or a list")


def resolve(base: dict, path: tuple) -> tuple:
    """Check a key path against the base spec data; return it with names turned into indices.

    Missing mapping keys are allowed (an optional key the base spec leaves
    out); the validation of each variant then decides whether the key exists
    in the spec format at all.
    """
    node: Any = base
    out = []
    trail = ""
    for k, part in enumerate(path):
        idx = _locate(node, part, trail or "the spec")
        out.append(idx)
        trail = f"{trail}.{part}" if trail else str(part)
        if isinstance(node, dict) and idx not in node:
            rest = path[k + 1:]
            if any(isinstance(p, int) for p in rest):
                raise ValueError(f"{trail} is not in the spec; vary the whole key rather than its entries")
            out.extend(rest)
            return tuple(out)
        node = node[idx]
    return tuple(out)


def with_value(data, path: tuple, value):
    """A copy of ``data`` with the key at ``path`` set to ``value``.

    Only the containers along the path are copied; the rest is shared with
    ``data`` (never modified).
    """
    if not path:
        return value
    head, rest = path[0], path[1:]
    if isinstance(data, dict):
        new = dict(data)
        new[head] = with_value(data.get(head, {}) if rest else None, rest, value)
        return new
    new = list(data)
    new[head] = with_value(data[head], rest, value)
    return new


def _show(v) -> str:
    if isinstance(v, float):
        return format(v, ".10g")
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_show(x) for x in v) + "]"
    return str(v)


@dataclass(frozen=True)
class Axis:
    """One varied key: the dotted key as given, the resolved path, the values."""

    key: str
    path: tuple
    values: tuple


@dataclass(frozen=True)
class Plan:
    """A sweep: the base spec data and the varied keys (a full grid)."""

    base: dict
    axes: tuple[Axis, ...]
    source: str | None = None

    def __len__(self) -> int:
        return math.prod(len(a.values) for a in self.axes)

    @property
    def keys(self) -> list[str]:
        return [a.key for a in self.axes]

    def values(self, index: int) -> tuple:
        """The varied values of variant ``index`` (the last key varies fastest)."""
        out = []
        for a in reversed(self.axes):
            index, r = divmod(index, len(a.values))
            out.append(a.values[r])
        return tuple(reversed(out))

    def variants(self, skip: Iterable[int] = ()) -> Iterator[tuple[int, tuple]]:
        skip = set(skip)
        for i, vals in enumerate(itertools.product(*(a.values for a in self.axes))):
            if i not in skip:
                yield i, vals

    def data(self, values: Sequence) -> dict:
        """The spec data of the variant with these varied values."""
        d = self.base
        for a, v in zip(self.axes, values):
            d = with_value(d, a.path, v)
        return d

    def describe(self, index: int, values: Sequence | None = None) -> str:
        """``variant 3 (effector.mass=2, frame.upper.0=1.8)``."""
        values = self.values(index) if values is None else values
        return f"variant {index} (" + ", ".join(f"{a.key}={_show(v)}" for a, v in zip(self.axes, values)) + ")"

    def fingerprint(self, options: "Options") -> str:
        """A hash of everything that decides the rows (for resuming the right sweep)."""
        from cdpr_design import __version__

        blob = json.dumps({"base": self.base, "axes": [[a.key, list(a.values)] for a in self.axes],
                           "options": options.fingerprint(), "version": __version__},
                          sort_keys=True, default=repr)
        return hashlib.sha256(blob.encode()).hexdigest()[:20]


def make_plan(design, vary: Sequence[tuple[str, Sequence]], max_problems: int = 10) -> Plan:
    """Check a sweep definition against the design and validate every variant up front.

    Parameters
    ----------
    design : Design
        The base design (its ``raw`` spec data is varied).
    vary : list of (key, values)
        From :func:`parse_vary` / :func:`vary_from_spec`.

    Raises
    ------
    SpecError
        An unknown key path, a key given twice, or a variant the spec format
        rejects; each message names the variant by index and varied values.
    """
    from cdpr_design.model import spec

    base = design.raw
    if not vary:
        raise InputError("nothing to vary: give --vary KEY=VALUES or a sweep.vary section in the spec")
    axes = []
    problems = []
    seen = {}
    for key, values in vary:
        try:
            path = resolve(base, parse_path(key))
        except ValueError as exc:
            problems.append((f"--vary {key}", str(exc)))
            continue
        if path in seen:
            problems.append((f"--vary {key}", f"the same key as {seen[path]}"))
            continue
        seen[path] = key
        if not values:
            problems.append((f"--vary {key}", "expected at least one value"))
            continue
        axes.append(Axis(key, path, tuple(values)))
    if problems:
        raise SpecError(problems, design.source)
    plan = Plan(base, tuple(axes), design.source)
    bad = 0
    seen_problems: set = set()
    hidden = 0
    for i, vals in plan.variants():
        try:
            spec.validate(plan.data(vals))
        except SpecError as exc:
            bad += 1
            new = [(p, m) for p, m in exc.problems if (p, m) not in seen_problems]
            seen_problems.update(exc.problems)
            if not new:
                hidden += 1  # the same problem as a variant already named (an unknown key)
            elif bad - hidden <= max_problems:
                problems.extend((f"{plan.describe(i, vals)}: {p}" if p else plan.describe(i, vals), m)
                                for p, m in new)
    if bad:
        shown = min(bad - hidden, max_problems)
        if bad > shown:
            problems.append(("", f"{bad} of {len(plan)} variants are rejected by the spec format "
                                 f"({bad - shown} not listed)"))
        raise SpecError(problems, design.source)
    return plan


# ----------------------------------------------------------------------------
# Evaluation of one variant (the same code as ``report``)
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Options:
    """What :func:`cdpr_design.design.evaluate.evaluate` is asked, besides the design."""

    step: float | None = None
    safety_factor: float | None = None
    motor: str | None = None
    trajectory: str | None = None
    catalogue: Any = None  # a model.catalogue.Catalogue; None: the shipped one
    #: engine of every variant's grid sweeps (results are identical: not in the fingerprint)
    engine: str = "auto"

    def fingerprint(self) -> dict:
        return {"step": self.step, "safety_factor": self.safety_factor, "motor": self.motor,
                "trajectory": self.trajectory, "catalogue": repr(self.catalogue)}


@dataclass(frozen=True)
class Job:
    """What a worker needs: the plan and the options (sent once per worker)."""

    plan: Plan
    options: Options
    #: load the numba kernels in each worker before the first variant: the sweep
    #: holds more poses than the numpy closed form is worth (workspace.ENGINES)
    kernels: bool = False


def record(index: int, values: Sequence, figures: dict | None = None, error: str = "") -> dict:
    """A sweep row as plain data (one journal line)."""
    return {"variant": int(index), "values": list(values), "figures": figures or {}, "error": error}


def evaluate_variant(job: Job, index: int, values: Sequence) -> dict:
    """Build and evaluate one variant; an exception becomes the row's ``error``."""
    from cdpr_design.model import spec

    # by module path: the package's lazy API also has a function named ``evaluate``
    ev = importlib.import_module("cdpr_design.design.evaluate")
    opt = job.options
    try:
        design = spec.from_dict(job.plan.data(values), source=job.plan.source)
        samples = None
        if opt.trajectory is not None:
            from cdpr_design.motion import trajectory as tr

            samples = tr.sample(design, opt.trajectory)
        row = ev.evaluate(design, step=opt.step, catalogue=opt.catalogue, samples=samples,
                          safety_factor=opt.safety_factor, motor=opt.motor, engine=opt.engine)
    except Exception as exc:  # noqa: BLE001 - a failing variant is a row, the sweep goes on
        msg = " ".join(str(exc).split())
        return record(index, values, error=f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__)
    return record(index, values, row)


def evaluate_chunk(job: Job, items: Sequence[tuple[int, tuple]]) -> list[dict]:
    return [evaluate_variant(job, i, v) for i, v in items]


# --- worker processes --------------------------------------------------------

_WORKER_JOB: Job | None = None


def _single_thread_kernels() -> None:
    """Run numba's parallel kernels on one thread in this process (parallelism is across variants).

    Nothing to do while numba is not loaded (small planar2 sweeps take the numpy engine)."""
    if "numba" not in sys.modules:
        return
    try:
        import numba

        numba.set_num_threads(1)
    except Exception:  # noqa: BLE001 - numba missing or layer refused: results are the same
        pass


def _prepare_process(job: Job) -> None:
    """The kernels loaded if the sweep is big; one numba thread (parallelism is across variants)."""
    if job.kernels:
        from cdpr_design import workspaces as ws

        ws.load_kernels()
    _single_thread_kernels()


def _init_worker(job: Job) -> None:
    global _WORKER_JOB
    _WORKER_JOB = job
    _prepare_process(job)
    if job.options.catalogue is None:
        from cdpr_design.model import spec

        _WORKER_JOB = Job(job.plan, _with_catalogue(job.options, spec.load_catalogue()), job.kernels)


def _pool_chunk(items):
    return evaluate_chunk(_WORKER_JOB, items)


_DASK_READY: dict = {}


def _dask_chunk(job: Job, items):
    if not _DASK_READY:
        _prepare_process(job)
        _DASK_READY["ok"] = True
    return evaluate_chunk(job, items)


def _with_catalogue(opt: Options, cat) -> Options:
    return Options(opt.step, opt.safety_factor, opt.motor, opt.trajectory, cat, opt.engine)


# ----------------------------------------------------------------------------
# Running a sweep
# ----------------------------------------------------------------------------


def default_workers() -> int:
    """One worker per core available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def chunk_size(n: int, workers: int, minimum: int = 1, maximum: int = 200) -> int:
    """Variants per task: about 16 tasks per worker, at least ``minimum``."""
    return max(minimum, min(maximum, math.ceil(n / max(1, 16 * workers))))


def chunks(items: list, size: int) -> list[list]:
    return [items[k:k + size] for k in range(0, len(items), size)]


def guided_chunks(items: list, size: int, workers: int, minimum: int = 1) -> list[list]:
    """Chunks of at most ``size`` that shrink towards the end (guided self-scheduling):
    each about a quarter of what is left per worker, never below ``minimum`` (unless
    ``size`` is smaller), so the
    workers finish together instead of one idling through the other's last big chunk."""
    out = []
    k = 0
    while k < len(items):
        left = len(items) - k
        n = min(size, max(minimum, math.ceil(left / (4 * max(1, workers)))))
        out.append(items[k:k + n])
        k += n
    return out


@dataclass
class RunStats:
    """How a sweep ran."""

    variants: int
    evaluated: int = 0
    skipped: int = 0
    errors: int = 0
    backend: str = ""
    workers: int = 1
    chunk: int = 1
    elapsed_s: float = 0.0
    notes: list[str] = field(default_factory=list)


def run(plan: Plan, options: Options | None = None, *, workers: int | None = None,
        scheduler: str | None = None, skip: Iterable[int] = (),
        on_record: Callable[[dict], None] | None = None,
        progress: Callable[[int, int], None] | None = None,
        chunk: int | None = None, start_method: str = "spawn",
        connect_timeout: float = 10.0, pool: bool | None = None) -> RunStats:
    """Evaluate every variant of ``plan`` not in ``skip``; rows go to ``on_record`` as they finish.

    Parameters
    ----------
    plan : Plan
    options : Options
    workers : int, optional
        Processes (default: one per core).  1 runs in this process.  With a
        scheduler: the LocalCluster's worker count (``"local"``), ignored for
        an existing cluster (its thread count is used to size the chunks).
    scheduler : str, optional
        ``"local"`` starts a :class:`distributed.LocalCluster` on 127.0.0.1;
        anything else is the address of a running Dask scheduler.
    skip : variant indices already done (``--resume``).
    on_record : callback(record)
        Called in this process, in completion order, once per variant.
    progress : callback(done, total)
        Variants done (including skipped) out of all.
    chunk : int, optional
        Variants per task (default :func:`chunk_size`).
    start_method : str
        How pool workers start (``spawn``; see the module notes on ``fork``).
    connect_timeout : float
        Seconds to wait for a Dask scheduler at an address.
    pool : bool, optional
        True: a process pool even for one worker (benchmarks); default: one
        worker runs in this process.

    Returns
    -------
    RunStats
    """
    options = options or Options()
    skip = set(skip)
    total = len(plan)
    todo = list(plan.variants(skip))
    stats = RunStats(variants=total, skipped=total - len(todo))
    t0 = time.perf_counter()
    done = [stats.skipped]

    def emit(recs):
        for r in recs:
            stats.evaluated += 1
            if r["error"]:
                stats.errors += 1
            if on_record is not None:
                on_record(r)
        done[0] += len(recs)
        if progress is not None:
            progress(done[0], total)

    if progress is not None:
        progress(done[0], total)
    if options.catalogue is None:
        from cdpr_design.model import spec

        options = _with_catalogue(options, spec.load_catalogue())
    job = Job(plan, options, kernels=_worth_kernels(plan, options, len(todo)))
    w = workers if workers is not None else default_workers()
    if w < 1:
        raise InputError(f"--workers: expected at least 1, got {w}")
    if scheduler:
        _run_dask(job, todo, scheduler, w, chunk, emit, stats, connect_timeout)
    elif not pool and (w == 1 or len(todo) <= 1):
        stats.backend, stats.workers, stats.chunk = "serial", 1, 1
        if todo:
            _run_serial(job, todo, emit)
    else:
        _run_pool(job, todo, w, chunk, emit, stats, start_method)
    stats.elapsed_s = time.perf_counter() - t0
    return stats


def _worth_kernels(plan: Plan, options: Options, variants: int) -> bool:
    """Whether the sweep holds more grid poses than the numpy engine is worth (about
    ``workspace.NUMPY_MAX_POSES``): then every process loads the numba kernels first."""
    from cdpr_design.model import spec
    from cdpr_design import workspaces as ws
    from cdpr_design.workspaces import engine as eng

    try:
        poses = ws.make_grid(spec.from_dict(plan.base), options.step, force=True).size
    except Exception:  # noqa: BLE001 - a bad base shows up as the variants' errors
        return True
    return variants * poses > eng.NUMPY_MAX_POSES


def _run_serial(job: Job, todo, emit) -> None:
    numba = sys.modules.get("numba")
    before = numba.get_num_threads() if numba is not None else None
    _prepare_process(job)
    try:
        for i, vals in todo:
            emit([evaluate_variant(job, i, vals)])
    finally:
        numba = sys.modules.get("numba")
        if numba is not None:
            try:
                numba.set_num_threads(before if before is not None else numba.config.NUMBA_NUM_THREADS)
            except Exception:  # noqa: BLE001
                pass


def _run_pool(job: Job, todo, w: int, chunk: int | None, emit, stats: RunStats, start_method: str) -> None:
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    w = min(w, len(todo))
    size = chunk or chunk_size(len(todo), w)
    stats.backend, stats.workers, stats.chunk = f"processes ({start_method})", w, size
    parts = chunks(todo, size) if chunk else guided_chunks(todo, size, w, minimum=2)
    ex = ProcessPoolExecutor(max_workers=w, mp_context=mp.get_context(start_method),
                             initializer=_init_worker, initargs=(job,))
    try:
        # keep a bounded number of tasks in flight (memory stays bounded for huge sweeps)
        pending = set()
        it = iter(parts)
        for part in itertools.islice(it, 4 * w):
            pending.add(ex.submit(_pool_chunk, part))
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in finished:
                emit(f.result())
                nxt = next(it, None)
                if nxt is not None:
                    pending.add(ex.submit(_pool_chunk, nxt))
    except BaseException:
        ex.shutdown(wait=False, cancel_futures=True)
        _stop_pool(ex)
        raise
    # every row is in: the workers' exit (~0.4 s of interpreter teardown with
    # numba loaded) overlaps the caller's next steps; wait_closed() joins it
    # (the executor's manager thread joins the processes; joining them here as
    # well would race it for the exit status)
    manager = getattr(ex, "_executor_manager_thread", None)
    ex.shutdown(wait=False)
    if manager is not None:
        _closing(manager)


#: threads still shutting down finished sweeps' workers (see :func:`wait_closed`)
_CLOSING: list[threading.Thread] = []


def _closing(thread: threading.Thread) -> None:
    """Remember a shut-down under way (and forget those that are over)."""
    _CLOSING[:] = [t for t in _CLOSING if t.is_alive()] + [thread]


def wait_closed() -> None:
    """Wait until the workers of finished sweeps have exited.

    :func:`run` returns as soon as every row is in; the pool's or the
    LocalCluster's worker processes then exit in the background (Python waits
    for them before this process ends).  Benchmarks call this between runs.
    """
    while _CLOSING:
        _CLOSING.pop(0).join()


def _stop_pool(ex) -> None:
    """End the pool's worker processes (an interrupted sweep must not leave them running)."""
    procs = getattr(ex, "_processes", None) or {}
    for p in list(procs.values()):
        try:
            p.terminate()
        except Exception:  # noqa: BLE001
            pass


#: Settings of the LocalCluster (scheduler and nannies live in this process,
#: the workers get them as environment variables).  One numba thread per worker
#: (the parallelism is across variants); neither dask's statistical profiler (a
#: stack walk every 10 ms) nor its GIL monitor (every 1 ms), which take the GIL
#: from short Python-heavy tasks; the event-loop health check, memory monitor and
#: system monitor at 1-2 s instead of 20-500 ms (no dashboard is served, and a
#: sweep's memory is bounded chunk buffers): with two cores shared by the
#: scheduler, the nannies and the workers, these cost about 0.4 s of CPU per
#: 1,000 variants.
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.gil.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
}
LOCAL_WORKER_ENV = {"NUMBA_NUM_THREADS": "1", **{
    "DASK_" + key.upper().replace(".", "__").replace("-", "_"): str(value)
    for key, value in LOCAL_CLUSTER_CONFIG.items()}}


#: A job pickling to fewer bytes goes with every Dask task instead of being scattered.
INLINE_JOB_BYTES = 1_000_000


def _start_local_cluster(LocalCluster, workers: int):
    """A LocalCluster of ``workers`` single-threaded worker processes on 127.0.0.1.

    dask's nannies start workers with ``MALLOC_TRIM_THRESHOLD_=65536``
    (``distributed.nanny.pre-spawn-environ``).  Setting that variable turns off
    glibc's dynamic mmap threshold, so every array above 128 kB is a fresh
    mmap with its page faults: a variant's sweep ran 1.6-2x slower than in a
    pool worker.  The sweep's memory is bounded chunk buffers, so the workers
    keep glibc's default.  The nannies also write their variables into this
    process's environment; it is restored once the workers are up.
    """
    import logging

    import dask

    saved = dict(os.environ)
    os.environ.update(LOCAL_WORKER_ENV)
    try:
        with dask.config.set({**LOCAL_CLUSTER_CONFIG,
                              "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
            return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                dashboard_address=None, host="127.0.0.1",
                                # a task's error comes back with its future (the variant's row);
                                # what dask logs at ERROR are shut-down races of heartbeats
                                silence_logs=logging.CRITICAL)
    finally:
        os.environ.clear()
        os.environ.update(saved)


def _run_dask(job: Job, todo, scheduler: str, w: int, chunk: int | None, emit, stats: RunStats,
              connect_timeout: float = 10.0) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError as exc:  # pragma: no cover - a dependency
        raise InputError(f"--scheduler: dask.distributed is not installed ({exc})") from None
    cluster = None
    try:
        if scheduler == "local":
            cluster = _start_local_cluster(LocalCluster, w)
            client = Client(cluster)
        else:
            try:
                client = Client(scheduler, timeout=f"{connect_timeout}s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"--scheduler: cannot connect to {scheduler}: {exc}") from None
    except BaseException:
        if cluster is not None:
            cluster.close()
        raise
    try:
        nthreads = sum(client.nthreads().values()) or w
        size = chunk or chunk_size(len(todo), nthreads, minimum=10)
        stats.backend = "dask LocalCluster" if cluster is not None else f"dask {scheduler}"
        stats.workers, stats.chunk = nthreads, size
        if todo:
            # a small job (the usual: a few kB) travels with each task, which spares
            # a broadcast round trip before the first task; a big one is sent once
            small = len(pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL)) < INLINE_JOB_BYTES
            job_f = job if small else client.scatter(job, broadcast=True)
            parts = chunks(todo, size) if chunk else guided_chunks(todo, size, nthreads, minimum=10)
            futures = [client.submit(_dask_chunk, job_f, part, pure=False) for part in parts]
            try:
                for fut in as_completed(futures):
                    emit(fut.result())
            except BaseException:
                client.cancel(futures)
                raise
    except BaseException:
        client.close()
        if cluster is not None:
            cluster.close()
        raise
    client.close()
    if cluster is not None:
        # every row is in: the cluster closes (~0.5 s: the workers shut down and
        # exit) while the caller goes on; wait_closed() joins it
        closer = threading.Thread(target=cluster.close, name="cdpr-design LocalCluster close")
        closer.start()
        _closing(closer)


# ----------------------------------------------------------------------------
# Tables: sweep.csv, the best variants, regression checks
# ----------------------------------------------------------------------------


def table(plan: Plan, records: Iterable[dict]) -> tuple[list[str], list[list]]:
    """``sweep.csv`` as (header, rows): variant, the varied keys, the figures, ``error``.

    Rows are sorted by variant index (a variant recorded twice keeps its
    first record); the figure columns are those of the rows in index order,
    by first appearance, so the table does not depend on completion order.
    """
    by_index: dict[int, dict] = {}
    for r in records:
        by_index.setdefault(int(r["variant"]), r)
    ordered = [by_index[i] for i in sorted(by_index)]
    keys = plan.keys
    figs: dict[str, None] = {}
    for r in ordered:
        for k in r["figures"]:
            if k not in keys and k not in ("variant", "error"):
                figs.setdefault(k, None)
    header = ["variant"] + keys + list(figs) + ["error"]
    rows = []
    for r in ordered:
        f = r["figures"]
        rows.append([r["variant"]] + list(r["values"]) + [f.get(k) for k in figs] + [r["error"]])
    return header, rows


def parse_rank(text: str | None) -> tuple[str, bool]:
    """``--rank-by FIGURE[:asc|:desc]`` -> (figure, descending).

    Default direction: descending for figures where more is better, ascending
    for tensions, torques and speeds.
    """
    text = (text or "fraction").strip()
    name, _, direction = text.partition(":")
    name = name.strip()
    if direction not in ("", "asc", "desc"):
        raise InputError(f"--rank-by {text!r}: expected FIGURE, FIGURE:asc or FIGURE:desc")
    if not (name in KNOWN_FIGURES or name.startswith(("peak_tension_", "motor_"))):
        known = ", ".join(sorted(HIGHER_IS_BETTER | LOWER_IS_BETTER))
        raise InputError(f"--rank-by {name!r}: not a figure of design_report.csv (numbers: {known})")
    if direction:
        return name, direction == "desc"
    return name, not (name in LOWER_IS_BETTER or name.startswith("peak_tension_"))


def _num(v) -> float | None:
    if v is None or v == "":
        return None
    if isinstance(v, bool):
        return float(v)
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def best(header: list[str], rows: list[list], rank_by: str, descending: bool) -> tuple[list[str], list[list]]:
    """The variants that pass every requirement, ranked by ``rank_by`` (missing figures last).

    Returns (header, rows) with a ``rank`` column first.
    """
    if rank_by not in header:
        return ["rank"] + header, []
    ip = header.index("checks_passed") if "checks_passed" in header else None
    ie = header.index("error")
    ir = header.index(rank_by)
    passing = [r for r in rows if not r[ie] and ip is not None and r[ip] in (True, 1, "1")]

    def key(r):
        v = _num(r[ir])
        if v is None:
            return (1, 0.0, r[0])
        return (0, -v if descending else v, r[0])

    ranked = sorted(passing, key=key)
    return ["rank"] + header, [[k + 1] + r for k, r in enumerate(ranked)]


@dataclass
class Difference:
    """One figure of one variant that moved against the baseline."""

    variant: int
    column: str
    baseline: str
    current: str
    change: str  # "worse", "better", "changed", "missing"

    def as_dict(self) -> dict:
        return {"variant": self.variant, "column": self.column, "baseline": self.baseline,
                "current": self.current, "change": self.change}


def _direction(column: str) -> int:
    if column in HIGHER_IS_BETTER:
        return 1
    if column in LOWER_IS_BETTER or column.startswith("peak_tension_"):
        return -1
    return 0


def compare(header: list[str], rows: list[list[str]], base_header: list[str], base_rows: list[list[str]],
            keys: Sequence[str], tolerance: float = 1e-6, abs_tolerance: float = 1e-9,
            strict: bool = False) -> tuple[list[Difference], list[Difference]]:
    """Compare a sweep table with a baseline table (cells as CSV text).

    Variants are matched by index, and their varied values must agree.  A
    number differs when |current - baseline| > tolerance * max(|baseline|,
    |current|) + abs_tolerance.  For figures with a known direction a
    difference is ``worse`` or ``better``; for the others (counts, names) any
    difference is ``changed``.  A variant that fails now and did not fail in
    the baseline is ``worse``; a baseline column missing now is ``missing``.

    Returns
    -------
    regressions, improvements : lists of :class:`Difference`
        Regressions are ``worse``, ``changed`` and ``missing`` (and, with
        ``strict``, ``better`` too).

    Raises
    ------
    InputError
        The baseline is not a sweep table, or it is from another sweep
        (other varied keys or values, or variants this sweep does not have).
    """
    if "variant" not in base_header:
        raise InputError("--check-against: the baseline has no 'variant' column (not a sweep.csv)")
    missing_keys = [k for k in keys if k not in base_header]
    if missing_keys:
        raise InputError(f"--check-against: the baseline does not vary {', '.join(missing_keys)} "
                         "(it is from another sweep)")
    cur = {str(r[0]): r for r in rows}
    bi = {c: j for j, c in enumerate(base_header)}
    ci = {c: j for j, c in enumerate(header)}
    worse: list[Difference] = []
    better: list[Difference] = []
    for br in base_rows:
        if len(br) != len(base_header):
            raise InputError(f"--check-against: a baseline row has {len(br)} cells, the header {len(base_header)}")
        v = br[bi["variant"]]
        r = cur.get(v)
        if r is None:
            raise InputError(f"--check-against: the baseline has variant {v}, this sweep does not "
                             "(it is from another sweep)")
        for k in keys:
            a, b = _num(br[bi[k]]), _num(r[ci[k]])
            same = (a is not None and b is not None and math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)) \
                or br[bi[k]] == r[ci[k]]
            if not same:
                raise InputError(f"--check-against: variant {v} has {k}={br[bi[k]]} in the baseline, "
                                 f"{r[ci[k]]} here (it is from another sweep)")
        for col in base_header:
            if col in keys or col == "variant":
                continue
            old = br[bi[col]]
            if col not in ci:
                worse.append(Difference(int(v), col, old, "", "missing"))
                continue
            new = r[ci[col]]
            if old == new:
                continue
            if col == "error":
                d = Difference(int(v), col, old, new, "worse" if new and not old else
                               ("better" if old and not new else "changed"))
                (better if d.change == "better" else worse).append(d)
                continue
            a, b = _num(old), _num(new)
            direction = _direction(col)
            if a is not None and b is not None:
                if abs(b - a) <= tolerance * max(abs(a), abs(b)) + abs_tolerance:
                    continue
                if direction == 0:
                    change = "changed"
                else:
                    change = "better" if (b - a) * direction > 0 else "worse"
            elif direction != 0 and a is None and b is not None:
                change = "better"
            elif direction != 0 and a is not None and b is None:
                change = "worse"
            else:
                change = "changed"
            d = Difference(int(v), col, old, new, change)
            if change == "better":
                better.append(d)
                if strict:
                    worse.append(d)
            else:
                worse.append(d)
    return worse, better
