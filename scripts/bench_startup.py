#!/usr/bin/env python3
"""Benchmark: what a short command costs to start, in CPU time, against bare Python and numpy.

Each command runs in a new process (``python -m cdpr_design ...`` from the
repository root, picture worker off so that every CPU second is counted: the
pictures are then drawn in the command's process, which loads matplotlib),
``--repeat`` times; the figure is the least user + system CPU time
of the process and what it waits for (``resource.getrusage(RUSAGE_CHILDREN)``
around it), less sensitive than wall time to other work on a shared machine.
The baselines are ``python -c pass`` and ``python -c "import numpy"`` timed
the same way: a command's start-up is what it adds to them.  Beside each
command, the heavy libraries its process loaded (``-X importtime``): numba
(0.2-0.3 s to import, about 0.8 s with its first cached kernel), scipy,
matplotlib, rich, pyarrow -- a short command should load only what it uses.

    python3 scripts/bench_startup.py [--repeat 3]

Figures (the 2-core machine shared with five sessions, load average 12.7, least of 3)::

    python -c pass                            0.036 s   loads: -
    python -c 'import numpy'                  0.199 s   loads: -
    cdpr-design --help                        0.321 s   loads: typer, yaml
    cdpr-design schema                        0.439 s   loads: typer, yaml
    cdpr-design pose --help                   0.325 s   loads: typer, yaml
    cdpr-design pose planar2 --json           1.240 s   loads: numba, scipy, typer, yaml
    cdpr-design check planar2 (exit 1)        0.539 s   loads: rich, typer, yaml
    cdpr-design workspace planar2 --json      2.003 s   loads: matplotlib, typer, yaml
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("numba", "scipy", "matplotlib", "rich", "pyarrow", "typer", "yaml")


def commands(out: Path) -> list[tuple[str, list[str]]]:
    planar2 = str(ROOT / "designs" / "planar2.yaml")
    return [
        ("python -c pass", ["-c", "pass"]),
        ("python -c 'import numpy'", ["-c", "import numpy"]),
        ("cdpr-design --help", ["-m", "cdpr_design", "--help"]),
        ("cdpr-design schema", ["-m", "cdpr_design", "schema"]),
        ("cdpr-design pose --help", ["-m", "cdpr_design", "pose", "--help"]),
        ("cdpr-design pose planar2 --json", ["-m", "cdpr_design", "pose", planar2, "--at", "0.75,0.75", "--json"]),
        ("cdpr-design check planar2 (exit 1)", ["-m", "cdpr_design", "check", planar2]),
        ("cdpr-design workspace planar2 --json", ["-m", "cdpr_design", "workspace", planar2, "--json", "--quiet",
                                                  "--overwrite", "--out", str(out)]),
    ]


def run(argv: list[str], env: dict) -> subprocess.CompletedProcess:
    """The command; exit 0, or 1 (``check``: a requirement not met), else an error."""
    r = subprocess.run([sys.executable, *argv], env=env, cwd=ROOT, capture_output=True, text=True)
    if r.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(argv)}: exit {r.returncode}\n{r.stderr[-2000:]}")
    return r


def cpu_of(args: list[str], env: dict) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    run(args, env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def heavy_loaded(args: list[str], env: dict) -> list[str]:
    r = run(["-X", "importtime", *args], env)
    names = {line.rsplit("|", 1)[-1].strip() for line in r.stderr.splitlines() if line.startswith("import time:")}
    return [h for h in HEAVY if h in names]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    env = dict(os.environ, PYTHONPATH=str(ROOT), CDPR_DESIGN_PICTURE_WORKER="0")
    print(f"load average {os.getloadavg()[0]:.1f}; CPU s (user + system), least of {args.repeat}")
    with tempfile.TemporaryDirectory() as tmp:
        for label, argv in commands(Path(tmp) / "out"):
            cpu_of(argv, env)  # bytecode and numba's cache written
            best = min(cpu_of(argv, env) for _ in range(args.repeat))
            print(f"  {label:40s} {best:6.3f} s   loads: {', '.join(heavy_loaded(argv, env)) or '-'}")


if __name__ == "__main__":
    main()
