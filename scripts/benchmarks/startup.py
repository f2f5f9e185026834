"""What a short command costs to start, in CPU time, against bare Python and numpy.

Each command runs in a new process (started as the installed ``cdpr-design`` starts,
:data:`~benchmarks.harness.ENTRY_POINT`, from the repository root, the
picture worker off so that every CPU second is counted: the pictures are then drawn in the
command's process, which loads matplotlib), in interleaved rounds; the figure is the user + system
CPU of the process and what it waits for, less sensitive than wall time to other work on a shared
machine.  The baseline is ``python -c "import numpy"`` timed in the same rounds: a command's
start-up is what it adds to it.  Beside each command, the heavy libraries its process loaded
(``-X importtime``) -- a short command should load only what it uses.
"""

from __future__ import annotations

import sys

from benchmarks import harness as h

OPTIONS = {}
CLI = ("-c", h.ENTRY_POINT)
HEAVY = ("numba", "scipy", "matplotlib", "rich", "pyarrow", "typer", "yaml")


def commands(out: str) -> dict[str, list[str]]:
    planar2 = str(h.ROOT / "designs" / "planar2.yaml")
    return {
        "python -c pass": ["-c", "pass"],
        "python -c 'import numpy'": ["-c", "import numpy"],
        "cdpr-design --help": [*CLI, "--help"],
        "cdpr-design schema": [*CLI, "schema"],
        "cdpr-design pose --help": [*CLI, "pose", "--help"],
        "cdpr-design pose planar2 --json": [*CLI, "pose", planar2, "--at", "0.75,0.75", "--json"],
        "cdpr-design check planar2 (exit 1)": [*CLI, "check", planar2],
        "cdpr-design workspace planar2 --json": [*CLI, "workspace", planar2, "--json", "--quiet",
                                                 "--overwrite", "--out", out],
    }


def start(argv: list[str], env: dict):
    """The command (exit 0, or 1: ``check``'s requirement not met)."""
    return h.process([sys.executable, *argv], env, ok=(0, 1))


def run(b: h.Bench) -> None:
    env = h.env_for(CDPR_DESIGN_PICTURE_WORKER="0")
    cmds = commands(str(b.folder("out")))
    for argv in cmds.values():
        start(argv, env)  # bytecode and numba's cache written
    t = h.rounds({k: (lambda a=argv: start(a, env)[0]) for k, argv in cmds.items()}, b.rounds)
    base = t["python -c 'import numpy'"]
    for k, argv in cmds.items():
        _, r = start(["-X", "importtime", *argv], env)
        names = {line.rsplit("|", 1)[-1].strip() for line in r.stderr.splitlines() if line.startswith("import time:")}
        loads = ", ".join(x for x in HEAVY if x in names) or "-"
        cpu = h.spread(x.cpu for x in t[k])
        b.row(f"start-up: {k}", f"{cpu.text('.3f')} CPU-s; loads {loads}",
              h.ratios(t[k], base, "cpu") if k.startswith("cdpr") else None,
              "CPU ÷ python -c 'import numpy'" if k.startswith("cdpr") else "")
