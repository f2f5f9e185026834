"""The workspace's boundary between grid points (workspaces/boundary.py) and the frame loads
(workspaces/frame_loads.py): against closed forms (tests/reference_boundary.py), the STL read
back by trimesh, an independent computation from workspace.csv, and bad inputs."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
import yaml

from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.model.design import Grid
from cdpr_design.statics.robot import Analysis, resolve
from cdpr_design.workspaces import boundary as wb
from cdpr_design.workspaces.frame_loads import rotations
from cdpr_design.workspaces.orientation import orientation_set

from .helpers import DESIGNS, PLANAR2, invoke, planar2_raw, read_csv, write_spec
from .reference_boundary import planar_area, spatial_volume


def solid(design, step=None):
    g = ws.make_grid(design, step)
    return ws.plan(resolve(design), g, solid=True).run()


def planar2_exact(design, grid: Grid) -> float:
    """The seed paper's robot as a point mass from the outlets shifted by its attachments."""
    A = design.outlets[:, :2] - design.attachments[:, :2]
    assert A[0, 1] == A[1, 1]
    mg = design.effector.mass * 9.81
    return planar_area(A[0, 0], A[1, 0], A[0, 1], mg, design.tension_min[0], design.tension_max[0],
                       grid.lower[1], box_top(grid, 1))


def pod_data(tmax=60.0) -> dict:
    """designs/pointmass3.yaml with a tension limit low enough to bound the workspace from above."""
    raw = yaml.safe_load((DESIGNS / "pointmass3.yaml").read_text())
    raw["name"], raw["tension"] = "pod", [0.0, tmax]
    raw["cable"]["axial_stiffness"] = 5.0e5  # PyYAML reads the file's 5.0e5 as text
    return raw


def twocable_data() -> dict:
    """A point mass on two cables from a 3 m bar, with a lower tension bound (our own example)."""
    return {"name": "twocable", "motion": "2T", "gravity": [0.0, -9.81],
            "frame": {"lower": [0.0, 0.0], "upper": [3.5, 3.5]},
            "effector": {"mass": 2.0, "size": [0.0, 0.0]}, "tension": [5.0, 60.0],
            "cables": [{"name": "a", "outlet": [0.25, 3.3], "attachment": [0.0, 0.0]},
                       {"name": "b", "outlet": [3.25, 3.3], "attachment": [0.0, 0.0]}],
            "workspace": {"grid": {"lower": [0.0, 0.0], "upper": [3.5, 3.5], "step": 0.05}}}


def box_top(g: Grid, axis: int) -> float:
    return g.lower[axis] + (g.shape[axis] - 1) * g.step[axis]


def test_planar2_area_within_half_a_percent_at_005(planar2):
    r = solid(planar2, 0.05)
    exact = planar2_exact(planar2, r.grid)
    assert abs(r.boundary.measure / exact - 1) < 0.005
    # the grid count is further off: the boundary is the better figure
    assert abs(r.boundary.measure / exact - 1) < abs(r.measure / exact - 1)
    s = r.summary()
    assert s["boundary_measure"] == r.boundary.measure and s["boundary_surface"] > 0


def test_two_cable_point_mass_area_within_half_a_percent_at_005(tmp_path):
    d = spec.from_dict(twocable_data())
    r = solid(d, 0.05)
    g = r.grid
    exact = planar_area(0.25, 3.25, 3.3, 2.0 * 9.81, 5.0, 60.0, g.lower[1], box_top(g, 1))
    assert abs(r.boundary.measure / exact - 1) < 0.005, (r.boundary.measure, exact)


def test_spatial_pod_volume_within_one_percent_at_its_coarse_step():
    d = spec.from_dict(pod_data())
    r = solid(d)  # the design's 0.5 m step
    g = r.grid
    exact = spatial_volume(d.outlets[:, :2], 6.0, 5.0 * 9.81, 60.0, g.lower[2], box_top(g, 2), box_top(g, 1))
    assert abs(r.boundary.measure / exact - 1) < 0.01, (r.boundary.measure, exact)
    assert abs(r.measure / exact - 1) > 0.05  # the grid count is not


def test_the_error_falls_with_the_step(planar2):
    errs = []
    for step in (0.1, 0.05, 0.025):
        r = solid(planar2, step)
        errs.append(abs(r.boundary.measure / planar2_exact(planar2, r.grid) - 1))
    assert errs[2] < errs[0]


def test_refined_vertices_lie_on_the_boundary(planar2):
    """Every loop vertex off the box lies where feasibility changes: within the bisection's
    tolerance along its grid edge, one side feasible and the other not."""
    r = solid(planar2, 0.05)
    test = ws.plan(resolve(planar2), r.grid).point_test()
    xy = np.concatenate(r.boundary.loops)
    g = r.grid
    top = np.array([box_top(g, 0), box_top(g, 1)])
    inside = np.all((xy > np.array(g.lower) + 1e-9) & (xy < top - 1e-9), axis=1)
    P = np.zeros((int(inside.sum()), 3))
    P[:, :2] = xy[inside]
    tol = 0.05 / 2 ** wb.BISECTIONS
    flips = 0
    for ax in range(2):
        lo, hi = P.copy(), P.copy()
        lo[:, ax] -= tol
        hi[:, ax] += tol
        flips += np.count_nonzero(test(lo)[0] != test(hi)[0])
    assert flips >= len(P)  # each vertex has a change of feasibility within tol along some axis


@pytest.mark.parametrize("step", [0.5, 0.4])
def test_stl_is_closed_and_its_volume_is_boundary_measure(tmp_path, step):
    trimesh = pytest.importorskip("trimesh")
    path = write_spec(tmp_path, pod_data())
    out = tmp_path / "out"
    res = invoke("workspace", path, "--out", out, "--step", step, "--json", "--quiet")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    mesh = trimesh.load(io.BytesIO((out / "workspace.stl").read_bytes()), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0  # normals outwards
    assert mesh.volume == pytest.approx(s["boundary_measure"], rel=1e-6)
    assert mesh.area == pytest.approx(s["boundary_surface"], rel=1e-6)
    lo, hi = mesh.bounds
    g = s["grid"]
    tops = [lo_ + (n - 1) * st for lo_, n, st in zip(g["lower"], g["shape"], g["step"])]
    assert np.all(lo >= np.array(g["lower"]) - 1e-5) and np.all(hi <= np.array(tops) + 1e-5)  # clipped by the box


def whole_field_boundary(grid, field, evaluator):
    """The boundary of a whole signed margin ``field`` (the grid's shape) as the sweep's
    :class:`~cdpr_design.workspaces.boundary.Slabs` find it from streamed rows, the field given at
    once; ``evaluator()`` gives the feasibility test at positions (k, 3) [m]."""
    slabs = wb.Slabs(grid, 1.0)
    flat = np.ascontiguousarray(field, dtype=np.float32).reshape(-1)
    slabs.add(0, flat > 0, np.abs(flat))
    return slabs.boundary(evaluator)


def test_random_fields_give_closed_meshes():
    """Noise fields (the hardest topology) with a random refinement: always closed, consistently
    wound, outward, and the volume trimesh finds."""
    trimesh = pytest.importorskip("trimesh")
    rng = np.random.default_rng(5)
    for _ in range(60):
        shape = tuple(int(s) for s in rng.integers(2, 8, 3))
        f = rng.normal(size=shape) + rng.uniform(-1.0, 1.5)
        g = Grid((0.0, 0.0, 0.0), tuple((s - 1) * 0.1 for s in shape), (0.1, 0.1, 0.1))
        def test(P):
            ok = rng.random(len(P)) < 0.5
            return ok, np.where(ok, 1.0, -1.0) * rng.random(len(P))  # margins that agree, sometimes

        b = whole_field_boundary(g, wb.signed_margin(f > 0, np.abs(f)), lambda: test)
        if len(b.faces):
            m = trimesh.Trimesh(b.vertices, b.faces, process=False)
            assert m.is_watertight and m.is_winding_consistent
            assert m.volume == pytest.approx(b.measure, rel=1e-9) and b.measure > 0


def test_a_broken_mesh_is_refused():
    verts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    wb.check_closed(verts, faces)
    with pytest.raises(RuntimeError, match="not closed"):
        wb.check_closed(verts, faces[:3])
    with pytest.raises(RuntimeError, match="not closed"):
        wb.check_closed(verts, np.vstack([faces[:3], faces[3:, ::-1]]))
    with pytest.raises(RuntimeError, match="not closed"):  # every edge twice each way
        wb.check_closed(verts, np.vstack([faces, faces]))
    with pytest.raises(RuntimeError, match="not closed"):  # a triangle with a repeated vertex
        wb.check_closed(verts, np.vstack([faces, [[0, 0, 1], [1, 0, 0]]]))


# ---------------------------------------------------------------- bad inputs


def test_no_feasible_pose_gives_zero_and_an_empty_boundary(tmp_path):
    raw = planar2_raw()
    raw["tension"] = [0.0, 1.0]  # 1 N cannot hold 1 kg
    path = write_spec(tmp_path, raw)
    res = invoke("workspace", path, "--out", tmp_path / "o", "--step", 0.1, "--json", "--quiet")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["feasible"] == 0 and s["boundary_measure"] == 0.0 and s["boundary_surface"] == 0.0
    header, rows = read_csv(tmp_path / "o" / "boundary.csv")
    assert header == ["x", "y", "loop"] and rows == []
    header, rows = read_csv(tmp_path / "o" / "frame_loads.csv")
    assert [r[0] for r in rows] == ["c1", "c2"] and all(c == "" for r in rows for c in r[1:])
    raw = pod_data(tmax=1.0)
    res = invoke("workspace", write_spec(tmp_path, raw, "pod.yaml"), "--out", tmp_path / "p", "--json", "--quiet")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["boundary_measure"] == 0.0
    assert (tmp_path / "p" / "workspace.stl").read_bytes()[80:84] == b"\0\0\0\0"  # no triangle


def test_a_too_coarse_grid_says_so(tmp_path):
    path = write_spec(tmp_path, planar2_raw())
    res = invoke("workspace", path, "--out", tmp_path / "o", "--step", 0.5, "--json")
    assert res.exit_code == 0, res.output
    warning = json.loads(res.stdout)["boundary_warning"]
    assert "too coarse" in warning
    d = spec.load(path)
    r = ws.run(d, step=0.5, solid=True)
    short, crossings = _short_runs(r.feasible_map > 0)
    assert short > wb.THIN_SHARE * crossings and f": {short} runs of poses" in warning
    res = invoke("workspace", path, "--out", tmp_path / "o", "--step", 0.5)
    assert res.exit_code == 0 and "too coarse" in res.stderr  # a note beside the table
    res = invoke("workspace", path, "--out", tmp_path / "f", "--step", 0.05, "--json")
    assert "boundary_warning" not in json.loads(res.stdout) and "too coarse" not in res.stderr


def _short_runs(feasible: np.ndarray) -> tuple[int, int]:
    """(short runs, crossings) of a feasibility array (the grid's shape), line by line along each
    axis: a crossing where two neighbours differ, a short run between two crossings of one line
    fewer than MIN_STEPS steps apart (the coarse-grid warning's rule, counted the slow way)."""
    short = crossings = 0
    for ax in range(feasible.ndim):
        lines = np.moveaxis(feasible, ax, -1).reshape(-1, feasible.shape[ax])
        for line in lines:
            at = [i for i in range(len(line) - 1) if line[i] != line[i + 1]]
            crossings += len(at)
            short += sum(b - a < wb.MIN_STEPS for a, b in zip(at, at[1:]))
    return short, crossings


@pytest.mark.parametrize("name,step", [("pointmass3.yaml", 1.0), ("ipanema3.yaml", 0.5)])
def test_the_boundary_does_not_depend_on_the_chunks(name, step):
    """Rows streamed in chunks of any size (parts of a plane of the grid's first axis, several
    planes) give the same boundary, bit for bit, and the coarse-grid count of the slow rule."""
    d = spec.load(DESIGNS / name)
    g = ws.make_grid(d, step)
    robot = resolve(d)
    plane = int(np.prod(g.shape[1:]))
    results = [ws.plan(robot, g, solid=True).run(chunk=c) for c in (g.size, plane // 3 + 1, 2 * plane + 5)]
    for r in results[1:]:
        assert r.boundary.measure == results[0].boundary.measure
        np.testing.assert_array_equal(r.boundary.vertices, results[0].boundary.vertices)
        np.testing.assert_array_equal(r.boundary.faces, results[0].boundary.faces)
        assert r.boundary.warning == results[0].boundary.warning
    short, crossings = _short_runs(results[0].feasible_map > 0)
    assert crossings > 0
    warning = results[0].boundary.warning
    assert (warning is not None) == (short > wb.THIN_SHARE * crossings)
    if warning is not None:
        assert f": {short} runs of poses" in warning


# ---------------------------------------------------------------- frame loads


def _frame_loads_from_table(design, out, planar: bool):
    """frame_loads.csv's envelope recomputed from workspace.csv: force t_i along the unit vector
    from the outlet to the attachment, over the feasible rows."""
    header, rows = read_csv(out / "workspace.csv")
    col = {n: i for i, n in enumerate(header)}
    feas = [r for r in rows if r[col["feasible"]] == "1"]
    coords = ["x", "y"] if planar else ["x", "y", "z"]
    P = np.array([[float(r[col[c]]) for c in coords] for r in feas])
    out_rows = {}
    for i, c in enumerate(design.cable_names):
        t = np.array([float(r[col[f"tension_{c}"]]) for r in feas])
        a = design.outlets[i, :len(coords)]
        b = design.attachments[i, :len(coords)]
        D = P + b - a
        F = t[:, None] * D / np.linalg.norm(D, axis=1, keepdims=True)
        G = design.tension_max[i] * D / np.linalg.norm(D, axis=1, keepdims=True)
        row = {"max_force": np.linalg.norm(F, axis=1).max(), "limit_max_force": np.linalg.norm(G, axis=1).max()}
        for j, ax in enumerate(coords):
            row[f"min_f{ax}"], row[f"max_f{ax}"] = F[:, j].min(), F[:, j].max()
            row[f"limit_min_f{ax}"], row[f"limit_max_f{ax}"] = G[:, j].min(), G[:, j].max()
        out_rows[c] = row
    return out_rows


@pytest.mark.parametrize("name,step", [("planar2.yaml", 0.05), ("pointmass3.yaml", 1.0), ("ipanema3.yaml", 0.25)])
def test_frame_loads_match_workspace_csv(tmp_path, name, step):
    d = spec.load(DESIGNS / name)
    out = tmp_path / "o"
    res = invoke("workspace", DESIGNS / name, "--out", out, "--step", step, "--json", "--quiet")
    assert res.exit_code == 0, res.output
    planar = d.motion.planar
    want = _frame_loads_from_table(d, out, planar)
    header, rows = read_csv(out / "frame_loads.csv")
    assert header[0] == "cable" and len(rows) == d.m
    for r in rows:
        got = dict(zip(header[1:], map(float, r[1:])))
        assert set(got) == set(want[r[0]])
        for k, v in want[r[0]].items():
            assert got[k] == pytest.approx(v, rel=1e-6, abs=1e-6), (r[0], k)
    s = json.loads(res.stdout)["frame_loads"]
    assert s["max_force"] == pytest.approx(max(w["max_force"] for w in want.values()), rel=1e-6)


@pytest.mark.parametrize("name,step", [("planar4.yaml", 0.1), ("ipanema3.yaml", 0.5)])
def test_total_orientation_frame_loads_cover_every_orientation(name, step):
    """--orientations total: the loads are the envelope over the positions feasible at every
    orientation of the set and over every orientation, each with its own tensions: recomputed here
    from a plain sweep at each orientation (its tensions along t_i (B_i - A_i) / |B_i - A_i|,
    B_i = P + R b_i) over the total sweep's feasible positions."""
    d = spec.load(DESIGNS / name)
    g = ws.make_grid(d, step)
    oset = orientation_set(d)
    assert len(oset) > 1
    chunks = []
    r = ws.plan(resolve(d, Analysis(orientations="total")), g, frame_loads=True).run(on_chunk=chunks.append)
    feasible = np.concatenate([c.feasible for c in chunks]).astype(bool)
    assert 0 < feasible.sum() < g.size
    P = ws.grid.positions3(g, 0, g.size)[feasible]
    F_all, n = [], 0
    for o in oset:
        one = []
        ws.plan(resolve(d), g, o, tilt=False).run(on_chunk=one.append)
        t = np.concatenate([c.tensions for c in one])[feasible]
        ok = np.isfinite(t).all(axis=1)
        n += int(ok.sum())
        R = rotations(np.asarray(o, float)[None])[0]
        D = P[ok][:, None, :] + (d.attachments @ R.T)[None] - d.outlets[None]
        F_all.append(t[ok][:, :, None] * D / np.linalg.norm(D, axis=2, keepdims=True))
    F = np.concatenate(F_all)  # (poses, m, 3)
    planar = d.motion.planar
    axes = "xy" if planar else "xyz"
    got = r.frame_loads.rows(d.cable_names)
    for i, c in enumerate(d.cable_names):
        assert got["max_force"][i] == pytest.approx(np.linalg.norm(F[:, i], axis=1).max(), rel=1e-9)
        for j, a in enumerate(axes):
            assert got[f"min_f{a}"][i] == pytest.approx(F[:, i, j].min(), rel=1e-9, abs=1e-9), (c, a)
            assert got[f"max_f{a}"][i] == pytest.approx(F[:, i, j].max(), rel=1e-9, abs=1e-9), (c, a)
    s = r.summary()["frame_loads"]
    assert s["poses"] == n
    total = F.sum(axis=1)[:, :len(axes)]
    assert s["total_force"]["max_magnitude"] == pytest.approx(np.linalg.norm(total, axis=1).max(), rel=1e-9)


def _axle_forces(design, P, t, axes, radii):
    """Forces (k, m, 3) [N] on the axles of swivel pulleys at effector positions ``P`` (k, 3) [m]
    (orientation 0) with tensions ``t`` (k, m) [N]: the cable arrives at the swivel point A along the
    unit axis k, wraps the pulley (radius rho, centre A + rho e in the plane of k and the attachment
    B, e the unit vector across k towards B) and leaves it at the tangent point T towards B, so the
    axle carries t (d - k), d = (B - T) / |B - T|.  Plane coordinates (along e, along k): the centre
    (rho, 0); of the two tangent points from B the one where the cable, running on round the pulley
    from A, leaves it towards B: the circle's direction of travel (sin beta, cos beta) at
    T = (rho - rho cos beta, rho sin beta), beta the wrap angle, points at B."""
    A = design.outlets
    B = P[:, None, :] + design.attachments[None]
    out = np.empty(B.shape)
    for i in range(design.m):
        k, rho = axes[i] / np.linalg.norm(axes[i]), radii[i]
        D = B[:, i] - A[i]
        across = D - np.outer(D @ k, k)
        e = across / np.linalg.norm(across, axis=1, keepdims=True)
        bx, by = np.einsum("kj,kj->k", D, e), D @ k
        cx = bx - rho
        dist = np.hypot(cx, by)
        phi, gap = np.arctan2(by, cx), np.arccos(rho / dist)
        best = np.full((len(P), 3), np.nan)
        for sign in (1.0, -1.0):
            ang = phi + sign * gap  # the tangent point's angle about the centre
            beta = np.pi - ang
            tx, ty = rho - rho * np.cos(beta), rho * np.sin(beta)
            travel = np.stack([np.sin(beta), np.cos(beta)], axis=1)
            to_b = np.stack([bx - tx, by - ty], axis=1)
            pick = np.einsum("kj,kj->k", travel, to_b) > 0  # at the other one it points away from B
            d = travel[:, :1] * e + travel[:, 1:] * k
            best[pick] = d[pick]
        out[:, i] = t[:, i:i + 1] * (best - k)
    return out


@pytest.mark.parametrize("name", ["planar", "spatial"])
def test_swivel_pulley_frame_loads_match_the_axle_forces_from_workspace_csv(tmp_path, name):
    """frame_loads.csv of a design with swivel pulleys: the force on each pulley's axle, the
    resultant of the cable run from the winch (along -k) and of the free run towards the
    attachment, recomputed from workspace.csv's tensions with the pulley geometry above; the
    limit_ columns the same at the upper tension bound."""
    from .helpers import add_pulleys, ipanema3_data

    if name == "planar":
        raw = planar2_raw()
        add_pulleys(raw["cables"], 0.05, [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
        step = 0.05
    else:
        raw = ipanema3_data("pulleys3", radius=0.2, workspace={
            "grid": {"lower": [-6.0, -3.5, 0.0], "upper": [6.0, 3.5, 2.5], "step": 0.5}})
        step = 0.5
    d = spec.from_dict(raw)
    out = tmp_path / "o"
    res = invoke("workspace", write_spec(tmp_path, raw), "--out", out, "--step", step, "--json", "--quiet")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(out / "workspace.csv")
    col = {n: i for i, n in enumerate(header)}
    feas = [r for r in rows if r[col["feasible"]] == "1"]
    assert len(feas) > 50
    dim = d.motion.dim
    P = np.zeros((len(feas), 3))
    P[:, :dim] = [[float(r[col[c]]) for c in "xyz"[:dim]] for r in feas]
    t = np.array([[float(r[col[f"tension_{c}"]]) for c in d.cable_names] for r in feas])
    axes = np.array([c["pulley"]["axis"] for c in raw["cables"]], float)
    radii = np.array([c["pulley"]["radius"] for c in raw["cables"]], float)
    F = _axle_forces(d, P, t, axes, radii)
    U = _axle_forces(d, P, np.ones_like(t), axes, radii)
    assert np.isfinite(F).all()
    # the axle force is not the straight cable's: the run from the winch adds -t k
    assert np.abs(np.linalg.norm(F, axis=2) - t).max() > 0.1 * t.max()
    header_f, rows_f = read_csv(out / "frame_loads.csv")
    assert [r[0] for r in rows_f] == list(d.cable_names)
    for i, r in enumerate(rows_f):
        got = dict(zip(header_f[1:], map(float, r[1:])))
        want = {"max_force": np.linalg.norm(F[:, i], axis=1).max(),
                "limit_max_force": d.tension_max[i] * np.linalg.norm(U[:, i], axis=1).max()}
        for j, a in enumerate("xyz"[:dim]):
            want[f"min_f{a}"], want[f"max_f{a}"] = F[:, i, j].min(), F[:, i, j].max()
            want[f"limit_min_f{a}"] = d.tension_max[i] * U[:, i, j].min()
            want[f"limit_max_f{a}"] = d.tension_max[i] * U[:, i, j].max()
        assert set(got) == set(want)
        for key, v in want.items():
            assert got[key] == pytest.approx(v, rel=1e-6, abs=1e-6 * d.tension_max[i]), (r[0], key)
    s = json.loads(res.stdout)["frame_loads"]
    total = F.sum(axis=1)
    moment = np.cross(d.outlets[None], F).sum(axis=1)
    assert s["poses"] == len(feas)
    assert s["total_force"]["max_magnitude"] == pytest.approx(np.linalg.norm(total[:, :dim], axis=1).max(), rel=1e-6)
    mom = moment[:, 2:] if dim == 2 else moment
    assert s["total_moment"]["max_magnitude"] == pytest.approx(np.linalg.norm(mom, axis=1).max(), rel=1e-6)


@pytest.mark.slow
def test_frame_carries_the_weight_with_sagging_cables(tmp_path):
    """Statics: the frame carries the effector's and the cables' weight, whatever the cables'
    shapes: the total force is -(m + sum mu_i L0_i) g at every feasible pose."""
    d = spec.load(DESIGNS / "sagging40.yaml")
    g = ws.make_grid(d, 1.0)
    rob = resolve(d)
    chunks = []
    r = ws.plan(rob, g, solid=True).run(on_chunk=chunks.append)
    assert r.feasible > 0
    from cdpr_design.workspaces.frame_loads import outlet_forces

    up = rob.cable.up
    for ch in chunks:
        ok = ch.feasible.astype(bool)
        if not ok.any():
            continue
        P = np.zeros((int(ok.sum()), 3))
        P[:, :2] = ch.poses[ok, :2]
        F = outlet_forces(rob, P, np.eye(3), ch.tensions[ok], {k: v[ok] for k, v in ch.extra.items()})[0]
        L0 = np.stack([ch.extra[f"unstretched_length_{c}"][ok] for c in d.cable_names], axis=1)
        weight = d.effector.mass * 9.81 + (L0 * rob.cable.w).sum(axis=1)
        total = F.sum(axis=0).T
        np.testing.assert_allclose(total @ up, -weight, rtol=1e-6)
        np.testing.assert_allclose(np.linalg.norm(total - np.outer(total @ up, up), axis=1), 0.0,
                                   atol=1e-6 * weight.max())
    assert r.summary()["frame_loads"]["total_force"]["max_magnitude"] > d.effector.mass * 9.81


@pytest.mark.slow
def test_compiled_frame_loads_equal_numpy_ones():
    """The one-pass kernel (straight cables from point outlets) gives numpy's envelope, on random
    spatial and planar robots and IPAnema 3; the grid sweep's own (the envelope raised pose by pose
    on its threads, the plan's with the frame loads) gives the one-pass kernel's, bit for bit (0.0
    and -0.0 as they come)."""
    import dataclasses

    from cdpr_design.workspaces.frame_loads import FrameLoads

    from .helpers import random_planar_data

    rng = np.random.default_rng(3)
    designs = [spec.load(DESIGNS / "ipanema3.yaml"), spec.load(DESIGNS / "pointmass3.yaml")]
    designs += [spec.from_dict(random_planar_data(rng, m)) for m in (2, 3, 4)]
    for d in designs:
        g = ws.make_grid(d, None)
        robot = resolve(d, Analysis(engine="numba"))
        p = ws.plan(robot, g)
        n = min(g.size, 20000)
        P = ws.grid.positions3(g, 0, n)
        r = p.rows(0, n, P)
        a, b = FrameLoads(robot, p.orientation), FrameLoads(robot, p.orientation)
        # the kernels' robots take the compiled pass; a two-cable planar robot's engine is the closed
        # form (numpy), and the pass is asked for there so that it is compared on two cables as well
        assert a.compiled == (robot.engine == "numba")
        a.compiled, b.compiled = True, False
        a.add(r, 0, P)
        b.add(r, 0, P)
        names = d.cable_names
        ra, rb = a.table.rows(names), b.table.rows(names)
        pl = ws.plan(robot, g, frame_loads=True)
        inline = next(w for w in pl.wrappers if isinstance(w, FrameLoads))
        assert inline.inline == (robot.engine == "numba")
        if inline.inline:
            pl.rows(0, n, P)  # the plan's rows raise its wrappers' tallies
            rc = inline.table.rows(names)
            assert ({k: [repr(v) for v in vs] for k, vs in rc.items()}
                    == {k: [repr(v) for v in vs] for k, vs in ra.items()}), d.name
            assert inline.table.summary(names) == a.table.summary(names)
        for k in ra:
            if k != "cable":
                np.testing.assert_allclose(ra[k], rb[k], rtol=1e-9, atol=1e-9, err_msg=f"{d.name} {k}")
        sa, sb = a.table.summary(names), b.table.summary(names)
        assert sa["poses"] == sb["poses"] > 0
        for key in ("total_force", "total_moment"):
            for part in ("min", "max"):
                for ax in sa[key][part]:
                    assert sa[key][part][ax] == pytest.approx(sb[key][part][ax], rel=1e-9, abs=1e-9)
            assert sa[key]["max_magnitude"] == pytest.approx(sb[key]["max_magnitude"], rel=1e-9)


# ---------------------------------------------------------------- checks, figures, commands


def test_max_frame_load_is_a_check(tmp_path):
    raw = planar2_raw()
    raw["requirements"]["max_frame_load"] = 15.0  # the paper's robot puts up to 19.98 N on an outlet
    res = invoke("check", write_spec(tmp_path, raw, "fail.yaml"), "--json")
    assert res.exit_code == 1
    out = json.loads(res.stdout)
    row = next(c for c in out["checks"] if c["requirement"] == "max_frame_load")
    assert row["passed"] is False and out["figures"]["max_frame_load"] == pytest.approx(19.98, abs=0.01)
    raw["requirements"]["max_frame_load"] = 25.0
    res = invoke("check", write_spec(tmp_path, raw, "pass.yaml"), "--json")
    out = json.loads(res.stdout)
    assert next(c for c in out["checks"] if c["requirement"] == "max_frame_load")["passed"] is True
    raw["requirements"]["max_frame_load"] = -1.0
    res = invoke("check", write_spec(tmp_path, raw, "bad.yaml"))
    assert res.exit_code == 2 and "requirements.max_frame_load" in res.stderr


def test_boundary_measure_is_a_figure_of_the_design_report(planar2):
    from cdpr_design.design.evaluate import evaluate
    from cdpr_design.optimize import objectives as opt

    row = evaluate(planar2, step=0.05, figures=frozenset({"boundary_measure"}))
    assert row["boundary_measure"] == pytest.approx(planar2_exact(planar2, ws.make_grid(planar2, 0.05)), rel=0.005)
    assert "boundary_measure" in opt.FIGURES and "max_frame_load" in opt.FIGURES
    assert [o.figure for o in opt.make_objectives(planar2, ["boundary_measure"], ["max_frame_load"])] == [
        "boundary_measure", "max_frame_load"]


def test_size_motors_and_the_report_show_the_frame_loads(tmp_path):
    res = invoke("size-motors", PLANAR2, "--out", tmp_path / "s", "--json", "--quiet")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["frame_loads"]["max_force"] == pytest.approx(19.98, abs=0.01)
    assert [r["cable"] for r in s["frame_loads_per_cable"]] == ["c1", "c2"]
    res = invoke("size-motors", PLANAR2, "--out", tmp_path / "t")
    assert res.exit_code == 0 and "loads on the frame" in res.stdout
    res = invoke("workspace", DESIGNS / "pointmass3.yaml", "--out", tmp_path / "w", "--html", "--quiet")
    assert res.exit_code == 0, res.output
    page = (tmp_path / "w" / "report.html").read_text()
    assert '"mesh3d"' in page and "Loads on the frame" in page and "limit_max_force" in page


def test_rotations_are_the_kinematics_ones():
    from cdpr_design.statics.kinematics import rotation_matrix
    from cdpr_design.workspaces.frame_loads import rotations

    a = np.random.default_rng(2).uniform(-3, 3, (20, 3))
    np.testing.assert_allclose(rotations(a), np.array([rotation_matrix(*x) for x in a]), atol=1e-15)


@pytest.mark.slow
def test_a_hanging_effector_puts_its_weight_on_the_frame():
    """crane4 hangs its load (effector.orientation: free): at every feasible pose the frame carries
    the load's weight, straight down, whatever orientation it hangs in."""
    d = spec.load(DESIGNS / "crane4.yaml")
    g = ws.make_grid(d, 0.5)
    robot = resolve(d)
    assert robot.orientation.free
    r = ws.plan(robot, g, solid=True).run()
    s = r.summary()["frame_loads"]
    w = d.effector.mass * 9.81
    assert s["poses"] == r.feasible > 0
    assert s["total_force"]["min"]["z"] == pytest.approx(-w, rel=1e-6)
    assert s["total_force"]["max"]["z"] == pytest.approx(-w, rel=1e-6)
    assert max(abs(s["total_force"][m][a]) for m in ("min", "max") for a in "xy") < 1e-6 * w


# ---------------------------------------------------------------- pictures


def test_a_slice_through_a_mesh_with_level_edges_warns_nothing():
    """The unit cube (12 triangles) cut at its faces' heights and between them: the outline is the
    square, and edges level with the plane (or not reaching it) form no 0 / 0."""
    import warnings

    from cdpr_design.plots.solid import slice_segments

    v = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    f = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for z in (0.0, 0.25, 0.5, 1.0):
            segs = slice_segments(v, f, z)
            if z == 1.0:  # nothing above the top face
                assert len(segs) == 0
                continue
            assert len(segs) == 8 and np.all(np.isfinite(segs))
            length = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1).sum()
            assert length == pytest.approx(4.0)
            assert np.all(np.isclose(np.abs(segs - 0.5), 0.5).any(axis=2))  # on the square's sides


def test_frame_loads_picture_keeps_its_title_above_the_panels(planar2):
    """frame_loads.png: the figure's title does not run into the two panels' (two-line) titles."""
    from cdpr_design.plots.solid import frame_load_figure

    fig = frame_load_figure(solid(planar2, 0.05))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    sup = [t for t in fig.texts if t.get_text().startswith(planar2.name)]
    assert len(sup) == 1
    top = sup[0].get_window_extent(renderer)
    for ax in fig.axes:
        box = ax.title.get_window_extent(renderer)
        assert ax.title.get_text() and box.y1 < top.y0, (ax.title.get_text(), box, top)
