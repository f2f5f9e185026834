"""The benchmarks' one harness: timing, interleaved rounds, numba's cache cold or warm, the table.

Every benchmark in this package compares a candidate with a baseline run in the same process
(a per-pose scipy solve, the numpy engine, another checkout of the project), in interleaved
rounds, and reports the ratio of each round: on a shared machine absolute times drift by the
minute, a ratio measured within one round much less.  A figure is the median of the rounds
with their range.  Times are wall clock and CPU seconds (user + system of this process and
its threads, or of a child process and everything it waited for).

- :func:`timed` / :func:`repeat` / :func:`rounds`: a call, a call ``n`` times, variants in
  interleaved rounds (the order rotated every round);
- :func:`process` / :func:`python` / :func:`command`: a new process (``python -c CODE``,
  ``python -m cdpr_design ...``) with a given checkout on the path and numba's cache in a
  given folder (:meth:`Bench.fresh_cache`: a new, empty one, for a cold run);
- :class:`Spread`: the median and range of samples; :func:`ratios`: per-round ratios;
- :class:`Report`: the rows every benchmark adds, printed as one markdown table.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Sequence

#: The checkout this harness belongs to (its ``designs/``, and the package benchmarked by default).
ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Timing:
    """Wall-clock and CPU seconds of one measured run."""

    wall: float
    cpu: float

    def get(self, what: str) -> float:
        return self.wall if what == "wall" else self.cpu


@dataclass(frozen=True)
class Spread:
    """Samples summarised as their median and range."""

    values: tuple

    @property
    def median(self) -> float:
        return statistics.median(self.values)

    @property
    def lo(self) -> float:
        return min(self.values)

    @property
    def hi(self) -> float:
        return max(self.values)

    def text(self, fmt: str | None = None) -> str:
        """``median (lo–hi)``, three significant digits (whole numbers from 100) unless ``fmt``."""
        def f(v):
            return format(v, fmt) if fmt else (f"{v:,.0f}" if abs(v) >= 100 else f"{v:.3g}")

        if len(self.values) == 1 or self.lo == self.hi:
            return f(self.median)
        return f"{f(self.median)} ({f(self.lo)}–{f(self.hi)})"


def spread(values: Iterable[float]) -> Spread:
    return Spread(tuple(float(v) for v in values))


# ----------------------------------------------------------------------------
# Timing in this process
# ----------------------------------------------------------------------------


def timed(fn: Callable, *args, **kw):
    """(:class:`Timing`, result) of ``fn(*args, **kw)`` in this process (CPU: all its threads)."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args, **kw)
    return Timing(time.perf_counter() - t0, time.process_time() - c0), out


def repeat(fn: Callable, n: int) -> tuple[list[Timing], object]:
    """``fn()`` ``n`` times: the timings and the last result."""
    times, out = [], None
    for _ in range(max(1, n)):
        t, out = timed(fn)
        times.append(t)
    return times, out


def best(times: Sequence[Timing], what: str = "wall") -> float:
    return min(t.get(what) for t in times)


def rounds(variants: dict[str, Callable[[], Timing | float]], n: int) -> dict[str, list[Timing]]:
    """Interleaved rounds: each round runs every variant once, the order rotated from round to
    round, so that the variants share the machine's drift.  A variant returns its own
    :class:`Timing` (or a wall time), else it is timed around its call."""
    names = list(variants)
    out: dict[str, list[Timing]] = {k: [] for k in names}
    for r in range(max(1, n)):
        for k in names[r % len(names):] + names[:r % len(names)]:
            t, got = timed(variants[k])
            if isinstance(got, Timing):
                t = got
            elif isinstance(got, float):
                t = Timing(got, got)
            out[k].append(t)
    return out


def ratios(baseline: Sequence[Timing | float], candidate: Sequence[Timing | float], what: str = "wall",
           scale: float = 1.0) -> Spread:
    """Per-round ratios ``scale * baseline / candidate`` (``scale``: e.g. the grid's poses over the
    baseline's sample)."""
    def v(x):
        return x.get(what) if isinstance(x, Timing) else float(x)

    return spread(scale * v(b) / v(c) for b, c in zip(baseline, candidate))


# ----------------------------------------------------------------------------
# New processes
# ----------------------------------------------------------------------------


def env_for(root: Path = ROOT, cache: str | Path | None = None, **extra: str) -> dict:
    """The environment of a child: ``root`` first on the path, numba's cache in ``cache`` (else
    the usual one), Python's bytecode cache allowed (an installed package has its ``.pyc``
    files), and ``extra`` variables."""
    env = dict(os.environ, PYTHONPATH=str(root))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    env.update(extra)
    return env


def process(argv: Sequence[str], env: dict | None = None, cwd: Path = ROOT, ok=(0,)):
    """(:class:`Timing`, CompletedProcess) of a new process: wall, and the CPU of it and of every
    process it waited for.  An exit status not in ``ok`` stops the benchmark."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(list(map(str, argv)), env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode not in ok:
        raise SystemExit(f"{' '.join(map(str, argv))} failed ({r.returncode}):\n{r.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Timing(wall, cpu), r


def python(code: str, *args, root: Path = ROOT, cache=None, **extra):
    """(:class:`Timing`, CompletedProcess) of ``python -c code args...`` on ``root``."""
    return process([sys.executable, "-c", code, *args], env_for(root, cache, **extra), cwd=root)


def child_json(code: str, *args, root: Path = ROOT, cache=None, **extra) -> dict:
    """The JSON a ``python -c code`` child prints as its last line."""
    _, r = python(code, *args, root=root, cache=cache, **extra)
    return json.loads(r.stdout.strip().splitlines()[-1])


def call_in_child(function: str, *args, cache=None, **extra):
    """``benchmarks.MODULE.FUNCTION(*args)`` in a new process (numba's cache in ``cache``: a fresh
    one for a cold run), returning what it returns (JSON)."""
    module, _, name = function.rpartition(".")
    code = (f"import json, sys; sys.path.insert(0, {str(Path(__file__).parents[1])!r}); "
            f"from {module} import {name}; print(json.dumps({name}(*json.loads(sys.argv[1]))))")
    return child_json(code, json.dumps(list(args)), cache=cache, **extra)


#: What the installed ``cdpr-design`` command runs (the entry point pip writes for
#: ``[project.scripts]``), run on any checkout with ``-c``.  Not ``python -m cdpr_design``: that
#: starts the command two frames deeper (runpy's), and a cold first run's system time depends on
#: how deep the stack is where numba compiles (docs/performance.md, "Where a first run's system
#: time goes").
ENTRY_POINT = "import sys\nfrom cdpr_design.__main__ import main\nsys.exit(main())"


def command(args: Sequence[str], root: Path = ROOT, cache=None, **extra):
    """(:class:`Timing`, parsed ``--json`` output) of ``cdpr-design ARGS --json`` on ``root``
    (:data:`ENTRY_POINT`)."""
    t, r = process([sys.executable, "-c", ENTRY_POINT, *args, "--json"], env_for(root, cache, **extra), cwd=root)
    return t, json.loads(r.stdout)


# ----------------------------------------------------------------------------
# The run and its table
# ----------------------------------------------------------------------------


@dataclass
class Row:
    bench: str
    what: str
    value: str
    ratio: Spread | None = None
    against: str = ""
    note: str = ""


@dataclass
class Report:
    rows: list[Row] = field(default_factory=list)

    def markdown(self) -> str:
        lines = ["| benchmark | measurement | figure | ratio: median (range) | against (the same rounds) |",
                 "|---|---|---|---|---|"]
        for r in self.rows:
            ratio = f"{r.ratio.text()}×" if r.ratio is not None else ""
            value = r.value + (f"; {r.note}" if r.note else "")
            lines.append(f"| {r.bench} | {r.what} | {value} | {ratio} | {r.against} |")
        return "\n".join(lines)


def machine() -> str:
    """One line: the date, the machine, its load, Python, numba and the checkout measured."""
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        cpu = platform.processor() or platform.machine()
    try:
        import numba

        nb = numba.__version__
    except ImportError:
        nb = "-"
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "-"
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {cpu}, {os.cpu_count()} cores, "
            f"load average {load}; Python {platform.python_version()}, numba {nb}; checkout {commit}")


class Bench:
    """What a benchmark's ``run`` is given: its options, the baseline checkout, a temporary folder,
    a random generator and the report to add its rows to."""

    def __init__(self, name: str, options: dict, report: Report, tmp: Path, baseline: Path | None,
                 quick: bool, rounds: int):
        self.name, self.opt, self.report, self.tmp = name, options, report, tmp
        self.baseline, self.quick, self.rounds = baseline, quick, rounds
        import numpy as np

        self.rng = np.random.default_rng(0)

    def fresh_cache(self) -> Path:
        """A new, empty folder for numba's cache: a run given it compiles every kernel it needs."""
        return Path(tempfile.mkdtemp(prefix="numba-", dir=self.tmp))

    def folder(self, name: str) -> Path:
        """A new output folder under the run's temporary folder."""
        return Path(tempfile.mkdtemp(prefix=f"{name}-", dir=self.tmp))

    def row(self, what: str, value: str, ratio: Spread | None = None, against: str = "", note: str = "") -> None:
        self.report.rows.append(Row(self.name, what, value, ratio, against, note))
        shown = f" = {ratio.text()}× {against}" if ratio is not None else ""
        print(f"  {what}: {value}{shown}" + (f" ({note})" if note else ""), flush=True)

    def say(self, text: str) -> None:
        print(f"  {text}", flush=True)


def option_cost(b: Bench, designs: dict, option: str, what: str, threads: int) -> None:
    """A row per design: the whole workspace sweep as a command runs it (``workspaces.run``: the
    plan, its wrappers, the maps; no files) with ``Analysis(option=True)`` against without, the
    two runs of a round back to back (each order in every other round), CPU on ``threads`` kernel
    threads (the caller's setting): the median and range of the rounds' own ratios.  ``designs``:
    name -> Design; ``what`` names the option in the rows."""
    from cdpr_design import workspaces as ws

    for d in designs.values():  # the plan's kernels compiled or loaded outside the timing
        one = ws.grid.first_pose(ws.make_grid(d))
        ws.run(d, ws.Analysis(**{option: True}), grid=one, tilt=False)
        ws.run(d, grid=one, tilt=False)
    for n, d in designs.items():
        pairs = []
        for r in range(b.rounds):
            pair = {}
            for on in ((False, True) if r % 2 == 0 else (True, False)):
                pair[on], _ = timed(ws.run, d, ws.Analysis(**{option: on}), tilt=False)
            pairs.append(pair)
        b.row(f"{n} ({d.workspace.grid.size:,} poses): the whole workspace sweep with {what}",
              seconds(spread(p[True].cpu for p in pairs)) + " CPU",
              ratios([p[True] for p in pairs], [p[False] for p in pairs], "cpu"),
              f"time ÷ without {what} (CPU, {threads} thread(s))")


def seconds(t: Spread | float) -> str:
    v = t.text(".3g") if isinstance(t, Spread) else format(t, ".3g")
    return f"{v} s"


def per_pose(seconds_: float, poses: int) -> str:
    us = seconds_ / poses * 1e6
    return f"{us:.3g} µs a pose" if us < 1000 else f"{us / 1000:.3g} ms a pose"
