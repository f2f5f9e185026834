#!/usr/bin/env python3
"""Run the benchmarks and print one table of every ratio (markdown, for docs/performance.md).

    python3 scripts/bench.py                       # every benchmark
    python3 scripts/bench.py outputs first_run --quick
    python3 scripts/bench.py first_run --baseline /tmp/base --set first_run.designs=ipanema3,planar2
    python3 scripts/bench.py --list

Each benchmark is a module of ``scripts/benchmarks`` with a ``run(bench)`` and its options
(``OPTIONS``, ``QUICK``: smaller sizes); ``--set NAME.KEY=VALUE`` changes one.  ``--baseline DIR``
is another checkout (e.g. ``git worktree add /tmp/base main``) the command-level benchmarks run
beside this one, interleaved.  The old script names (``bench_outputs``) are accepted.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(1, str(Path(__file__).resolve().parents[1]))

from benchmarks import harness  # noqa: E402

#: name -> what it measures; every one of them is ``benchmarks.<name>``.
BENCHMARKS = {
    "outputs": "IPAnema 3's whole workspace command and its kernels against a per-pose scipy HiGHS LP",
    "first_run": "every shipped design's first workspace command, cold (empty numba cache) and warm",
    "workspace": "planar2: numba kernel against the numpy engine; the quick start, cold and warm",
    "wrench": "IPAnema 3's sweep against per-pose linprog, cvxpy/OSQP and a plain HSM; CASPR's IPAnema 2 grid",
    "startup": "short commands' start-up CPU against bare Python and numpy",
    "csv": "the numpy and numba CSV formatters, each in a fresh process",
    "pictures": "the workspace pictures' CPU, against another checkout's",
    "stiffness": "the stiffness kernel's cost beside the sweep's",
    "boundary": "IPAnema 3's sweep with the workspace's boundary and the frame loads against without",
    "accelerations": "workspace --accelerations against the plain sweep; the acceleration kernel a pose",
    "interference": "IPAnema 3's sweep with interference checks against without",
    "hanging": "planar2's tilt map, kernel against per-pose scipy",
    "hanging_spatial": "crane4's hanging orientations against per-position scipy",
    "hanging_cables": "a hanging effector's sweep on elastic cables, with --stiffness and --collisions, against ideal",
    "catenary": "the batched catenary inverse against per-cable scipy",
    "sagging": "sagging-cable workspaces against the ideal model and per-pose scipy",
    "sag_analyses": "sagging cables' interference checks and orientation workspaces against straight cables'",
    "setpoints": "real-cable set-points along a path against a per-pose loop; the simulation",
    "certify": "the certified paving against a grid sweep",
    "sweep": "sweep backends: process pool and Dask against one process",
    "optimize": "optimize trials per second, 1 and 2 workers, against the evaluation alone",
    "bridge": "the PLC gateway against the loopback test PLC",
}


def _value(text: str):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def options(module, quick: bool, sets: dict) -> dict:
    opt = dict(getattr(module, "OPTIONS", {}))
    if quick:
        opt.update(getattr(module, "QUICK", {}))
    for key, value in sets.items():
        if key not in opt:
            raise SystemExit(f"--set {module.__name__.split('.')[-1]}.{key}: no such option "
                             f"(options: {', '.join(opt) or 'none'})")
        opt[key] = value
    return opt


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer rounds")
    ap.add_argument("--rounds", type=int, default=None, help="interleaved rounds (default 3, --quick 2)")
    ap.add_argument("--baseline", type=Path, help="another checkout, run beside this one where a benchmark can")
    ap.add_argument("--set", action="append", default=[], metavar="NAME.KEY=VALUE", help="a benchmark's option")
    ap.add_argument("--markdown", type=Path, help="also write the table to this file")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and their options")
    args = ap.parse_args(argv)
    names = [n.removeprefix("bench_").removesuffix(".py") for n in args.names] or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        ap.error(f"unknown benchmark {', '.join(unknown)} (known: {', '.join(BENCHMARKS)})")
    if args.list:
        for n, what in BENCHMARKS.items():
            m = importlib.import_module(f"benchmarks.{n}")
            print(f"{n:16s} {what}\n{'':16s} options {getattr(m, 'OPTIONS', {})}")
        return 0
    sets: dict[str, dict] = {}
    for item in args.set:
        key, _, value = item.partition("=")
        name, _, opt = key.partition(".")
        sets.setdefault(name, {})[opt] = _value(value)
    n_rounds = args.rounds or (2 if args.quick else 3)
    report = harness.Report()
    print(harness.machine(), flush=True)
    with tempfile.TemporaryDirectory(prefix="cdpr-bench-") as tmp:
        for name in names:
            module = importlib.import_module(f"benchmarks.{name}")
            opt = options(module, args.quick, sets.get(name, {}))
            print(f"\n## {name}: {BENCHMARKS[name]}\n  options {opt}", flush=True)
            folder = Path(tmp) / name
            folder.mkdir()
            module.run(harness.Bench(name, opt, report, folder, args.baseline, args.quick, n_rounds))
    table = report.markdown()
    print(f"\n{harness.machine()}\n\n{table}")
    if args.markdown:
        args.markdown.write_text(table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
