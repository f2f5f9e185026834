#!/usr/bin/env python3
"""Golden outputs: a sha256 of every file every shipped design's commands write, before and after a change.

For every design in ``designs/*.yaml`` this runs, one process per command as a
user would, into ``ROOT/<design>/<case>/``:

==========================  ====================================================================
case                        command (every one with ``--json --quiet`` and a coarse ``--step``)
==========================  ====================================================================
``workspace``               ``workspace`` (CSV)
``workspace-parquet``       ``workspace --format parquet --html``
``wrench-feasible``         ``workspace --kind wrench-feasible`` (designs with ``workspace.external_wrench``)
``wrench-closure``          ``workspace --kind wrench-closure``
``collisions``              ``workspace --collisions``
``orientations-total``      ``workspace --orientations total`` (motions with a rotation: 1R2T, 3R3T)
``orientations-range``      ``workspace --orientations range`` (the same)
``pose``                    ``pose --at P --json``: P is the centre of ``requirements.task_box``, else
                            of ``workspace.grid``, at ``workspace.orientation`` (position only with
                            ``effector.orientation: free``)
``fk``                      ``fk --lengths L --json``: L the lengths ``pose`` gave (its
                            ``unstretched_lengths`` with elastic or sagging cables)
``size-motors``             ``size-motors --json``
``report``                  ``report --json``
==========================  ====================================================================

The step is the grid's longest edge / 24 for planar motions and / 8 for spatial
ones (``--orientations``: / 12 and / 4), rounded to 3 significant digits.
What ``--json`` prints on stdout is kept as ``stdout.json`` in the case's folder
(``pose.json``, ``fk.json`` for those two).

The manifest (``ROOT/manifest.json`` unless ``--manifest``) holds, per case, the
command line and its exit status (and, when it is not 0, the last line of its
stderr with ROOT and the code's folder replaced by ``<root>`` and ``<code>``),
and a sha256 per output file.  Hidden files (``.cdpr-design-outputs``,
``.cdpr-design.lock``) are not listed: they record what was written, not
results.  Before hashing, what legitimately varies between two runs of the same
code is normalised out (and nothing else):

- JSON files (``*.json``, stdout): every key named ``elapsed_s``, ``timings``
  or ``trials_per_s`` is removed, at any depth (wall-clock seconds); the JSON is
  then re-serialised with sorted keys.  No output holds a date or an absolute
  path (``--out`` is the only absolute path given, and no summary of the
  commands run here prints it); the spec is passed as ``designs/<name>.yaml``
  relative to the code's folder, so the Parquet metadata's ``spec`` is the same
  on every machine.
- ``report.html``: the cells of the summary table's rows ``sweep time`` and
  ``load / sweep / write / pictures / total`` (wall-clock seconds) become ``*``.
- CSV, Parquet and PNG files are hashed as written (the PNGs carry no date:
  matplotlib writes only a ``Software`` text chunk into a PNG).

numba's cache is a new, empty folder for every run (``ROOT/.numba-cache``), not the
user's: the machine code numba caches for a kernel can differ with what the cache
already held when it was compiled (the same signatures, objects of other sizes), and
with it the last bits of results (IPAnema 3's ``acceleration_direction`` by one in its
17th digit, on a long-used cache against empty ones), so a run starting from whatever
earlier runs left behind can differ from another of the same code.  With the default
``--jobs 1`` the commands run, and compile, in the same order every time.

``--compare OLD.json`` compares this run's manifest with OLD's: every file that
differs, is missing or is new, every case whose exit status or error changed;
for CSV and HTML the first differing line, for JSON the first differing key
(both read from the two roots the manifests name), for Parquet the first
differing column or the metadata.  Exit status 1 when anything differs.

    python3 scripts/golden_outputs.py /tmp/golden-a                   # run, write the manifest
    python3 scripts/golden_outputs.py /tmp/golden-b --compare /tmp/golden-a/manifest.json
    python3 scripts/golden_outputs.py --compare OLD.json --with NEW.json   # two existing runs
    python3 scripts/golden_outputs.py /tmp/old --code /work/old-checkout  # run another checkout's code
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]

#: JSON keys removed at any depth before hashing: wall-clock seconds.
VOLATILE_KEYS = frozenset({"elapsed_s", "timings", "trials_per_s"})
#: report.html summary rows whose value is wall-clock seconds.
_HTML_TIMES = re.compile(r"(<tr><td>(?:sweep time|[a-z]+(?: / [a-z]+)+)</td><td>)[^<]*(</td></tr>)")


# ----------------------------------------------------------------------------
# The cases
# ----------------------------------------------------------------------------

def _step(extent: float, divisions: int) -> str:
    return f"{extent / divisions:.3g}"


def _centre(box: dict) -> list[float]:
    return [(float(lo) + float(hi)) / 2 for lo, hi in zip(box["lower"], box["upper"])]


def _pose_at(spec: dict) -> list[float]:
    """Centre of the task box (else the grid), at the workspace orientation (position only when free)."""
    box = (spec.get("requirements") or {}).get("task_box") or spec["workspace"]["grid"]
    pos = [round(v, 6) for v in _centre(box)]
    if (spec.get("effector") or {}).get("orientation") == "free":
        return pos
    return pos + [float(v) for v in (spec["workspace"].get("orientation") or [])]


def cases(spec_path: Path) -> list[tuple[str, list[str]]]:
    """(case, command-line arguments without --out) of one design; the spec path relative to the code."""
    spec = yaml.safe_load(spec_path.read_text())
    rel = f"designs/{spec_path.name}"
    grid = spec["workspace"]["grid"]
    planar = spec["motion"] in ("2T", "1R2T")
    extent = max(float(hi) - float(lo) for lo, hi in zip(grid["lower"], grid["upper"]))
    step = _step(extent, 24 if planar else 8)
    ostep = _step(extent, 12 if planar else 4)
    ws = ["workspace", rel, "--step", step, "--json", "--quiet"]
    out = [("workspace", ws),
           ("workspace-parquet", ws + ["--format", "parquet", "--html"])]
    if spec["workspace"].get("external_wrench"):
        out.append(("wrench-feasible", ws + ["--kind", "wrench-feasible"]))
    out.append(("wrench-closure", ws + ["--kind", "wrench-closure"]))
    out.append(("collisions", ws + ["--collisions"]))
    if spec["motion"] in ("1R2T", "3R3T"):
        for mode in ("total", "range"):
            out.append((f"orientations-{mode}", ["workspace", rel, "--step", ostep, "--orientations", mode,
                                                "--json", "--quiet"]))
    out.append(("pose", ["pose", rel, "--at", ",".join(repr(v) for v in _pose_at(spec)), "--json", "--quiet"]))
    out.append(("fk", ["fk", rel, "--lengths", "<from pose>", "--json", "--quiet"]))
    out.append(("size-motors", ["size-motors", rel, "--step", step, "--json", "--quiet"]))
    out.append(("report", ["report", rel, "--step", step, "--json", "--quiet"]))
    return out


# ----------------------------------------------------------------------------
# Normalising and hashing
# ----------------------------------------------------------------------------

def _drop_volatile(v):
    if isinstance(v, dict):
        return {k: _drop_volatile(x) for k, x in v.items() if k not in VOLATILE_KEYS}
    if isinstance(v, list):
        return [_drop_volatile(x) for x in v]
    return v


def normalised(path: Path) -> bytes:
    """The bytes that are hashed: the file with what varies between runs of one code removed."""
    data = path.read_bytes()
    if path.suffix == ".json":
        try:
            obj = json.loads(data)
        except ValueError:
            return data  # not JSON (a failed command's stdout): hashed as it is
        return json.dumps(_drop_volatile(obj), sort_keys=True, indent=1).encode() + b"\n"
    if path.suffix == ".html":
        return _HTML_TIMES.sub(rb"\1*\2".decode(), data.decode()).encode()
    return data


def sha256(path: Path) -> str:
    return hashlib.sha256(normalised(path)).hexdigest()


# ----------------------------------------------------------------------------
# Running
# ----------------------------------------------------------------------------

def _run_case(code: Path, root: Path, design: str, case: str, args: list[str], env: dict) -> dict:
    folder = root / design / case
    folder.mkdir(parents=True, exist_ok=True)
    argv = list(args)
    if case == "fk":
        pose = json.loads((root / design / "pose" / "pose.json").read_text() or "null") if \
            (root / design / "pose" / "pose.json").exists() else None
        lengths = pose and (pose.get("unstretched_lengths") or pose.get("lengths"))
        if not lengths or any(v is None for v in lengths.values()):
            return {"argv": argv, "exit": None, "error": "no lengths from pose"}
        argv[argv.index("<from pose>")] = ",".join(repr(float(v)) for v in lengths.values())
    if argv[0] not in ("pose", "fk"):
        argv += ["--out", str(folder)]
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "cdpr_design", *argv], cwd=code, env=env,
                       capture_output=True, text=True)
    name = f"{case}.json" if case in ("pose", "fk") else "stdout.json"
    (folder / name).write_text(r.stdout)
    rec = {"argv": [a if a != str(folder) else "<out>" for a in argv], "exit": r.returncode,
           "wall_s": round(time.perf_counter() - t0, 2)}
    if r.returncode:
        lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
        last = lines[-1] if lines else ""
        rec["error"] = last.replace(str(root), "<root>").replace(str(code), "<code>")
        rec["traceback"] = "Traceback (most recent call last)" in r.stderr
    return rec


def run(root: Path, code: Path, only: str | None, jobs: int) -> dict:
    root = root.resolve()
    code = code.resolve()
    env = dict(os.environ, PYTHONPATH=str(code) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               NUMBA_CACHE_DIR=str(root / ".numba-cache"))
    plan = []
    for spec_path in sorted((code / "designs").glob("*.yaml")):
        design = spec_path.stem
        if only and not re.search(only, design):
            continue
        plan.append((design, cases(spec_path)))

    def one_design(item):
        design, todo = item
        return design, {case: _run_case(code, root, design, case, args, env) for case, args in todo}

    t0 = time.perf_counter()
    c0 = os.times()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        results = dict(pool.map(one_design, plan))
    c1 = os.times()
    files = {}
    for p in sorted(root.rglob("*")):
        hidden = any(part.startswith(".") for part in p.relative_to(root).parts)
        if p.is_file() and not hidden and p.name != "manifest.json":
            files[p.relative_to(root).as_posix()] = sha256(p)
    commit = subprocess.run(["git", "-C", str(code), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    return {"root": str(root), "code": str(code), "commit": commit,
            "volatile_json_keys": sorted(VOLATILE_KEYS),
            "run": {"wall_s": round(time.perf_counter() - t0, 1),
                    "children_cpu_s": round((c1.children_user - c0.children_user)
                                            + (c1.children_system - c0.children_system), 1),
                    "jobs": jobs, "designs": len(results),
                    "commands": sum(len(v) for v in results.values()), "files": len(files)},
            "cases": {f"{d}/{c}": rec for d, cs in results.items() for c, rec in cs.items()},
            "files": files}


# ----------------------------------------------------------------------------
# Comparing
# ----------------------------------------------------------------------------

def _first_json_difference(a, b, path="") -> str | None:
    if type(a) is not type(b):
        return f"{path or '<top>'}: {json.dumps(a)[:100]} -> {json.dumps(b)[:100]}"
    if isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{path}.{k}: {'missing in old' if k not in a else 'missing in new'}"
            d = _first_json_difference(a[k], b[k], f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list):
        for i, (x, y) in enumerate(zip(a, b)):
            d = _first_json_difference(x, y, f"{path}[{i}]")
            if d:
                return d
        return None if len(a) == len(b) else f"{path}: length {len(a)} -> {len(b)}"
    return None if a == b else f"{path or '<top>'}: {json.dumps(a)[:100]} -> {json.dumps(b)[:100]}"


def _first_line_difference(a: bytes, b: bytes) -> str:
    la, lb = a.decode(errors="replace").split("\n"), b.decode(errors="replace").split("\n")
    i = next((i for i, (x, y) in enumerate(zip(la, lb)) if x != y), min(len(la), len(lb)))
    return (f"line {i + 1} (of {len(la)} / {len(lb)}):\n      old: {la[i][:200] if i < len(la) else '<end>'}"
            f"\n      new: {lb[i][:200] if i < len(lb) else '<end>'}")


def _parquet_difference(a: Path, b: Path) -> str:
    import pyarrow.parquet as pq
    ta, tb = pq.read_table(a), pq.read_table(b)
    if ta.schema.names != tb.schema.names:
        return f"columns {ta.schema.names} -> {tb.schema.names}"
    for name in ta.schema.names:
        ca, cb = ta.column(name), tb.column(name)
        if ca.type != cb.type:
            return f"column {name}: type {ca.type} -> {cb.type}"
        xa, xb = ca.to_pylist(), cb.to_pylist()
        if xa != xb and not all((x == y) or (x != x and y != y) for x, y in zip(xa, xb)) or len(xa) != len(xb):
            i = next((i for i, (x, y) in enumerate(zip(xa, xb)) if not (x == y or (x != x and y != y))),
                     min(len(xa), len(xb)))
            return f"column {name}, row {i}: {xa[i] if i < len(xa) else '<end>'} -> {xb[i] if i < len(xb) else '<end>'}"
    ma, mb = ta.schema.metadata or {}, tb.schema.metadata or {}
    if ma != mb:
        keys = sorted(k.decode() for k in set(ma) | set(mb) if ma.get(k) != mb.get(k))
        detail = ""
        if b"cdpr-design" in ma and b"cdpr-design" in mb:
            detail = " " + (_first_json_difference(json.loads(ma[b"cdpr-design"]), json.loads(mb[b"cdpr-design"]),
                                                   "cdpr-design") or "")
        return f"schema metadata {keys}{detail}"
    return "same table and metadata; the file's bytes differ (encoding, row groups or writer)"


def describe(name: str, old_root: Path, new_root: Path) -> str:
    a, b = old_root / name, new_root / name
    if not a.exists() or not b.exists():
        return "(file not kept under its root)"
    try:
        if a.suffix == ".json":
            try:
                return _first_json_difference(_drop_volatile(json.loads(a.read_bytes())),
                                              _drop_volatile(json.loads(b.read_bytes()))) or "?"
            except ValueError:
                return _first_line_difference(a.read_bytes(), b.read_bytes())
        if a.suffix in (".csv", ".html"):
            return _first_line_difference(normalised(a), normalised(b))
        if a.suffix == ".parquet":
            return _parquet_difference(a, b)
    except Exception as e:  # noqa: BLE001 - a description, never the verdict
        return f"(could not describe: {e})"
    return f"{a.stat().st_size} -> {b.stat().st_size} bytes"


def compare(old: dict, new: dict) -> int:
    """Print every difference between two manifests; the number of differences."""
    n = 0
    for key in sorted(set(old["cases"]) | set(new["cases"])):
        a, b = old["cases"].get(key), new["cases"].get(key)
        if a is None or b is None:
            print(f"case {key}: {'new' if a is None else 'missing'}")
            n += 1
            continue
        sa = (a["exit"], a.get("error"), a["argv"])
        sb = (b["exit"], b.get("error"), b["argv"])
        if sa != sb:
            print(f"case {key}: exit {a['exit']} -> {b['exit']}" +
                  (f"\n      old: {a.get('error')}\n      new: {b.get('error')}"
                   if a.get("error") != b.get("error") else "") +
                  (f"\n      argv {a['argv']} -> {b['argv']}" if a["argv"] != b["argv"] else ""))
            n += 1
    old_root, new_root = Path(old["root"]), Path(new["root"])
    for name in sorted(set(old["files"]) | set(new["files"])):
        a, b = old["files"].get(name), new["files"].get(name)
        if a == b:
            continue
        n += 1
        if a is None or b is None:
            print(f"{name}: {'new file' if a is None else 'missing'}")
        else:
            print(f"{name}: differs, {describe(name, old_root, new_root)}")
    same = sum(1 for k, v in old["files"].items() if new["files"].get(k) == v)
    print(f"{same} of {len(old['files'])} files identical; {n} difference(s)")
    return n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", type=Path, nargs="?", help="folder for this run's outputs (made fresh)")
    ap.add_argument("--manifest", type=Path, help="where to write the manifest (default ROOT/manifest.json)")
    ap.add_argument("--code", type=Path, default=ROOT, help="checkout whose code runs (default: this one)")
    ap.add_argument("--only", help="regular expression: only the designs whose name matches")
    ap.add_argument("--jobs", type=int, default=1, help="designs run side by side (default 1)")
    ap.add_argument("--compare", type=Path, metavar="OLD.json", help="compare with an earlier manifest")
    ap.add_argument("--with", dest="with_", type=Path, metavar="NEW.json",
                    help="with --compare: compare this manifest instead of running")
    a = ap.parse_args(argv)
    if a.with_ is not None:
        if a.compare is None:
            ap.error("--with needs --compare")
        new = json.loads(a.with_.read_text())
    else:
        if a.root is None:
            ap.error("ROOT is required unless --compare OLD --with NEW")
        if a.root.exists() and any(a.root.iterdir()):
            ap.error(f"{a.root} is not empty: give a fresh folder")
        new = run(a.root, a.code, a.only, a.jobs)
        manifest = a.manifest or a.root / "manifest.json"
        manifest.parent.mkdir(parents=True, exist_ok=True)
        manifest.write_text(json.dumps(new, indent=1) + "\n")
        r = new["run"]
        bad = {k: v for k, v in new["cases"].items() if v["exit"] != 0}
        print(f"{r['designs']} designs, {r['commands']} commands, {r['files']} files; {r['wall_s']} s wall, "
              f"{r['children_cpu_s']} s CPU of the commands; manifest {manifest}")
        for k, v in bad.items():
            print(f"  {k}: exit {v['exit']}{' (traceback)' if v.get('traceback') else ''}: {v.get('error')}")
    if a.compare is None:
        return 0
    return 1 if compare(json.loads(a.compare.read_text()), new) else 0


if __name__ == "__main__":
    sys.exit(main())
