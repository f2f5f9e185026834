"""Interference: kernels against slow obvious computations, hand-built cases, symmetries,
the sweep's collision_free column and the pose command's collisions key."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

from cdpr_design import kernels as K
from cdpr_design.statics import interference as itf
from cdpr_design.statics import kinematics as kin
from cdpr_design.model import spec
from cdpr_design import workspaces as ws
from cdpr_design import api

from .helpers import PLANAR2, invoke


def seg_dist_slow(p0, p1, q0, q1):
    """min over (s, t) in [0, 1]^2 of |p(s) - q(t)| (a convex bounded QP, L-BFGS-B)."""
    def f(x):
        d = p0 + x[0] * (p1 - p0) - q0 - x[1] * (q1 - q0)
        return d @ d

    best = np.inf
    for x0 in ([0.5, 0.5], [0.1, 0.9]):
        r = minimize(f, x0, bounds=[(0, 1), (0, 1)], method="L-BFGS-B", options={"ftol": 1e-16, "gtol": 1e-12})
        best = min(best, r.fun)
    # the endpoint-to-segment distances (exact) guard the optimiser
    for a, (b0, b1) in ((p0, (q0, q1)), (p1, (q0, q1)), (q0, (p0, p1)), (q1, (p0, p1))):
        d = b1 - b0
        t = np.clip((a - b0) @ d / max(d @ d, 1e-300), 0, 1)
        best = min(best, np.sum((b0 + t * d - a) ** 2))
    return np.sqrt(max(best, 0.0))


@pytest.mark.slow
def test_segment_distance_kernel_against_optimiser():
    rng = np.random.default_rng(1)
    for k in range(150):
        p0, p1, q0, q1 = rng.uniform(-1, 1, (4, 3))
        if k % 5 == 0:  # parallel segments
            q1 = q0 + rng.uniform(-2, 2) * (p1 - p0)
        if k % 7 == 0:  # a point segment
            q1 = q0.copy()
        d = np.sqrt(K.seg_seg_dist2(*p0, *p1, *q0, *q1))
        assert d == pytest.approx(seg_dist_slow(p0, p1, q0, q1), abs=1e-6)


def chord_slow(s0, s1, half, dim, shrink, n=20001):
    t = np.linspace(0, 1, n)
    P = s0[None] + t[:, None] * (s1 - s0)[None]
    inside = np.all(np.abs(P[:, :dim]) < half[:dim] - shrink, axis=1)
    return inside.mean() * np.linalg.norm(s1 - s0)


def test_segment_box_chord_against_sampling():
    rng = np.random.default_rng(2)
    for _ in range(300):
        half = rng.uniform(0.05, 0.5, 3)
        s0, s1 = rng.uniform(-1, 1, (2, 3))
        dim = 3 if rng.random() < 0.7 else 2
        c = K.segment_box_chord(s0, s1, half, dim, 0.0)
        assert c == pytest.approx(chord_slow(s0, s1, half, dim, 0.0), abs=3e-4 * np.linalg.norm(s1 - s0) + 1e-12)


def design3t(cables, size=(0.1, 0.1, 0.1), diameter=0.0, frame=((-3, -3, -3), (3, 3, 3))):
    return spec.from_dict({
        "name": "hand", "motion": "3T", "frame": {"lower": list(frame[0]), "upper": list(frame[1])},
        "effector": {"mass": 1.0, "size": list(size)}, "tension": [0, 100],
        "cable": {"diameter": diameter},
        "cables": [{"name": n, "outlet": list(a), "attachment": list(b)} for n, a, b in cables],
    })


@pytest.mark.parametrize("h, hit", [(0.0, True), (0.004 - 1e-6, True), (0.004 + 1e-6, False), (0.02, False)])
def test_two_cables_crossing_at_a_known_point(h, hit):
    """c1 runs along the x axis, c2 horizontally at height h and crosses it above
    (1, 0, 0): the free segments are exactly h apart (closest points (1, 0, 0)
    and (1, 0, h)); 2 mm cables (radii sum 4 mm) touch when h <= 4 mm."""
    b2 = np.array([0.05, 0.05, h])
    a2 = b2 + 2 * (np.array([1.0, 0.0, h]) - b2)
    d = design3t([("c1", (2, 0, 0), (0.05, 0, 0)), ("c2", tuple(a2), tuple(b2))], diameter=0.004)
    r = itf.check_pose(d, [0, 0, 0])
    assert r.cable_distances[0, 1] == pytest.approx(h, abs=1e-12)
    assert (("c1", "c2") in r.pairs) is hit
    assert r.effector_chords.max() == 0.0
    assert r.pairs == ([("c1", "c2")] if hit else [])
    # the sweep kernel gives the same verdict
    res = api.pose(d, [0, 0, 0])
    assert (("c1", "c2") in res.collisions) is hit


def test_zero_diameter_cables_collide_only_when_they_meet():
    d = design3t([("c1", (2, 0, 0), (0.05, 0, 0)), ("c2", (1.95, -0.05, 0.0), (0.05, 0.05, 0.0))])
    assert itf.collisions(d, [0, 0, 0]) == [("c1", "c2")]   # they cross at (1, 0, 0)
    d = design3t([("c1", (2, 0, 0), (0.05, 0, 0)), ("c2", (1.95, -0.05, 1e-4), (0.05, 0.05, 1e-4))])
    assert itf.collisions(d, [0, 0, 0]) == []


@pytest.mark.parametrize("eps, hit", [(0.0, False), (1e-4, True), (-1e-4, False)])
def test_cable_grazing_the_effector_edge(eps, hit):
    """Box half size 0.05: the line x + z = 0.1 (y = 0) touches it only at the edge
    point (0.05, 0, 0.05).  Shifted by eps towards the box it cuts the corner
    from (0.05, 0, 0.05 - eps) to (0.05 - eps, 0, 0.05) (chord sqrt(2) eps, less the
    geometric tolerance); away from it, it misses."""
    s = 0.1 - eps
    b = (0.15, 0.0, s - 0.15)        # attachment on a bracket, off the box
    a = (-0.05, 0.0, s + 0.05)
    d = design3t([("c1", a, b)])
    r = itf.check_pose(d, [0, 0, 0])
    assert (("c1", "effector") in r.pairs) is hit
    assert r.effector_chords[0] == pytest.approx(np.sqrt(2) * max(eps, 0.0), abs=1e-7)


@pytest.mark.parametrize("dz, hit", [(0.0, False), (-1e-3, True), (1e-3, False)])
def test_own_attachment_is_exempt_but_running_through_the_body_is_not(dz, hit):
    """A cable attached at the centre of the top face running level along it grazes;
    tilted down it runs through the effector; tilted up it leaves freely."""
    d = design3t([("c1", (-2.0, 0.0, 0.05 + dz), (0.0, 0.0, 0.05))])
    assert (("c1", "effector") in itf.collisions(d, [0, 0, 0])) is hit
    # an attachment slightly inside the box counts as on its nearest face
    d = design3t([("c1", (-2.0, 0.0, 0.05 + dz), (0.0, 0.0, 0.049))])
    assert (("c1", "effector") in itf.collisions(d, [0, 0, 0])) is hit


def test_effector_leaving_the_frame():
    d = design3t([("c1", (0, 0, 3), (0, 0, 0.05))], size=(0.2, 0.2, 0.2))
    assert itf.collisions(d, [0, 0, 0]) == []
    assert itf.collisions(d, [2.95, 0, 0]) == [("effector", "frame")]
    assert ("effector", "frame") not in itf.collisions(d, [2.9, 0, 0])
    # planar: only x, y count
    p = spec.load(PLANAR2)
    assert itf.collisions(p, [0.75, 0.75]) == []
    assert ("effector", "frame") in itf.collisions(p, [0.05, 0.75])


def slow_check(d, pose):
    """Obvious reference: dense sampling and the optimiser, no kernels."""
    full = d.full_pose(pose)
    R = kin.rotation_matrix(*full[3:])
    g = kin.cable_geometry(d, pose)
    m = d.m
    half = np.asarray(d.effector.size) / 2
    dim = d.motion.dim
    pairs = set()
    rho = [c.props.diameter / 2 for c in d.cables]
    t = np.linspace(0, 1, 101)
    for i in range(m):
        for j in range(i + 1, m):
            p0, p1, q0, q1 = g.anchors[i], g.exits[i], g.anchors[j], g.exits[j]
            thr = rho[i] + rho[j] + 1e-8
            # dense (s, t) grid: an upper bound within h (|p1 - p0| + |q1 - q0|) / 2 of the
            # true distance; the optimiser decides the close calls
            P = p0 + t[:, None] * (p1 - p0)
            Q = q0 + t[:, None] * (q1 - q0)
            dense = np.sqrt(((P[:, None, :] - Q[None, :, :]) ** 2).sum(axis=2).min())
            err = 0.01 * (np.linalg.norm(p1 - p0) + np.linalg.norm(q1 - q0)) / 2
            if dense <= thr:
                hit = True
            elif dense - err > thr:
                hit = False
            else:
                hit = seg_dist_slow(p0, p1, q0, q1) <= thr
            if hit:
                pairs.add((d.cables[i].name, d.cables[j].name))
    for i in range(m):
        b = np.array(d.cables[i].attachment, float)
        dep = half[:dim] - np.abs(b[:dim])
        if np.all(dep >= 0):
            k = int(np.argmin(dep))
            b[k] = np.sign(b[k]) * half[k] if b[k] != 0 else half[k]
        c = R.T @ (g.exits[i] - full[:3])
        if chord_slow(b, c, half, dim, 1e-9, n=200001) > 0:
            pairs.add((d.cables[i].name, "effector"))
    return pairs


@pytest.mark.slow
def test_random_robots_against_slow_reference():
    rng = np.random.default_rng(4)
    checked = hits = 0
    for _ in range(30):
        m = int(rng.integers(3, 7))
        half = rng.uniform(0.05, 0.3, 3)
        cables = []
        for i in range(m):
            a = rng.uniform(-2, 2, 3)
            b = rng.uniform(-1, 1, 3) * half  # inside the box
            face = rng.integers(0, 3)
            b[face] = np.sign(b[face] or 1) * half[face]  # on a face
            cables.append((f"c{i}", tuple(a), tuple(b)))
        d = design3t(cables, size=tuple(2 * half), diameter=float(rng.uniform(0, 0.05)))
        for _ in range(5):
            pose = rng.uniform(-0.5, 0.5, 3)
            fast = {p for p in itf.collisions(d, pose) if "frame" not in p}
            r = itf.check_pose(d, pose)
            # skip the measure-zero borderline cases sampling cannot decide
            if np.any((r.effector_chords > 0) & (r.effector_chords < 1e-3)):
                continue
            assert fast == slow_check(d, pose)
            checked += 1
            hits += len(fast)
    assert checked > 100 and hits > 20


IP1 = [((-2, 1.5, 2), (-0.06, 0.06, 0)), ((2, 1.5, 2), (0.06, 0.06, 0)), ((2, -1.5, 2), (0.06, -0.06, 0)),
       ((-2, -1.5, 2), (-0.06, -0.06, 0)), ((-2, 1.5, 0), (-0.06, 0.06, 0)), ((2, 1.5, 0), (0.06, 0.06, 0)),
       ((2, -1.5, 0), (0.06, -0.06, 0)), ((-2, -1.5, 0), (-0.06, -0.06, 0))]


def ipanema1(shift=(0, 0, 0), diameter=0.01):
    """IPAnema 1 (docs/sources.md: the WireX robot file): cables i and i+4 share an attachment point."""
    sh = np.asarray(shift, float)
    return spec.from_dict({
        "name": "ip1", "motion": "3R3T", "gravity": [0, 0, -9.81],
        "frame": {"lower": list(sh + [-2, -1.5, 0]), "upper": list(sh + [2, 1.5, 2])},
        "effector": {"mass": 25.0, "size": [0.12, 0.12, 0.12]}, "tension": [0, 720],
        "cable": {"diameter": diameter},
        "cables": [{"name": f"c{i + 1}", "outlet": list(np.add(a, sh)), "attachment": list(b)}
                   for i, (a, b) in enumerate(IP1)],
    })


MIRROR = {1: 2, 2: 1, 3: 4, 4: 3, 5: 6, 6: 5, 7: 8, 8: 7}


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=6, max_size=6))
def test_symmetries(u):
    x, y, z = 1.6 * u[0], 1.2 * u[1], 1.0 + 0.8 * u[2]
    rx, ry, rz = 0.6 * u[3], 0.6 * u[4], 0.6 * u[5]
    pose = [x, y, z, rx, ry, rz]
    d = ipanema1()
    pairs = set(itf.collisions(d, pose))
    # translating the whole robot changes nothing
    sh = (3.0, -2.0, 1.5)
    assert set(itf.collisions(ipanema1(sh), [x + sh[0], y + sh[1], z + sh[2], rx, ry, rz])) == pairs
    # mirror x -> -x (R -> S R S: ry, rz change sign) swaps cables 1<->2, 3<->4, ...
    def mir(n):
        return n if n in ("effector", "frame") else f"c{MIRROR[int(n[1:])]}"
    mirrored = {tuple(sorted((mir(a), mir(b)), key=_order)) for a, b in pairs}
    assert set(itf.collisions(d, [-x, y, z, rx, -ry, -rz])) == mirrored
    # the distance matrix is symmetric, cables sharing an attachment do not count as touching
    r = itf.check_pose(d, pose)
    np.testing.assert_allclose(r.cable_distances, r.cable_distances.T)
    for i in range(4):
        assert r.cable_distances[i, i + 4] > 0


def _order(name):
    return (1, 0) if name == "effector" else (2, 0) if name == "frame" else (0, int(name[1:]))


def test_sweep_collision_free_column_matches_pose_checks():
    d = spec.from_dict({
        "name": "p4", "motion": "1R2T", "gravity": [0, -9.81],
        "frame": {"lower": [0, 0], "upper": [2, 2]}, "effector": {"mass": 1.0, "size": [0.2, 0.1]},
        "tension": [1, 60], "cable": {"diameter": 0.004},
        "cables": [{"name": "c1", "outlet": [0, 2], "attachment": [0.1, 0.05]},   # crossed pair
                   {"name": "c2", "outlet": [2, 2], "attachment": [-0.1, 0.05]},
                   {"name": "c3", "outlet": [2, 0], "attachment": [0.1, -0.05]},
                   {"name": "c4", "outlet": [0, 0], "attachment": [-0.1, -0.05]}],
        "workspace": {"grid": {"step": 0.1}, "orientation": [0.1]},
    })
    chunks = []
    res = ws.run(d, ws.Analysis(collisions=True), on_chunk=chunks.append, chunk=97)
    plain = []
    ws.run(d, on_chunk=plain.append, chunk=97)
    n_free = n_stat = 0
    assert len(chunks) == len(plain) > 0
    for c, p in zip(chunks, plain):
        assert c.collision_free is not None
        np.testing.assert_array_equal(c.feasible, p.feasible & c.collision_free)
        n_free += int(c.collision_free.sum())
        n_stat += int(p.feasible.sum())
        for j in range(0, c.poses.shape[0], 5):
            pairs = itf.collisions(d, c.poses[j])
            assert bool(c.collision_free[j]) == (pairs == [])
    s = res.summary()
    assert s["collision_free"] == n_free and s["feasible_statics"] == n_stat
    assert s["feasible"] == sum(int(c.feasible.sum()) for c in chunks)
    assert 0 < s["collisions_by_kind"]["cable-cable"] < s["poses"]


def test_cli_pose_collisions_and_workspace_flag(tmp_path):
    r = invoke("pose", PLANAR2, "--at", "0.05,0.75", "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert ["effector", "frame"] in data["collisions"] and ["c1", "frame"] in data["collisions"]
    r = invoke("pose", PLANAR2, "--at", "0.75,0.75", "--json")
    assert json.loads(r.stdout)["collisions"] == []
    r = invoke("workspace", PLANAR2, "--step", "0.05", "--collisions", "--json", "--out", tmp_path)
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["feasible"] <= s["feasible_statics"] and s["interference"] is True
    header = (tmp_path / "workspace.csv").read_text().splitlines()[0].split(",")
    # after the contract's columns; planar2 is under-constrained, so its hanging tilt follows
    assert header[:4] == ["x", "y", "feasible", "margin"]
    assert header[8:] == ["collision_free", "tilt", "orientation_phi"]


def design2t(cables, diameter=0.004, size=(0.1, 0.1)):
    """A planar (2T) design: cables (name, outlet, attachment, plane_offset)."""
    return spec.from_dict({
        "name": "flat", "motion": "2T", "gravity": [0.0, -9.81], "frame": {"lower": [-3, -3], "upper": [3, 3]},
        "effector": {"mass": 1.0, "size": list(size)}, "tension": [0, 100], "cable": {"diameter": diameter},
        "cables": [{"name": n, "outlet": list(a), "attachment": list(b), "plane_offset": z}
                   for n, a, b, z in cables],
    })


def _kernel_pairs(d, pose):
    """The cable-cable verdicts of the sweep kernel (workspaces.hardware) at one position."""
    from cdpr_design.workspaces.hardware import Evaluator

    P = np.zeros((1, 3))
    P[0, :2] = pose
    from cdpr_design.statics.robot import Analysis, resolve

    *_, mask = Evaluator(resolve(d, Analysis(collisions=True)))(P, [0.0, 0.0, 0.0])
    return bool(mask[0] & K.HIT_CABLE_CABLE)


@pytest.mark.parametrize("h, hit", [(0.0, True), (0.002 - 1e-6, True), (0.002 + 1e-6, False), (0.01, False)])
def test_crossed_planar_cables_in_offset_planes(h, hit):
    """Two planar cables cross above the effector at (0, 0.0976): in planes z = +h and -h they
    are 2 h apart there, and 4 mm cables (radii sum 4 mm) touch when 2 h <= 4 mm; the pose
    check and the sweep kernel agree."""
    d = design2t([("c1", (-2.0, 2.0), (0.05, 0.05), h), ("c2", (2.0, 2.0), (-0.05, 0.05), -h)])
    r = itf.check_pose(d, [0.0, 0.0])
    assert r.cable_distances[0, 1] == pytest.approx(2 * h, abs=1e-12)
    assert (("c1", "c2") in r.pairs) is hit
    assert r.effector_chords.max() == 0.0
    assert _kernel_pairs(d, [0.0, 0.0]) is hit


def test_plane_offsets_change_the_interference_only():
    """planar4's crossed lower cables run in offset planes: no cable-cable contact anywhere on
    the grid; without the offsets they meet at every position.  Feasibility, margins, tensions
    and lengths are the same with and without them (the offsets are out of the motion plane)."""
    from cdpr_design.workspaces.hardware import Evaluator
    from .helpers import DESIGNS

    data = spec.read_yaml(DESIGNS / "planar4.yaml")
    with_offsets = spec.from_dict(data)
    assert [c.plane_offset for c in with_offsets.cables] == [0.005, -0.005, 0.0, 0.0]
    for c in data["cables"]:
        c.pop("plane_offset", None)
    flat = spec.from_dict(data)
    g = ws.make_grid(with_offsets, 0.05)
    from cdpr_design.workspaces.grid import positions3

    P = positions3(g, 0, g.size)
    from cdpr_design.statics.robot import Analysis, resolve

    a = Evaluator(resolve(with_offsets, Analysis(collisions=True)))(P, [0.0, 0.0, 0.0])
    b = Evaluator(resolve(flat, Analysis(collisions=True)))(P, [0.0, 0.0, 0.0])
    for x, y in zip(a[:4], b[:4]):
        np.testing.assert_array_equal(x, y)
    assert not np.any(a[4] & K.HIT_CABLE_CABLE)
    assert np.all(b[4] & K.HIT_CABLE_CABLE)
    assert np.any(a[4] == 0)  # collision-free positions exist now


@pytest.mark.slow
def test_random_planar_robots_with_plane_offsets_against_the_slow_distance():
    """Random planar robots whose cables lie in random planes: the kernel's and the pose check's
    cable-cable verdicts against the slow segment distance of the 3-D segments."""
    rng = np.random.default_rng(9)
    checked = hits = 0
    for _ in range(25):
        m = int(rng.integers(2, 6))
        diameter = float(rng.uniform(0.0, 0.02))
        z = rng.choice([0.0, 0.004, -0.004, 0.02], m)
        cables = [(f"c{i}", tuple(rng.uniform(-2.5, 2.5, 2)), tuple(rng.uniform(-0.05, 0.05, 2)), float(z[i]))
                  for i in range(m)]
        d = design2t(cables, diameter=diameter)
        for _ in range(4):
            pose = rng.uniform(-0.5, 0.5, 2)
            r = itf.check_pose(d, pose)
            g = kin.cable_geometry(d, pose)
            slow = set()
            for i in range(m):
                for j in range(i + 1, m):
                    p0, p1 = g.anchors[i] + [0, 0, z[i]], g.exits[i] + [0, 0, z[i]]
                    q0, q1 = g.anchors[j] + [0, 0, z[j]], g.exits[j] + [0, 0, z[j]]
                    dist = seg_dist_slow(p0, p1, q0, q1)
                    assert r.cable_distances[i, j] == pytest.approx(dist, abs=1e-6)
                    if abs(dist - diameter) < 1e-6:
                        continue  # borderline: the optimiser cannot decide
                    if dist <= diameter:
                        slow.add((f"c{i}", f"c{j}"))
            fast = {p for p in r.pairs if "effector" not in p and "frame" not in p}
            if any(abs(r.cable_distances[i, j] - diameter) < 1e-6 for i in range(m) for j in range(i + 1, m)):
                continue
            assert fast == slow
            assert _kernel_pairs(d, pose) is bool(fast)
            checked += 1
            hits += len(fast)
    assert checked > 80 and hits > 5


@pytest.mark.parametrize("dz", [0.0, 0.002, 0.01])
def test_planar_cables_on_one_pin_at_two_heights_meet_there_by_design(dz):
    """Two planar cables share their attachment point in x and y, in planes dz apart: they touch
    at the pin by construction (as on one plane), and do not collide while their far ends stay
    apart; the pose check and the sweep kernel agree."""
    d = design2t([("c1", (-2.0, 2.0), (0.0, 0.05), dz / 2), ("c2", (2.0, 2.0), (0.0, 0.05), -dz / 2)])
    r = itf.check_pose(d, [0.0, 0.0])
    assert ("c1", "c2") not in r.pairs
    assert r.cable_distances[0, 1] > 1.0  # the far ends' distance to the other segment
    assert _kernel_pairs(d, [0.0, 0.0]) is False
