"""Interference of sagging cables and orientation workspaces with sagging cables.

The kernels (:mod:`cdpr_design.kernels.sag_clearance`) take each catenary as a polyline within a
stated bound of the curve.  Checked here against plain numpy: each cable's catenary sampled densely
from Irvine's equations as printed (not the kernels' forms), the distances between the dense
samples (a k-d tree), and the polylines' stated bounds; the weightless limit against the straight
cables' checks; the sweep's ``collision_free`` against ``pose``'s collisions; and the total
orientation workspace of sagging cables against the sagging pose solved at every orientation.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial import cKDTree

from cdpr_design import api
from cdpr_design.kernels import sag_clearance as KC
from cdpr_design.model import spec
from cdpr_design.model.design import Grid
from cdpr_design.statics import interference as itf
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.hardware import hardware_arrays
from cdpr_design.statics.cables import sag_robot
from cdpr_design.statics.robot import Analysis, resolve
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design import workspaces as ws
from cdpr_design.workspaces.pose import evaluate_pose

from .helpers import invoke, read_csv
from .test_sagging import random_planar, random_spatial

#: Points of the dense sampling of each catenary.
DENSE = 20001


def with_cable(design, **props):
    """``design`` with every cable's properties replaced (e.g. ``mass_per_length``)."""
    cables = tuple(dataclasses.replace(c, props=dataclasses.replace(c.props, **props)) for c in design.cables)
    return dataclasses.replace(design, cables=cables)


def with_diameter(design, diameter):
    return with_cable(design, diameter=diameter)


def irvine_points(H, VB, L0, w, EA, s):
    """(x(s), z(s)) [m] of the elastic catenary as printed (Irvine 1981): from B, x horizontal towards
    A, z up, at unstretched arc lengths ``s`` (array)."""
    V = VB + w * s
    x = H / w * (np.arcsinh(V / H) - np.arcsinh(VB / H)) + H * s / EA
    z = H / w * (np.sqrt(1 + (V / H) ** 2) - np.sqrt(1 + (VB / H) ** 2)) + (VB * s + 0.5 * w * s**2) / EA
    return x, z


def curve_of(B, u, up, H, VB, L0, w, EA, zoff=0.0):
    """The catenary's points as a function of the unstretched arc length: s (k,) -> (k, 3) [m]."""
    shift = np.array([0.0, 0.0, zoff])

    def at(s):
        x, z = irvine_points(H, VB, L0, w, EA, np.asarray(s, float))
        return B[None] + x[:, None] * u[None] + z[:, None] * up[None] + shift
    at.L0 = L0
    return at


def dense_cables(robot, full, shapes, zoff):
    """Per cable (points (DENSE, 3) [m], the curve :func:`curve_of`) of the converged catenaries
    ``shapes`` (m, 3) (H, VB, L0) at the full pose; each curve's end is checked against the outlet."""
    R = kin.rotation_matrix(*full[3:])
    B = full[:3] + robot.attachments @ R.T
    A = robot.outlet_points
    up = robot.cable.up
    out = []
    for i, (H, VB, L0) in enumerate(shapes):
        d = A[i] - B[i]
        h = d - (d @ up) * up
        u = h / np.linalg.norm(h)
        curve = curve_of(B[i], u, up, H, VB, L0, robot.cable.w[i], robot.cable.EA[i], zoff[i])
        P = curve(np.linspace(0.0, L0, DENSE))
        assert np.linalg.norm(P[-1] - A[i] - [0, 0, zoff[i]]) <= 1e-7 * (1 + np.linalg.norm(d)), "not at A"
        out.append((P, curve))
    return out


def curves_distance(ci, cj):
    """The least distance [m] between two catenaries (:func:`curve_of`): the closest pair of DENSE
    samples, then refined about it by samples 1000 times finer (the curves are smooth, and the
    closest samples are within a sample's spacing of the closest points)."""
    si, sj = np.linspace(0, ci.L0, DENSE), np.linspace(0, cj.L0, DENSE)
    Pi, Pj = ci(si), cj(sj)
    dist, k = cKDTree(Pj).query(Pi)
    a = int(np.argmin(dist))
    b = int(k[a])
    hi, hj = ci.L0 / (DENSE - 1), cj.L0 / (DENSE - 1)
    fi = np.clip(si[a] + hi * np.linspace(-2, 2, 2001), 0, ci.L0)
    fj = np.clip(sj[b] + hj * np.linspace(-2, 2, 2001), 0, cj.L0)
    return min(float(dist[a]), float(cKDTree(cj(fj)).query(ci(fi))[0].min()))


def shapes_at(robot, full):
    """The kernels' rows at one pose with the shapes kept: (mask, shapes (m, 3))."""
    m = robot.m
    R = np.ascontiguousarray(kin.rotation_matrix(*full[3:]))
    Rb = np.ascontiguousarray(robot.attachments @ R.T)
    srob = sag_robot(robot, wrench_vertices(robot.design, robot.kind, full[3:]), robot.kcode)
    rows = KC.SagRows(np.zeros(1, np.uint8), np.zeros(1), *(np.zeros((1, m)) for _ in range(5)),
                      np.zeros(1, np.int8), np.zeros(1, np.uint8), np.zeros((1, m, 3)))
    KC.sag_rows_at(np.ascontiguousarray(full[None, :3]), Rb, R, srob, itf.sagging_clearance(robot, True), rows)
    return int(rows.mask[0]), rows.shapes[0]


def random_robots(seed, count):
    """``count`` random sagging robots and poses of every motion whose cables converge there."""
    rng = np.random.default_rng(seed)
    builders = [(random_planar, 2, "2T"), (random_planar, 3, "1R2T"), (random_planar, 4, "1R2T"),
                (random_spatial, 6, "3T"), (random_spatial, 8, "3R3T"), (random_spatial, 7, "3R3T")]
    out = []
    k = 0
    while len(out) < count and k < 40 * count:
        build, m, motion = builders[k % len(builders)]
        k += 1
        design, pose = build(rng, m, motion)
        design = with_diameter(design, float(rng.uniform(0.002, 0.02)))
        robot = resolve(design, Analysis(command="pose"))
        full = design.full_pose(pose)
        mask, shapes = shapes_at(robot, full)
        if mask & KC.HIT_UNKNOWN:
            continue
        out.append((design, robot, full, shapes, pose))
    assert len(out) == count
    return out


def _dense_distance(Pi, Pj):
    return float(cKDTree(Pj).query(Pi)[0].min())


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_distances_agree_with_dense_catenaries_within_the_stated_bound(seed):
    """Every pair's distance is within the two polylines' bounds of the curves': the dense samples'
    least distance d satisfies d - (h_i + h_j) / 2 - b <= kernel <= d + b (b = bound_i + bound_j,
    h the samples' spacing); each polyline lies within its bound of its dense curve, and that
    bound is at most CURVE_TOL; cables that share an end are measured by their far ends."""
    checked = 0
    for design, robot, full, shapes, _ in random_robots(seed, 6):
        c = itf.check_sagging_pose(robot, full)
        zoff = hardware_arrays(design).zoff
        dense = dense_cables(robot, full, shapes, zoff)
        assert np.all(c.curve_bounds <= KC.CURVE_TOL)
        for i in range(robot.m):
            # the polyline's vertices lie on the curve, and the curve within the bound of the polyline
            Pi = dense[i][0]
            assert _polyline_distance(Pi, _polyline(robot, full, shapes, zoff, i)) <= c.curve_bounds[i] + 1e-9
            for j in range(i + 1, robot.m):
                Pj = dense[j][0]
                shared_b = np.allclose(Pi[0, :2], Pj[0, :2], atol=1e-9) and (
                    design.motion.dim == 2 or abs(Pi[0, 2] - Pj[0, 2]) <= 1e-9)
                if shared_b:  # a shared attachment: the far ends to the other curve
                    d = min(_dense_distance(Pi[-1:], Pj), _dense_distance(Pj[-1:], Pi))
                    slack = 2 * max(np.linalg.norm(np.diff(P, axis=0), axis=1).max() for P in (Pi, Pj))
                else:
                    d, slack = curves_distance(dense[i][1], dense[j][1]), 1e-7
                b = c.curve_bounds[i] + c.curve_bounds[j]
                got = c.cable_distances[i, j]
                assert d - slack - b - 1e-9 <= got <= d + b + 1e-9, (i, j, got, d, b)
                checked += 1
    assert checked >= 15


def _polyline(robot, full, shapes, zoff, i):
    """Cable i's polyline as the kernel builds it (:func:`~cdpr_design.kernels.sag_clearance.cable_curve`)."""
    R = kin.rotation_matrix(*full[3:])
    curves = KC.make_curves(robot.m, KC.MAX_SEGMENTS)
    B = np.ascontiguousarray(full[:3] + robot.attachments[i] @ R.T)
    KC.cable_curve(i, B, np.ascontiguousarray(robot.outlet_points[i]), *shapes[i], robot.cable.w[i],
                   robot.cable.EA[i], robot.cable.up, float(zoff[i]), KC.CURVE_TOL, KC.MAX_SEGMENTS, curves)
    return curves.pts[i, :curves.nseg[i] + 1]


def _polyline_distance(P, V):
    """Largest distance [m] from the points ``P`` (k, 3) to the polyline of vertices ``V``."""
    best = np.full(len(P), np.inf)
    for a, b in zip(V[:-1], V[1:]):
        d = b - a
        t = np.clip((P - a) @ d / max(d @ d, 1e-300), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(a + t[:, None] * d - P, axis=1))
    return float(best.max())


def crossing_pair(rng):
    """Two heavy cables in crossing vertical planes whose curves pass within a few cm of each other,
    as ``Curves`` of the kernel and the dense samples of each (points, spacing)."""
    up = np.array([0.0, 0.0, 1.0])
    curves = KC.make_curves(2, KC.MAX_SEGMENTS)
    dense = []
    for i in range(2):
        span = rng.uniform(5, 30)
        ang = rng.uniform(0, np.pi) + i * np.pi / 2
        u = np.array([np.cos(ang), np.sin(ang), 0.0])
        w, EA = rng.uniform(0.5, 5.0), rng.uniform(1e5, 1e7)
        H = w * span * rng.uniform(0.3, 3.0)
        VB = rng.uniform(-0.8, 0.2) * w * span
        L0 = span * rng.uniform(1.0, 1.3)
        mid = curve_of(np.zeros(3), u, up, H, VB, L0, w, EA)(np.array([L0 / 2]))[0]
        B = -mid + rng.uniform(-0.05, 0.05, 3) * (i == 1)  # the middles near the origin
        curve = curve_of(B, u, up, H, VB, L0, w, EA)
        A = curve(np.array([L0]))[0]
        KC.cable_curve(i, np.ascontiguousarray(B), np.ascontiguousarray(A), H, VB, L0, w, EA, up, 0.0,
                       KC.CURVE_TOL, KC.MAX_SEGMENTS, curves)
        dense.append(curve)
    return curves, dense


def test_near_contact_distances_agree_with_dense_catenaries():
    """Crossing catenaries that nearly touch, where a chord would be far off: the kernel's distance is
    within the bounds of the dense samples' (and far from the chords' distance)."""
    rng = np.random.default_rng(7)
    for _ in range(12):
        curves, dense = crossing_pair(rng)
        got = KC.curve_distance(curves.pts, curves.nseg, 0, 1, -1.0)
        d = curves_distance(*dense)
        b = curves.bound[0] + curves.bound[1]
        assert curves.nseg[0] > 1 and curves.nseg[1] > 1
        assert d - b - 1e-7 <= got <= d + b + 1e-9, (got, d, b)
        # an early stop returns a distance at or below the stop as soon as one is found
        early = KC.curve_distance(curves.pts, curves.nseg, 0, 1, got + 1e-3)
        assert got <= early <= got + 1e-3


@pytest.mark.parametrize("seed", [4, 5])
def test_weightless_limit_is_the_straight_cables_result(seed):
    """As the mass per length goes to 0 the pairs' distances and the chords inside the effector tend
    to the straight cables' (first order in w), and the colliding pairs become theirs; at poses
    where every straight cable is taut (a cable at zero tension is slack when weightless, its
    shape undetermined, but hangs at its least tension, a deep catenary of the same shape
    whatever its weight, when it has one)."""
    taut = 0
    for design, _, full, _, pose in random_robots(seed, 6):
        t = api.pose(spec.with_cable_model(design, "ideal"), pose).tensions
        if not np.all(t > 1e-6 * t.max()):
            continue
        taut += 1
        straight = itf.check_pose(design, pose)
        mu = design.cables[0].props.mass_per_length
        errs = []
        for scale in (1e-2, 1e-3, 1e-4, 1e-8):
            light = with_cable(design, mass_per_length=mu * scale)
            c = itf.check_sagging_pose(resolve(light, Analysis(command="pose")), full)
            assert c.known
            errs.append(np.nanmax(np.abs(c.cable_distances - straight.cable_distances)))
            if scale == 1e-8:
                np.testing.assert_allclose(c.cable_distances, straight.cable_distances, atol=1e-9)
                np.testing.assert_allclose(c.effector_chords, straight.effector_chords, atol=1e-9)
                assert c.pairs == straight.pairs
        assert errs[1] <= 0.2 * errs[0] + 1e-12 and errs[2] <= 0.2 * errs[1] + 1e-12, errs
    assert taut >= 2


def sagging40(**keys):
    design = spec.load("designs/sagging40.yaml")
    return dataclasses.replace(design, **keys) if keys else design


def test_a_sagging_cable_below_the_floor_leaves_the_frame():
    """A cable whose catenary dips below the frame box collides with the frame, although its chord
    and its attachment are inside: sagging40 at (3, 15), where the long cable leaves the effector
    pointing down (its horizontal tension is small beside its 20 N weight), with the frame's floor
    raised to between the effector and that cable's lowest point."""
    design = sagging40()
    robot = resolve(design, Analysis(command="pose"))
    at = [3.0, 15.0]
    full = design.full_pose(at)
    c = itf.check_sagging_pose(robot, full)
    assert c.known and not c.mask & itf.K.HIT_CABLE_FRAME
    mask, shapes = shapes_at(robot, full)
    dense = dense_cables(robot, full, shapes, np.zeros(2))
    low = min(P[:, 1].min() for P, _ in dense)
    bottom = at[1] - design.effector.size[1] / 2
    assert low < bottom - 0.05  # the curves dip below the effector's box
    lo = design.frame_lower
    raised = dataclasses.replace(design, frame_lower=(lo[0], (low + bottom) / 2, lo[2]))
    c2 = itf.check_sagging_pose(resolve(raised, Analysis(command="pose")), full)
    assert c2.mask & itf.K.HIT_CABLE_FRAME and not itf.check_pose(raised, at).mask & itf.K.HIT_CABLE_FRAME


def test_sweep_collision_free_matches_pose_collisions(tmp_path):
    """``workspace --collisions`` of sagging40 (coarse grid): ``collision_free`` is 1 exactly where
    ``pose`` reports no interfering pair at that row, ``feasible`` is statics-feasible and collision
    free, and rows without converged shapes are not collision free (pose: null)."""
    out = tmp_path / "o"
    r = invoke("workspace", "designs/sagging40.yaml", "--collisions", "--step", "4", "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    header, rows = read_csv(out / "workspace.csv")
    ix, iy = header.index("x"), header.index("y")
    icf, ist, ife = header.index("collision_free"), header.index("cable_status"), header.index("feasible")
    design = spec.load("designs/sagging40.yaml")
    robot = resolve(design, Analysis(command="pose"))
    seen = set()
    for row in rows[:: max(1, len(rows) // 40)]:
        at = [float(row[ix]), float(row[iy])]
        p = evaluate_pose(robot, at)
        if row[ist] != "0":
            assert p.collisions is None and row[icf] == "0"
            continue
        assert row[icf] == ("0" if p.collisions else "1"), (at, p.collisions)
        assert row[ife] == ("1" if (p.feasible and not p.collisions) else "0")
        seen.add(row[icf])
    assert seen == {"0", "1"}  # both answers occur on this grid


@pytest.mark.slow
def test_orientation_total_with_sagging_cables_is_every_orientations_pose():
    """The total orientation workspace of sagging cables, on random rotational robots: a position is
    feasible exactly when the sagging pose solve (rotated attachments, moments balanced) is feasible at
    every orientation of the set, with the least margin and largest tensions over them."""
    rng = np.random.default_rng(11)
    builders = [(random_planar, 3, "1R2T"), (random_planar, 4, "1R2T"), (random_spatial, 8, "3R3T")]
    seen = set()
    for k in range(6):
        build, m, motion = builders[k % 3]
        design, pose = build(rng, m, motion)
        dim = design.motion.dim
        c = np.asarray(pose[:dim])
        half = 0.08 * (np.asarray(design.frame_upper[:dim]) - np.asarray(design.frame_lower[:dim]))
        g = Grid(tuple(c - half), tuple(c + half), tuple(half))  # 3 per axis
        nominal = design.default_orientation_full()
        oset = np.array([nominal + d for d in (np.zeros(3), np.array([0, 0, 0.08]), np.array([0.05, -0.05, -0.1]))])
        if motion == "1R2T":
            oset[:, :2] = 0.0
        res_rows = []
        ws.run(design, Analysis(orientations="total"), grid=g, orientation=nominal, orientations=oset,
               on_chunk=res_rows.append)
        robot = resolve(design, Analysis(command="pose"))
        for ch in res_rows:
            for r in range(len(ch.feasible)):
                pos = ch.poses[r, :dim]
                rot = [i - 3 for i in design.motion.pose_index[dim:]]
                answers = [evaluate_pose(robot, list(pos) + list(o[rot])) for o in oset]
                feasible = all(a.feasible for a in answers)
                assert bool(ch.feasible[r]) == feasible, (pos, [a.feasible for a in answers])
                margins = [a.margin for a in answers]
                if all(np.isfinite(margins)):
                    assert ch.margin[r] == pytest.approx(min(margins), rel=1e-9, abs=1e-9)
                if feasible:
                    np.testing.assert_allclose(ch.tensions[r], np.max([a.tensions for a in answers], axis=0),
                                               rtol=1e-9, atol=1e-9)
                assert int(ch.extra["orientations_feasible"][r]) == sum(a.feasible for a in answers)
                seen.add(feasible)
    assert seen == {True, False}  # both answers occur


def test_path_interference_is_the_pose_checks_at_each_sample():
    """Along a path, each sample's interference is that of its pose: straight cables
    :func:`check_pose` (swivel pulleys and cable planes honoured); sagging cables the catenaries of
    the samples' unstretched lengths, which at a pose held at rest are the pose's own
    (:func:`check_sagging_pose`); a sample without a set-point is not checked."""
    design = sagging40()
    sag = resolve(design, Analysis(command="pose"))
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(1, 39, 30), rng.uniform(1, 25, 30)])
    L0 = np.full((30, 2), np.nan)
    want = []
    for k, p in enumerate(poses):
        res = evaluate_pose(sag, list(p))
        c = itf.check_sagging_pose(sag, design.full_pose(p))
        if res.cable_state.status == "ok" and np.all(np.isfinite(res.cable_state.unstretched_lengths)):
            L0[k] = res.cable_state.unstretched_lengths
            want.append(c.mask)
        else:
            want.append(KC.HIT_UNKNOWN)
    motion = resolve(design, Analysis(command="motion", collisions=True))
    got = itf.path_interference(motion, poses, L0)
    np.testing.assert_array_equal(got, want)
    assert (got == 0).any()
    straight = resolve(spec.with_cable_model(design, "elastic"), Analysis(command="motion", collisions=True))
    np.testing.assert_array_equal(itf.path_interference(straight, poses),
                                  [itf.check_pose(straight.design, p).mask for p in poses])


def test_trajectory_collisions_column_and_summary(tmp_path):
    """``trajectory --collisions``: a ``collision_free`` column, ``feasible`` collision free too,
    ``collision_samples`` and ``collisions_by_kind`` in the JSON; planar2's square path runs clear of
    its frame and its cables, and the same path on an effector wider than the frame collides
    everywhere."""
    import json

    r = invoke("trajectory", "designs/planar2.yaml", "square_fast", "--collisions", "--out", tmp_path / "a",
               "--json", "--quiet")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    header, rows = read_csv(tmp_path / "a" / "trajectory.csv")
    free = [row[header.index("collision_free")] for row in rows]
    assert s["collision_samples"] == free.count("0") == 0 and set(s["collisions_by_kind"]) == set(
        itf.HIT_NAMES.values())
    import yaml

    raw = yaml.safe_load(open("designs/planar2.yaml").read())
    raw["effector"]["size"] = [2.0, 0.12]  # wider than the frame
    p = tmp_path / "wide.yaml"
    p.write_text(yaml.safe_dump(raw))
    r = invoke("trajectory", p, "square_fast", "--collisions", "--out", tmp_path / "b", "--json", "--quiet")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["collision_samples"] == s["samples"] and s["feasible"] is False
    assert s["collisions_by_kind"]["effector-frame"] == s["samples"]
    r = invoke("trajectory", p, "square_fast", "--out", tmp_path / "c", "--json", "--quiet")
    assert "collision_samples" not in json.loads(r.stdout)
