"""Orientation workspaces: the total orientation workspace is the intersection of
the fixed-orientation ones; the orientation range per position against brute force."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from cdpr_design.workspaces import orientation as hwm
from cdpr_design.model import spec
from cdpr_design import workspaces as ws
from cdpr_design import api
from cdpr_design.errors import SpecError

from .helpers import PLANAR2, collect_chunks, invoke, ipanema3_data, planar4_orient


def planar4(**wsx):
    return planar4_orient("p4", **wsx)


def ipanema3(**wsx):
    """IPAnema 3 (docs/sources.md: cdpyr sample) on a coarse grid."""
    return spec.from_dict(ipanema3_data(
        "ip3", cable={"diameter": 0.006},
        workspace={"grid": {"lower": [-7, -4.5, 0], "upper": [7, 4.5, 2.5], "step": [2.0, 1.5, 1.25]},
                   "orientation": [0, 0, 0], **wsx}))


def _collect(fn, *a, **kw):
    res, chunks = collect_chunks(fn, *a, **kw)
    cat = {k: np.concatenate([getattr(c, k) for c in chunks]) for k in ("feasible", "margin")}
    cat["tensions"] = np.vstack([c.tensions for c in chunks])
    cat["poses"] = np.vstack([c.poses for c in chunks])
    if chunks[0].collision_free is not None:
        cat["collision_free"] = np.concatenate([c.collision_free for c in chunks])
    for k in chunks[0].extra:
        cat[k] = np.concatenate([c.extra[k] for c in chunks])
    return res, cat


@pytest.mark.slow
@pytest.mark.parametrize("make, oset, kind", [
    (planar4, {"lower": [-0.2], "upper": [0.3], "count": 4}, "static"),
    (ipanema3, {"lower": [-0.1, 0, -0.17], "upper": [0.1, 0, 0.17], "count": [2, 1, 3]}, "wrench-closure"),
    (ipanema3, {"lower": [0, 0, -0.17], "upper": [0, 0, 0.17], "count": [1, 1, 3]}, "static"),
])
@pytest.mark.parametrize("interference", [False, True])
def test_total_orientation_workspace_is_the_intersection(make, oset, kind, interference):
    d = make(orientation_set=oset)
    res, tot = _collect(ws.run, d, ws.Analysis(orientations="total", kind=kind, collisions=interference), chunk=53)
    orients = hwm.orientation_set(d)
    # the set is the sampled box of the spec
    idx = [i - 3 for i in d.motion.pose_index[d.motion.dim:]]
    assert len(orients) == int(np.prod(np.atleast_1d(oset["count"])))
    np.testing.assert_allclose(orients[:, idx].min(axis=0), oset["lower"])
    np.testing.assert_allclose(orients[:, idx].max(axis=0), oset["upper"])
    allok = np.ones(res.poses, dtype=bool)
    count = np.zeros(res.poses, dtype=int)
    marg = np.full(res.poses, np.inf)
    tmax = np.full(tot["tensions"].shape, -np.inf)
    cfree = np.ones(res.poses, dtype=bool)
    for o in orients:
        _, one = _collect(ws.run, d, ws.Analysis(kind=kind, collisions=interference), orientation=o)
        ok = one["feasible"].astype(bool)
        allok &= ok
        count += ok
        marg = np.fmin(marg, one["margin"])
        tmax = np.maximum(tmax, one["tensions"])  # none at one orientation (wrench closure): none over the set
        if interference:
            cfree &= one["collision_free"].astype(bool)
    np.testing.assert_array_equal(tot["feasible"].astype(bool), allok)
    np.testing.assert_array_equal(tot["orientations_feasible"], count)
    np.testing.assert_allclose(tot["margin"], np.where(np.isfinite(marg), marg, np.nan), rtol=1e-12)
    np.testing.assert_allclose(tot["tensions"][allok], tmax[allok], rtol=1e-12)
    assert np.isnan(tot["tensions"][~allok]).all()
    if interference:
        np.testing.assert_array_equal(tot["collision_free"].astype(bool), cfree)
    assert res.feasible == int(allok.sum())
    if kind == "static" and (make is planar4 or not interference):
        assert 0 < res.feasible < res.poses   # a non-trivial intersection
    # (IPAnema 3's 0.19 x 1.5 x 0.53 m bounding box: its upper cables leave the
    # bottom face through the box, so no pose is interference free; see the note)


def test_total_with_one_orientation_is_the_fixed_orientation_workspace():
    d = ipanema3()
    ori = np.array([0.05, -0.02, 0.1])
    _, tot = _collect(ws.run, d, ws.Analysis(orientations="total"), orientations=[ori])
    _, one = _collect(ws.run, d, orientation=ori)
    np.testing.assert_array_equal(tot["feasible"], one["feasible"])


def brute_range(d, pose_pos, scale, levels, count, interference):
    nominal = d.default_orientation_full()
    idx = [i - 3 for i in d.motion.pose_index[d.motion.dim:]]

    def ok(o):
        pose = np.concatenate([pose_pos, o])[list(d.motion.pose_index)]
        r = api.pose(d, pose)
        return r.feasible and (not interference or r.collisions == [])

    if not ok(nominal):
        return np.nan
    best = 0.0
    for k in range(1, levels + 1):
        s = k / levels
        axes = [[c] if h == 0 else np.linspace(c - s * h, c + s * h, count) for c, h in zip(nominal[idx], scale)]
        for combo in itertools.product(*axes):
            o = nominal.copy()
            o[idx] = combo
            if not ok(o):
                return best
        best = s
    return best


@pytest.mark.slow
@pytest.mark.parametrize("interference", [False, True])
def test_orientation_range_against_brute_force_planar(interference):
    d = planar4(orientation_range={"max": 0.5, "levels": 5, "count": 3})
    res, out = _collect(ws.run, d, ws.Analysis(orientations="range", collisions=interference))
    rng = np.random.default_rng(0)
    for j in rng.choice(res.poses, 40, replace=False):
        ref = brute_range(d, np.pad(out["poses"][j, :2], (0, 1)), [0.5], 5, 3, interference)
        got = out["range_phi"][j]
        if np.isnan(ref):
            assert np.isnan(got) and out["feasible"][j] == 0
        else:
            assert got == pytest.approx(ref * 0.5)
    vals = out["range_phi"][np.isfinite(out["range_phi"])]
    assert vals.min() == 0.0 and vals.max() > 0.0   # the map is not constant
    assert res.summary()["orientation_mode"] == "range"


@pytest.mark.slow
def test_orientation_range_against_brute_force_spatial():
    d = ipanema3(orientation_range={"max": [0.2, 0.0, 0.4], "levels": 4, "count": 2})
    res, out = _collect(ws.run, d, ws.Analysis(orientations="range"))
    assert "range_ry" in out and np.all(out["range_ry"][np.isfinite(out["range_ry"])] == 0)
    rng = np.random.default_rng(1)
    for j in rng.choice(res.poses, 12, replace=False):
        ref = brute_range(d, out["poses"][j, :3], [0.2, 0.0, 0.4], 4, 2, False)
        if np.isnan(ref):
            assert np.isnan(out["range_rx"][j])
        else:
            assert out["range_rx"][j] == pytest.approx(ref * 0.2)
            assert out["range_rz"][j] == pytest.approx(ref * 0.4)


def test_spec_and_cli(tmp_path):
    with pytest.raises(SpecError) as e:
        planar4(orientation_set={"lower": [0, 0], "upper": [1, 1]})
    assert e.value.problems[0][0] == "workspace.orientation_set.lower"
    with pytest.raises(SpecError) as e:
        planar4(orientation_range={"max": 0.0})
    assert e.value.problems[0][0] == "workspace.orientation_range.max"
    r = invoke("workspace", PLANAR2, "--orientations", "total", "--json", "--out", tmp_path / "a")
    assert r.exit_code == 2 and "fixed orientation" in r.output and "Traceback" not in r.output
    p = tmp_path / "p4.yaml"
    p.write_text(json.dumps(planar4().raw))
    r = invoke("workspace", p, "--orientations", "range", "--collisions", "--json", "--out", tmp_path / "b")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["orientation_mode"] == "range" and s["interference"] is True
    header = (tmp_path / "b" / "workspace.csv").read_text().splitlines()[0].split(",")
    assert header[-2:] == ["collision_free", "range_phi"]
    assert (tmp_path / "b" / "orientation_workspace.png").stat().st_size > 1000
