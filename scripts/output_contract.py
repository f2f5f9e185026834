#!/usr/bin/env python3
"""Reference CSV outputs of every shipped design, and their comparison across versions.

``generate DIR`` runs every table-writing command on every design in
``designs/`` (workspace, with ``--collisions`` and ``--orientations`` where the
motion has them; size-motors; report; trajectory, simulate and a small sweep
where the spec has trajectories) into ``DIR/<case>/``, one process per
command, as a user would.  ``compare OLD NEW`` then checks that every CSV of
OLD is byte-identical in NEW up to the one change the output contract allows
(a cell ``-0`` is written ``0``), and prints what differs.

Run ``generate`` with the old code and with the new, then ``compare``:

    git stash; python3 scripts/output_contract.py generate /tmp/old; git stash pop
    python3 scripts/output_contract.py generate /tmp/new
    python3 scripts/output_contract.py compare /tmp/old /tmp/new
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cases(designs: list[Path]) -> list[tuple[str, list[str]]]:
    """(case name, command-line arguments) of every table-writing command on every design."""
    sys.path.insert(0, str(ROOT))
    from cdpr_design.model import spec

    out = []
    for path in designs:
        d = spec.load(path)
        n = d.name
        out.append((f"{n}-workspace", ["workspace", str(path)]))
        out.append((f"{n}-wrench", ["workspace", str(path), "--kind", "wrench-feasible", "--step",
                                    "0.05" if d.motion.planar else "0.4"]))
        out.append((f"{n}-collisions", ["workspace", str(path), "--collisions", "--step",
                                        "0.05" if d.motion.planar else "0.4"]))
        if d.motion.rotation_coords:
            step = "0.1" if d.motion.planar else "0.8"
            out.append((f"{n}-total", ["workspace", str(path), "--orientations", "total", "--step", step]))
            out.append((f"{n}-range", ["workspace", str(path), "--orientations", "range", "--step", step]))
        out.append((f"{n}-size-motors", ["size-motors", str(path)]))
        out.append((f"{n}-report", ["report", str(path)]))
        for t in d.trajectories:
            out.append((f"{n}-trajectory-{t}", ["trajectory", str(path), t, "--cycle-time", "0.01"]))
        if d.trajectories:
            t = next(iter(d.trajectories))
            out.append((f"{n}-simulate-{t}", ["simulate", str(path), t, "--cycle-time", "0.01"]))
            out.append((f"{n}-sweep", ["sweep", str(path), "--vary", "effector.mass=0.5:2:3",
                                       "--vary", "tension.1=15,25", "--step", "0.05", "--workers", "1"]))
    return out


def generate(folder: Path, only: str | None) -> None:
    designs = sorted((ROOT / "designs").glob("*.yaml"))
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    for name, args in cases(designs):
        if only and not re.search(only, name):
            continue
        out = folder / name
        cmd = [sys.executable, "-m", "cdpr_design", *args, "--out", str(out), "--quiet", "--overwrite"]
        r = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True)
        print(f"{name:40s} exit {r.returncode}" + (f"  {r.stderr.strip()[-200:]}" if r.returncode else ""))


_NEG0 = re.compile(r"(?<![^,\n])-0(?![^,\n])")


def compare(old: Path, new: Path) -> int:
    """Number of CSVs of ``old`` that differ in ``new`` beyond ``-0`` -> ``0``."""
    bad = same = neg0 = skipped = 0
    for a in sorted(old.rglob("*.csv")):
        b = new / a.relative_to(old)
        if not b.parent.exists():  # a case not generated in NEW (generate --only)
            skipped += 1
            continue
        if not b.exists():
            print(f"missing: {b}")
            bad += 1
            continue
        ta, tb = a.read_text(), b.read_text()
        fixed = _NEG0.sub("0", ta)
        if fixed == tb:
            same += 1
            neg0 += ta != fixed
            continue
        bad += 1
        la, lb = fixed.split("\n"), tb.split("\n")
        first = next((i for i, (x, y) in enumerate(zip(la, lb)) if x != y), min(len(la), len(lb)))
        print(f"DIFFERS: {a.relative_to(old)} (lines {len(la)} / {len(lb)}), first at line {first + 1}:\n"
              f"  old: {la[first][:200] if first < len(la) else '<end>'}\n"
              f"  new: {lb[first][:200] if first < len(lb) else '<end>'}")
    print(f"{same} identical ({neg0} of them after -0 -> 0), {bad} differ"
          + (f", {skipped} in cases not generated in {new}" if skipped else ""))
    return bad


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    g = sub.add_parser("generate")
    g.add_argument("folder", type=Path)
    g.add_argument("--only", help="regular expression: only the cases whose name matches")
    c = sub.add_parser("compare")
    c.add_argument("old", type=Path)
    c.add_argument("new", type=Path)
    a = ap.parse_args(argv)
    if a.what == "generate":
        generate(a.folder, a.only)
        return 0
    return 1 if compare(a.old, a.new) else 0


if __name__ == "__main__":
    sys.exit(main())
