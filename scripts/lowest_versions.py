"""The test suite against the lowest versions pyproject.toml allows.

Every direct dependency (``[project] dependencies`` and the ``test`` extra) is
pinned to its declared lower bound (``name>=X`` becomes ``name==X`` in a pip
constraints file); everything they pull in comes at its newest allowed
version, as ``uv``'s ``--resolution lowest-direct`` would have it.  The
project is installed with those constraints into a new virtual environment in
a temporary folder.  Nothing of this machine's site-packages is seen: the
environment is made without them, ``PYTHONPATH`` cleared and the user site off,
and checked before the tests (every path it imports from is its own, every
direct dependency at its bound).  pytest runs there on the given selection, by
default the fast tier (``-m "not slow"``).  Numba compiles into a cache folder of that environment,
so the kernels cached for the usual environment are left alone.

Usage::

    python3 scripts/lowest_versions.py                 # the fast tier
    python3 scripts/lowest_versions.py -- tests/test_spec.py -n 0 -q
    python3 scripts/lowest_versions.py --keep --venv /tmp/lowest   # keep (and reuse) the environment
    python3 scripts/lowest_versions.py --print         # only print the constraints
    python3 scripts/lowest_versions.py --make-only --venv /tmp/lowest   # make and check it, run nothing

Exit status: pytest's (0: passed), or 1 when the environment could not be made
(pip's output is in ``<venv>/install.log``, kept with ``--keep``); with
``--make-only``, 0 once the environment is made and checked (it is kept: a
later run with ``--keep --venv`` the same folder reuses it).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: what the fast tier runs by default (pyproject's addopts add ``-n auto``)
DEFAULT_SELECTION = ["-m", "not slow", "-q", "-p", "no:cacheprovider"]

_REQ = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*(\[[^\]]*\])?\s*(.*?)\s*(;.*)?$")


def requirements(pyproject: Path = ROOT / "pyproject.toml", extras=("test",)) -> list[str]:
    """The direct requirements: the project's dependencies and those of ``extras``."""
    project = tomllib.loads(pyproject.read_text())["project"]
    reqs = list(project.get("dependencies", []))
    for extra in extras:
        reqs += project.get("optional-dependencies", {}).get(extra, [])
    return reqs


def lower_bounds(reqs: list[str]) -> dict[str, str]:
    """name -> the version of its ``>=`` bound, for each requirement (extras dropped: a constraint
    names the distribution only).  A requirement with no lower bound is an error: say it."""
    out = {}
    for req in reqs:
        m = _REQ.match(req)
        if m is None:
            raise ValueError(f"cannot read the requirement {req!r}")
        name, spec = m.group(1), m.group(3)
        lows = [s.strip()[2:].strip() for s in spec.split(",") if s.strip().startswith(">=")]
        if not lows:
            raise ValueError(f"{req!r} declares no lower bound (name>=version)")
        out[name] = lows[0]
    return out


def constraints_text(bounds: dict[str, str]) -> str:
    return "".join(f"{name}=={version}\n" for name, version in bounds.items())


def isolated_env(venv: Path | None = None) -> dict:
    """This process's environment without what would let the machine's packages into the new
    environment: no ``PYTHONPATH``, ``PYTHONHOME`` or ``VIRTUAL_ENV``, the user site off
    (``PYTHONNOUSERSITE``); with ``venv``, its ``bin`` first on the ``PATH``."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["PYTHONNOUSERSITE"] = "1"
    if venv is not None:
        env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return env


#: Run by the new environment's Python: every path it imports from is inside that environment or
#: the base interpreter's standard library (no other site-packages), and each direct dependency's
#: installed version equals its bound (argv[1]: JSON of name -> bound).
CHECK = r"""
import importlib.metadata as md, json, re, sys, sysconfig
assert sys.prefix != sys.base_prefix, "not a virtual environment"
std = {sysconfig.get_path("stdlib"), sysconfig.get_path("platstdlib")}
leaks = [p for p in sys.path if "site-packages" in p and not p.startswith(sys.prefix)]
assert not leaks, f"site-packages from outside the environment on sys.path: {leaks}"
def key(v):
    parts = [int(x) for x in re.findall(r"\d+", v.split("+")[0])[:3]]
    while parts and parts[-1] == 0:
        parts.pop()
    return parts
wrong = {n: (b, md.version(n)) for n, b in json.loads(sys.argv[1]).items() if key(md.version(n)) != key(b)}
assert not wrong, f"not at the lower bound (bound, installed): {wrong}"
print(f"isolated: {sys.prefix}; every direct dependency at its lower bound")
"""


def run(cmd, **kw) -> int:
    print("+", " ".join(map(str, cmd)), flush=True)
    return subprocess.run(list(map(str, cmd)), **kw).returncode


def make_venv(venv: Path, python: str, text: str) -> bool:
    """A new environment at ``venv`` with the project installed (editable, with the test extra) under
    the constraints ``text`` (kept as ``venv/lowest-constraints.txt``); False when pip failed (its
    output in ``venv/install.log``)."""
    env = isolated_env()
    if run([python, "-m", "venv", "--clear", venv], env=env) != 0:  # without --system-site-packages
        return False
    constraints = venv / "lowest-constraints.txt"
    constraints.write_text(text)
    py = venv / "bin" / "python"
    log = venv / "install.log"
    with open(log, "w") as fh:
        ok = run([py, "-m", "pip", "install", "--upgrade", "pip"], stdout=fh, stderr=subprocess.STDOUT, env=env) == 0
        # a constraints file given here replaces any the machine's pip configuration names
        ok = ok and run([py, "-m", "pip", "install", "--constraint", constraints, "-e", f"{ROOT}[test]"],
                        stdout=fh, stderr=subprocess.STDOUT, env=env) == 0
    if not ok:
        print(log.read_text()[-4000:], file=sys.stderr)
        print(f"pip failed: {log}", file=sys.stderr)
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--python", default=sys.executable, help="the Python to make the environment with "
                    "(default: the one running this script)")
    ap.add_argument("--venv", type=Path, help="where to make the environment (default: a new temporary folder)")
    ap.add_argument("--keep", action="store_true", help="keep the environment; an existing --venv is reused")
    ap.add_argument("--print", action="store_true", help="print the constraints and stop")
    ap.add_argument("--make-only", action="store_true", help="make and check the environment at --venv, keep "
                    "it and stop (no tests): a later run with --keep and that --venv reuses it")
    ap.add_argument("pytest_args", nargs="*", help="after --: pytest's arguments (default: the fast tier, "
                    f"{' '.join(DEFAULT_SELECTION)})")
    args = ap.parse_args(argv)
    if args.make_only and args.venv is None:
        ap.error("--make-only needs --venv: the folder a later run with --keep reuses")
    keep = args.keep or args.make_only

    bounds = lower_bounds(requirements())
    text = constraints_text(bounds)
    if args.print:
        print(text, end="")
        return 0
    venv = args.venv or Path(tempfile.mkdtemp(prefix="cdpr-lowest-")) / "venv"
    try:
        print(f"lower bounds:\n{text}", flush=True)
        if not (keep and (venv / "bin" / "python").exists()) and not make_venv(venv, args.python, text):
            return 1
        py = venv / "bin" / "python"
        env = isolated_env(venv)
        freeze = subprocess.run([py, "-m", "pip", "freeze", "--exclude-editable"], capture_output=True, text=True,
                                env=env)
        print(f"installed ({venv}):\n{freeze.stdout}", flush=True)
        if run([py, "-c", CHECK, json.dumps(bounds)], cwd=venv, env=env) != 0:
            return 1
        if args.make_only:
            return 0
        env["NUMBA_CACHE_DIR"] = str(venv / "numba-cache")  # not the usual environment's cache
        return run([py, "-m", "pytest", *(args.pytest_args or DEFAULT_SELECTION)], cwd=ROOT, env=env)
    finally:
        if not keep:
            shutil.rmtree(venv if args.venv else venv.parent, ignore_errors=True)

if __name__ == "__main__":
    sys.exit(main())
