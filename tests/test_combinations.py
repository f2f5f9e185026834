"""The combination matrix (issue 37, item 5): every shipped design x kind x cable model x
orientation mode x output option either computes - and its table agrees with ``pose`` at
sampled rows - or is refused with exit status 2 and a one-line reason. Never a traceback.

The axes:

- design: every ``designs/*.yaml``;
- ``--kind``: static, wrench-feasible, wrench-closure;
- ``--cable-model``: ideal, elastic, sagging;
- ``effector.orientation``: fixed, free (a spec variant written to ``tmp_path``). The spec loader
  accepts ``free`` on every design; on a design whose cables fix its orientation (planar4,
  pointmass3, the IPAnemas, CoGiRo) it changes nothing, and the test checks that as any other
  combination. crane4 ships ``free``: its ``fixed`` variant drops ``requirements.max_tilt``,
  which the spec format allows only with ``free``;
- output option: plain, ``--collisions``, ``--orientations total``, ``--html --format parquet``.

Every computed combination also has its boundary and frame loads: the summary's keys, a positive
``boundary_measure`` exactly when a pose is feasible, ``boundary.csv`` (planar) or a closed,
consistently wound ``workspace.stl`` enclosing ``boundary_measure`` (spatial, read back with numpy:
an independent reading of the binary STL), one ``frame_loads.csv`` (``.parquet``) row per cable, the
frame loads over as many poses as the table has feasible rows with tensions.  The second matrix's
computed cells are held to the same.

Every variant gets an explicit ``workspace.orientation_set`` on rotational motions (the nominal
orientation and +-0.1 rad about its last rotation coordinate: 3 orientations) so that a row of
``--orientations total`` can be checked against ``pose`` at each of them.

What "agrees" means at a sampled row (the first feasible, the first infeasible, the middle one):
``pose --at <the row's pose> --kind K --cable-model M --json`` gives the same ``feasible`` (with
``--collisions``: statics feasible and no interference, and ``collision_free`` = no interfering
pair; with ``--orientations total``: feasible at every orientation of the set), the same
``margin`` (``total``: the least over the set) and, where the row is feasible, the same tensions
(``total``: the largest over the set), within ``RTOL`` relative + ``ATOL`` absolute. The table's
pose is read back from the CSV (10 significant digits), so at a pose whose margin is within
``ATOL`` of 0 a different ``feasible`` is not counted.

A second matrix asks what a user asks first: every shipped design as shipped x static,
wrench-feasible, wrench-closure x ideal, elastic, sagging x plain, ``--collisions``,
``--orientations total``, ``--stiffness`` (``workspace`` on a coarse grid), and checks that each
computes or is refused for missing data or as meaningless (the table's row and its cause,
``statics.robot.CAUSES``, or the spec loader naming the keys a cable model needs): no capability
refused.  A cell a capability still refuses is an expected failure, named in ``PENDING``.

Counts of the matrix (computed, refused by reason, failed): ``python -m tests.test_combinations``
from the repository root runs it outside pytest and prints the table (``-h``: a subset, the
outcomes kept in a JSON file, the table of several such files).
"""

from __future__ import annotations

import collections
import csv
import io
import json
import math
import re
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DESIGNS = sorted((ROOT / "designs").glob("*.yaml"))
KINDS = ("static", "wrench-feasible", "wrench-closure", "dynamic")
MODELS = ("ideal", "elastic", "sagging")
MODES = ("fixed", "free")
OPTIONS = {"plain": [], "collisions": ["--collisions"], "orientations-total": ["--orientations", "total"],
           "html-parquet": ["--html", "--format", "parquet"], "accelerations": ["--accelerations"]}
#: The box of accelerations every variant is given (``requirements.acceleration``, for the dynamic
#: kind): [m/s^2] on the positions, [rad/s^2] on the rotations.
ACCELERATION, ANGULAR_ACCELERATION = 0.5, 0.1
#: Agreement of a table row with ``pose``: relative and absolute (N, N of margin) tolerance.
RTOL, ATOL = 1e-6, 1e-6
#: Half-width [rad] of the orientation set about the last rotation coordinate, and its samples.
SET_HALF, SET_COUNT = 0.1, 3

pytestmark = pytest.mark.slow


def _step(raw: dict) -> float:
    """A coarse grid step [m]: the grid's longest edge / 6 (planar) or / 3 (spatial), 3 digits."""
    g = raw["workspace"]["grid"]
    extent = max(float(hi) - float(lo) for lo, hi in zip(g["lower"], g["upper"]))
    return float(f"{extent / (6 if raw['motion'] in ('2T', '1R2T') else 3):.3g}")


def spec_variant(folder: Path, design: Path, mode: str) -> tuple[Path, dict]:
    """The design with ``effector.orientation: mode`` (and the explicit orientation set), written
    to ``folder``; its path and data."""
    raw = yaml.safe_load(design.read_text())
    raw["effector"]["orientation"] = mode
    if mode == "fixed" and (raw.get("requirements") or {}).get("max_tilt") is not None:
        del raw["requirements"]["max_tilt"]  # the spec format allows a tilt limit only with free
    nrot = {"1R2T": 1, "3R3T": 3}.get(raw["motion"], 0)
    dim = 2 if raw["motion"] in ("2T", "1R2T") else 3
    box = [ACCELERATION] * dim + [ANGULAR_ACCELERATION] * nrot
    raw.setdefault("requirements", {})["acceleration"] = {"lower": [-v for v in box], "upper": box}
    if nrot:
        nominal = [float(v) for v in (raw["workspace"].get("orientation") or [0.0] * nrot)]
        lower, upper = list(nominal), list(nominal)
        lower[-1] -= SET_HALF
        upper[-1] += SET_HALF
        raw["workspace"]["orientation_set"] = {"lower": lower, "upper": upper,
                                               "count": [1] * (nrot - 1) + [SET_COUNT]}
    path = folder / f"{design.stem}-{mode}.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path, raw


def _set_orientations(raw: dict) -> list[list[float]]:
    s = raw["workspace"]["orientation_set"]
    out = []
    for k in range(SET_COUNT):
        o = list(s["lower"])
        o[-1] = s["lower"][-1] + (s["upper"][-1] - s["lower"][-1]) * k / (SET_COUNT - 1)
        out.append(o)
    return out


# ----------------------------------------------------------------------------
# Running one combination
# ----------------------------------------------------------------------------


@dataclass
class Outcome:
    """What one combination did: ``status`` computed | refused | failed, and why."""

    key: tuple
    status: str
    reason: str = ""
    detail: list = field(default_factory=list)


def _invoke(args: list[str]):
    from typer.testing import CliRunner

    from cdpr_design.cli.app import app

    return CliRunner().invoke(app, [str(a) for a in args])


def _traceback_lines(result) -> list[str]:
    """First and last lines of the exception's traceback (a CliRunner result), or of stderr."""
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        lines = "".join(traceback.format_exception(*result.exc_info)).rstrip().splitlines()
    else:
        lines = (result.stderr or result.output).rstrip().splitlines()
    return lines[:1] + lines[-1:] if len(lines) > 1 else lines


#: The spec loader's message for several problems (docs/spec-format.md): a first line, then one
#: indented line per problem.
_PROBLEMS = re.compile(r"^error: .*: \d+ problems$")


def _classify(result, spec: Path | None = None) -> tuple[str, str, list]:
    """(status, reason, detail) of a command's result: computed (exit 0), refused (exit 2, no
    traceback, one line on stderr - or the spec loader's list of problems, one indented line each)
    or failed (anything else). In the reason, the spec variant's path reads ``SPEC``."""
    err = (result.stderr or "").strip()
    if spec is not None:
        err = err.replace(str(spec), "SPEC")
    crashed = result.exception is not None and not isinstance(result.exception, SystemExit)
    if result.exit_code == 0 and not crashed:
        return "computed", "", []
    if result.exit_code == 2 and not crashed and "Traceback" not in err:
        lines = err.splitlines()
        if len(lines) == 1:
            return "refused", lines[0], []
        if _PROBLEMS.match(lines[0]) and all(ln.startswith("  ") for ln in lines[1:]):
            return "refused", " / ".join(ln.strip() for ln in lines), []
        return "failed", f"exit 2 with {len(lines)} lines on stderr", lines[:3]
    return "failed", f"exit {result.exit_code}" + (f": {type(result.exception).__name__}" if crashed else ""), \
        _traceback_lines(result)


def _read_table(folder: Path) -> tuple[list[str], list[dict]]:
    """Header and rows (column -> float or None) of workspace.csv or workspace.parquet."""
    if (folder / "workspace.parquet").exists():
        import pyarrow.parquet as pq

        t = pq.read_table(folder / "workspace.parquet")
        cols = {n: t.column(n).to_pylist() for n in t.schema.names}
        rows = [{n: (None if cols[n][i] is None or (isinstance(cols[n][i], float) and math.isnan(cols[n][i]))
                     else float(cols[n][i])) for n in cols} for i in range(t.num_rows)]
        return list(t.schema.names), rows
    text = (folder / "workspace.csv").read_text()
    r = list(csv.reader(io.StringIO(text)))
    return r[0], [{n: (float(v) if v != "" else None) for n, v in zip(r[0], row)} for row in r[1:]]


def _close(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= ATOL + RTOL * max(abs(a), abs(b))


def _samples(rows: list[dict]) -> list[int]:
    feasible = [i for i, r in enumerate(rows) if r["feasible"] == 1.0]
    infeasible = [i for i, r in enumerate(rows) if r["feasible"] == 0.0]
    return sorted({*feasible[:1], *infeasible[:1], len(rows) // 2})


def _pose_json(spec: Path, at: list[float], kind: str, model: str) -> tuple[dict | None, str]:
    r = _invoke(["pose", spec, "--at", ",".join(repr(v) for v in at), "--kind", kind, "--cable-model", model,
                 "--json", "--quiet"])
    status, reason, detail = _classify(r, spec)
    if status != "computed":
        return None, f"pose --at {at}: {status}: {reason} {' | '.join(detail)}".strip()
    return json.loads(r.stdout), ""


def _agreement(spec: Path, raw: dict, header: list[str], rows: list[dict], kind: str, model: str,
               option: str) -> list[str]:
    """Disagreements between sampled table rows and ``pose`` (empty: they agree)."""
    coords = header[:header.index("feasible")]
    cables = [c["name"] for c in raw["cables"]]
    nrot = {"1R2T": 1, "3R3T": 3}.get(raw["motion"], 0)
    problems = []
    for i in _samples(rows):
        row = rows[i]
        pose = [row[c] for c in coords]
        if option == "orientations-total":
            ats = [pose[:len(pose) - nrot] + o for o in _set_orientations(raw)]
        else:
            ats = [pose]
        answers = []
        for at in ats:
            p, err = _pose_json(spec, at, kind, model)
            if p is None:
                problems.append(f"row {i}: {err}")
                break
            answers.append(p)
        if len(answers) != len(ats):
            continue
        feasible = all(p["feasible"] for p in answers)
        # null: the sagging cables' shapes did not converge, nothing was checked: not collision free
        collides = any(p.get("collisions") is None or p.get("collisions") for p in answers)
        if option == "collisions":
            if row.get("collision_free") != (0.0 if collides else 1.0):
                problems.append(f"row {i} {pose}: collision_free {row.get('collision_free')}, pose collisions "
                                f"{[p.get('collisions') for p in answers]}")
            feasible = feasible and not collides
        margins = [p["margin"] for p in answers]
        margin = None if any(m is None for m in margins) else min(margins)
        near_zero = margin is not None and abs(margin) <= ATOL
        if (row["feasible"] == 1.0) != feasible and not near_zero:
            problems.append(f"row {i} {pose}: feasible {row['feasible']:g}, pose {feasible} (margin {margin})")
        if not _close(row["margin"], margin):
            problems.append(f"row {i} {pose}: margin {row['margin']}, pose {margin}")
        if row["feasible"] == 1.0 and feasible:
            for c in cables:
                ts = [(p.get("tensions") or {}).get(c) for p in answers]
                t = None if any(v is None for v in ts) else max(ts)
                if not _close(row[f"tension_{c}"], t):
                    problems.append(f"row {i} {pose}: tension_{c} {row[f'tension_{c}']}, pose {t}")
        if option == "accelerations" and not _close(row["acceleration_radius"], answers[0]["acceleration_radius"]):
            problems.append(f"row {i} {pose}: acceleration_radius {row['acceleration_radius']}, pose "
                            f"{answers[0]['acceleration_radius']}")
        if option == "orientations-total" and row.get("orientations_feasible") is not None:
            n = sum(bool(p["feasible"]) for p in answers)
            if int(row["orientations_feasible"]) != n:
                problems.append(f"row {i} {pose}: orientations_feasible {row['orientations_feasible']:g}, "
                                f"pose feasible at {n} of {len(answers)}")
    return problems


def _solid_problems(out: Path, raw: dict, rows: list[dict]) -> list[str]:
    """What is wrong with the boundary and the frame loads of a computed combination: the summary's
    keys, boundary.csv (planar) or a closed workspace.stl whose volume is boundary_measure
    (spatial), one frame_loads row per cable, a positive measure when a pose is feasible."""
    import numpy as np

    s = json.loads((out / "summary.json").read_text())
    problems = []
    if not all(k in s for k in ("boundary_measure", "boundary_surface", "frame_loads")):
        return ["summary.json lacks boundary_measure, boundary_surface or frame_loads"]
    feasible = any(r["feasible"] == 1.0 for r in rows) and min(s["grid"]["shape"]) > 1  # a flat grid: no volume
    if feasible != (s["boundary_measure"] > 0):
        problems.append(f"boundary_measure {s['boundary_measure']} with feasible poses: {feasible}")
    ext = "parquet" if (out / "workspace.parquet").exists() else "csv"
    if raw["motion"] in ("2T", "1R2T"):
        if not (out / f"boundary.{ext}").exists():
            problems.append(f"no boundary.{ext}")
    else:
        data = (out / "workspace.stl").read_bytes()
        n = int(np.frombuffer(data[80:84], "<u4")[0])
        tri = np.frombuffer(data[84:], dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])["v"]
        if len(tri) != n or (n > 0) != feasible:
            problems.append(f"workspace.stl: {n} triangles, {len(tri)} read, feasible poses: {feasible}")
        elif n:
            ids = np.unique(tri.reshape(-1, 3), axis=0, return_inverse=True)[1].reshape(-1, 3)
            e = ids[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
            fwd, back = np.sort(e[:, 0] * (n * 3) + e[:, 1]), np.sort(e[:, 1] * (n * 3) + e[:, 0])
            if not (np.all(fwd[1:] != fwd[:-1]) and np.array_equal(fwd, back)):
                problems.append("workspace.stl is not closed and consistently wound")
            v = tri.astype(float)
            volume = float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6)
            if abs(volume - s["boundary_measure"]) > 1e-4 * max(1.0, abs(volume)):
                problems.append(f"workspace.stl encloses {volume}, boundary_measure {s['boundary_measure']}")
    if ext == "csv":
        cables = [line.split(",")[0] for line in (out / "frame_loads.csv").read_text().splitlines()[1:]]
    else:
        import pyarrow.parquet as pq

        cables = pq.read_table(out / "frame_loads.parquet").column("cable").to_pylist()
    names = [c["name"] for c in raw["cables"]]
    if cables != names:
        problems.append(f"frame_loads.{ext} has not one row per cable")
    # the loads cover every feasible row with tensions (the table's own count, read independently); a
    # row of the total orientation workspace stands for each orientation of the set, its tensions for
    # the largest over them: empty where one has none, so between that count and every feasible row
    with_tensions = sum(r["feasible"] == 1.0 and all(r[f"tension_{c}"] is not None for c in names) for r in rows)
    feasible_rows = sum(r["feasible"] == 1.0 for r in rows)
    q = s.get("orientation_count", 1) if s.get("orientation_mode") == "total" else 1
    poses = s["frame_loads"]["poses"]
    if not (q * with_tensions <= poses <= q * (feasible_rows if q > 1 else with_tensions)):
        problems.append(f"frame loads over {poses} poses, the table has {with_tensions} feasible rows with tensions "
                        f"({feasible_rows} feasible) at {q} orientations")
    return problems


def run_combination(folder: Path, design: Path, kind: str, model: str, mode: str, option: str) -> Outcome:
    """Run ``workspace`` for one combination in this process and judge it (see the module's text)."""
    key = (design.stem, kind, model, mode, option)
    folder.mkdir(parents=True, exist_ok=True)
    spec, raw = spec_variant(folder, design, mode)
    out = folder / "out"
    args = ["workspace", spec, "--kind", kind, "--cable-model", model, "--step", repr(_step(raw)),
            "--out", out, "--json", "--quiet", *OPTIONS[option]]
    status, reason, detail = _classify(_invoke(args), spec)
    if status != "computed":
        return Outcome(key, status, reason, detail)
    try:
        header, rows = _read_table(out)
        problems = _agreement(spec, raw, header, rows, kind, model, option) + _solid_problems(out, raw, rows)
    except Exception as e:  # noqa: BLE001 - the test reports it as this combination's failure
        return Outcome(key, "failed", f"checking the table: {type(e).__name__}: {e}",
                       traceback.format_exc().rstrip().splitlines()[-3:])
    if problems:
        return Outcome(key, "failed", "table disagrees with pose", problems)
    return Outcome(key, "computed")


COMBINATIONS = [(d, k, m, o, opt) for d in DESIGNS for k in KINDS for m in MODELS for o in MODES for opt in OPTIONS]


@pytest.fixture(autouse=True)
def _pictures_in_process(monkeypatch):
    # the picture worker is a helper process a command starts; in-process runs draw in this one
    monkeypatch.setenv("CDPR_DESIGN_PICTURE_WORKER", "0")


@pytest.mark.parametrize("design,kind,model,mode,option", COMBINATIONS,
                         ids=[f"{d.stem}-{k}-{m}-{o}-{opt}" for d, k, m, o, opt in COMBINATIONS])
def test_combination_computes_and_agrees_or_is_refused(tmp_path, design, kind, model, mode, option):
    o = run_combination(tmp_path, design, kind, model, mode, option)
    assert o.status in ("computed", "refused"), f"{o.reason}\n" + "\n".join(o.detail)


def test_agreement_check_sees_a_wrong_row(tmp_path):
    """The check above can fail: a table whose feasible flag, margin or tension is changed at a
    sampled row disagrees with ``pose``."""
    design = ROOT / "designs" / "planar2.yaml"
    spec, raw = spec_variant(tmp_path, design, "fixed")
    out = tmp_path / "out"
    r = _invoke(["workspace", spec, "--step", repr(_step(raw)), "--out", out, "--json", "--quiet"])
    assert r.exit_code == 0, r.output
    header, rows = _read_table(out)
    assert _agreement(spec, raw, header, rows, "static", "ideal", "plain") == []
    j = next(k for k in _samples(rows) if rows[k]["feasible"] == 1.0)
    bad = [dict(r) for r in rows]
    bad[j]["tension_c1"] *= 1 + 10 * RTOL
    bad[j]["margin"] += 10 * ATOL
    problems = " ".join(_agreement(spec, raw, header, bad, "static", "ideal", "plain"))
    assert f"row {j}" in problems and "tension_c1" in problems and "margin" in problems
    i = next(k for k in _samples(rows) if rows[k]["feasible"] == 0.0)
    bad = [dict(r) for r in rows]
    bad[i]["feasible"] = 1.0
    problems = " ".join(_agreement(spec, raw, header, bad, "static", "ideal", "plain"))
    assert f"row {i}" in problems and "feasible 1, pose False" in problems


# ----------------------------------------------------------------------------
# No capability refused: designs x kinds x cable models x {plain, --collisions, --orientations
# total, --stiffness}
# ----------------------------------------------------------------------------

#: The options of the refusal matrix.
MATRIX_OPTIONS = {"plain": [], "collisions": ["--collisions"], "orientations-total": ["--orientations", "total"],
                  "stiffness": ["--stiffness"]}
MATRIX_KINDS = ("static", "wrench-feasible", "wrench-closure")
MATRIX = [(d, k, m, opt) for d in DESIGNS for k in MATRIX_KINDS for m in MODELS for opt in MATRIX_OPTIONS]
#: Capabilities still refused, by the cells they refuse: a predicate on (design's facts, kind, model,
#: option) and why.  A cell in one of them is expected to fail (strictly) while the table refuses it
#: for a capability; once the capability lands the cell is a plain cell, which must compute.
PENDING: tuple = ()


def _matrix_refusal(design: Path, kind: str, model: str, option: str):
    """(facts, row) of the table's refusal of a matrix cell, resolved in this process (row None: the
    table computes it; facts None: the spec loader refuses the cable model for missing data)."""
    from cdpr_design.errors import CdprError
    from cdpr_design.model import spec
    from cdpr_design.statics import robot as R

    try:
        d = spec.with_cable_model(spec.load(design), model)
    except CdprError:
        return None, None
    f = R.facts(d)
    return f, R.refusal(f, _analysis(kind, option))


def _matrix_params():
    out = []
    for d, k, m, opt in MATRIX:
        f, row = _matrix_refusal(d, k, m, opt)
        marks = []
        if row is not None and row.cause_of(f, _analysis(k, opt)) == "capability":
            why = [reason for test, reason in PENDING if test(f, k, m, opt)]
            if why:
                marks = [pytest.mark.xfail(strict=True, reason=why[0])]
        out.append(pytest.param(d, k, m, opt, marks=marks, id=f"{d.stem}-{k}-{m}-{opt}"))
    return out


def _analysis(kind: str, option: str):
    from cdpr_design.statics import robot as R

    return R.Analysis(kind=kind, collisions=option == "collisions",
                      orientations="total" if option == "orientations-total" else None,
                      stiffness=option == "stiffness")


def _matrix_step(raw: dict) -> float:
    """A coarser grid step [m] than :func:`_step`: the longest edge / 4 (planar) or / 2 (spatial)."""
    g = raw["workspace"]["grid"]
    extent = max(float(hi) - float(lo) for lo, hi in zip(g["lower"], g["upper"]))
    return float(f"{extent / (4 if raw['motion'] in ('2T', '1R2T') else 2):.3g}")


def matrix_cell(folder: Path, design: Path, kind: str, model: str, option: str) -> Outcome:
    """``workspace`` of one cell of the refusal matrix, run as a user would (the shipped spec, a coarse
    grid), judged: computed (with its boundary and frame loads, :func:`_solid_problems`); refused for
    missing data or meaningless (the table's row, or the spec loader naming the keys to give);
    anything else (a capability refused, a crash) fails."""
    key = (design.stem, kind, model, option)
    raw = yaml.safe_load(design.read_text())
    out = folder / "out"
    args = ["workspace", design, "--kind", kind, "--cable-model", model, "--step", repr(_matrix_step(raw)),
            "--out", out, "--json", "--quiet", *MATRIX_OPTIONS[option]]
    status, reason, detail = _classify(_invoke(args))
    if status == "computed":
        problems = _solid_problems(out, raw, _read_table(out)[1])
        return Outcome(key, "failed", "no boundary or frame loads", problems) if problems else Outcome(key, status)
    if status != "refused":
        return Outcome(key, status, reason, detail)
    f, row = _matrix_refusal(design, kind, model, option)
    if f is None:  # the spec loader: every problem a key the cable model requires, named with what to give
        problems = reason.split(" / ")[1:] or [reason]  # several problems, or the one on the first line
        ok = all("required by cable model" in p and ": give " in p for p in problems)
        return Outcome(key, "refused" if ok else "failed", f"missing data: {reason}")
    a = _analysis(kind, option)
    cause = row.cause_of(f, a) if row is not None else "none"
    if row is None or reason != f"error: {row.message(f, a)}":
        return Outcome(key, "failed", f"refused with {reason!r}, the table's row: {row and row.message(f, a)!r}")
    return Outcome(key, "refused" if cause in ("missing data", "meaningless") else "failed", f"{cause}: {reason}")


@pytest.mark.parametrize("design,kind,model,option", _matrix_params())
def test_every_cell_computes_or_is_refused_for_missing_data_or_meaningless(tmp_path, design, kind, model, option):
    o = matrix_cell(tmp_path, design, kind, model, option)
    assert o.status in ("computed", "refused"), f"{o.reason}\n" + "\n".join(o.detail)


# ----------------------------------------------------------------------------
# The table of counts: python -m tests.test_combinations [REGEX]
# ----------------------------------------------------------------------------


def print_table(outcomes: list[dict]) -> None:
    """The counts of the matrix: computed, refused by reason, failed with their errors."""
    counts = collections.Counter(o["status"] for o in outcomes)
    print(f"{len(outcomes)} combinations: " + ", ".join(f"{counts[s]} {s}" for s in ("computed", "refused", "failed")))
    by_reason = collections.Counter(o["reason"] for o in outcomes if o["status"] == "refused")
    print("\nrefused, by reason:")
    for reason, c in by_reason.most_common():
        print(f"  {c:4d}  {reason}")
    failed = [o for o in outcomes if o["status"] == "failed"]
    if failed:
        print("\nfailed:")
        for o in failed:
            print(f"  {o['name']}: {o['reason']}")
            for line in o["detail"][:4]:
                print(f"      {line[:300]}")


def main(argv: list[str]) -> int:
    """``python -m tests.test_combinations [REGEX] [--json FILE]``: run the combinations whose name
    matches (all by default), print each and the table of counts, and keep them in FILE;
    ``--table FILE ...`` prints the table of earlier runs' FILEs together."""
    import argparse
    import os
    import resource
    import tempfile

    ap = argparse.ArgumentParser(prog="python -m tests.test_combinations")
    ap.add_argument("pattern", nargs="?", help="regular expression on design-kind-model-mode-option")
    ap.add_argument("--json", type=Path, help="write the outcomes to this file")
    ap.add_argument("--table", type=Path, nargs="+",
                    help="print the table of these outcome files (a combination in several: the last)")
    a = ap.parse_args(argv)
    if a.table:
        by_name = {o["name"]: o for f in a.table for o in json.loads(f.read_text())}  # later files win
        outcomes = list(by_name.values())
        print_table(outcomes)
        return 1 if any(o["status"] == "failed" for o in outcomes) else 0
    os.environ["CDPR_DESIGN_PICTURE_WORKER"] = "0"
    pattern = re.compile(a.pattern) if a.pattern else None
    outcomes = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, (d, k, m, o, opt) in enumerate(COMBINATIONS):
            name = f"{d.stem}-{k}-{m}-{o}-{opt}"
            if pattern and not pattern.search(name):
                continue
            c0 = time.process_time()
            outcome = run_combination(Path(tmp) / str(n), d, k, m, o, opt)
            cpu = time.process_time() - c0
            outcomes.append({"name": name, "status": outcome.status, "reason": outcome.reason,
                             "detail": outcome.detail, "cpu_s": round(cpu, 2)})
            print(f"{name:60s} {outcome.status:9s} {cpu:6.2f} s  {outcome.reason[:150]}", flush=True)
            if a.json:
                a.json.write_text(json.dumps(outcomes, indent=1))
    print()
    print_table(outcomes)
    ru = resource.getrusage(resource.RUSAGE_SELF)
    print(f"\nCPU: {ru.ru_utime + ru.ru_stime:.1f} s (this process)")
    return 1 if any(o["status"] == "failed" for o in outcomes) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
