"""Workspace sweeps: the numba kernels against a plain numpy reference; chunking; maps."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design import kernels as K
from cdpr_design.statics import kinematics as kin
from cdpr_design.model import spec
from cdpr_design import workspaces as ws
from cdpr_design.workspaces import grid as wsg
from cdpr_design.workspaces.grid import Rows, chunk_stats
from cdpr_design.statics.robot import combinations, resolve
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.errors import InputError
from cdpr_design.model.design import Grid

from .helpers import PLANAR2, collect_chunks, invoke, planar2_raw, random_planar_data
from .reference.general_sweep import general_kernel_rows


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


COLUMNS = ("poses", "feasible", "margin", "tensions", "lengths")


def sweep_columns(design, kind="static", **kw):
    """ws.run's result and its chunks' columns (poses, feasible, margin, tensions, lengths) joined."""
    r, rows = collect_chunks(ws.run, design, ws.Analysis(kind=kind), **kw)
    return r, {name: np.concatenate([getattr(c, name) for c in rows]) for name in COLUMNS}


def sweep_all(design, kind="static", **kw):
    cols = sweep_columns(design, kind, **kw)[1]
    return tuple(cols[name] for name in COLUMNS)


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


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_planar_closed_form_matches_numpy_on_random_robots(seed):
    """Two-cable planar robots: the product's closed form, the general kernel and a per-pose
    numpy reference agree."""
    rng = np.random.default_rng(seed)
    design = spec.from_dict(random_planar_data(rng, m=2))
    assert resolve(design).engine == "numpy"
    got = sweep_all(design)
    poses = got[0]
    wreq = wrench_vertices(design, "static")
    ref = numpy_reference(design, poses, wreq)
    # feasibility identical except where the margin is within rounding of zero
    band = np.abs(ref[1]) < 1e-9
    assert band.sum() <= 2
    keep = ~band
    assert_same(tuple(r[keep] for r in ref), tuple(g[keep] for g in got), design)
    assert got[1].any(), "the random robot should have some feasible poses"

    # the general kernel gives the same numbers as the closed form
    assert_same(general_kernel_rows(design), got, design)


@pytest.mark.slow
def test_planar2_wrench_feasible_matches_numpy():
    data = planar2_raw()
    data["workspace"]["external_wrench"] = {"lower": [-2.0, -1.0], "upper": [2.0, 1.0]}
    design = spec.from_dict(data)
    got = sweep_all(design, kind="wrench-feasible", step=0.03)
    wreq = wrench_vertices(design, "wrench-feasible")
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
    """A grid of more cells than MAP_CELLS (22,801 against 2,000 here) keeps every k-th cell a map."""
    design = spec.load(PLANAR2)
    full = ws.run(design, step=0.01)
    monkeypatch.setattr(wsg, "MAP_CELLS", 2000)
    small = ws.run(design, step=0.01)
    assert np.prod(small.feasible_map.shape) <= 2000
    sx, sy = small.map_stride
    assert sx > 1 and sy > 1
    np.testing.assert_array_equal(small.feasible_map, full.feasible_map[::sx, ::sy])
    np.testing.assert_array_equal(small.margin_map, full.margin_map[::sx, ::sy])
    np.testing.assert_allclose(small.map_axes[0], full.map_axes[0][::sx])
    assert small.summary()["feasible"] == full.summary()["feasible"]


def test_grid_and_positions():
    g = spec.load(PLANAR2).workspace.grid
    assert g.shape == (151, 151)
    pos = wsg.grid_positions(g, 150, 3)
    np.testing.assert_allclose(pos, [[0.0, 1.5], [0.01, 0.0], [0.01, 0.01]], atol=1e-12)


def test_unknown_kind_is_spec_error():
    with pytest.raises(spec.SpecError):
        ws.run(spec.load(PLANAR2), ws.Analysis(kind="kinematic"))


# ----------------------------------------------------------------------------
# Two cables, two wrench rows: the closed form (numpy) against the general kernel
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(25))
def test_closed_form_equals_the_general_kernel(seed):
    """The product's closed form of two cables against the general kernel on random robots, in
    chunks of 1000 rows: every flag identical away from a zero margin, numbers equal to rounding,
    the summary's figures those of the reference's rows."""
    rng = np.random.default_rng(1000 + seed)
    data = random_planar_data(rng, m=2)
    kind = "static"
    if seed % 2:
        data["workspace"]["external_wrench"] = {"lower": [-1.0, -2.0], "upper": [1.5, 0.5]}
        kind = "wrench-feasible"
    design = spec.from_dict(data)
    r, got = sweep_columns(design, kind, chunk=1000)
    assert r.robot.engine == "numpy"
    feas, marg, ten, lens = general_kernel_rows(design, kind)
    edge = np.abs(marg) <= 1e-9 * design.tension_max.max()  # rounding decides the flag there
    assert edge.sum() <= 2
    np.testing.assert_array_equal(got["feasible"][~edge], feas[~edge])
    np.testing.assert_allclose(got["lengths"], lens, rtol=1e-14)
    for key, ref in (("margin", marg), ("tensions", ten)):
        np.testing.assert_array_equal(np.isnan(got[key][~edge]), np.isnan(ref[~edge]))
        np.testing.assert_allclose(got[key], ref, rtol=1e-9, atol=1e-9 * design.tension_max.max(), equal_nan=True)
    s = r.summary()
    ok = got["feasible"].astype(bool)
    assert s["feasible"] == ok.sum() > 0 and abs(s["feasible"] - int(feas.sum())) <= edge.sum()
    assert s["min_margin"] == pytest.approx(float(marg[ok].min()), rel=1e-9, abs=1e-9)
    assert s["max_margin"] == pytest.approx(float(marg[ok].max()), rel=1e-9)
    np.testing.assert_allclose(list(s["max_tension_per_cable"].values()), np.nanmax(np.where(ok[:, None], ten, np.nan), axis=0),
                               rtol=1e-9)


def test_closed_form_degenerate_poses():
    """A grid through an outlet (zero-length cable) and along the line between the outlets
    (parallel cables, rank deficient): infeasible with NaN margin and tensions in the closed
    form, as in the general kernel."""
    data = planar2_raw()
    data["effector"]["size"] = [0.0, 0.0]
    for c in data["cables"]:
        c["attachment"] = [0.0, 0.0]
    design = spec.from_dict(data)
    top = design.outlets[0, 1]
    grid = Grid((0.0, top - 0.5), (1.5, top), (0.05, 0.05))
    _, b = sweep_columns(design, grid=grid)
    feas, marg, ten, _ = general_kernel_rows(design, grid=grid)
    on_line = np.isclose(b["poses"][:, 1], top)
    assert on_line.sum() == 31
    for f, m, t in ((b["feasible"], b["margin"], b["tensions"]), (feas, marg, ten)):
        assert not f[on_line].any()
        assert np.isnan(m[on_line]).all() and np.isnan(t[on_line]).all()
    assert (b["lengths"][on_line] == 0).any(axis=1).sum() == 2  # the two outlets themselves
    np.testing.assert_array_equal(b["feasible"], feas)
    np.testing.assert_allclose(b["margin"], marg, rtol=1e-9, equal_nan=True)
    np.testing.assert_allclose(b["tensions"], ten, rtol=1e-9, equal_nan=True)


def test_engine_choice():
    """The resolved robot's engine is the design's, not the process's or the grid's: the closed
    form (numpy) for two cables with two wrench rows, whatever is asked; the kernels otherwise;
    an unknown engine, or numpy where the closed form does not apply, is refused with the reason."""
    from cdpr_design.statics.robot import Analysis, resolve

    design = spec.load(PLANAR2)
    for engine in ("auto", "numba", "numpy"):
        assert resolve(design, Analysis(engine=engine)).engine == "numpy"
        assert resolve(design, Analysis(engine=engine, kind="wrench-feasible")).engine == "numpy"
    assert resolve(design, Analysis(kind="wrench-closure")).engine == "numba"
    assert resolve(design, Analysis(collisions=True)).engine == "numba"
    with pytest.raises(InputError, match="engine: expected one of auto, numba, numpy"):
        ws.run(design, ws.Analysis(engine="fortran"))
    ipanema = spec.load(PLANAR2.parent / "ipanema3.yaml")
    assert resolve(ipanema, Analysis()).engine == "numba"
    with pytest.raises(InputError, match="engine=numpy: the numpy engine covers two cables"):
        ws.run(ipanema, ws.Analysis(engine="numpy"), step=0.5)


def test_engine_variable_is_read_by_the_command_line(tmp_path, monkeypatch):
    """Only the command line reads CDPR_DESIGN_ENGINE: ``numpy`` where the closed form does not
    cover the sweep is exit 2 with the reason, and a bad value is exit 2 naming the variable."""
    monkeypatch.setenv("CDPR_DESIGN_ENGINE", "numpy")
    r = invoke("workspace", PLANAR2, "--kind", "wrench-closure", "--out", tmp_path / "a", "--json", "--quiet")
    assert r.exit_code == 2
    assert "engine=numpy: the numpy engine covers two cables" in r.output
    assert not (tmp_path / "a").exists()
    monkeypatch.setenv("CDPR_DESIGN_ENGINE", "fortran")
    r = invoke("workspace", PLANAR2, "--out", tmp_path / "b", "--json", "--quiet")
    assert r.exit_code == 2
    assert "CDPR_DESIGN_ENGINE: expected one of auto, numba, numpy" in r.output


def test_kernel_codes_match():
    """workspace keeps copies of kernel constants so that it need not import numba (the numpy
    engine's rank tolerance is held to the kernels' by the sweeps agreeing at degenerate poses,
    test_numpy_engine_degenerate_poses)."""
    from cdpr_design.statics.robot import KINDS

    assert KINDS == {"static": K.KIND_STATIC, "wrench-feasible": K.KIND_WRENCH_FEASIBLE,
                        "wrench-closure": K.KIND_WRENCH_CLOSURE, "dynamic": K.KIND_WRENCH_FEASIBLE}


def _loaded(stderr: str) -> set[str]:
    """The modules a process imported, from its ``-X importtime`` lines."""
    return {line.rsplit("|", 1)[-1].strip() for line in stderr.splitlines() if line.startswith("import time:")}


@pytest.mark.slow
def test_planar2_commands_run_without_numba(tmp_path):
    """The paper's robot on its default grid -- ``workspace``, ``size-motors``, ``report`` -- runs
    without numba's start-up: the user's process never imports numba, even when asked for the
    numba engine (the closed form is that robot's one implementation)."""
    import subprocess
    import sys

    from .helpers import subprocess_env

    found = {}
    for cmd, engine in (("workspace", ""), ("size-motors", ""), ("report", ""), ("workspace", "numba")):
        env = subprocess_env(CDPR_DESIGN_ENGINE=engine)
        r = subprocess.run([sys.executable, "-X", "importtime", "-m", "cdpr_design", cmd, str(PLANAR2), "--json",
                            "--quiet", "--out", str(tmp_path / f"{cmd}{engine}")], capture_output=True, text=True,
                           env=env, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        loaded = _loaded(r.stderr)
        assert "yaml" in loaded, cmd  # the lines were read (the spec's reader)
        assert "numba" not in loaded, (cmd, engine)
        found[cmd + engine] = json.loads(r.stdout)
    assert found["workspacenumba"]["feasible"] == found["workspace"]["feasible"] > 0


@pytest.mark.slow
def test_kernels_package_alone_is_not_the_kernels_loaded():
    """``cdpr_design.kernels`` is lazy and imported without numba (batch and optimize import its
    ``parallel``); planar2 resolves to its closed form whether or not the process has loaded the
    kernels, and its sweep then imports no numba."""
    import subprocess
    import sys

    code = ("import sys; import cdpr_design.batch.local, cdpr_design.optimize.study; "
            "from cdpr_design.model import spec; from cdpr_design.statics.robot import resolve; "
            "from cdpr_design import workspaces as ws; "
            f"d = spec.load({str(PLANAR2)!r}); a = resolve(d).engine; ws.run(d, step=0.1); "
            "b = 'numba' in sys.modules; import cdpr_design.kernels.sweep; "
            "print(a, b, 'numba' in sys.modules, resolve(d).engine)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["numpy", "False", "True", "numpy"]


def _chunk_stats_reference(feas, marg, ten, count, tpeak):
    """The obvious reduction: the feasible rows among the first ``count``, their least and largest
    margin (a zero without its sign) and, per cable, the largest tension into ``tpeak``."""
    rows = [k for k in range(count) if feas[k]]
    for k in rows:
        for i in range(ten.shape[1]):
            if ten[k, i] > tpeak[i]:
                tpeak[i] = ten[k, i]
    if not rows:
        return 0, np.inf, -np.inf
    return len(rows), min(float(marg[k]) for k in rows) + 0.0, max(float(marg[k]) for k in rows) + 0.0


@pytest.mark.parametrize("count", [0, 1, 63, 64, 65, 1000, 4099])
def test_chunk_stats_matches_the_obvious_reduction(count):
    """A chunk's reduction equals the obvious one (a margin of -0.0 is reported as 0.0; a feasible
    row without tensions, NaN, raises no peak)."""
    rng = np.random.default_rng(count)
    n = count + 17
    feas = (rng.random(n) < 0.6).astype(np.uint8)
    marg = rng.normal(size=n)
    marg[rng.random(n) < 0.1] = -0.0
    ten = rng.uniform(0, 20, size=(n, 3))
    ten[rng.random(n) < 0.05] = np.nan
    tp_k, tp_r = np.full(3, -np.inf), np.full(3, -np.inf)
    got = chunk_stats(Rows(feas[:count], marg[:count], ten[:count], None), tp_k)
    ref = _chunk_stats_reference(feas, marg, ten, count, tp_r)
    assert got == ref and got[0] == int(feas[:count].sum())
    assert not np.signbit(got[1]) or got[1] < 0
    np.testing.assert_array_equal(tp_k, tp_r)


def _chunk_stats_boolean_rows(feas, marg, ten, tpeak):
    """The reduction over the boolean-indexed feasible rows (the formulation the blocked one
    replaced): fmax/fmin along the rows, NaN passed over, a margin of -0.0 reported as 0.0."""
    f = np.asarray(feas).astype(bool)
    nf = int(np.count_nonzero(f))
    if not nf:
        return 0, np.inf, -np.inf
    mm = np.asarray(marg)[f]
    np.fmax(tpeak, np.fmax.reduce(np.asarray(ten)[f], axis=0), out=tpeak)
    return nf, float(np.fmin.reduce(mm, initial=np.inf)) + 0.0, float(np.fmax.reduce(mm, initial=-np.inf)) + 0.0


_SPECIAL = [np.nan, 0.0, -0.0, 1.0, -1.0, np.inf, -np.inf, 5e-324, -5e-324]


@st.composite
def _chunks(draw):
    """A chunk of rows: k rows (0 .. 300, across whole blocks and the rows left), m cables
    (1 .. 9); feasibility all, none, one row or mixed (uint8 or bool); margins and tensions drawn
    from NaN, +-0.0, +-inf, subnormals and ordinary numbers; a peak already raised by earlier
    chunks."""
    k = draw(st.integers(0, 300))
    m = draw(st.integers(1, 9))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    p = draw(st.sampled_from([0.0, 1.0, 1.0 / max(k, 1), 0.5, 0.95]))
    feas = (rng.random(k) < p).astype(draw(st.sampled_from([np.uint8, np.bool_])))

    def column(shape):
        x = rng.normal(scale=draw(st.sampled_from([1.0, 1e3])), size=shape)
        special = rng.random(shape) < draw(st.sampled_from([0.0, 0.1, 0.5, 1.0]))
        x[special] = rng.choice(_SPECIAL, size=int(special.sum()))
        return x

    tpeak = rng.choice([-np.inf, 0.0, 0.5], size=m)  # as a sweep leaves it: never NaN nor -0.0
    return feas, column(k), column((k, m)), tpeak


@settings(max_examples=400, deadline=None)
@given(_chunks())
def test_chunk_stats_is_the_boolean_rows_reduction_bit_for_bit(chunk):
    """A chunk's blocked reduction gives, bit for bit, the boolean-indexed rows' one -- except that
    a largest tension of zero is always 0.0 (fmax keeps either of two equal zeros, so the sign of
    the boolean rows' zero peak depends on the order of reduction)."""
    feas, marg, ten, tpeak = chunk
    got_peak, ref_peak = tpeak.copy(), tpeak.copy()
    got = chunk_stats(Rows(feas, marg, ten, None), got_peak)
    ref = _chunk_stats_boolean_rows(feas, marg, ten, ref_peak)
    assert np.array(got).view(np.int64).tolist() == np.array(ref).view(np.int64).tolist()
    assert got[0] == int(np.count_nonzero(feas))
    expect = np.where(ref_peak == 0, 0.0, ref_peak)  # NaN stays NaN, the zeros without sign
    np.testing.assert_array_equal(got_peak.view(np.int64), expect.view(np.int64))


def test_chunk_stats_reports_a_zero_margin_without_its_sign():
    feas = np.ones(3, np.uint8)
    ten = np.ones((3, 2))
    got = chunk_stats(Rows(feas, np.array([-0.0, 1.0, -0.0]), ten, None), np.full(2, -np.inf))
    assert got == (3, 0.0, 1.0) and not np.signbit(got[1])
    got = chunk_stats(Rows(feas, np.full(3, -0.0), ten, None), np.full(2, -np.inf))
    assert got == (3, 0.0, 0.0) and not np.signbit(got[1]) and not np.signbit(got[2])


def test_warm_up_runs_the_sweeps_first_pose_with_the_whole_grids_robot(monkeypatch):
    """The warm-up sweeps the plan's first pose alone with the robot resolved for the whole grid."""
    design = spec.load(PLANAR2)
    big = ws.make_grid(design, 0.004)
    p = ws.plan(resolve(design), big)
    one = p.on(ws.grid.first_pose(big))
    assert one.robot is p.robot and one.grid.size == 1 and tuple(one.grid.lower) == tuple(big.lower)
    assert one.columns == p.columns and one.pictures == p.pictures
