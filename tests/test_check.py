"""size-motors, report and check on the command line; evaluate() as the sweep uses it."""

from __future__ import annotations

import copy
import csv
import json
import pickle

import pytest

from cdpr_design.model import spec
from cdpr_design.design.evaluate import check_table, evaluate

from .helpers import invoke, write_spec, resolved

CONTRACT = ["cable", "peak_tension", "peak_cable_speed", "drum_torque", "peak_motor_torque",
            "rms_motor_torque", "peak_motor_speed", "motor", "torque_margin", "speed_margin"]


@pytest.fixture
def data(planar2_data) -> dict:
    planar2_data["workspace"]["grid"]["step"] = 0.05  # fast
    return planar2_data


def test_check_passes_and_fails_by_requirement(tmp_path, data):
    # the paper's motors hold the task box's upper corners only briefly: the default
    # cycle (half the time at the worst pose) overheats them, the square trajectory does not
    p = write_spec(tmp_path, data)
    r = invoke("check", p)
    assert r.exit_code == 1, r.output
    assert "motors" in r.output and "FAIL" in r.output
    r = invoke("check", p, "--trajectory", "square_fast", "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["passed"] is True
    assert [c["requirement"] for c in out["checks"]] == ["task_box", "min_margin", "motors"]
    assert all(c["passed"] for c in out["checks"])

    # a task box reaching the frame's bottom corners is not fully feasible
    bad = copy.deepcopy(data)
    bad["requirements"] = {"task_box": {"lower": [0.0, 0.0], "upper": [1.5, 0.5]}}
    r = invoke("check", write_spec(tmp_path, bad, "bad.yaml"), "--json")
    assert r.exit_code == 1
    out = json.loads(r.stdout)
    res = {c["requirement"]: c["passed"] for c in out["checks"]}
    assert res["task_box"] is False and "min_margin" not in res
    assert out["figures"]["task_feasible"] < out["figures"]["task_poses"]

    # a margin requirement above the best margin fails; min_fraction is tested too
    hard = copy.deepcopy(data)
    hard["requirements"] = {"task_box": data["requirements"]["task_box"], "min_margin": 50.0, "min_fraction": 0.99}
    hard["winch"].pop("motor")  # no motor named, no speed/acceleration asked: no motor check
    r = invoke("check", write_spec(tmp_path, hard, "hard.yaml"), "--json")
    assert r.exit_code == 1
    res = {c["requirement"]: c["passed"] for c in json.loads(r.stdout)["checks"]}
    assert res == {"task_box": True, "min_margin": False, "min_fraction": False}

    easy = copy.deepcopy(hard)
    easy["requirements"].update(min_margin=0.5, min_fraction=0.5)
    assert invoke("check", write_spec(tmp_path, easy, "easy.yaml")).exit_code == 0


def test_check_bad_input_is_exit_2(tmp_path, data):
    p = write_spec(tmp_path, data)
    r = invoke("check", p, "--trajectory", "nope")
    assert r.exit_code == 2 and "nope" in r.output
    cat = tmp_path / "cat.yaml"
    cat.write_text("motors:\n  - {name: x, rated_torque: -1, peak_torque: 1, max_speed: 1, rotor_inertia: 0}\n")
    r = invoke("check", p, "--catalogue", cat)
    assert r.exit_code == 2 and "motors[0].rated_torque" in r.output
    d = copy.deepcopy(data)
    d["winch"]["motor"] = "NoSuchMotor"
    r = invoke("check", write_spec(tmp_path, d, "m.yaml"))
    assert r.exit_code == 2 and "winch.motor" in r.output
    assert "Traceback" not in r.output


def test_size_motors_writes_contract_columns(tmp_path, data):
    p = write_spec(tmp_path, data)
    out = tmp_path / "out"
    r = invoke("size-motors", p, "--out", out, "--json")
    assert r.exit_code == 0, r.output
    js = json.loads(r.stdout)
    assert [a["cable"] for a in js["axes"]] == ["c1", "c2"]
    with open(out / "motor_sizing.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0][: len(CONTRACT)] == CONTRACT
    assert len(rows) == 3
    assert rows[1][CONTRACT.index("motor")] == "AM8112-0F21-EL7211"
    assert float(rows[1][rows[0].index("implied_tension_max")]) == pytest.approx(20.0)
    assert js["axes"][0]["peak_motor_torque"] == pytest.approx(float(rows[1][4]), rel=1e-9)
    # a user catalogue and --motor: evaluate a bigger motor on every axis
    r = invoke("size-motors", p, "--out", out, "--motor", "AM8121-0F00", "--json")
    assert r.exit_code == 0
    assert {a["motor"] for a in json.loads(r.stdout)["axes"]} == {"AM8121-0F00"}


def test_size_motors_with_a_trajectory_sizes_on_its_duty_cycle(tmp_path, data):
    # the command's sizing is the library's on the trajectory's samples, not the default cycle
    from cdpr_design.design import sizing as sz
    from cdpr_design.motion import trajectory as tr

    p = write_spec(tmp_path, data)
    r = invoke("size-motors", p, "--trajectory", "square_fast", "--out", tmp_path / "t", "--json")
    assert r.exit_code == 0, r.output
    js = json.loads(r.stdout)
    design = spec.load(p)
    want = sz.size_motors(resolved(design, "size-motors"), spec.load_catalogue(), samples=tr.sample(resolved(design, "motion"), "square_fast")).summary()
    assert js["cycle"] == want["cycle"] == "trajectory square_fast"
    for got, ref in zip(js["axes"], want["axes"], strict=True):
        assert got["rms_motor_torque"] == pytest.approx(ref["rms_motor_torque"], rel=1e-12)
        assert got["peak_motor_speed"] == pytest.approx(ref["peak_motor_speed"], rel=1e-12)
    default = json.loads(invoke("size-motors", p, "--out", tmp_path / "d", "--json").stdout)
    assert default["cycle"] != js["cycle"]
    assert [a["rms_motor_torque"] for a in default["axes"]] != [a["rms_motor_torque"] for a in js["axes"]]
    # an unknown name: exit 2 naming the option, nothing written
    r = invoke("size-motors", p, "--trajectory", "nope", "--out", tmp_path / "n")
    assert r.exit_code == 2 and "--trajectory" in r.output and "nope" in r.output, r.output
    assert "Traceback" not in r.output and not (tmp_path / "n").exists()


def test_report_writes_every_artefact(tmp_path, data):
    p = write_spec(tmp_path, data)
    out = tmp_path / "rep"
    r = invoke("report", p, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output  # report writes; only check fails on requirements
    for name in ("workspace.csv", "workspace.png", "tension_map.png", "summary.json", "motor_sizing.csv",
                 "design_report.csv", "report.json"):
        assert (out / name).is_file(), name
    with open(out / "design_report.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 1
    row = rows[0]
    assert row["name"] == "planar2" and row["check_motors"] == "0" and row["checks_passed"] == "0"
    assert row["check_task_box"] == "1" and row["check_min_fraction"] == ""
    summary = json.loads((out / "summary.json").read_text())
    assert float(row["fraction"]) == pytest.approx(summary["fraction"])


def test_evaluate_is_a_picklable_row(data):
    d = spec.from_dict(data)
    row = evaluate(d)
    again = pickle.loads(pickle.dumps(row))
    assert again == row
    assert all(isinstance(v, (str, int, float, bool, type(None))) for v in row.values())
    assert row["checks_passed"] is False and row["check_motors"] is False
    tab = check_table(row)
    assert [t["requirement"] for t in tab] == ["task_box", "min_margin", "motors"]
    # no requirements: nothing to check, everything passes
    free = copy.deepcopy(data)
    free.pop("requirements")
    free["winch"].pop("motor")
    row = evaluate(spec.from_dict(free))
    assert row["checks_passed"] is True and check_table(row) == []
    assert row["sizing_poses"] == row["feasible"]  # no task box: the feasible workspace
