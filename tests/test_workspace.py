"""Workspace sweeps: the numba kernels against a plain numpy reference; chunking; maps."""

from __future__ import annotations

import numpy as np
import pytest

from cdpr_design import _kernels as K
from cdpr_design import kinematics as kin
from cdpr_design import spec
from cdpr_design import workspace as ws

from .conftest import PLANAR2, random_planar_data


def numpy_reference(design, poses, wreq):
    """Per pose, plain numpy: W from kinematics, t = W^-1 w, bounds, closed-form margin."""
    k = len(poses)
    feas = np.zeros(k, dtype=np.uint8)
    margin = np.full(k, np.nan)
    T = np.full((k, design.m), np.nan)
    L = np.empty((k, design.m))
    tmin, tmax = design.tension_min, design.tension_max
    for j, p in enumerate(poses):
        L[j] = kin.inverse_kinematics(design, p)
        W = kin.structure_matrix(design, p)
        if np.linalg.matrix_rank(W, tol=1e-9) < design.n:
            continue
        Winv = np.linalg.inv(W)
        rn = np.linalg.norm(Winv, axis=1)
        ts = wreq @ Winv.T  # (nv, m)
        s = np.minimum(ts - tmin, tmax - ts) / rn
        margin[j] = s.min()
        feas[j] = margin[j] >= 0
        if np.all((ts[0] >= tmin) & (ts[0] <= tmax)):
            T[j] = ts[0]
    return feas, margin, T, L


def sweep_all(design, kind="static", **kw):
    rows = []
    ws.run(design, kind=kind, on_chunk=rows.append, **kw)
    cat = lambda name: np.concatenate([getattr(c, name) for c in rows])  # noqa: E731
    return cat("poses"), cat("feasible"), cat("margin"), cat("tensions"), cat("lengths")


def assert_same(ref, got, design):
    feas_r, marg_r, T_r, L_r = ref
    _, feas, marg, T, L = got
    np.testing.assert_array_equal(feas, feas_r)
    np.testing.assert_allclose(L, L_r, rtol=1e-12)
    np.testing.assert_array_equal(np.isnan(T), np.isnan(T_r))
    ok = ~np.isnan(T_r)
    np.testing.assert_allclose(T[ok], T_r[ok], rtol=1e-9, atol=1e-9 * design.tension_max.max())
    np.testing.assert_array_equal(np.isnan(marg), np.isnan(marg_r))
    fin = ~np.isnan(marg_r)
    np.testing.assert_allclose(marg[fin], marg_r[fin], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("seed", range(40))
def test_planar_kernels_match_numpy_on_random_robots(seed):
    """Two-cable planar robots: closed-form kernel, generic kernel and numpy agree."""
    rng = np.random.default_rng(seed)
    design = spec.from_dict(random_planar_data(rng, m=2))
    got = sweep_all(design)
    poses = got[0]
    wreq = ws.wrench_vertices(design, "static")
    ref = numpy_reference(design, poses, wreq)
    # feasibility identical except where the margin is within rounding of zero
    band = np.abs(ref[1]) < 1e-9
    assert band.sum() <= 2
    keep = ~band
    assert_same(tuple(r[keep] for r in ref), tuple(g[keep] for g in got), design)
    assert got[1].any(), "the random robot should have some feasible poses"

    # the generic per-pose kernel gives the same numbers as the closed-form one
    g = design.workspace.grid
    lower, step, shape = ws._grid3(g)
    n = g.size
    f2, m2, T2, L2 = np.empty(n, np.uint8), np.empty(n), np.empty((n, 2)), np.empty((n, 2))
    K.sweep_grid(0, n, lower, step, shape, design.attachments.copy(), design.outlets, design.rows,
                 wreq, design.tension_min, design.tension_max, ws.combinations(2, 2), K.KIND_STATIC,
                 f2, m2, T2, L2)
    assert_same((f2, m2, T2, L2), got, design)


def test_planar2_wrench_feasible_matches_numpy():
    data = spec.read_yaml(PLANAR2)
    data["workspace"]["external_wrench"] = {"lower": [-2.0, -1.0], "upper": [2.0, 1.0]}
    design = spec.from_dict(data)
    got = sweep_all(design, kind="wrench-feasible", step=0.03)
    wreq = ws.wrench_vertices(design, "wrench-feasible")
    assert wreq.shape == (5, 2)
    ref = numpy_reference(design, got[0], wreq)
    assert_same(ref, got, design)
    static = sweep_all(design, kind="static", step=0.03)
    # resisting extra wrench can only shrink the workspace
    assert np.all(got[1] <= static[1]) and got[1].sum() < static[1].sum()


def test_chunking_does_not_change_results():
    design = spec.load(PLANAR2)
    a = ws.run(design, step=0.02)
    rows = []
    b = ws.run(design, step=0.02, chunk=777, on_chunk=rows.append)
    assert [c.start for c in rows][:3] == [0, 777, 1554]
    assert sum(len(c.feasible) for c in rows) == a.poses
    sa, sb = a.summary(), b.summary()
    for key in ("poses", "feasible", "fraction", "measure", "min_margin", "max_margin", "max_tension"):
        assert sa[key] == sb[key], key
    np.testing.assert_array_equal(a.feasible_map, b.feasible_map)
    np.testing.assert_array_equal(a.tension_maps, b.tension_maps)


def test_summary_figures_are_consistent():
    design = spec.load(PLANAR2)
    poses, feas, marg, T, L = sweep_all(design)
    r = ws.run(design)
    s = r.summary()
    assert s["poses"] == len(poses) == 151 * 151
    assert s["feasible"] == int(feas.sum())
    assert s["fraction"] == pytest.approx(feas.mean())
    assert s["measure"] == pytest.approx(feas.sum() * 0.01 * 0.01)
    assert s["min_margin"] == pytest.approx(marg[feas == 1].min())
    assert s["max_margin"] == pytest.approx(marg[feas == 1].max())
    assert s["max_tension"] == pytest.approx(np.nanmax(T))
    assert s["max_tension"] <= 20.0
    # feasible <=> tensions present and within bounds
    assert np.array_equal(feas == 1, ~np.isnan(T).any(axis=1))
    # symmetric robot: the maps are mirror images, cable 1 <-> cable 2
    fm = r.feasible_map
    np.testing.assert_array_equal(fm, fm[::-1, :])
    np.testing.assert_allclose(r.tension_maps[0], r.tension_maps[1][::-1, :], rtol=1e-9)


def test_large_grid_maps_are_subsampled(monkeypatch):
    design = spec.load(PLANAR2)
    full = ws.run(design, step=0.005)
    monkeypatch.setattr(ws, "MAP_CELLS", 5000)
    small = ws.run(design, step=0.005)
    assert np.prod(small.feasible_map.shape) <= 5000
    sx, sy = small.map_stride
    assert sx > 1 and sy > 1
    np.testing.assert_array_equal(small.feasible_map, full.feasible_map[::sx, ::sy])
    np.testing.assert_array_equal(small.margin_map, full.margin_map[::sx, ::sy])
    np.testing.assert_allclose(small.map_axes[0], full.map_axes[0][::sx])
    assert small.summary()["feasible"] == full.summary()["feasible"]


def test_grid_and_positions():
    g = spec.load(PLANAR2).workspace.grid
    assert g.shape == (151, 151)
    pos = ws.grid_positions(g, 150, 3)
    np.testing.assert_allclose(pos, [[0.0, 1.5], [0.01, 0.0], [0.01, 0.01]], atol=1e-12)


def test_unknown_kind_is_spec_error():
    with pytest.raises(spec.SpecError):
        ws.run(spec.load(PLANAR2), kind="dynamic")
