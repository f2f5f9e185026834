"""A pose is the sweep's row there: at random rows of random robots' workspace sweeps, the
``pose`` evaluation (the Python API and the command) reports the row's feasibility, margin,
tensions, lengths and cable state, to the bit.

Random planar robots (2T and 1R2T, two to five cables) and spatial ones (3T, 3R3T), with
ideal, elastic and sagging cables, swivel pulleys on some, under every kind of workspace.  The
rows are independent of this agreement's code: they come from the chunks a sweep streams
(what ``workspace.csv`` holds); the reference statics (``reference_pose``) check the pose's
answers themselves in test_tension.py and test_kernels_general.py.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cdpr_design import api
from cdpr_design import workspaces as ws
from cdpr_design.model import spec

from .helpers import invoke, planar2_raw, random_planar_data, random_spatial_data, write_spec

KINDS = ("static", "wrench-feasible", "wrench-closure")


def _random_spatial_data(rng: np.random.Generator, m: int, motion: str) -> dict:
    """A random spatial robot (:func:`~tests.helpers.random_spatial_data`) with a unit external wrench box."""
    data = random_spatial_data(rng, m, motion)
    n = 3 if motion == "3T" else 6
    data["workspace"]["external_wrench"] = {"lower": [-1.0] * n, "upper": [1.0] * n}
    return data


def _random_design(seed: int):
    """A random robot and its cable model (a third each ideal, elastic, sagging; swivel pulleys on
    some straight-cable ones; two cables on some planar ones)."""
    rng = np.random.default_rng(seed)
    model = ("ideal", "elastic", "sagging")[seed % 3]
    if seed % 4 == 3:
        data = _random_spatial_data(rng, int(rng.integers(4, 9)) if seed % 8 == 7 else int(rng.integers(3, 6)),
                                    "3R3T" if seed % 8 == 7 else "3T")
    else:
        motion = "1R2T" if seed % 2 else "2T"
        m = 2 if seed % 6 == 0 else int(rng.integers(3, 6))  # two cables: the sweep's closed form
        data = random_planar_data(rng, m, motion)
        data["workspace"]["external_wrench"] = {"lower": [-0.5] * (3 if motion == "1R2T" else 2),
                                                "upper": [0.5] * (3 if motion == "1R2T" else 2)}
        if motion == "1R2T":
            data["workspace"]["orientation"] = [float(rng.uniform(-0.2, 0.2))]
    if model != "ideal":
        data["cable"] = {"model": model, "axial_stiffness": float(rng.uniform(2e3, 5e4))}
        if model == "sagging":
            data["cable"]["mass_per_length"] = float(rng.uniform(0.01, 0.2))
    if model != "sagging" and seed % 4 == 0 and data["motion"] in ("2T", "3T"):
        for c in data["cables"]:
            axis = [0.0, 1.0, 0.0] if data["motion"] == "2T" else [0.0, 0.0, 1.0]
            c["pulley"] = {"radius": float(rng.uniform(0.01, 0.05)), "axis": axis}
    return spec.from_dict(data), model


def _same(a, b) -> bool:
    """Equal to the bit, NaN equal to NaN."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))


@pytest.mark.parametrize("seed", range(24))
def test_pose_is_the_sweeps_row_on_random_robots(seed):
    design, model = _random_design(seed)
    rng = np.random.default_rng(1000 + seed)
    compared = feasible = 0
    for kind in KINDS:
        chunks = []
        try:
            ws.run(design, ws.Analysis(kind=kind), on_chunk=chunks.append, keep_maps=False, tilt=False)
        except Exception as e:  # a refused combination is not a disagreement
            assert "wrench-closure" in kind or "orientation: free" in str(e), e
            continue
        rows = [(c, k) for c in chunks for k in range(len(c.feasible))]
        for i in rng.choice(len(rows), size=min(12, len(rows)), replace=False):
            c, k = rows[i]
            p = api.pose(design, c.poses[k], kind)
            assert p.feasible == bool(c.feasible[k]), (kind, c.poses[k])
            assert _same(p.margin, c.margin[k]), (kind, c.poses[k], p.margin, c.margin[k])
            assert _same(p.tensions, c.tensions[k]) and _same(p.lengths, c.lengths[k]), (kind, c.poses[k])
            if model != "ideal" and f"sag_{design.cable_names[0]}" in c.extra:
                st = p.cable_state
                for name, values in (("outlet_tension", st.outlet_tensions),
                                     ("unstretched_length", st.unstretched_lengths), ("sag", st.sag)):
                    assert _same(values, [c.extra[f"{name}_{n}"][k] for n in design.cable_names]), (name, kind)
            compared += 1
            feasible += p.feasible
    assert compared >= 12


def test_pose_command_reports_the_workspace_row(tmp_path):
    """The command line: ``pose --json`` at a row of ``workspace.csv`` prints that row's
    feasibility, margin and tensions (planar2, elastic cables: the stretched lengths too)."""
    data = planar2_raw()
    data["cable"] = {"model": "elastic", "axial_stiffness": 20000.0}
    path = write_spec(tmp_path, data)
    design = spec.load(path)
    chunks = []
    ws.run(design, on_chunk=chunks.append, keep_maps=False, tilt=False)
    c = chunks[0]
    k = int(np.flatnonzero(c.feasible)[len(np.flatnonzero(c.feasible)) // 2])
    r = invoke("pose", path, "--at", ",".join(repr(float(v)) for v in c.poses[k]), "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["cable_model"] == "elastic"
    assert out["feasible"] is True and out["margin"] == float(c.margin[k])
    assert [out["tensions"][n] for n in design.cable_names] == [float(v) for v in c.tensions[k]]
    assert [out["unstretched_lengths"][n] for n in design.cable_names] == [
        float(c.extra[f"unstretched_length_{n}"][k]) for n in design.cable_names]
