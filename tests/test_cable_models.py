"""Cable models through the spec, the library and every command (issue 15).

The kernel's physics is checked against independent references in
test_sagging.py and test_catenary.py; here: the spec keys and their errors,
ideal outputs unchanged, elastic arithmetic, the sagging columns and summary,
sizing from the winch side, forward kinematics round trips, sweeps of the model.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cdpr_design.model import spec
from cdpr_design.model.spec import with_cable_model
from cdpr_design.statics import cables
from cdpr_design import api
from cdpr_design.statics.robot import cable_model

from .helpers import DESIGNS, PLANAR2, invoke, planar2_raw, read_csv, write_spec, resolved

SAG40 = DESIGNS / "sagging40.yaml"


# ----------------------------------------------------------------------------
# spec
# ----------------------------------------------------------------------------


def test_default_model_is_ideal_and_spec_keys_resolve(planar2_data):
    d = spec.from_dict(planar2_data)
    assert cable_model(d).name == "ideal"
    planar2_data["cable"]["model"] = "elastic"
    planar2_data["cables"][1]["model"] = "sagging"
    d = spec.from_dict(planar2_data)
    assert [c.props.model for c in d.cables] == ["elastic", "sagging"]
    assert cable_model(d).name == "sagging"  # the heaviest


@pytest.mark.parametrize("model, drop, key", [
    ("elastic", "axial_stiffness", "cable.axial_stiffness"),
    ("sagging", "axial_stiffness", "cable.axial_stiffness"),
    ("sagging", "mass_per_length", "cable.mass_per_length"),
])
def test_missing_property_names_the_key(planar2_data, model, drop, key):
    planar2_data["cable"]["model"] = model
    del planar2_data["cable"][drop]
    with pytest.raises(spec.SpecError) as e:
        spec.from_dict(planar2_data)
    assert key in str(e.value) and model in str(e.value)


@pytest.mark.parametrize("key, value", [("mass_per_length", 0.0), ("mass_per_length", -0.1),
                                        ("axial_stiffness", 0.0), ("axial_stiffness", -5.0)])
def test_non_positive_properties_are_refused(tmp_path, planar2_data, key, value):
    planar2_data["cable"]["model"] = "sagging"
    planar2_data["cable"][key] = value
    r = invoke("pose", write_spec(tmp_path, planar2_data), "--at", "0.75,0.75")
    assert r.exit_code == 2, r.output
    assert f"cable.{key}" in r.output and "Traceback" not in r.output


def test_cable_model_option_errors(tmp_path):
    r = invoke("pose", PLANAR2, "--at", "0.75,0.75", "--cable-model", "bogus")
    assert r.exit_code == 2 and "--cable-model" in r.output
    r = invoke("pose", DESIGNS / "ipanema3.yaml", "--at", "0,0,1,0,0,0", "--cable-model", "sagging")
    assert r.exit_code == 2
    assert "cable.axial_stiffness" in r.output and "--cable-model" in r.output


def test_with_cable_model_keeps_the_override_in_raw(planar2):
    d = with_cable_model(planar2, "sagging")
    assert d.raw["cable"]["model"] == "sagging"
    assert cable_model(spec.from_dict(d.raw)).name == "sagging"
    assert with_cable_model(planar2, None) is planar2


@pytest.mark.slow
def test_sagging_refuses_pulleys(tmp_path, planar2_data):
    planar2_data["cable"]["model"] = "sagging"
    planar2_data["cables"][0]["pulley"] = {"radius": 0.02, "axis": [0.0, 1.0, 0.0]}
    r = invoke("workspace", write_spec(tmp_path, planar2_data), "--out", tmp_path / "o", "-q")
    assert r.exit_code == 2 and "swivel pulleys" in r.output
    # every analysis that builds the catenaries from point outlets refuses the pulley, none ignores it
    spec_path = write_spec(tmp_path, planar2_data)
    r = invoke("size-motors", spec_path, "--out", tmp_path / "o3", "-q")
    assert r.exit_code == 2 and "swivel pulleys" in r.output, r.output
    for command in ("trajectory", "simulate"):  # the table's reason as it is, before any file
        r = invoke(command, spec_path, "square_fast", "--out", tmp_path / command, "-q")
        assert r.exit_code == 2 and "--cable-model: cable model 'sagging' assumes point outlets" in r.output
        assert "trajectories." not in r.output and not (tmp_path / command).exists(), r.output
    for model in ("sagging", "elastic"):
        r = invoke("fk", spec_path, "--lengths", "1.0,1.0", "--cable-model", model)
        assert r.exit_code == 2 and "swivel pulleys" in r.output and model in r.output, r.output
    assert invoke("fk", spec_path, "--lengths", "1.0,1.0", "--cable-model", "ideal").exit_code == 0


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["total", "range"])
def test_orientation_workspaces_take_elastic_and_sagging_cables(tmp_path, mode):
    cogiro = DESIGNS / "cogiro.yaml"
    runs = {}
    for model in ("ideal", "elastic", "sagging"):
        r = invoke("workspace", cogiro, "--orientations", mode, "--cable-model", model, "--step", "2",
                   "--out", tmp_path / model, "-q")
        assert r.exit_code == 0, r.output
        runs[model] = (read_csv(tmp_path / model / "workspace.csv"),
                       json.loads((tmp_path / model / "summary.json").read_text()))
    (ideal_rows, ideal_sum), (el_rows, el_sum) = runs["ideal"], runs["elastic"]
    # straight elastic cables have the ideal statics; the rows stand for a set of orientations, so no
    # per-pose cable columns; the summary names the model
    assert el_rows == ideal_rows
    assert el_sum["cable_model"] == "elastic" and "cable_model" not in ideal_sum
    assert el_sum["max_outlet_tension_per_cable"] == ideal_sum["max_tension_per_cable"]
    assert el_sum["feasible"] == ideal_sum["feasible"] > 0
    # sagging cables: their own statics at every orientation, the same columns, the model's summary
    (sag_rows, sag_sum) = runs["sagging"]
    assert sag_rows[0] == ideal_rows[0] and sag_rows != ideal_rows
    assert sag_sum["cable_model"] == "sagging" and sum(sag_sum["cable_status"].values()) == \
        sag_sum["orientations_evaluated"]
    assert 0 < sag_sum["feasible"] <= ideal_sum["feasible"]


# ----------------------------------------------------------------------------
# pose
# ----------------------------------------------------------------------------


def test_ideal_pose_json_is_unchanged():
    r = invoke("pose", PLANAR2, "--at", "0.3,0.9", "--json")
    data = json.loads(r.output)
    # planar2 is under-constrained: the tilt its free body would hang with comes beside (issue 16);
    # the stiffness keys (issue 39) and the acceleration keys come with every design, null with a reason
    # where undefined
    assert set(data) == {"pose", "lengths", "tensions", "feasible", "margin", "structure_matrix",
                         "collisions", "objective", "tilt", "hanging", "stiffness_matrix",
                         "translational_stiffness", "min_stiffness", "natural_frequencies", "mode_shapes",
                         "cable_frequencies", "stiffness_reason", "acceleration_radius", "axis_accelerations",
                         "acceleration_direction", "acceleration_reason"}


def test_elastic_pose_is_the_ideal_one_with_stretch(planar2):
    ideal = api.pose(planar2, [0.3, 0.9])
    el = api.pose(with_cable_model(planar2, "elastic"), [0.3, 0.9])
    np.testing.assert_array_equal(el.tensions, ideal.tensions)
    assert el.margin == ideal.margin
    EA = 20000.0
    np.testing.assert_allclose(el.cable_state.unstretched_lengths, ideal.lengths / (1 + ideal.tensions / EA),
                               rtol=1e-15)
    np.testing.assert_array_equal(el.cable_state.outlet_tensions, ideal.tensions)
    assert np.all(el.cable_state.sag == 0)


def test_sagging_pose_json_keys_and_physics():
    r = invoke("pose", SAG40, "--at", "20,10", "--json")
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    assert d["cable_model"] == "sagging" and d["cable_status"] == "ok"
    for c in ("left", "right"):
        # a cable hanging from its outlet: the winch holds more than the effector feels,
        # by less than the cable's weight; it pays out more than the chord minus stretch
        assert d["tensions"][c] < d["outlet_tensions"][c] < d["tensions"][c] + 0.6 * 40
        assert d["sag"][c] > 0
        assert d["unstretched_lengths"][c] < d["lengths"][c] * 1.01
    ideal = json.loads(invoke("pose", SAG40, "--at", "20,10", "--json", "--cable-model", "ideal").output)
    assert "cable_model" not in ideal
    for c in ("left", "right"):
        assert d["tensions"][c] > ideal["tensions"][c]  # sag: the end forces turn down, more tension


@pytest.mark.slow
def test_other_objectives_with_sagging_cables(planar2):
    d = with_cable_model(planar2, "sagging")
    mn = api.pose(d, [0.3, 0.9])
    mm = api.pose(d, [0.3, 0.9], objective="min-max")
    assert mm.cable_state.status == "ok"
    # m = n: every objective has the same (unique) tensions
    np.testing.assert_allclose(mm.tensions, mn.tensions, rtol=1e-6)
    np.testing.assert_allclose(mm.W @ mm.tensions, mm.wrench, atol=1e-6)


# ----------------------------------------------------------------------------
# workspace
# ----------------------------------------------------------------------------


@pytest.mark.slow
def test_ideal_workspace_columns_unchanged(tmp_path):
    r = invoke("workspace", PLANAR2, "--out", tmp_path, "-q")
    assert r.exit_code == 0
    header, _ = read_csv(tmp_path / "workspace.csv")
    # planar2 is under-constrained: its hanging tilt follows the contract's columns (issue 16)
    assert header == ["x", "y", "feasible", "margin", "tension_c1", "tension_c2", "length_c1", "length_c2",
                      "tilt", "orientation_phi"]
    assert "cable_model" not in json.loads((tmp_path / "summary.json").read_text())
    assert not (tmp_path / "cable_models.png").exists()


@pytest.mark.slow
def test_elastic_workspace_columns(tmp_path):
    r = invoke("workspace", PLANAR2, "--cable-model", "elastic", "--out", tmp_path, "-q", "--step", "0.05")
    assert r.exit_code == 0, r.output
    header, rows = read_csv(tmp_path / "workspace.csv")
    assert header[8:] == ["outlet_tension_c1", "outlet_tension_c2", "unstretched_length_c1",
                          "unstretched_length_c2", "sag_c1", "sag_c2"]
    a = np.array([[float(v) if v else np.nan for v in row] for row in rows])
    feas = a[:, 2] == 1
    assert feas.sum() > 100
    np.testing.assert_allclose(a[feas, 10], a[feas, 6] / (1 + a[feas, 4] / 20000.0), rtol=1e-9)
    assert np.all(np.isnan(a[~feas, 10]))


@pytest.mark.slow
def test_sagging_workspace_files_and_summary(tmp_path):
    r = invoke("workspace", SAG40, "--out", tmp_path, "--json", "--step", "0.5")
    assert r.exit_code == 0, r.output
    s = json.loads(r.output)
    assert s["cable_model"] == "sagging"
    assert sum(s["cable_status"].values()) == s["poses"]
    assert s["cable_status"]["not-converged"] == 0
    header, rows = read_csv(tmp_path / "workspace.csv")
    assert header[-1] == "cable_status"
    status = np.array([int(row[-1]) for row in rows])
    feas = np.array([row[2] == "1" for row in rows])
    assert feas.sum() == s["feasible"] and np.all(status[feas] == 0)
    for row in rows:  # a pose that is not ok carries no numbers
        if row[-1] != "0":
            assert row[3] == "" and row[4] == "" and row[8] == ""
    assert (tmp_path / "cable_models.png").stat().st_size > 10_000
    for c, v in s["max_outlet_tension_per_cable"].items():
        assert v >= s["max_tension_per_cable"][c]


def test_sagging_is_more_restrictive_near_the_top_of_sagging40():
    from cdpr_design import workspaces as ws

    d = spec.load(SAG40)
    g = ws.make_grid(d, 0.5)
    sag = ws.run(d, grid=g)
    ideal = ws.run(with_cable_model(d, "ideal"), grid=g)
    a, b = ideal.feasible_map.astype(bool), sag.feasible_map.astype(bool)
    assert (a & ~b).sum() > 0  # the straight model promises poses the real cables cannot hold
    assert not (~a & b).any()


# ----------------------------------------------------------------------------
# sizing, fk, sweep
# ----------------------------------------------------------------------------


def test_sizing_uses_the_winch_side_tension(planar2):
    from cdpr_design.design.envelope import task_envelope

    e_i = task_envelope(resolved(planar2, "size-motors"))
    e_s = task_envelope(resolved(with_cable_model(planar2, "sagging"), "size-motors"))
    assert np.all(e_s.static_tension > e_i.static_tension)
    assert np.all(e_s.peak_tension > e_i.peak_tension)
    # the difference is about the cable's weight share: w L < 0.004 * 9.81 * 2.2 m
    assert np.all(e_s.static_tension - e_i.static_tension < 0.004 * 9.81 * 2.2)


@pytest.mark.parametrize("name, pose", [("planar2.yaml", [0.3, 0.9]), ("sagging40.yaml", [20.0, 10.0]),
                                        ("sagging40.yaml", [3.1, 7.3]), ("cogiro.yaml", [1, 0.5, 2, 0, 0, 0])])
@pytest.mark.parametrize("model", ["elastic", "sagging"])
def test_fk_inverts_the_inverse_statics(name, pose, model):
    from cdpr_design.statics.cable_fk import forward

    d = with_cable_model(spec.load(DESIGNS / name), model)
    r = api.pose(d, pose)
    assert r.cable_state.status == "ok"
    fk = forward(resolved(d, "fk"), r.cable_state.unstretched_lengths)
    np.testing.assert_allclose(fk.pose, pose, atol=1e-9)
    np.testing.assert_allclose(fk.tensions, r.tensions, rtol=1e-7)
    np.testing.assert_allclose(fk.outlet_tensions, r.cable_state.outlet_tensions, rtol=1e-7)
    assert fk.length_residual < 1e-9 and fk.force_residual < 1e-9


def test_fk_cli_with_cable_model():
    r = invoke("fk", SAG40, "--lengths", "22.7,22.7", "--json")
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    assert d["cable_model"] == "sagging" and d["slack"] == []
    assert set(d["tensions"]) == {"left", "right"}
    assert abs(d["pose"][0] - 20.0) < 1e-6  # symmetric lengths: the middle
    r = invoke("fk", SAG40, "--lengths", "22.7,-1", "--json")
    assert r.exit_code == 2 and "--lengths" in r.output


def test_fk_elastic_slack_cable(planar2):
    """A weightless cable longer than its chord is slack: the effector hangs from the other."""
    from cdpr_design.statics.cable_fk import forward

    d = with_cable_model(planar2, "elastic")
    fk = forward(resolved(d, "fk"), [1.0, 3.0])
    assert fk.slack == ["c2"] and fk.tensions[1] == 0.0
    # hanging straight below the outlet of c1, at the stretched length
    assert abs(fk.pose[0] - (0.0 + 0.06)) < 1e-9
    assert abs(fk.tensions[0] - 9.81) < 1e-9


@pytest.mark.slow
def test_sweep_varies_the_cable_model(tmp_path):
    r = invoke("sweep", PLANAR2, "--vary", "cable.model=ideal,sagging", "--out", tmp_path, "-q", "--json",
               "--workers", "1")
    assert r.exit_code == 0, r.output
    header, rows = read_csv(tmp_path / "sweep.csv")
    col = header.index("peak_tension")
    ideal, sag = (float(row[col]) for row in rows)
    assert sag > ideal


def test_ideal_planar2_workspace_and_sizing_numbers_unchanged():
    """The default model gives the historical figures (README: 18,421 of 22,801 poses; ipanema1 peak 719.82 N)."""
    from cdpr_design import workspaces as ws

    assert ws.run(spec.load(PLANAR2)).feasible == 18421
    assert planar2_raw()["cable"].get("model") is None


def test_trajectory_duty_cycle_uses_the_winch_side_tension(planar2):
    from cdpr_design.design.duty import trajectory_cycle
    from cdpr_design.motion import trajectory

    d = with_cable_model(planar2, "sagging")
    samples = trajectory.sample(resolved(d, "motion"), "square_slow")
    cyc = trajectory_cycle(samples)
    np.testing.assert_array_equal(cyc.tension, samples.cables.outlet_tensions)
    ok = np.isfinite(samples.tensions)
    assert ok.any() and np.all(cyc.tension[ok] > samples.tensions[ok])


@pytest.mark.parametrize("source", ["sagging40", "planar2-3"])
def test_sagging_wrench_closure_is_the_chords(tmp_path, source):
    """Issue 37: a sagging wrench-closure workspace ended in a traceback (its chunks lacked the
    cable_status column the table declared).  Closure ignores the tensions, which grow without
    bound: every catenary straightens onto its chord, so the rows are the ideal cables' (the
    chords'), the sagging columns are empty and every cable_status is 0."""
    if source == "sagging40":
        raw = spec.read_yaml(DESIGNS / "sagging40.yaml")
        step = "2"
    else:  # a third cable below: closure is possible in the plane
        raw = planar2_raw()
        raw["cables"].append({"name": "c3", "outlet": [0.75, 0.0], "attachment": [0.0, -0.06]})
        raw.pop("plc")
        raw["cable"]["model"] = "sagging"
        step = "0.1"
    outs = {}
    for model in ("sagging", "ideal"):
        path = write_spec(tmp_path, raw, f"{model}.yaml")
        res = invoke("workspace", path, "--kind", "wrench-closure", "--cable-model", model, "--step", step,
                     "--out", tmp_path / model, "--json")
        assert res.exit_code == 0 and "Traceback" not in res.output, res.output
        outs[model] = read_csv(tmp_path / model / "workspace.csv")
    (hs, rs), (hi, ri) = outs["sagging"], outs["ideal"]
    assert hs[-1] == "cable_status"
    common = [c for c in hs if c in hi]  # the ideal under-constrained design adds its hanging tilt
    assert common == hs[:len(common)] and len(common) == 4 + 2 * len(raw["cables"])
    assert [r[:len(common)] for r in rs] == [[r[hi.index(c)] for c in common] for r in ri]
    assert all(r[-1] == "0" and all(v == "" for v in r[len(common):-1]) for r in rs)
    if source != "sagging40":
        assert any(r[2] == "1" for r in ri)
