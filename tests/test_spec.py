"""Spec loading: every rejected case exits 2 and names the key; the JSON schema."""

from __future__ import annotations

import copy
import json

import pytest

from cdpr_design.model import spec
from cdpr_design.errors import SpecError

from .helpers import DESIGNS, PLANAR2, invoke, write_spec


def _set(data, path, value):
    """Set a dotted path (ints index lists) in nested data; value DELETE removes it."""
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    obj = data
    for k in keys[:-1]:
        obj = obj[k]
    if value is DELETE:
        del obj[keys[-1]]
    else:
        obj[keys[-1]] = value


DELETE = object()

# (dotted path to change, new value, text the message must contain: the key path)
BAD = [
    ("motion", "4T", "motion: expected one of"),
    ("cables.1.outlet", [1.5, 1.5, 0.0], "cables[1].outlet: expected 2 numbers for motion 2T, got 3"),
    ("cables.0.attachment", [0.1], "cables[0].attachment: expected 2 numbers for motion 2T, got 1"),
    ("frame.upper", [1.5], "frame.upper: expected 2 numbers"),
    ("gravity", [0.0, 0.0, -9.81], "gravity: expected 2 numbers"),
    ("cables.0.outlet", [0.0, float("nan")], "cables[0].outlet[1]: expected a finite number"),
    ("effector.mass", float("inf"), "effector.mass: expected a finite number"),
    ("tension", [30.0, 20.0], "tension: expected min <= max"),
    ("effector.mass", -1.0, "effector.mass: expected a value greater than or equal to 0"),
    ("cables.1.name", "c1", "cables[1].name: duplicate cable name 'c1'"),
    ("cables", [], "cables: expected at least 1 entry"),
    ("winch.drum_radius", [], "winch.drum_radius: expected at least 1 entry, got 0"),
    ("winch.gear_ratio", [], "winch.gear_ratio: expected at least 1 entry, got 0"),
    ("winch.gear_ratio", 1e-300, "winch.gear_ratio[0]: expected a value in [0.001, 1e+06]"),
    ("winch.drum_radius", [0.03, 1e-300], "winch.drum_radius[1]: expected a value in [0.0001, 10000] m"),
    ("workspace.grid.step", 0.0, "workspace.grid.step[0]: expected a value greater than 0"),
    ("workspace.grid.step", -0.1, "workspace.grid.step[0]: expected a value greater than 0"),
    ("workspace.grid.step", [0.1, 0.1, 0.1], "workspace.grid.step: expected a scalar or 2 numbers"),
    ("effector.mass", "heavy", "effector.mass: expected a number, got 'heavy'"),
    ("frame.lower", [2.0, 0.0], "frame.upper[0]: expected a value above frame.lower[0]"),
    ("cables.0.colour", "red", "cables[0].colour: unknown key"),
    ("winch.efficiency", 1.5, "winch.efficiency: expected a value less than or equal to 1"),
    ("winch.gear_ratio", [3.0, -1.0], "winch.gear_ratio[1]: expected a value greater than 0"),
    ("requirements.task_box.lower", [0.3], "requirements.task_box.lower: expected 2 numbers"),
    ("trajectories.square_slow.side", DELETE, "trajectories.square_slow.side: required for a square path"),
    ("trajectories.square_slow.type", "spiral", "trajectories.square_slow.type: expected one of"),
    ("name", DELETE, "name: required key is missing"),
    ("tension", DELETE, "cables[0].tension: required: no design-wide tension is given"),
    ("workspace.orientation", [0.1], "workspace.orientation: motion 2T has a fixed orientation"),
    ("workspace.external_wrench", {"lower": [0, 0, 0], "upper": [1, 1, 1]},
     "workspace.external_wrench.lower: expected 2 numbers (fx, fy) for motion 2T, got 3"),
    ("effector.inertia", [[1, 0, 0], [0, 1, 0]], "effector.inertia: expected a 3x3 matrix"),
    ("cables.0.plane_offset", "front", "cables[0].plane_offset: expected a number, got 'front'"),
    ("cables.1.plane_offset", float("nan"), "cables[1].plane_offset: expected a finite number"),
]


@pytest.mark.parametrize("path,value,message", BAD, ids=[b[0] + ":" + b[2][:30] for b in BAD])
def test_bad_spec_exit_2_names_key(tmp_path, planar2_data, path, value, message):
    data = copy.deepcopy(planar2_data)
    _set(data, path, value)
    p = write_spec(tmp_path, data)
    res = invoke("workspace", p, "--out", tmp_path / "o")
    assert res.exit_code == 2, res.output
    assert message in res.output, res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "o" / "workspace.csv").exists()
    with pytest.raises(SpecError):
        spec.load(p)


def test_a_spatial_cable_has_no_plane_offset(tmp_path):
    """plane_offset places a planar design's cable out of the motion plane; a spatial cable's
    outlet and attachment already give its height: refused, naming the key (exit 2)."""
    data = spec.read_yaml(DESIGNS / "ipanema3.yaml")
    data["cables"][2]["plane_offset"] = 0.01
    with pytest.raises(SpecError) as exc:
        spec.from_dict(data)
    assert [p for p, _ in exc.value.problems] == ["cables[2].plane_offset"]
    res = invoke("workspace", write_spec(tmp_path, data), "--out", tmp_path / "o")
    assert res.exit_code == 2 and "cables[2].plane_offset: only for planar motions" in res.output, res.output
    assert "Traceback" not in res.output


def test_several_problems_are_all_reported(tmp_path, planar2_data):
    data = copy.deepcopy(planar2_data)
    data["cables"][0]["outlet"] = [0, 1, 2]
    data["cables"][1]["attachment"] = [0]
    with pytest.raises(SpecError) as exc:
        spec.from_dict(data)
    paths = [p for p, _ in exc.value.problems]
    assert "cables[0].outlet" in paths and "cables[1].attachment" in paths


def test_huge_grid_needs_force(tmp_path):
    res = invoke("workspace", PLANAR2, "--step", "0.0001", "--out", tmp_path)
    assert res.exit_code == 2
    assert "225,030,001 poses" in res.output and "--force" in res.output


def test_bad_step_option(tmp_path):
    res = invoke("workspace", PLANAR2, "--step", "-1", "--out", tmp_path)
    assert res.exit_code == 2 and "--step" in res.output


@pytest.mark.parametrize("text,message", [
    ("name: [unclosed", "not valid YAML"),
    ("- just\n- a list\n", "expected a mapping of keys at the top"),
    ("name: a\nname: b\n", "given twice"),
    ("!!python/object/apply:os.system ['echo hi']", "not valid YAML"),
    # explicit tags the value does not fit: ValueError / TypeError inside PyYAML (found by test_fuzz)
    ("!!float cables:\n- a\nname: x\n", "a tagged value cannot be read"),
    ("name: !!int twelve\n", "a tagged value cannot be read"),
    ("name: !!float 1e999999999999\n", None),
    ("name: !!timestamp 2026-13-45\n", "a tagged value cannot be read"),
    ("!!float ", "a tagged value cannot be read"),
    ("name: !!float\n", "a tagged value cannot be read"),
    ("name: !!binary '@@@'\n", None),  # reads as b'': the schema refuses it
    ("name: !!bool maybe\n", "a tagged value cannot be read"),
])
def test_bad_yaml(tmp_path, text, message):
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    res = invoke("workspace", p, "--out", tmp_path / "o")
    assert res.exit_code == 2
    assert message is None or message in res.output
    assert "Traceback" not in res.output


def test_missing_file(tmp_path):
    res = invoke("pose", tmp_path / "nope.yaml", "--at", "1,1")
    assert res.exit_code == 2 and "no such file" in res.output


def test_defaults_and_overrides(planar2_data):
    data = copy.deepcopy(planar2_data)
    del data["gravity"]
    data["cables"][1]["tension"] = [1.0, 30.0]
    data["cables"][1]["winch"] = {"drum_radius": [0.02, 0.03]}
    data["cables"][1]["diameter"] = 0.004
    d = spec.from_dict(data)
    assert d.gravity == (0.0, -9.81, 0.0)
    assert (d.cables[0].tension_min, d.cables[0].tension_max) == (0.0, 20.0)
    assert (d.cables[1].tension_min, d.cables[1].tension_max) == (1.0, 30.0)
    # per-cable winch keys override the design-wide ones key by key
    assert d.cables[1].winch.drum_radii == (0.02, 0.03)
    assert d.cables[1].winch.motor == d.cables[0].winch.motor
    assert d.cables[1].props.diameter == 0.004 and d.cables[0].props.diameter == 0.002
    # planar default inertia: a uniform box of the effector's size
    assert d.effector.inertia_matrix[2, 2] == pytest.approx(1.0 * (0.12**2 + 0.12**2) / 12)


def test_every_shipped_design_loads():
    files = sorted(DESIGNS.glob("*.yaml"))
    assert files
    for f in files:
        d = spec.load(f)
        assert d.m >= 1 and d.workspace.grid.size > 0


def test_schema_command():
    res = invoke("schema")
    assert res.exit_code == 0
    schema = json.loads(res.stdout)
    assert schema["title"] == "cdpr-design spec"
    assert {"motion", "frame", "effector", "cables"} <= set(schema["properties"])
    assert set(schema["required"]) >= {"name", "motion", "frame", "effector", "cables"}


def test_an_underconstrained_effector_without_weight_names_the_keys(tmp_path, planar2_data):
    """planar2 hangs from two cables: with no mass its hanging pose does not exist, and the
    message names the spec's keys (not the command's options)."""
    planar2_data["effector"]["mass"] = 0.0
    p = write_spec(tmp_path, planar2_data)
    r = invoke("fk", p, "--lengths", "1,1")
    assert r.exit_code == 2 and "Traceback" not in r.output, r.output
    assert "effector.mass, gravity:" in r.output and "--lengths" not in r.output, r.output


def test_a_held_weightless_effector_gets_its_statics_and_no_tilt(tmp_path, planar2_data):
    """effector.orientation: fixed holds the effector, so its statics stand without a weight; the tilt
    it would hang with does not exist, and pose and workspace agree on leaving it out (pose refused
    the pose while workspace swept it, with a tilt of nan everywhere)."""
    planar2_data["effector"]["mass"] = 0.0
    p = write_spec(tmp_path, planar2_data)
    r = invoke("pose", p, "--at", "0.75,0.75", "--json")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["feasible"] and d["tilt"] is None and d["hanging"] is None
    assert all(t == 0 for t in d["tensions"].values())  # nothing to carry
    r = invoke("pose", p, "--at", "0.75,0.75")
    assert r.exit_code == 0 and "weightless effector" in r.output, r.output
    r = invoke("workspace", p, "--step", "0.25", "--out", tmp_path / "ws", "--quiet")
    assert r.exit_code == 0, r.output
    header = (tmp_path / "ws" / "workspace.csv").read_text().splitlines()[0].split(",")
    assert "tilt" not in header and not (tmp_path / "ws" / "tilt_map.png").exists()


@pytest.mark.parametrize("mass, gravity", [(0.0, [0.0, -9.81]), (1.0, [0.0, 0.0]), (1e-300, [0.0, -9.81]),
                                           (1.0, [0.0, -1e-300]), (5e-14, [0.0, -9.81])])
def test_a_hanging_effector_without_weight_is_refused_when_the_spec_is_read(tmp_path, planar2_data, mass, gravity):
    """effector.orientation: free on an under-constrained design: every analysis needs the hanging
    pose, which a weightless effector does not have (workspace reported every pose infeasible).
    A weight below 1e-12 N counts as none: a 1e-300 kg effector overflowed the balance, scaled by
    its weight, and came out "balanced" on 1e-300 N tensions with numpy's warnings on stderr."""
    planar2_data["effector"].update(mass=mass, orientation="free")
    planar2_data["gravity"] = gravity
    p = write_spec(tmp_path, planar2_data)
    for args in (("workspace", p, "--out", tmp_path / "ws"), ("pose", p, "--at", "0.75,0.75"), ("fk", p, "--lengths", "1,1")):
        r = invoke(*args)
        assert r.exit_code == 2 and "effector.mass: effector.orientation: free" in r.output, (args, r.output)
        assert "of at least 1e-12 N" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "ws").exists()


def test_a_light_hanging_effector_hangs_as_a_heavy_one(tmp_path, planar2_data):
    """The hanging balance is solved scaled by the weight: a 1e-9 kg effector (just above the 1e-12 N
    floor) hangs in the orientation a 1 kg one does, on tensions 1e-9 times theirs, with no numpy
    warning on the way."""
    import warnings

    out = {}
    for mass in (1.0, 1e-9):
        planar2_data["effector"].update(mass=mass, orientation="free")
        p = write_spec(tmp_path, planar2_data, f"m{mass:g}.yaml")
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            r = invoke("pose", p, "--at", "0.6,0.7", "--json")
        assert r.exit_code == 0 and "Warning" not in r.output, r.output
        out[mass] = json.loads(r.stdout)
    heavy, light = out[1.0], out[1e-9]
    assert heavy["feasible"] and light["feasible"]
    assert light["tilt"] == pytest.approx(heavy["tilt"], abs=1e-9)
    for name, t in heavy["tensions"].items():
        assert t > 0 and light["tensions"][name] == pytest.approx(1e-9 * t, rel=1e-6)


def test_a_held_fully_constrained_design_needs_no_weight_even_when_free(tmp_path):
    """A fully constrained design is held whatever effector.orientation says: no weight needed."""
    import yaml

    data = yaml.safe_load((DESIGNS / "ipanema3.yaml").read_text())
    data["effector"].update(mass=0.0, orientation="free")
    d = spec.load(write_spec(tmp_path, data))
    assert d.effector.mass == 0.0 and d.effector.orientation == "free"
