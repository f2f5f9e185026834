"""Stiffness through the commands (issue 39, item 4): ``workspace --stiffness`` columns, map and
summary agree with ``pose --json`` at the same poses; the requirements ``min_stiffness`` and
``min_frequency`` are checked over the task box; both figures are ``optimize`` objectives; the
combinations the stiffness does not model are refused with the reason."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from cdpr_design import workspaces as ws
from cdpr_design.design.envelope import task_grid
from cdpr_design.model import spec

from .helpers import DESIGNS, PLANAR2, invoke, read_csv, write_spec


def columns(path) -> dict:
    """The CSV's columns as float arrays (an empty cell is NaN; true/false are 1/0)."""
    header, rows = read_csv(path)
    cell = {"": np.nan, "true": 1.0, "false": 0.0, "True": 1.0, "False": 0.0}
    return {h: np.array([cell[v] if v in cell else float(v) for v in col]) for h, col in zip(header, zip(*rows))}


@pytest.mark.parametrize("name, step", [("planar2", 0.05), ("cogiro", 1.0), ("planar4", 0.1)])
def test_workspace_columns_are_the_pose_commands(tmp_path, name, step):
    """At feasible rows of the table, min_stiffness and lowest_frequency are ``pose --json``'s
    min_stiffness and its lowest natural frequency; infeasible rows are empty; the summary holds
    the least of each over the feasible rows; stiffness_map.png is written."""
    path = DESIGNS / f"{name}.yaml"
    r = invoke("workspace", path, "--step", step, "--stiffness", "--out", tmp_path, "--json", "--quiet")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    cols = columns(tmp_path / "workspace.csv")
    feas = cols["feasible"].astype(bool)
    k, f = cols["min_stiffness"], cols["lowest_frequency"]
    assert feas.any() and np.isnan(k[~feas]).all() and np.isnan(f[~feas]).all()
    assert s["min_stiffness"] == pytest.approx(np.nanmin(k[feas]), rel=1e-9)  # the CSV's 10 digits
    assert s["lowest_frequency"] == pytest.approx(np.nanmin(f[feas]), rel=1e-9)
    assert (tmp_path / "stiffness_map.png").stat().st_size > 0
    design = spec.load(path)
    coords = list(design.motion.coords)
    rows = np.flatnonzero(feas)
    for i in rows[:: max(1, len(rows) // 4)][:4]:
        at = ",".join(f"{cols[c][i]:.12g}" for c in coords)
        p = json.loads(invoke("pose", path, "--at", at, "--json").stdout)
        assert p["min_stiffness"] == pytest.approx(k[i], rel=1e-7)
        assert p["natural_frequencies"][0] == pytest.approx(f[i], rel=1e-7)


def test_without_the_option_the_table_is_unchanged(tmp_path):
    r = invoke("workspace", PLANAR2, "--step", 0.1, "--out", tmp_path, "--json", "--quiet")
    s = json.loads(r.stdout)
    assert "min_stiffness" not in s and "min_stiffness" not in read_csv(tmp_path / "workspace.csv")[0]
    assert not (tmp_path / "stiffness_map.png").exists()


@pytest.mark.parametrize("name, args, reason", [
    ("ipanema3", (), "--stiffness: ideal cables without cable.axial_stiffness"),
    ("planar4", ("--orientations", "total"), "--stiffness: an orientation workspace's rows"),
])
def test_undefined_stiffness_is_refused_with_the_reason(tmp_path, name, args, reason):
    r = invoke("workspace", DESIGNS / f"{name}.yaml", "--stiffness", "--step", 1.0, *args, "--out", tmp_path)
    assert r.exit_code == 2 and reason in r.output and "Traceback" not in r.output


def _with_requirements(tmp_path, **req):
    data = yaml.safe_load(PLANAR2.read_text())
    data["requirements"] = {**data.get("requirements", {}), **req}
    data["requirements"].pop("max_speed", None)  # the motors' check apart
    data["requirements"].pop("max_acceleration", None)
    return write_spec(tmp_path, data, "stiff.yaml")


def test_check_reads_the_least_stiffness_and_frequency_over_the_task_box(tmp_path):
    """The figures are the least over the task box's feasible poses (the same sweep with
    --stiffness on the task grid); a limit above the figure fails, one below passes."""
    design = spec.load(PLANAR2)
    task = ws.run(design, ws.Analysis(stiffness=True), grid=task_grid(design), tilt=False).summary()
    kmin, fmin = task["min_stiffness"], task["lowest_frequency"]
    passing = _with_requirements(tmp_path, min_stiffness=0.99 * kmin, min_frequency=0.99 * fmin)
    r = invoke("check", passing, "--json")
    assert r.exit_code in (0, 1), r.output  # 1: planar2's motor is short of torque (its own check)
    checks = {c["requirement"]: c for c in json.loads(r.stdout)["checks"]}
    assert checks["min_stiffness"]["passed"] and checks["min_frequency"]["passed"]
    failing = _with_requirements(tmp_path, min_stiffness=1.01 * kmin)
    r = invoke("check", failing, "--json")
    assert r.exit_code == 1 and "min_stiffness" in r.output
    checks = {c["requirement"]: c for c in json.loads(r.stdout)["checks"]}
    assert checks["min_stiffness"]["passed"] is False and "min_frequency" not in checks


def test_both_figures_are_optimize_objectives():
    """``--maximize task_min_stiffness`` names a known figure, and an evaluation asked for it
    computes it (the task box's least stiffness)."""
    from cdpr_design.design.evaluate import evaluate
    from cdpr_design.optimize.objectives import make_objectives

    design = spec.load(PLANAR2)
    obj = make_objectives(design, ["task_min_stiffness", "task_lowest_frequency"], None)
    assert [o.direction for o in obj] == ["maximize", "maximize"]
    row = evaluate(design, figures={"task_min_stiffness", "task_lowest_frequency"})
    task = ws.run(design, ws.Analysis(stiffness=True), grid=task_grid(design), tilt=False).summary()
    assert row["task_min_stiffness"] == task["min_stiffness"] > 0
    assert row["task_lowest_frequency"] == task["lowest_frequency"] > 0
    assert "task_min_stiffness" not in evaluate(design, figures={"fraction"})


def test_the_readmes_planar2_figures(tmp_path):
    """README 'Stiffness and vibration': planar2 at its spec's grid is softest at the bottom
    corners, 3.2 kN/m and 9.0 Hz at (0.06, 0)."""
    import re

    from .helpers import ROOT

    text = (ROOT / "README.md").read_text()
    k, f, x, y = re.search(r"([\d.]+) kN/m and ([\d.]+) Hz\nat \(([\d.]+), ([\d.]+)\)", text).groups()
    r = invoke("workspace", PLANAR2, "--stiffness", "--out", tmp_path, "--json", "--quiet")
    s = json.loads(r.stdout)
    assert round(s["min_stiffness"] / 1e3, 1) == float(k) and round(s["lowest_frequency"], 1) == float(f)
    cols = columns(tmp_path / "workspace.csv")
    i = int(np.nanargmin(cols["min_stiffness"]))
    assert (cols["x"][i], cols["y"][i]) == pytest.approx((float(x), float(y)), abs=1e-9)
