"""Hostile input (issue 19): one test per finding of the probe, each failing on the code before the fix.

Hangs and deep recursion run in a subprocess with a timeout, so a regression
fails the test instead of stalling the suite.  The signal tests are in
test_signals.py, the fuzzing in test_fuzz.py.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from cdpr_design.cli.common import QuietOpt, command

from .helpers import PLANAR2, ROOT, invoke, planar2_raw, read_csv, subprocess_env, write_spec, resolved


def run_cli(*args, timeout: float = 60, cwd=None):
    """``python -m cdpr_design ARGS`` in a subprocess: (exit status, stdout, stderr, seconds)."""
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "cdpr_design", *map(str, args)], capture_output=True, text=True,
                       timeout=timeout, cwd=cwd, env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0"))
    return p.returncode, p.stdout, p.stderr, time.perf_counter() - t0


def assert_clean_error(res, *needles):
    """Exit 2, each needle in the message, no traceback (in-process ``invoke`` result)."""
    assert res.exit_code == 2, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit), repr(res.exception)
    assert "Traceback" not in res.output
    for n in needles:
        assert n in res.output, (n, res.output)


def spec_with(tmp_path, change, name="spec.yaml"):
    d = planar2_raw()
    change(d)
    return write_spec(tmp_path, d, name)


# ----------------------------------------------------------------------------
# Hangs: alias bombs, FIFOs and devices
# ----------------------------------------------------------------------------

BOMB = "".join(f"{k}: &{k} [{', '.join(['*' + p] * 9) if p else ', '.join(['1'] * 9)}]\n"
               for p, k in zip([None, *"abcdefgh"], "abcdefghi"))


def test_an_alias_bomb_is_refused_at_once(tmp_path):
    # nine levels of nine aliases: 387 million numbers where the spec wants one; the old error
    # message built repr() of it (effector.mass: expected a number, got [[[...
    text = PLANAR2.read_text().replace("  mass: 1.0", "  mass: *i")
    p = tmp_path / "bomb.yaml"
    p.write_text("x_anchors:\n" + "".join("  " + line + "\n" for line in BOMB.splitlines()) + text)
    rc, out, err, dt = run_cli("pose", p, "--at", "0.75,0.75", timeout=60)
    assert rc == 2 and "Traceback" not in err, err
    assert "expands to more than" in err and dt < 30


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_the_spec_is_refused(tmp_path):
    fifo = tmp_path / "spec.fifo"
    os.mkfifo(fifo)
    rc, out, err, dt = run_cli("pose", fifo, "--at", "0.75,0.75", timeout=60)  # used to block forever
    assert rc == 2 and "not a regular file" in err and "Traceback" not in err, err


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero here")
def test_dev_zero_as_the_spec_is_refused():
    rc, out, err, dt = run_cli("pose", "/dev/zero", "--at", "0.75,0.75", timeout=60)  # used to read forever
    assert rc == 2 and "not a regular file" in err, err


def test_a_spec_file_over_the_size_limit_is_refused(tmp_path):
    from cdpr_design.errors import SpecError
    from cdpr_design.model import limits, spec

    p = tmp_path / "big.yaml"
    p.write_text(PLANAR2.read_text() + "#" * limits.MAX_SPEC_BYTES)
    with pytest.raises(SpecError, match="more than the 1,048,576"):
        spec.load(p)


# ----------------------------------------------------------------------------
# Tracebacks
# ----------------------------------------------------------------------------


def test_a_ragged_inertia_matrix_is_a_spec_error(tmp_path):
    p = spec_with(tmp_path, lambda d: d["effector"].update(inertia=[[1, 0, 0], [0, 1], [0, 0, 1]]))
    assert_clean_error(invoke("pose", p, "--at", "0.75,0.75"), "effector.inertia", "3 rows of 3 numbers")


@pytest.mark.parametrize("depth", [33, 999, 1001, 20000])
def test_deep_nesting_is_refused(tmp_path, depth):
    """One message naming the file and the spec format's limit, however deep and whatever PyYAML
    is installed (20,000 was a RecursionError; libyaml 0.2.6 and later, in PyYAML's wheels since
    6.0.4, refuse 1,000 levels and more themselves, in their own words, before yielding an event)."""
    p = tmp_path / "nested.yaml"
    p.write_text("name: " + "[" * depth + "]" * depth + "\n")
    rc, out, err, dt = run_cli("pose", p, "--at", "0.75,0.75", timeout=60)
    assert rc == 2 and "Traceback" not in err and out == "", err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and str(p) in lines[0], err
    assert "nests deeper than 32 levels" in lines[0], err  # the spec format's limit (model/limits.py)


@pytest.mark.parametrize("step", ["1e-11", "1e-300", "0", "-1", "nan", "inf"])
def test_tiny_zero_and_negative_steps_are_refused(tmp_path, step):
    for cmd in ("workspace", "size-motors"):
        res = invoke(cmd, PLANAR2, "--step", step, "--out", tmp_path / cmd)
        assert_clean_error(res, "--step")
        assert not (tmp_path / cmd).exists()


@pytest.mark.parametrize("step", [1e-11, 1e-300])
def test_grid_sizes_are_counted_without_overflow(planar2, step):
    # the library entry points (no typer range in front): the count overflowed int64 before the limit check
    from cdpr_design import workspaces as ws
    from cdpr_design.errors import SpecError

    with pytest.raises(SpecError, match="--step: the grid would have"):
        ws.make_grid(planar2, step)
    with pytest.raises(SpecError, match="--step: the grid would have"):
        ws.make_grid(planar2, step, force=True)  # past the hard limit even with force


def test_a_tiny_spec_step_is_refused_with_the_count(tmp_path):
    p = spec_with(tmp_path, lambda d: d["workspace"]["grid"].update(step=1e-11))
    assert_clean_error(invoke("workspace", p, "--out", tmp_path / "o"), "workspace.grid.step", "poses")


@pytest.mark.parametrize("step", [0.0, -1.0, float("nan")])
def test_size_motors_library_refuses_bad_steps(planar2, catalogue, step):
    from cdpr_design.design import sizing
    from cdpr_design.errors import SpecError

    with pytest.raises(SpecError, match="--step: expected a positive number"):
        sizing.size_motors(resolved(planar2, "size-motors"), catalogue, step=step)


def test_an_out_under_a_file_is_refused(tmp_path):
    (tmp_path / "afile").write_text("x")
    res = invoke("workspace", PLANAR2, "--step", "0.1", "--out", tmp_path / "afile" / "sub")
    assert_clean_error(res, "--out", "is a file, not a folder")
    res = invoke("workspace", PLANAR2, "--step", "0.1", "--out", tmp_path / "afile")
    assert_clean_error(res, "--out", "not a folder")


def _read_only_folder(tmp_path):
    """A folder this process cannot write: chmod 555 (not root), else /proc/sys where the kernel
    mounts it read-only (a container); None when neither holds."""
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        return ro
    if os.path.isdir("/proc/sys") and not os.access("/proc/sys", os.W_OK):
        return "/proc/sys"
    return None


def test_a_read_only_out_is_refused_before_any_work(tmp_path):
    ro = _read_only_folder(tmp_path)
    if ro is None:
        pytest.skip("no read-only folder for this user here")
    for out in (ro, os.path.join(ro, "sub")):
        res = invoke("trajectory", PLANAR2, "square_slow", "--out", out)
        assert_clean_error(res, "--out", "not writable")


def test_the_out_pre_flight_check_asks_the_file_system(tmp_path, monkeypatch):
    # what os.access says decides (a read-only file system refuses even root)
    from cdpr_design.errors import InputError
    from cdpr_design.io.files import OutputDir

    monkeypatch.setattr(os, "access", lambda path, mode: False)
    with pytest.raises(InputError, match="is not writable"):
        OutputDir(tmp_path)
    with pytest.raises(InputError, match="cannot create .*sub.*is not writable"):
        OutputDir(tmp_path / "sub")


# ----------------------------------------------------------------------------
# Wrong successes
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("change,path", [
    (lambda d: d["effector"].update(mass=True), "effector.mass"),
    (lambda d: d["effector"].update(mass="1.0"), "effector.mass"),
    (lambda d: d.update(name="."), "name"),
    (lambda d: d.update(name=".."), "name"),
    (lambda d: d.update(name="a/b"), "name"),
    (lambda d: d.update(name="x" * 65), "name"),
    (lambda d: d["effector"].update(mass=1e308), "effector.mass"),
    (lambda d: d["cables"][0].update(outlet=[1e300, 1.5]), "cables[0].outlet[0]"),
    (lambda d: d["cables"][0].update(name="[/x]"), "cables[0].name"),
    (lambda d: d["cables"][0].update(name="a,b"), "cables[0].name"),
    (lambda d: d["trajectories"].update({"../x": d["trajectories"]["square_slow"]}), "trajectories"),
    (lambda d: d.update(description="x" * 20_000), "description"),
    (lambda d: d["trajectories"]["square_slow"].update(laps=2.0), "trajectories.square_slow.laps"),
])
def test_nonsense_specs_are_refused(tmp_path, change, path):
    from cdpr_design.errors import SpecError
    from cdpr_design.model import spec

    with pytest.raises(SpecError) as info:
        spec.load(spec_with(tmp_path, change))
    assert any(p.startswith(path) for p, _ in info.value.problems), info.value.problems
    assert len(str(info.value)) < 600  # the offending value is quoted short, never whole


def test_exponent_numbers_are_numbers_and_quoted_ones_text(tmp_path):
    """``1.0e6`` and ``1e6`` (YAML 1.2 floats; PyYAML's 1.1 reads them as text) are numbers;
    the quoted ``"1.0e6"`` stays text and is refused where a number is meant."""
    from cdpr_design.errors import SpecError
    from cdpr_design.model import spec

    text = (ROOT / "designs" / "planar2.yaml").read_text()
    for written, value in (("1.0e0", 1.0), ("1e0", 1.0), ("25E-1", 2.5), ("+.5e1", 5.0)):
        p = tmp_path / "s.yaml"
        p.write_text(text.replace("mass: 1.0", f"mass: {written}", 1))
        assert spec.load(p).effector.mass == value, written
    for text_value in ('"1.0e0"', "._e5", "_1e5"):  # quoted, or no digit before the exponent: text
        p.write_text(text.replace("mass: 1.0", f"mass: {text_value}", 1))
        with pytest.raises(SpecError, match="effector.mass"):  # found by the fuzz run: ._e5 was a ValueError
            spec.load(p)


def test_size_motors_and_sweep_options_are_ranged(tmp_path):
    assert_clean_error(invoke("size-motors", PLANAR2, "--step", "-1", "--out", tmp_path / "a"), "--step")
    assert_clean_error(invoke("sweep", PLANAR2, "--vary", "effector.mass=1,2", "--top", "-1",
                              "--out", tmp_path / "b"), "--top")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_fk_on_unreachable_lengths_is_an_error_with_the_residual():
    # two cables too short to meet: no pose has them; the message gives the miss
    res = invoke("fk", PLANAR2, "--lengths", "0.1,0.1", "--json")
    assert_clean_error(res, "--lengths", "cannot both reach", "short by 1.18 m")
    assert res.stdout == ""
    res = invoke("fk", PLANAR2, "--lengths", "0.5,0.5")
    assert_clean_error(res, "--lengths", "short by 0.38 m")
    # one cable far too long is not unreachable: it hangs slack and the effector hangs from the other
    hang = invoke("fk", PLANAR2, "--lengths", "30,0.1", "--json")
    assert hang.exit_code == 0, hang.output
    data = json.loads(hang.stdout)
    assert data["slack"] == ["c1"] and data["residual"] < 1e-9 and data["tensions"]["c1"] == 0.0
    ok = invoke("fk", PLANAR2, "--lengths", "0.975807,0.975807", "--json")  # pose 0.75, 0.75: reachable
    assert ok.exit_code == 0, ok.output
    assert json.loads(ok.stdout)["residual"] < 1e-9


def test_fk_with_pulleys_refuses_lengths_it_cannot_reach(tmp_path):
    """The kinematic solve (swivel pulleys) returns the pose that misses least: refused with its residual."""
    p = spec_with(tmp_path, lambda d: [c.update(pulley={"radius": 0.02, "axis": [0, 1, 0]}) for c in d["cables"]])
    res = invoke("fk", p, "--lengths", "0.1,0.1")
    assert_clean_error(res, "--lengths", "no pose found with these cable lengths", "residual")


def test_a_sample_at_a_zero_length_cable_is_infeasible_as_pose_says(tmp_path):
    # (0.06, 1.44) puts c1's attachment on its outlet: `pose` calls it infeasible (zero-length cable)
    p = spec_with(tmp_path, lambda d: d["trajectories"].update(
        z={"type": "polyline", "waypoints": [[0.06, 1.44], [0.75, 0.8]], "speed": 0.1, "acceleration": 1.0}))
    pose = invoke("pose", p, "--at", "0.06,1.44", "--json")
    assert json.loads(pose.stdout)["feasible"] is False
    from cdpr_design.jobs.motion import sample_named
    from cdpr_design.model import spec

    s = sample_named(resolved(spec.load(p), "motion"), "z")
    assert np.allclose(s.pose[0], [0.06, 1.44]) and s.lengths[0, 0] < 1e-12
    assert not s.feasible[0] and np.all(np.isnan(s.tensions[0]))
    assert s.feasible[1:].all() and not s.all_feasible


def test_sizing_leaves_out_task_poses_with_a_zero_length_cable(catalogue):
    # a redundant planar robot (3 cables, 2T) whose c1 has zero length at (0.06, 0.94): c3 alone
    # (straight up) holds the effector there, so only the zero-length rule keeps the pose out,
    # as `pose` does (sizing counted it with 9.81 N on c3)
    from cdpr_design.design import envelope
    from cdpr_design.model import spec
    from cdpr_design import api

    d = planar2_raw()
    d.pop("plc")
    d["cables"][0]["outlet"] = [0.0, 1.0]
    d["cables"].append({"name": "c3", "outlet": [0.0, 1.5], "attachment": [-0.06, 0.06]})
    design = spec.from_dict(d)
    assert api.pose(design, [0.06, 0.94]).feasible is False
    chunk = envelope.envelope_chunk(resolved(design, "size-motors"), np.array([[0.06, 0.94], [0.75, 0.8]]), (0.0, 0.0, 0.0), 1.0, 1.0)
    assert list(chunk["ok"]) == [False, True]
    assert np.isnan(chunk["static"][0]).all() and np.isfinite(chunk["static"][1]).all()


def test_compare_refuses_a_column_of_nan(tmp_path):
    t = np.arange(50) * 0.01
    (tmp_path / "a.csv").write_text("time,x,y\n" + "".join(f"{v},{np.sin(v)},{np.cos(v)}\n" for v in t))
    (tmp_path / "b.csv").write_text("time,x,y\n" + "".join(f"{v},{np.sin(v)},nan\n" for v in t))
    assert_clean_error(invoke("compare", tmp_path / "a.csv", tmp_path / "b.csv", "--json"), "ACTUAL", "'y'",
                       "no number")
    ok = invoke("compare", tmp_path / "a.csv", tmp_path / "b.csv", "--columns", "x", "--json")
    assert ok.exit_code == 0 and list(json.loads(ok.stdout)["delay"]) == ["x"], ok.output


@pytest.mark.parametrize("args", [["--motor", "NOPE"], ["--safety-factor", "0.5"],
                                  ["--trajectory", "nope"]])
def test_report_writes_nothing_when_an_option_is_bad(tmp_path, args):
    out = tmp_path / "out"
    res = invoke("report", PLANAR2, "--step", "0.1", "--out", out, *args)
    assert res.exit_code == 2, res.output
    assert not out.exists(), sorted(p.name for p in out.iterdir())


def test_report_checks_a_motor_option_before_any_file(tmp_path, catalogue):
    # the library entry point too (no typer ranges in front)
    from cdpr_design.errors import InputError
    from cdpr_design.jobs import sizing as job
    from cdpr_design.model import spec

    with pytest.raises(InputError, match="NOPE"):
        job.report(spec.load(PLANAR2), motor="NOPE", step=0.1, out=tmp_path / "o")
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------------------
# Resources
# ----------------------------------------------------------------------------


def test_a_sweep_of_a_billion_variants_is_refused_at_once(tmp_path):
    t0 = time.perf_counter()
    res = invoke("sweep", PLANAR2, "--vary", "effector.mass=1:2:1000000000", "--out", tmp_path / "o")
    assert_clean_error(res, "--vary", "at most 1,000,000")
    res = invoke("sweep", PLANAR2, "--vary", "effector.mass=1:2:1000", "--vary", "tension.1=15:25:1000",
                 "--out", tmp_path / "o")
    assert_clean_error(res, "1,000,000 variants", "--max-variants")
    assert time.perf_counter() - t0 < 10 and not (tmp_path / "o").exists()


def test_max_variants_is_the_explicit_limit(planar2):
    from cdpr_design import batch as sw
    from cdpr_design.errors import InputError

    with pytest.raises(InputError, match="3 variants"):
        sw.make_plan(planar2, [("effector.mass", (1.0, 1.5, 2.0))], max_variants=2)
    assert len(sw.make_plan(planar2, [("effector.mass", (1.0, 1.5, 2.0))], max_variants=3)) == 3


def test_a_path_of_too_many_samples_is_refused_before_allocation(tmp_path):
    p = spec_with(tmp_path, lambda d: d["trajectories"]["square_slow"].update(speed=1e-6, acceleration=1e-6))
    t0 = time.perf_counter()
    assert_clean_error(invoke("trajectory", p, "square_slow", "--out", tmp_path / "o"), "samples")
    assert time.perf_counter() - t0 < 10 and not (tmp_path / "o").exists()


def test_orientation_samples_are_limited(tmp_path):
    from cdpr_design.errors import SpecError
    from cdpr_design.model import spec

    from .helpers import ipanema3_data

    d = ipanema3_data("ip3", workspace={"orientation_set": {"lower": [-0.1] * 3, "upper": [0.1] * 3,
                                                              "count": [100, 100, 100]}})
    with pytest.raises(SpecError, match="orientations per position"):
        spec.from_dict(d)


# ----------------------------------------------------------------------------
# Output
# ----------------------------------------------------------------------------


def test_messages_are_printed_as_plain_text(tmp_path):
    res = invoke("pose", PLANAR2, "--at", "[/x]")  # crashed rich's markup parser
    assert_clean_error(res, "--at", "[/x]")
    p = spec_with(tmp_path, lambda d: d.update(tension=[1.0]))
    assert_clean_error(invoke("pose", p, "--at", "0.75,0.75"), "expected [min, max] (2 numbers)")


def test_no_minus_zero_in_the_workspace_csv(tmp_path):
    res = invoke("workspace", PLANAR2, "--step", "0.02", "--out", tmp_path, "--quiet")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(tmp_path / "workspace.csv")
    cells = [c for r in rows for c in r]
    assert "0" in cells and "-0" not in cells  # 72 cells were "-0" (c2's tension at x = 0.06)


def test_the_formatters_never_write_minus_zero():
    from cdpr_design.io.csvfast import csv_rows
    from cdpr_design.io.tables import cell_rows, fmt

    assert fmt(-0.0) == "0" and fmt(np.float64(-0.0)) == "0" and fmt(-1e-300) == "-1e-300"
    for rows in (csv_rows, cell_rows):
        assert rows([np.array([-0.0, 1.5]), np.array([2.0, -0.0])]) == b"0,2\n1.5,0\n"


def test_json_never_holds_nan_or_infinity(tmp_path):
    from cdpr_design.io.files import OutputDir
    from cdpr_design.io.tables import json_text

    data = {"a": float("nan"), "b": [np.inf, -np.inf, np.float32("nan")], "c": np.array([1.0, np.nan]), "d": -0.0}
    strict = json.loads(json_text(data), parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert strict == {"a": None, "b": [None, None, None], "c": [1.0, None], "d": 0.0}
    OutputDir(tmp_path).write_json("x.json", data)
    assert json.loads((tmp_path / "x.json").read_text(), parse_constant=lambda c: pytest.fail(c)) == strict


def test_warnings_are_silent_under_quiet():
    import warnings

    import typer
    from typer.testing import CliRunner

    app = typer.Typer()

    @app.command()
    @command
    def noisy(quiet: QuietOpt = False):
        warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)

    for args, shown in (([], 1), (["--quiet"], 0)):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            res = CliRunner().invoke(app, args)
        assert res.exit_code == 0, res.output
        assert len([w for w in seen if "overflow" in str(w.message)]) == shown, args
    os.environ.pop("PYTHONWARNINGS", None)


def test_every_command_takes_json_and_quiet():
    from cdpr_design.cli.app import app

    names = [c.name or c.callback.__name__.replace("_", "-") for c in app.registered_commands]
    assert sorted(names) == sorted(["workspace", "pose", "fk", "schema", "size-motors", "report", "check",
                                    "certify", "sweep", "compare", "trajectory", "simulate", "bridge",
                                    "optimize"]), names
    for name in names:
        res = invoke(name, "--help")
        assert res.exit_code == 0 and "--json" in res.output and "--quiet" in res.output, name
    schema = invoke("schema", "--json", "--quiet")
    assert schema.exit_code == 0 and schema.stdout.count("\n") == 1
    assert json.loads(schema.stdout)["title"] == "cdpr-design spec"
    for args in (["pose", PLANAR2, "--at", "0.75,0.75"], ["fk", PLANAR2, "--lengths", "1,1"]):
        res = invoke(*args, "--quiet", "--json")
        assert res.exit_code == 0 and json.loads(res.stdout), res.output


def test_a_catalogue_with_overflowing_figures_is_refused(tmp_path):
    from cdpr_design.errors import SpecError
    from cdpr_design.model import spec

    p = tmp_path / "cat.yaml"
    p.write_text("motors:\n  - {name: BIG, rated_torque: 1.0e+300, peak_torque: 1.0e+308, max_speed: 3000,"
                 " rotor_inertia: 1.0e-5}\n")
    with pytest.raises(SpecError, match=r"motors\[0\]\.peak_torque: expected a value in \[-1e\+12, 1e\+12\]"):
        spec.load_catalogue(p)


def test_tables_on_screen_show_no_minus_zero():
    from cdpr_design.cli.common import fmt

    assert fmt(-0.0) == "0" and fmt(-0.5) == "-0.5"


# ----------------------------------------------------------------------------
# The options of the features merged after issue 19: optimize, --max-tilt, --cable-model, --format
# ----------------------------------------------------------------------------

OPT = ["optimize", PLANAR2, "--vary", "cables.0.outlet.0=-0.5:0.5", "--maximize", "task_min_margin", "--no-picture",
       "--quiet"]


@pytest.mark.parametrize("option, value", [
    ("--trials", "0"), ("--trials", "2000000"), ("--workers", "0"), ("--workers", "2000"),
    ("--timeout", "-1"), ("--timeout", "nan"), ("--timeout", "inf"), ("--seed", "-1"),
    ("--seed", "4294967296"), ("--seed", "99999999999999999999"), ("--step", "nan")])
def test_optimize_options_are_ranged(tmp_path, option, value):
    # --seed 2**32 was a numpy ValueError traceback after optimize.db was created; --workers 2000 and
    # --trials 2000000 started (2000 processes; a study of millions of trials held in memory at the end)
    out = tmp_path / "o"
    assert_clean_error(invoke(*OPT, option, value, "--out", out), option)
    assert not out.exists()


def test_optimize_out_under_a_file_or_read_only_is_refused_before_any_work(tmp_path):
    (tmp_path / "afile").write_text("x")
    assert_clean_error(invoke(*OPT, "--out", tmp_path / "afile" / "sub"), "--out", "is a file, not a folder")
    ro = _read_only_folder(tmp_path)
    if ro is not None:
        assert_clean_error(invoke(*OPT, "--out", os.path.join(ro, "sub")), "--out", "not writable")


@pytest.mark.parametrize("spec_path, args, option", [
    (PLANAR2, ["--max-tilt", "500"], "--max-tilt"), (PLANAR2, ["--max-tilt", "nan"], "--max-tilt"),
    (ROOT / "designs" / "crane4.yaml", ["--max-tilt", "-1"], "--max-tilt"),
    (ROOT / "designs" / "crane4.yaml", ["--max-tilt", "nan"], "--max-tilt"),
    (PLANAR2, ["--cable-model", "bogus"], "--cable-model"), (PLANAR2, ["--format", "xls"], "--format")])
def test_workspace_feature_options_are_checked(tmp_path, spec_path, args, option):
    out = tmp_path / "o"
    assert_clean_error(invoke("workspace", spec_path, "--step", "0.5", *args, "--out", out), option)
    assert not out.exists()


def test_cable_model_and_format_on_other_commands(tmp_path):
    assert_clean_error(invoke("pose", PLANAR2, "--at", "0.7,0.7", "--cable-model", "bogus"), "--cable-model")
    assert_clean_error(invoke("fk", PLANAR2, "--lengths", "1,1", "--cable-model", "bogus"), "--cable-model")
    # a model whose property the spec lacks: refused naming the key
    bare = spec_with(tmp_path, lambda d: d["cable"].pop("axial_stiffness"))
    for cmd in (["pose", bare, "--at", "0.7,0.7"], ["fk", bare, "--lengths", "1,1"],
                ["workspace", bare, "--step", "0.5", "--out", tmp_path / "o"]):
        assert_clean_error(invoke(*cmd, "--cable-model", "sagging"), "axial_stiffness")
    assert not (tmp_path / "o").exists()
