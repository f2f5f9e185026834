"""Keys that must agree with each other: ``pose``'s feasibility and its stiffness reason, stiffness
requirements and the task box they are checked over."""

from __future__ import annotations

import json

import pytest

from .helpers import DESIGNS, PLANAR2, invoke, planar2_raw, write_spec


def test_pose_under_wrench_closure_without_tensions_does_not_call_itself_infeasible():
    r = invoke("pose", DESIGNS / "planar4.yaml", "--kind", "wrench-closure", "--at", "0.5,1.4,0", "--json")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["feasible"] is True and all(v is None for v in d["tensions"].values())
    assert "infeasible" not in d["stiffness_reason"]  # was "no tensions hold ... (infeasible)" beside feasible
    assert "wrench closure holds" in d["stiffness_reason"]
    # where tensions exist the keys agree as before: feasible, tensions, a stiffness or its reason
    d = json.loads(invoke("pose", DESIGNS / "planar4.yaml", "--kind", "wrench-closure", "--at", "0.75,0.9,0",
                          "--json").stdout)
    assert d["feasible"] is True and all(v is not None for v in d["tensions"].values())
    assert d["stiffness_reason"] is None or "infeasible" not in d["stiffness_reason"]


@pytest.mark.parametrize("key, value", [("min_stiffness", 1000.0), ("min_frequency", 2.0)])
def test_a_stiffness_requirement_without_a_task_box_is_refused_naming_it(tmp_path, key, value):
    raw = planar2_raw()
    raw["requirements"] = {key: value}
    r = invoke("check", write_spec(tmp_path, raw), "--json")
    assert r.exit_code == 2 and f"requirements.{key}" in r.output and "task_box" in r.output, r.output
    # was: exit 0, the requirement silently not checked
    raw["requirements"]["task_box"] = {"lower": [0.45, 0.6], "upper": [1.05, 1.1]}
    r = invoke("check", write_spec(tmp_path, raw), "--json")
    assert r.exit_code in (0, 1) and key in {c["requirement"] for c in json.loads(r.stdout)["checks"]}, r.output
