"""A hanging effector (``effector.orientation: free``) in ``workspace`` and ``pose`` with elastic
and sagging cables, its stiffness and interference at the hanging pose.

The workspace of a hanging effector on elastic cables holds each grid position: the winches pay
out the unstretched lengths that put it there (L / (1 + T / EA)).  Checked here against what a
user can run independently: ``fk`` with those unstretched lengths (Levenberg-Marquardt on each
cable's closure and the effector's balance, cable_fk.py) must put the effector back at the
position, in the orientation and with the tensions of the row; ``pose --json`` gives the row's
stiffness and collisions; the tilted effector box's corners, computed here, are inside the frame
wherever a row is collision free.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.helpers import DESIGNS, invoke, planar2_raw, read_csv, write_spec

CRANE4 = DESIGNS / "crane4.yaml"


def free_planar2(tmp_path):
    data = planar2_raw()
    data["name"] = "planar2free"
    data["effector"]["orientation"] = "free"
    return write_spec(tmp_path, data, "free.yaml")


def sweep(path, out, *options):
    res = invoke("workspace", path, "--out", out, "--json", *options)
    assert res.exit_code == 0, res.output
    header, rows = read_csv(out / "workspace.csv")
    a = np.array([[float(v) if v != "" else np.nan for v in r] for r in rows])
    return json.loads(res.stdout), {name: a[:, j] for j, name in enumerate(header)}


def pose_json(path, position, *options):
    res = invoke("pose", path, "--at", ",".join(repr(float(v)) for v in position), "--json", *options)
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


@pytest.fixture(scope="module")
def planar(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hangel")
    path = free_planar2(tmp)
    ideal = sweep(path, tmp / "i", "--step", "0.05")
    elastic = sweep(path, tmp / "e", "--step", "0.05", "--cable-model", "elastic", "--stiffness", "--collisions")
    return path, tmp, ideal, elastic


def test_elastic_rows_hang_as_on_ideal_cables_with_the_lengths_that_hold_them(planar):
    """The position held, the balance is the chords' (straight cables): the tilt is the ideal cables'
    wherever the pose is stable on both; the unstretched lengths are L / (1 + T / EA) with the
    row's tensions, and the outlet tension is the tension."""
    path, _, (si, ideal), (se, el) = planar
    EA = 20e3  # planar2's cables
    both = np.isfinite(el["tilt"])
    assert both.sum() > 100 and np.all(np.isfinite(ideal["tilt"][both]))
    np.testing.assert_allclose(el["tilt"][both], ideal["tilt"][both], rtol=1e-9, atol=1e-12)
    for c in ("c1", "c2"):
        t, L = el[f"tension_{c}"], el[f"length_{c}"]
        ok = np.isfinite(t)
        np.testing.assert_allclose(el[f"unstretched_length_{c}"][ok], (L / (1 + t / EA))[ok], rtol=1e-9)
        np.testing.assert_allclose(el[f"outlet_tension_{c}"][ok], t[ok], rtol=1e-9)
    assert se["cable_model"] == "elastic" and se["hangs"] <= si["hangs"]


@pytest.mark.slow
def test_fk_with_the_rows_unstretched_lengths_comes_back_to_the_row(planar):
    """``fk --cable-model elastic`` with a feasible row's unstretched lengths: the effector rests at
    the row's position, orientation and tensions (an independent solver of the same physics)."""
    path, _, _, (_, el) = planar
    rows = np.flatnonzero(el["feasible"] == 1)
    rng = np.random.default_rng(1)
    for k in rng.choice(rows, 8, replace=False):
        L0 = [el[f"unstretched_length_{c}"][k] for c in ("c1", "c2")]
        res = invoke("fk", path, "--lengths", ",".join(repr(float(v)) for v in L0), "--cable-model", "elastic", "--json")
        assert res.exit_code == 0, res.output
        fk = json.loads(res.stdout)
        np.testing.assert_allclose(fk["pose"], [el["x"][k], el["y"][k]], atol=1e-7)
        assert abs(fk["orientation"] - el["orientation_phi"][k]) < 1e-6
        np.testing.assert_allclose([fk["tensions"]["c1"], fk["tensions"]["c2"]],
                                   [el["tension_c1"][k], el["tension_c2"][k]], rtol=1e-6, atol=1e-6)


def test_stiffness_and_collisions_columns_are_the_pose_commands(planar):
    """``min_stiffness``, ``min_rotational_stiffness`` and ``lowest_frequency`` of a row are
    ``pose --json``'s at its position, ``collision_free`` says whether ``pose`` lists collisions;
    the tilted effector box's corners are inside the frame wherever a row is collision free."""
    path, _, _, (se, el) = planar
    assert se["interference"] is True and se["min_stiffness"] > 0
    rows = np.flatnonzero(np.isfinite(el["tilt"]))
    rng = np.random.default_rng(2)
    picked = list(rng.choice(rows, 12, replace=False)) + list(np.flatnonzero(el["collision_free"] == 0)[:4])
    for k in picked:
        p = pose_json(path, [el["x"][k], el["y"][k]], "--cable-model", "elastic")
        assert (el["collision_free"][k] == 1) == (p["collisions"] == [])
        if el["feasible"][k] == 1:
            for key in ("min_stiffness", "min_rotational_stiffness", "lowest_frequency"):
                got = p[key] if key != "lowest_frequency" else p["natural_frequencies"][0]
                assert got == pytest.approx(el[key][k], rel=1e-9)
    # the box (0.12 m square, planar2's effector) at the hanging angle, inside the frame [0, 1.5]^2
    half = 0.06
    phi = el["orientation_phi"]
    co, si = np.cos(phi), np.sin(phi)
    inside = np.ones(len(phi), bool)
    for sx in (-half, half):
        for sy in (-half, half):
            x = el["x"] + co * sx - si * sy
            y = el["y"] + si * sx + co * sy
            inside &= (x >= -1e-9) & (x <= 1.5 + 1e-9) & (y >= -1e-9) & (y <= 1.5 + 1e-9)
    hangs = np.isfinite(phi)
    assert np.all(inside[hangs & (el["collision_free"] == 1)])
    assert np.any(~inside[hangs])  # the check has something to find
    assert np.all(el["feasible"][el["collision_free"] == 0] == 0)


@pytest.mark.slow
def test_crane4_elastic_workspace_and_fk_agree(tmp_path):
    """crane4 (4 cables, hanging from three or four) on elastic cables, a coarse grid: the tilt is the
    ideal cables', and ``fk`` with a row's unstretched lengths comes back to its position and tilt."""
    si, ideal = sweep(CRANE4, tmp_path / "i", "--step", "1.0", "--max-tilt", "90")
    se, el = sweep(CRANE4, tmp_path / "e", "--step", "1.0", "--max-tilt", "90", "--cable-model", "elastic",
                   "--stiffness")
    both = np.isfinite(el["tilt"])
    assert both.sum() > 40
    np.testing.assert_allclose(el["tilt"][both], ideal["tilt"][both], rtol=1e-9, atol=1e-9)
    from cdpr_design.model import spec
    from cdpr_design.statics.cable_fk import forward
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.hanging import free_pose

    d = spec.with_cable_model(spec.load(CRANE4), "elastic")
    robot = resolve(d, Analysis(command="pose", max_tilt=90.0))
    fk_robot = resolve(d, Analysis(command="fk"))
    names = d.cable_names
    t = np.column_stack([el[f"tension_{c}"] for c in names])
    # every feasible row, nearly slack cables included (crane4 at (1.5, 1.5, 1.5) hangs with c2 at 0.36 N)
    nearly = (el["feasible"] == 1) & np.any((t > 0) & (t < 5.0), axis=1)
    assert nearly.any()
    for k in np.flatnonzero(el["feasible"] == 1):
        position = [el["x"][k], el["y"][k], el["z"][k]]
        r = free_pose(robot, position)
        L0 = r.lengths[0] / (1.0 + r.tensions[0] / 1.2e6)
        fk = forward(fk_robot, L0)
        np.testing.assert_allclose(fk.pose, position, atol=1e-7)
        assert fk.tilt == pytest.approx(el["tilt"][k], abs=1e-6)
        np.testing.assert_allclose(fk.tensions, r.tensions[0], rtol=1e-6, atol=1e-6)
    assert se["min_stiffness"] > 0 and se["lowest_frequency"] > 0


@pytest.mark.slow
@pytest.mark.parametrize("name,step,limit", [("sagging40", 4.0, None), ("crane4", 1.0, 90.0)])
def test_sagging_rows_come_back_through_fk(tmp_path, name, step, limit):
    """A hanging effector on sagging cables: ``workspace`` rows are ``pose --json``'s, and ``fk
    --cable-model sagging`` (Levenberg-Marquardt on the catenaries' closure and the balance, from the
    ideal cables' rest pose) with a feasible row's unstretched lengths puts the effector back at its
    position and tilt, with its tensions."""
    import yaml

    from cdpr_design.model import spec
    from cdpr_design.statics.cable_fk import forward
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.hanging import free_pose

    raw = yaml.safe_load((DESIGNS / f"{name}.yaml").read_text())
    raw["effector"]["orientation"] = "free"
    if limit is not None:
        raw.setdefault("requirements", {})["max_tilt"] = limit
    path = write_spec(tmp_path, raw, f"{name}-free.yaml")
    s, rows = sweep(path, tmp_path / "o", "--step", str(step), "--cable-model", "sagging", "--stiffness")
    assert s["cable_model"] == "sagging" and s["feasible"] > 0
    d = spec.with_cable_model(spec.load(path), "sagging")
    robot, fk_robot = resolve(d, Analysis(command="pose")), resolve(d, Analysis(command="fk"))
    coords = ["x", "y"] + (["z"] if "z" in rows else [])
    feasible = np.flatnonzero(rows["feasible"] == 1)
    for k in feasible[:: max(1, len(feasible) // 4)][:4]:
        position = [rows[c][k] for c in coords]
        p = pose_json(path, position, "--cable-model", "sagging")
        assert p["feasible"] and p["tilt"] == pytest.approx(rows["tilt"][k], rel=1e-8, abs=1e-8)
        for c in d.cable_names:
            assert p["unstretched_lengths"][c] == pytest.approx(rows[f"unstretched_length_{c}"][k], rel=1e-8)
            assert p["tensions"][c] == pytest.approx(rows[f"tension_{c}"][k], rel=1e-8)
        assert p["min_stiffness"] == pytest.approx(rows["min_stiffness"][k], rel=1e-8)
        r = free_pose(robot, position)
        fk = forward(fk_robot, r.cables.unstretched[0])
        np.testing.assert_allclose(fk.pose[: len(coords)], position, atol=1e-6)
        assert fk.tilt == pytest.approx(rows["tilt"][k], abs=1e-5)
        np.testing.assert_allclose(fk.tensions, r.tensions[0], rtol=1e-5)
