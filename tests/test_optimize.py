"""Design search (``optimize``): search space, outcomes, Pareto front and knee, the exhaustive-grid
comparison, two objectives, interrupted runs resumed, bad input."""

from __future__ import annotations

import json
import math
import os
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pytest

from cdpr_design import batch
from cdpr_design import optimize as opt
from cdpr_design.errors import InputError
from cdpr_design.model import spec

from .helpers import PLANAR2, invoke, planar2_raw, read_csv, subprocess_env, write_spec

OUTLETS = ["--vary", "cables.0.outlet.0=-0.5:0.5", "--vary", "cables.1.outlet.0=1:2"]


def planar2_no_motors() -> dict:
    """planar2 without the motor requirements (no motor named, no speed or acceleration): trials sweep
    only the task box, the checks are the task box and min_margin >= 1 N."""
    raw = planar2_raw()
    raw["winch"].pop("motor")
    raw["requirements"].pop("max_speed")
    raw["requirements"].pop("max_acceleration")
    return raw


@pytest.fixture
def light_spec(tmp_path):
    return write_spec(tmp_path, planar2_no_motors(), "planar2_light.yaml")


def csv_dicts(path):
    header, rows = read_csv(path)
    return [dict(zip(header, r)) for r in rows]


# ----------------------------------------------------------------------------
# Search space and objectives
# ----------------------------------------------------------------------------


def test_space_ranges_logs_integers_and_choices(planar2, catalogue):
    raw = planar2_raw()
    raw["trajectories"]["square_slow"]["laps"] = 1
    d = spec.from_dict(raw)
    s = opt.make_space(d, ["cables.c2.outlet.1=1.2:1.8", "effector.mass=0.5:4:log", "winch.drum_radius=0.02:0.05",
                           "trajectories.square_slow.laps=1:4", "winch.motor=AM8112-0F21-EL7211,AM8121-0F00"])
    kinds = [(p.key, p.kind, p.log) for p in s.params]
    assert kinds == [("cables.c2.outlet.1", "float", False), ("effector.mass", "float", True),
                     ("winch.drum_radius", "float", False), ("trajectories.square_slow.laps", "int", False),
                     ("winch.motor", "categorical", False)]
    assert s.params[0].path == ("cables", 1, "outlet", 1)
    assert s.params[4].choices == ("AM8112-0F21-EL7211", "AM8121-0F00")
    data = s.data({"cables.c2.outlet.1": 1.3, "effector.mass": 2.0, "winch.drum_radius": 0.04,
                   "trajectories.square_slow.laps": 3, "winch.motor": "AM8121-0F00"})
    assert data["cables"][1]["outlet"] == [1.5, 1.3] and data["effector"]["mass"] == 2.0
    assert data["winch"]["drum_radius"] == 0.04 and data["winch"]["motor"] == "AM8121-0F00"
    assert planar2.raw["cables"][1]["outlet"] == [1.5, 1.5]  # the base is not modified
    spec.validate(data)


@pytest.mark.parametrize("option, words", [
    ("cables.0.outlet.0", "expected KEY=LO:HI"),
    ("cables.0.outlt.0=0:1", "cables.0.outlt is not in the spec"),
    ("effector.masss=0:1", "not a key of the spec format"),
    ("cables.5.outlet.0=0:1", "out of range"),
    ("cables.0.outlet.0=1:1", "LO < HI"),
    ("cables.0.outlet.0=2:1", "LO < HI"),
    ("effector.mass=0:2:log", "LO > 0"),
    ("effector.mass=1:2:lin", "LO:HI or LO:HI:log"),
    ("effector.mass=a:2", "expected a number"),
    ("name=0:1", "a range needs a numeric key"),
    ("cables.0.outlet=0:1", "a range needs a numeric key"),
    ("trajectories.square_slow.laps=1:2.5", "integer"),
    ("winch.motor=AM8112-0F21-EL7211,NOPE", "makes the spec invalid"),
    ("tension.0=0,5,30", "makes the spec invalid"),
    ("effector.mass=1,1", "given twice"),
])
def test_space_bad_input_names_the_option(planar2, option, words):
    with pytest.raises(InputError, match="--vary") as exc:
        opt.make_problem(planar2, [option], ["task_min_margin"], None, None, batch.Options())
    assert words in str(exc.value)


def test_objectives_and_limits(planar2):
    objs = opt.objectives.make_objectives(planar2, ["task_min_margin"], ["peak_tension_c2", "peak_motor_torque"])
    assert [(o.figure, o.maximize) for o in objs] == [("task_min_margin", True), ("peak_tension_c2", False),
                                                      ("peak_motor_torque", False)]
    lim = opt.objectives.parse_limit(planar2, "torque_margin >= 1.2")
    assert (lim.figure, lim.at_least, lim.bound) == ("torque_margin", True, 1.2)
    assert lim.violation(1.0) == pytest.approx(0.2) and lim.violation(1.5) < 0
    assert lim.violation(None) == opt.objectives.UNDEFINED
    assert opt.objectives.parse_limit(planar2, "peak_tension<=15").violation(17) == 2
    # every figure offered is a numeric column of report's row (the task box's stiffness figures,
    # the boundary's and the frame loads' are computed when an objective or a limit asks for them)
    row = opt.problem.evaluate_variant(opt.make_problem(
        planar2, ["effector.mass=0.5:2"], ["fraction", "task_min_stiffness", "task_lowest_frequency",
                                           "boundary_measure"], ["max_frame_load"], None,
        batch.Options()).job(), 0, [1.0])["figures"]
    for f in opt.known_figures(planar2):
        assert isinstance(row[f], (int, float)) and not isinstance(row[f], bool), f


def test_the_help_lists_every_figure():
    from cdpr_design.cli.optimize import _FIGURES

    listed = {f.strip() for f in _FIGURES.split(",")}
    assert listed == set(opt.FIGURES) | {"peak_tension_<cable>"}


def test_the_docs_list_every_figure():
    """docs/optimize.md and docs/cli.md give the same FIGURE list as --help and the code."""
    import re

    from .helpers import ROOT

    want = set(opt.FIGURES) | {"peak_tension_<cable>"}
    for doc, start in (("docs/optimize.md", "### FIGURE"), ("docs/cli.md", "**FIGURE** is one of")):
        text = (ROOT / doc).read_text()
        text = text[text.index(start):]
        head = text.index("`task_min_margin`, `min_margin_figure`")  # the list, up to the paragraph's end
        listed = set(re.findall(r"`([a-z_<>]+)`", text[head:text.index("\n\n", head)]))
        assert listed == want, (doc, listed ^ want)


def test_judge_outcomes(planar2):
    pb = opt.make_problem(planar2, ["effector.mass=0.5:2"], ["task_min_margin"], None, ["peak_tension<=18"],
                          batch.Options())
    assert pb.checks == ("task_box", "min_margin", "motors") and not pb.workspace
    assert pb.constraint_names == ["task_box", "min_margin", "motors", "peak_tension<=18"]
    ok = {"task_min_margin": 4.0, "task_poses": 10, "task_feasible": 10, "check_task_box": True,
          "min_margin_figure": 4.0, "req_min_margin": 1.0, "check_min_margin": True, "torque_margin": 1.2,
          "speed_margin": 3.0, "check_motors": True, "motor": "m", "peak_tension": 17.0}
    o = opt.judge(pb, ok)
    assert o.state == "complete" and o.values == [4.0] and all(v <= 0 for v in o.violations) and not o.reason
    o = opt.judge(pb, {**ok, "peak_tension": 19.0, "torque_margin": 0.9, "check_motors": False})
    assert o.state == "infeasible" and o.values == [4.0]
    assert o.violations[2] == pytest.approx(0.1) and o.violations[3] == pytest.approx(1.0)
    assert "motors" in o.reason and "peak_tension<=18" in o.reason
    o = opt.judge(pb, {**ok, "task_min_margin": None})
    assert o.state == "failed" and "task_min_margin is undefined" in o.reason and o.values is None
    o = opt.judge(pb, None, "SpecError: tension: min > max")
    assert o.state == "failed" and o.reason == "SpecError: tension: min > max"


def test_trials_sweep_only_what_their_figures_need(planar2):
    from cdpr_design.design import evaluate as ev

    cat = spec.load_catalogue()
    full = ev.evaluate(planar2, catalogue=cat, step=0.05)
    part = ev.evaluate(planar2, catalogue=cat, step=0.05, figures={"task_min_margin"})
    assert "fraction" not in part and "poses" not in part  # no workspace sweep
    for k, v in part.items():
        assert full[k] == v, k  # the same numbers
    assert ev.parts_needed(planar2, {"fraction"}) == (True, True)
    light = spec.from_dict(planar2_no_motors())
    assert ev.parts_needed(light, {"task_min_margin"}) == (False, False)
    assert ev.parts_needed(light, {"peak_tension_c1"}) == (False, True)
    part = ev.evaluate(light, catalogue=cat, step=0.05, figures={"task_min_margin"})
    assert "peak_tension" not in part and part["checks_passed"] == ev.evaluate(light, catalogue=cat,
                                                                                step=0.05)["checks_passed"]


# ----------------------------------------------------------------------------
# Pareto front and knee against brute force
# ----------------------------------------------------------------------------


def _fake_problem(planar2, directions):
    maxi = [f for f, d in zip(["task_min_margin", "fraction", "measure"], directions) if d]
    mini = [f for f, d in zip(["peak_tension", "peak_motor_torque", "max_tension"], directions) if not d]
    return opt.make_problem(planar2, ["effector.mass=0.5:2"], maxi, mini, None, batch.Options())


@pytest.mark.slow
@pytest.mark.parametrize("directions", [(True, False), (True, True), (False, False, True)])
def test_pareto_and_knee_against_brute_force(planar2, directions):
    rng = np.random.default_rng(len(directions) * 7 + sum(directions))
    pb = _fake_problem(planar2, directions)
    signs = [-1 if o.maximize else 1 for o in pb.objectives]
    for case in range(20):
        n = int(rng.integers(1, 40))
        vals = np.round(rng.normal(size=(n, len(signs))), 1)  # ties and duplicates happen
        states = rng.choice(["complete", "complete", "infeasible", "failed"], size=n)
        rows = [opt.Trial(k, s, {}, None if s == "failed" else list(v)) for k, (s, v) in enumerate(zip(states, vals))]
        done = [r for r in rows if r.state == "complete"]
        sc = {r.number: [s * v for s, v in zip(signs, r.values)] for r in done}
        brute = [r.number for r in done
                 if not any(all(a <= b for a, b in zip(sc[o.number], sc[r.number])) and sc[o.number] != sc[r.number]
                            for o in done)]
        front = opt.pareto(pb, rows)
        assert [r.number for r in front] == brute
        if not front:
            assert opt.knee(pb, front) is None and opt.best(pb, rows) is None
            continue
        arr = np.array([sc[n] for n in brute])
        span = arr.max(0) - arr.min(0)
        d = np.sqrt((((arr - arr.min(0)) / np.where(span > 0, span, 1)) ** 2).sum(1))
        assert opt.knee(pb, front).number == brute[int(np.argmin(d))]
        assert opt.best(pb, rows).number == brute[int(np.argmin(d))]


def test_single_objective_best_and_convergence(planar2):
    pb = _fake_problem(planar2, (True,))
    rows = [opt.Trial(0, "failed", {}, None), opt.Trial(1, "infeasible", {}, [9.0]),
            opt.Trial(2, "complete", {}, [3.0]), opt.Trial(3, "complete", {}, [5.0]),
            opt.Trial(4, "complete", {}, [5.0]), opt.Trial(5, "complete", {}, [1.0])]
    assert opt.best(pb, rows).number == 3  # the infeasible 9 does not count; the earliest of a tie
    assert opt.convergence(pb, rows) == [None, None, 3.0, 5.0, 5.0, 5.0]


def _drawn(ax) -> dict:
    """label -> (x, y, colour) of each labelled line of ``ax``."""
    return {ln.get_label(): (list(ln.get_xdata()), list(ln.get_ydata()), ln.get_color()) for ln in ax.get_lines()
            if not ln.get_label().startswith("_")}


def test_the_picture_shows_convergence_or_the_front_and_importances(planar2):
    """optimize.png, as the job builds it: one objective, each trial and the best so far; two, the front
    in colour, dominated complete trials grey, infeasible ones apart; importances only when given."""
    from matplotlib.colors import to_rgb

    from cdpr_design.jobs.optimize import picture_data
    from cdpr_design.plots.optimize import optimize_figure

    pb = _fake_problem(planar2, (True,))
    rows = [opt.Trial(0, "failed", {}, None), opt.Trial(1, "complete", {}, [2.0]), opt.Trial(2, "infeasible", {},
            [9.0]), opt.Trial(3, "complete", {}, [1.0]), opt.Trial(4, "complete", {}, [4.0])]
    fig = optimize_figure(picture_data(planar2, pb, rows, opt.best(pb, rows), [], {}))
    assert len(fig.axes) == 1  # no importances: no second panel
    lines = _drawn(fig.axes[0])
    assert lines["best so far"][:2] == ([1, 2, 3, 4], [2.0, 2.0, 2.0, 4.0])
    assert lines["complete"][:2] == ([1, 3, 4], [2.0, 1.0, 4.0]) and lines["infeasible"][:2] == ([2], [9.0])
    assert lines["best (trial 4)"][:2] == ([4], [4.0]) and lines["failed"][0] == [0]

    pb = _fake_problem(planar2, (True, False))
    rows = [opt.Trial(0, "complete", {}, [1.0, 1.0]), opt.Trial(1, "complete", {}, [2.0, 2.0]),
            opt.Trial(2, "complete", {}, [1.0, 3.0]), opt.Trial(3, "infeasible", {}, [5.0, 0.0]),
            opt.Trial(4, "failed", {}, None), opt.Trial(5, "complete", {}, [0.5, 1.5])]
    front = opt.pareto(pb, rows)
    imp = {"task_min_margin": {"effector.mass": 1.0}, "peak_motor_torque": {"effector.mass": 1.0}}
    fig = optimize_figure(picture_data(planar2, pb, rows, opt.best(pb, rows), front, imp))
    assert len(fig.axes) == 2 and fig.axes[1].get_title() == "which keys matter"
    lines = _drawn(fig.axes[0])
    assert sorted(zip(*lines["Pareto front"][:2])) == [(1.0, 1.0), (2.0, 2.0)]
    assert sorted(zip(*lines["dominated"][:2])) == [(0.5, 1.5), (1.0, 3.0)]
    assert to_rgb(lines["dominated"][2]) == (0.7, 0.7, 0.7)  # grey
    assert to_rgb(lines["Pareto front"][2]) != to_rgb(lines["dominated"][2])
    assert lines["infeasible"][:2] == ([5.0], [0.0])
    assert len(fig.axes[1].patches) == 2  # a bar per objective for the one key


# ----------------------------------------------------------------------------
# The command: exhaustive grid, report, two objectives, determinism, bad input
# ----------------------------------------------------------------------------

GRID = 41  # 0.025 m steps over the same box as the search


@pytest.mark.slow
def test_best_is_within_one_percent_of_the_exhaustive_grid(tmp_path, light_spec):
    """Two outlet x coordinates of planar2, task minimum margin: the exhaustive 41 x 41 grid against
    150 trials of the search; the best design, re-evaluated by ``report``, is within 1 %."""
    d = spec.load(light_spec)
    plan = batch.make_plan(d, [("cables.0.outlet.0", tuple(np.linspace(-0.5, 0.5, GRID))),
                               ("cables.1.outlet.0", tuple(np.linspace(1.0, 2.0, GRID)))])
    recs = []
    batch.run(plan, batch.Options(figures=frozenset({"task_min_margin"})), workers=1, on_record=recs.append)
    ok = [r for r in recs if not r["error"] and r["figures"]["checks_passed"]]
    assert len(recs) == GRID * GRID and 100 < len(ok) < len(recs)  # the requirements bind
    grid_best = max(r["figures"]["task_min_margin"] for r in ok)
    assert grid_best > 1.2 * 4.131  # the shipped layout's 4.13 N is far from the optimum

    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", 150, "--seed", 1,
               "--out", out, "--json", "--no-picture")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["trials_done"] == 150 and s["evaluates"] == "task box"
    found = s["best"]["objectives"]["task_min_margin"]
    assert found >= 0.99 * grid_best, (found, grid_best)

    r = invoke("report", out / "best.yaml", "--out", tmp_path / "report", "--json")
    assert r.exit_code == 0, r.output
    rep = json.loads(r.stdout)
    assert rep["checks_passed"] is True
    assert rep["task_min_margin"] == pytest.approx(found, rel=1e-12)
    assert csv_dicts(out / "optimize.csv")[s["best"]["trial"]]["state"] == "complete"


@pytest.mark.slow
def test_two_objectives_pareto_csv_is_the_front(tmp_path, light_spec):
    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--minimize", "peak_tension",
               "--require", "peak_tension<=19", "--trials", 40, "--seed", 3, "--out", out, "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    rows = csv_dicts(out / "optimize.csv")
    front = csv_dicts(out / "pareto.csv")
    assert len(rows) == 40 and {r["state"] for r in rows} >= {"complete", "infeasible"}
    done = [r for r in rows if r["state"] == "complete"]
    score = {r["trial"]: (-float(r["task_min_margin"]), float(r["peak_tension"])) for r in done}

    def dominated(t):
        return any(all(a <= b for a, b in zip(score[o], score[t])) and score[o] != score[t] for o in score)

    in_front = {r["trial"] for r in front}
    assert in_front and all(not dominated(t) for t in in_front)  # nothing in pareto.csv is dominated
    assert {t for t in score if not dominated(t)} == in_front  # every non-dominated trial is there
    assert [r["trial"] for r in front] == sorted(in_front, key=int)
    assert all(r == next(x for x in rows if x["trial"] == r["trial"]) for r in front)  # the same rows
    # best.yaml is the knee of the front
    knee = str(s["best"]["trial"])
    assert knee in in_front and s["best_rule"] == "knee of the Pareto front"
    text = (out / "best.yaml").read_text()
    best_row = next(r for r in rows if r["trial"] == knee)
    d = spec.from_dict(spec.read_yaml(out / "best.yaml"))
    assert d.raw["cables"][0]["outlet"][0] == pytest.approx(float(best_row["cables.0.outlet.0"]), rel=1e-9)
    assert f"trial {knee}" in text
    assert (out / "optimize.png").stat().st_size > 10_000
    # two keys: each objective's importances, over both keys
    assert {f: set(v) for f, v in s["importances"].items()} == {f: {OUTLETS[1][:17], OUTLETS[3][:17]}
                                                                for f in ("task_min_margin", "peak_tension")}


def test_one_worker_with_a_seed_is_repeatable(tmp_path, light_spec):
    tables = []
    for k in range(2):
        r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", 14,
                   "--seed", 7, "--out", tmp_path / str(k), "--quiet", "--no-picture")
        assert r.exit_code == 0, r.output
        header, rows = read_csv(tmp_path / str(k) / "optimize.csv")
        tables.append([row[:-1] for row in rows])  # all but the seconds column
    assert header[-1] == "seconds" and tables[0] == tables[1]


@pytest.mark.slow
def test_parquet_tables_are_the_csv_ones_and_the_summary_has_timings(tmp_path, light_spec):
    from cdpr_design.io.columns import read_table, table_metadata

    base = ["optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--minimize", "peak_tension",
            "--trials", 10, "--seed", 5, "--no-picture", "--json"]
    runs = {}
    for fmt_ in ("csv", "parquet"):
        r = invoke(*base, "--format", fmt_, "--out", tmp_path / fmt_)
        assert r.exit_code == 0, r.output
        runs[fmt_] = json.loads(r.stdout)
        t = runs[fmt_]["timings"]
        assert set(t) == {"sweep_s", "write_s", "pictures_s", "total_s"} and t["total_s"] >= t["sweep_s"] > 0
    assert not (tmp_path / "parquet" / "optimize.csv").exists()
    for stem in ("optimize", "pareto"):
        a, b = read_table(tmp_path / "csv" / f"{stem}.csv"), read_table(tmp_path / "parquet" / f"{stem}.parquet")
        assert list(a) == list(b) and len(b["trial"]) > 0
        for name in a:
            if name == "seconds":  # the evaluations' own wall time
                continue
            if b[name].dtype.kind in "biuf":
                np.testing.assert_allclose(b[name].astype(float), a[name], rtol=1e-9)  # CSV: 10 digits
            else:  # text; an empty cell is None in Parquet and NaN in a CSV column without text
                def cells(col):
                    return ["" if v is None or (isinstance(v, float) and math.isnan(v)) else v for v in col]

                assert cells(b[name]) == cells(a[name]), name
        meta = table_metadata(tmp_path / "parquet" / f"{stem}.parquet")
        assert meta["table"] == stem and meta["keys"] == [OUTLETS[1][:17], OUTLETS[3][:17]]
    assert b["trial"].dtype == np.int64


@pytest.mark.slow
def test_two_workers_end_with_exactly_the_trials_asked(tmp_path, light_spec):
    """This process (worker 0) and a spawned worker share the study: exactly N trials, each once."""
    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", 24, "--workers", 2,
               "--seed", 5, "--out", out, "--json", "--no-picture")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    rows = csv_dicts(out / "optimize.csv")
    assert s["workers"] == 2 and s["trials_done"] == s["evaluated_now"] == 24
    assert [int(r["trial"]) for r in rows] == list(range(24))
    assert len({(r["cables.0.outlet.0"], r["cables.1.outlet.0"]) for r in rows}) == 24
    workers = {t.user_attrs["result"]["worker"] for t in opt.finished(opt.study.load(out))}
    assert 0 in workers and workers <= {0, 1}


@pytest.mark.slow
def test_invalid_variants_in_a_range_are_failed_trials(tmp_path, light_spec):
    """tension.1 below tension.0 (0 N) breaks the spec: a failed trial with the spec's reason."""
    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, "--vary", "tension.1=-20:40", "--maximize", "task_min_margin",
               "--trials", 12, "--seed", 0, "--out", out, "--json", "--no-picture")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    rows = csv_dicts(out / "optimize.csv")
    assert len(rows) == 12 == s["trials_done"]
    failed = [r for r in rows if r["state"] == "failed"]
    assert failed and s["failed"] == len(failed)
    for f in failed:
        assert float(f["tension.1"]) < 0 and "SpecError" in f["reason"] and "tension" in f["reason"]
        assert f["task_min_margin"] == ""
    assert all(float(r["tension.1"]) >= 0 for r in rows if r["state"] != "failed")
    assert any(r["state"] == "complete" for r in rows)
    assert s["importances"] == {}  # one key: nothing to compare


def test_no_feasible_trial_exits_1_without_best(tmp_path, light_spec):
    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--require",
               "task_min_margin>=100", "--trials", 3, "--out", out, "--quiet", "--no-picture")
    assert r.exit_code == 1 and "no trial" in r.output
    assert (out / "optimize.csv").exists() and not (out / "best.yaml").exists()
    assert all(r["state"] == "infeasible" and "task_min_margin>=100" in r["reason"]
               for r in csv_dicts(out / "optimize.csv"))


@pytest.mark.parametrize("args, option", [
    (["--vary", "cables.0.outlt.0=0:1", "--maximize", "task_min_margin"], "--vary"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margn"], "--maximize"),
    (["--vary", "cables.0.outlet.0=0:1", "--minimize", "motor"], "--minimize"),
    (["--vary", "cables.0.outlet.0=0.5:0.5", "--maximize", "task_min_margin"], "--vary"),
    (["--vary", "winch.motor=AM8112-0F21-EL7211,NOPE", "--maximize", "task_min_margin"], "--vary"),
    (["--vary", "tension.0=0,30", "--maximize", "task_min_margin"], "--vary"),
    (["--vary", "cables.0.outlet.0=0:1"], "--maximize / --minimize"),
    ([], "--vary"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--trials", "0"], "--trials"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--workers", "0"], "--workers"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--timeout", "-1"], "--timeout"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--require", "fraction=1"], "--require"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--require", "frac>=1"], "--require"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "fraction", "--minimize", "fraction"], "--minimize"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--trajectory", "nope"], "--trajectory"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "task_min_margin", "--motor", "NOPE"], "--motor"),
])
def test_bad_input_exits_2_naming_the_option(tmp_path, args, option):
    r = invoke("optimize", PLANAR2, *args, "--out", tmp_path / "o")
    assert r.exit_code == 2, r.output
    assert option in r.output and "Traceback" not in r.output
    assert not (tmp_path / "o" / "optimize.db").exists()  # refused before any work


LONG = "a" * 5000


@pytest.mark.parametrize("args, option", [
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", LONG], "--maximize"),
    (["--vary", "cables.0.outlet.0=0:1", "--minimize", LONG], "--minimize"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "fraction", "--require", LONG], "--require"),
    (["--vary", "cables.0.outlet.0=0:1", "--maximize", "fraction", "--require", "fraction>=" + LONG], "--require"),
    (["--vary", "effector.mass=" + LONG, "--maximize", "fraction"], "--vary"),
    (["--vary", "effector.mass=1:" + LONG, "--maximize", "fraction"], "--vary"),
    (["--vary", LONG + "=1:2", "--maximize", "fraction"], "--vary"),
    (["--vary", "winch.motor=" + LONG, "--maximize", "fraction"], "--vary"),
])
def test_long_values_are_shortened_in_messages(tmp_path, args, option):
    """An offending value of 5,000 characters is quoted shortened (errors.quote), never whole."""
    r = invoke("optimize", PLANAR2, *args, "--out", tmp_path / "o")
    assert r.exit_code == 2 and option in r.output and "Traceback" not in r.output
    assert "a" * 100 not in r.output and len(r.output) < 600, r.output


def _damaged_study(tmp_path, light_spec):
    """A study of two trials, its pages then overwritten in the middle (the header intact)."""
    out = tmp_path / "opt"
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", 2, "--out", out,
               "--quiet", "--no-picture", "--seed", 0)
    assert r.exit_code == 0, r.output
    con = sqlite3.connect(out / "optimize.db")
    con.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    con.close()
    data = bytearray((out / "optimize.db").read_bytes())
    data[2 * 4096: 3 * 4096] = b"\xff" * 4096
    (out / "optimize.db").write_bytes(data)
    return out


def _sqlite_of_another_tool(tmp_path):
    out = tmp_path / "opt"
    out.mkdir()
    con = sqlite3.connect(out / "optimize.db")
    con.execute("CREATE TABLE samples (x REAL)")
    con.commit()
    con.close()
    return out


def _garbage(tmp_path):
    out = tmp_path / "opt"
    out.mkdir()
    (out / "optimize.db").write_text("garbage\n")
    return out


@pytest.mark.parametrize("make, extra, words", [
    (lambda tmp, spec: _garbage(tmp), ["--overwrite"], "not a readable optuna study"),
    (lambda tmp, spec: _garbage(tmp), ["--overwrite", "--resume"], "not a readable optuna study"),
    (_damaged_study, ["--resume"], "not a readable optuna study"),
    (lambda tmp, spec: _sqlite_of_another_tool(tmp), ["--overwrite"], "not an optuna study"),
])
def test_an_optimize_db_that_is_no_study_is_refused_and_kept(tmp_path, light_spec, make, extra, words):
    """optimize.db not an SQLite file, a damaged study, another tool's SQLite file: exit 2 naming it before
    any work, the file left as it was (--overwrite never replaces a study file), no file added."""
    out = make(tmp_path, light_spec)
    db = out / "optimize.db"
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", 2, "--out", out,
               "--no-picture", *extra)
    assert r.exit_code == 2, r.output
    assert str(db) in r.output and words in r.output and "Traceback" not in r.output
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before


def test_a_task_figure_needs_a_task_box(tmp_path):
    r = invoke("optimize", "designs/ipanema3.yaml", "--vary", "effector.mass=20:40", "--maximize",
               "task_min_margin", "--out", tmp_path)
    assert r.exit_code == 2 and "requirements.task_box" in r.output


@pytest.mark.slow
def test_an_existing_study_needs_resume_and_the_same_search(tmp_path, light_spec):
    out = tmp_path / "opt"
    base = ["optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--out", out, "--no-picture"]
    # seeded: most of this box is infeasible, so three unseeded trials can all fail (exit 1, rightly)
    assert invoke(*base, "--trials", 3, "--seed", 0, "--quiet").exit_code == 0
    r = invoke(*base, "--trials", 3)
    assert r.exit_code == 2 and "--resume" in r.output
    r = invoke(*base[:-3], "--vary", "effector.mass=1:2", "--out", out, "--trials", 3, "--resume")
    assert r.exit_code == 2 and "another search" in r.output
    r = invoke(*base, "--trials", 5, "--resume", "--json")  # continues to a new total
    s = json.loads(r.stdout)
    assert r.exit_code == 0 and s["resumed"] == 3 and s["evaluated_now"] == 2 and s["trials_done"] == 5


def test_timeout_stops_and_resume_completes(tmp_path, light_spec):
    out = tmp_path / "opt"
    base = ["optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--out", out, "--no-picture",
            "--json", "--trials", 400]
    # seed 0: the first trial is feasible, so a run the timeout stops after one trial still has a best
    # (unseeded, a loaded machine's one or two trials could all be infeasible: exit 1, rightly)
    r = invoke(*base, "--timeout", "0.3", "--seed", 0)
    s = json.loads(r.stdout)
    assert r.exit_code == 0 and s["stopped_by_timeout"] and 1 <= s["trials_done"] < 400
    assert len(csv_dicts(out / "optimize.csv")) == s["trials_done"]


# ----------------------------------------------------------------------------
# Interrupted runs
# ----------------------------------------------------------------------------

N_KILL = 30


def _finished_trials(db) -> dict:
    """number -> (state, params) of the trials the study holds, read straight from SQLite."""
    if not db.exists():
        return {}
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=30)
    try:
        trials = dict(con.execute("SELECT trial_id, number FROM trials").fetchall())
        states = dict(con.execute("SELECT trial_id, state FROM trials").fetchall())
        params: dict = {t: {} for t in trials}
        for tid, name, value in con.execute("SELECT trial_id, param_name, param_value FROM trial_params"):
            params[tid][name] = value
        attrs = {tid for tid, key in con.execute("SELECT trial_id, key FROM trial_user_attributes")
                 if key == "interrupted"}
    except sqlite3.OperationalError:  # the tables are being created
        return {}
    finally:
        con.close()
    return {trials[t]: (states[t], params[t], t in attrs) for t in trials}


def _start_and_kill(tmp_path, light_spec, sig, group: bool, workers: int):
    """Start a run of N_KILL trials in a subprocess, send ``sig`` once 6 trials have finished; the
    study's trials right after."""
    out = tmp_path / "opt"
    cmd = [sys.executable, "-m", "cdpr_design", "optimize", str(light_spec), *OUTLETS, "--maximize",
           "task_min_margin", "--trials", str(N_KILL), "--workers", str(workers), "--seed", "2", "--out", str(out),
           "--quiet", "--no-picture"]
    log = open(tmp_path / "stderr.txt", "wb")  # a file, not a pipe: workers of a killed run may hold it
    proc = subprocess.Popen(cmd, env=subprocess_env(), stdout=subprocess.DEVNULL, stderr=log,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline and proc.poll() is None:
            t = _finished_trials(out / "optimize.db")
            states = [s for s, _, _ in t.values()]
            if sum(s in ("COMPLETE", "FAIL") for s in states) >= 6 and "RUNNING" in states:
                break  # mid-trial
            time.sleep(0.05)
        assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
        (os.killpg if group else os.kill)(proc.pid, sig)
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)
        log.close()
    return out, code, (tmp_path / "stderr.txt").read_text()


def _check_resumed(out, before, light_spec):
    """Resume to N_KILL: exactly N_KILL trials, those finished before unchanged, interrupted ones
    evaluated once, no parameters twice."""
    r = invoke("optimize", light_spec, *OUTLETS, "--maximize", "task_min_margin", "--trials", N_KILL,
               "--seed", 2, "--out", out, "--json", "--no-picture", "--resume")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    rows = csv_dicts(out / "optimize.csv")
    assert len(rows) == N_KILL == s["trials_done"]
    assert len({r["trial"] for r in rows}) == N_KILL
    assert all(r["state"] in ("complete", "infeasible", "failed") for r in rows)
    key = ("cables.0.outlet.0", "cables.1.outlet.0")
    by_number = {int(r["trial"]): r for r in rows}
    done_before = {n: p for n, (st, p, intr) in before.items() if st in ("COMPLETE", "FAIL") and not intr}
    assert len(done_before) >= 6 and s["resumed"] == len(done_before)
    for n, p in done_before.items():  # nothing lost: the same trial, the same point
        assert [float(by_number[n][k]) for k in key] == pytest.approx([p[k] for k in key], rel=1e-9)
    points = [tuple(float(r[k]) for k in key) for r in rows]  # 10 significant digits in the CSV
    assert len(set(points)) == N_KILL  # nothing evaluated twice
    interrupted = [p for n, (st, p, intr) in before.items() if (st == "RUNNING" or intr) and p]
    for p in interrupted:  # each interrupted point evaluated once, after the resume (a trial killed between
        # its two suggestions has one key: the resumed trial keeps it and samples the other)
        assert sum(all(math.isclose(x, p[k], rel_tol=1e-9) for x, k in zip(q, key) if k in p) for q in points) == 1
    assert s["requeued_interrupted"] == len(interrupted)
    return s, interrupted


@pytest.mark.slow
def test_a_trial_left_running_is_evaluated_again_on_resume(tmp_path, light_spec):
    """What SIGKILL leaves (a RUNNING trial with its parameters) and SIGINT leaves (a failed trial
    marked interrupted): both queued again once, neither counted, the total exact."""
    import optuna

    pb = opt.make_problem(spec.load(light_spec), OUTLETS[1::2], ["task_min_margin"], None, None, batch.Options())
    opt.run(pb, tmp_path, 3, seed=0)
    study = opt.study.load(tmp_path)
    killed = study.ask()
    killed_point = {p.key: p.suggest(killed) for p in pb.space.params}
    stopped = study.ask()
    stopped_point = {p.key: p.suggest(stopped) for p in pb.space.params}
    stopped.set_user_attr("interrupted", True)
    study.tell(stopped, state=optuna.trial.TrialState.FAIL)
    assert opt.study.counted(study, opt.study.storage(tmp_path)) == 4  # the RUNNING one counts until a resume marks it
    stats = opt.run(pb, tmp_path, 6, seed=0, resume=True)
    assert (stats.resumed, stats.requeued, stats.evaluated) == (3, 2, 3)
    rows = opt.results.trials(opt.finished(opt.study.load(tmp_path)))
    assert [r.number for r in rows] == [0, 1, 2, 5, 6, 7]
    assert [rows[3].params, rows[4].params] == [killed_point, stopped_point]
    # a second resume queues nothing again
    stats = opt.run(pb, tmp_path, 6, resume=True)
    assert (stats.requeued, stats.evaluated) == (0, 0)


@pytest.mark.slow
def test_sigint_then_resume(tmp_path, light_spec):
    out, code, err = _start_and_kill(tmp_path, light_spec, signal.SIGINT, group=True, workers=2)
    assert code == 130, err
    assert not (out / "optimize.csv").exists()
    before = _finished_trials(out / "optimize.db")
    assert all(s != "RUNNING" for s, _, _ in before.values())  # interrupted trials were told so
    _check_resumed(out, before, light_spec)


@pytest.mark.slow
def test_sigkill_then_resume(tmp_path, light_spec):
    out, code, _ = _start_and_kill(tmp_path, light_spec, signal.SIGKILL, group=True, workers=1)
    assert code == -signal.SIGKILL
    before = _finished_trials(out / "optimize.db")
    running = [n for n, (st, p, _) in before.items() if st == "RUNNING" and p]
    _, interrupted = _check_resumed(out, before, light_spec)
    assert len(interrupted) == len(running) <= 1  # the trial under way when the run was killed


def _workers_gone(out, within_s: float = 60.0) -> bool:
    """Whether the worker processes of a run (which hold a shared lock on .optimize.workers) have ended."""
    import fcntl

    end = time.monotonic() + within_s
    with open(out / opt.study.WORKERS_LOCK, "a") as fh:
        while time.monotonic() < end:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                fcntl.flock(fh, fcntl.LOCK_UN)
                return True
            except BlockingIOError:
                time.sleep(0.05)
    return False


@pytest.mark.slow
def test_sigkill_of_the_run_alone_leaves_workers_that_end(tmp_path, light_spec):
    """The run's process killed alone: its worker process finishes its trial (told normally) and ends;
    the trial the run's process was evaluating (it is worker 0) is left running, and evaluated again on
    resume."""
    out, code, _ = _start_and_kill(tmp_path, light_spec, signal.SIGKILL, group=False, workers=2)
    assert code == -signal.SIGKILL
    assert _workers_gone(out)
    before = _finished_trials(out / "optimize.db")
    running = [n for n, (st, p, _) in before.items() if st == "RUNNING"]
    assert len(running) <= 1  # the run's own trial; the worker process's was told
    _, interrupted = _check_resumed(out, before, light_spec)
    assert len(interrupted) == len([n for n in running if before[n][1]])
