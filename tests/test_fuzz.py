"""Fuzzing (issue 19): random valid specs and hostile mutations of them through ``load`` and every
command's library entry point; each ends with a result or a clean error, within a time limit.

"Clean" means a :class:`~cdpr_design.errors.CdprError` (the command line's exit 2 or 1); anything
else is a crash.  On success the results must be valid JSON (no NaN), CSVs hold no ``-0`` and no
temporary file is left; on an error nothing has been written (not even the output folder).

CI runs a fixed, derandomised set (a few thousand examples in all, about a minute);
``pytest tests/test_fuzz.py --fuzz-scale 20`` (or ``python scripts/fuzz.py``) runs twenty times as
many with fresh random seeds.  Cases found are kept as files in tests/data/fuzz_corpus/ and
replayed by :func:`test_fuzz_corpus`.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from cdpr_design.errors import CdprError
from cdpr_design.statics.robot import Analysis, cable_model

from .fuzzing import EXTREME_NUMBERS, ODD_STRINGS, feature_spec_data, hostile_values, mutated_feature_data, \
    mutated_spec_data, mutated_yaml, option_floats, spec_data
from .helpers import PLANAR2, ROOT, resolved

CORPUS = ROOT / "tests" / "data" / "fuzz_corpus"
SCALE = float(os.environ.get("CDPR_FUZZ_SCALE", "1"))
#: Longest a spec may take to load or refuse [s]; longest a command's run [s]: a guard against hangs, not a
#: speed check, so it allows numba's cold compile of a command's kernels on a loaded 2-core machine (67 s seen
#: for cable_models.png's sweeps at the lowest dependency versions; speed is scripts/bench.py's to report).
LOAD_LIMIT, JOB_LIMIT = 2.0, 300.0
_counter = itertools.count()


def fuzz(n: int):
    """Hypothesis settings for ``n`` examples (times the scale); derandomised at scale 1 (CI)."""
    return settings(max_examples=max(1, int(n * SCALE)), deadline=None, derandomize=SCALE == 1,
                    database=None if SCALE == 1 else settings.default.database,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much, HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module", autouse=True)
def compiled_kernels():
    """numba's first compile of the pose kernels (up to a minute each on a cold cache and a loaded
    machine) done before the timed examples: JOB_LIMIT is there to catch hangs, not compiles."""
    from cdpr_design.model import spec
    from cdpr_design import api

    for name, kinds in (("planar4", ("static", "wrench-feasible", "wrench-closure")),
                        ("ipanema3", ("static", "wrench-feasible", "wrench-closure")),
                        ("pointmass3", ("static",)), ("sagging40", ("static",))):
        d = spec.load(ROOT / "designs" / f"{name}.yaml")
        g = d.workspace.grid
        centre = [(lo + hi) / 2 for lo, hi in zip(g.lower, g.upper)] + list(d.workspace.orientation or [])
        for kind in kinds:
            api.pose(d, centre[: len(d.motion.coords)], kind)


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def fresh(work: Path, what: str) -> Path:
    return work / f"{what}-{next(_counter)}"


def outcome(fn, *args, limit: float = JOB_LIMIT, **kwargs):
    """``fn(*args, **kwargs)``: (result, None) or (None, the CdprError); anything else fails the test,
    as does a run that takes more than ``limit`` seconds of this process's CPU time (the work the
    input costs, not how busy the machine is)."""
    t0 = time.process_time()
    try:
        res, exc = fn(*args, **kwargs), None
    except CdprError as e:
        res, exc = None, e
    dt = time.process_time() - t0
    assert dt < limit, f"{getattr(fn, '__name__', fn)} took {dt:.1f} CPU-s"
    if exc is not None:
        assert str(exc) and len(str(exc)) < 5000, "an error message quotes far too much"
    return res, exc


def load_both(work: Path, what: str, data) -> tuple:
    """``data`` loaded through a YAML file (:func:`spec.load`) and directly (:func:`spec.from_dict`):
    the design or None from each; both agree on whether it is one.  Data YAML cannot hold (a lone
    surrogate) is not a spec: the example is dropped."""
    from cdpr_design.model import spec

    p = fresh(work, what).with_suffix(".yaml")
    try:
        p.write_text(yaml.safe_dump(data, allow_unicode=True))
    except (yaml.YAMLError, UnicodeEncodeError):
        assume(False)
    res, exc = outcome(spec.load, p, limit=LOAD_LIMIT)
    assert (res is None) != (exc is None)
    res2, _ = outcome(spec.from_dict, data, limit=LOAD_LIMIT)  # the same data without YAML in between
    assert (res2 is None) == (res is None)
    return res


def strict_json(data) -> None:
    """``data`` as JSON the way the command line prints it: no NaN, no Infinity."""
    from cdpr_design.io.tables import json_text

    json.loads(json_text(data), parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))


def check_folder(out: Path, failed: bool) -> None:
    """After a job: nothing written when it failed; no temporary file and no "-0" cell when it worked."""
    if failed:
        assert not out.exists(), f"files written before the error: {sorted(p.name for p in out.iterdir())}"
        return
    assert not list(out.glob(".*.tmp")), "temporary files left behind"
    for csv in out.glob("*.csv"):
        text = csv.read_text()
        assert ",-0," not in text and ",-0\n" not in text and "\n-0," not in text, csv.name
        assert "nan" not in text.lower().replace("nan_", ""), csv.name


def load_design(data):
    from cdpr_design.model import spec

    try:
        return spec.from_dict(data)
    except CdprError:
        return None


# ----------------------------------------------------------------------------
# Spec loading
# ----------------------------------------------------------------------------


@fuzz(200)
@given(spec_data())
def test_random_valid_specs_load(data):
    from cdpr_design.model import spec

    d = spec.from_dict(data)
    assert d.m == len(data["cables"]) and d.name == data["name"]


@pytest.mark.slow
@fuzz(1000)
@given(mutated_spec_data())
def test_mutated_specs_load_or_are_refused(work, data):
    load_both(work, "spec", data)


@pytest.mark.slow
@fuzz(400)
@given(st.data())
def test_mutated_yaml_text_loads_or_is_refused(work, data):
    from cdpr_design.model import spec

    base = data.draw(st.sampled_from([PLANAR2.read_text(), yaml.safe_dump(data.draw(spec_data()))]))
    text = data.draw(mutated_yaml(base))
    p = fresh(work, "text").with_suffix(".yaml")
    p.write_text(text, encoding="utf-8", errors="surrogatepass")
    outcome(spec.load, p, limit=LOAD_LIMIT)


@pytest.mark.parametrize("path", sorted(CORPUS.glob("*.yaml")), ids=lambda p: p.name)
def test_fuzz_corpus(path):
    """Every kept case: its first line says ``# expect: ok`` or ``# expect: error <words in the message>``."""
    from cdpr_design.model import spec

    head = path.read_bytes().split(b"\n", 1)[0].decode()
    assert head.startswith("# expect: "), f"{path.name}: no expectation on its first line"
    expect = head[len("# expect: "):].strip()
    res, exc = outcome(spec.load, path, limit=LOAD_LIMIT)
    if expect == "ok":
        assert exc is None, str(exc)
    else:
        assert expect.startswith("error") and exc is not None, f"{path.name} loaded"
        assert expect[len("error"):].strip() in str(exc), str(exc)


def test_the_corpus_is_kept():
    assert len(list(CORPUS.glob("*.yaml"))) >= 20


# ----------------------------------------------------------------------------
# One pose, forward kinematics, the schema
# ----------------------------------------------------------------------------


number_text = st.one_of(st.floats(-3, 5).map(lambda v: f"{v:.4g}"), st.sampled_from(EXTREME_NUMBERS).map(str),
                        st.sampled_from(ODD_STRINGS))


@fuzz(100)
@given(spec_data(), st.lists(number_text, min_size=1, max_size=4),
       st.sampled_from(["static", "wrench-feasible", "wrench-closure"]),
       st.sampled_from(["min-norm", "min-norm", "min-max", "min-sum"]))
def test_pose(data, at, kind, objective):
    from cdpr_design.cli.common import parse_pose
    from cdpr_design.jobs.pose import pose_data, stiffness_data
    from cdpr_design import api

    design = load_design(data)
    assume(design is not None)
    pose, exc = outcome(parse_pose, design, ",".join(at))
    if exc is not None:
        return
    res, exc = outcome(lambda: api.pose(design, pose, kind, objective=objective))
    if res is not None:
        out = pose_data(design, res) | stiffness_data(design, pose, res.tensions)
        strict_json(out)
        assert not res.feasible or np.all(np.isfinite(res.tensions))


@fuzz(40)
@given(spec_data(), st.lists(st.floats(0.2, 0.8), min_size=3, max_size=3),
       st.one_of(st.none(), st.lists(st.one_of(st.floats(0, 10), st.sampled_from(EXTREME_NUMBERS)), min_size=4,
                                     max_size=4)))
def test_fk(data, where, lengths):
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.reach import reached, require_reached

    design = load_design(data)
    assume(design is not None)
    g = design.workspace.grid
    pose = [lo + f * (hi - lo) for lo, hi, f in zip(g.lower, g.upper, where)] + list(design.workspace.orientation)
    if lengths is None:  # lengths of a pose: reachable; the solver may miss them from its default start
        L = kin.inverse_kinematics(design, pose)
        res = kin.forward_kinematics(design, L)
        if not reached(res.residual, L):
            outcome(require_reached, res.residual, L)  # then refused cleanly, and found from the pose itself
            assert reached(kin.forward_kinematics(design, L, guess=pose).residual, L)
        return
    L = lengths[: design.m]
    try:
        with warnings.catch_warnings():  # 1e300 m lengths overflowed the solver (numpy's warnings on stderr)
            warnings.simplefilter("error", RuntimeWarning)
            res = kin.forward_kinematics(design, L)
    except ValueError as exc:  # the library's own refusal: negative, non-finite or beyond 10 km (as --lengths)
        assert not np.all(np.isfinite(np.asarray(L, float))) or min(L) < 0 or max(L) > 1e4, exc
        return
    outcome(require_reached, res.residual, L)
    strict_json({"pose": list(res.pose), "residual": res.residual})


def test_schema_is_strict_json():
    from cdpr_design.model import spec

    strict_json(spec.json_schema())


# ----------------------------------------------------------------------------
# The commands that write files
# ----------------------------------------------------------------------------

steps = option_floats(0.05, 1.0)


@pytest.mark.slow
@fuzz(8)
@given(spec_data(), steps, st.sampled_from(["static", "wrench-feasible", "wrench-closure", "nope"]))
def test_workspace_job(work, data, step, kind):
    from cdpr_design.jobs import workspace as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "ws")
    res, exc = outcome(job.workspace, design, job.WorkspaceSettings(Analysis(kind=kind), step=step), out)
    check_folder(out, exc is not None)
    if res is not None:
        strict_json(res[0].summary())


motors = st.one_of(st.none(), st.sampled_from(["AM8112-0F21", "SGMP-01", "NOPE", ""]))


@fuzz(15)
@given(spec_data(), steps, option_floats(1.0, 3.0), motors, st.sampled_from([None, "sq", "pl", "nope"]))
def test_size_motors_job(work, data, step, safety, motor, trajectory):
    from cdpr_design.jobs import sizing as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "sm")
    res, exc = outcome(job.size_motors, design, None, trajectory, safety, motor, step, out)
    check_folder(out, exc is not None)
    if res is not None:
        strict_json(res.result.summary())


@fuzz(10)
@given(spec_data(), steps, option_floats(1.0, 3.0), motors)
def test_check_job(data, step, safety, motor):
    from cdpr_design.jobs import sizing as job

    design = load_design(data)
    assume(design is not None)
    res, exc = outcome(job.check, design, None, None, safety, motor, step)
    if res is not None:
        strict_json({"checks": res.checks, "figures": res.evaluation.row})


@pytest.mark.slow
@fuzz(4)
@given(spec_data(), steps, motors)
def test_report_job(work, data, step, motor):
    from cdpr_design.jobs import sizing as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "rep")
    res, exc = outcome(job.report, design, motor=motor, step=step, out=out)
    check_folder(out, exc is not None)


vary_keys = st.sampled_from(["effector.mass", "tension.1", "cables.0.outlet.0", "frame.upper.1", "name",
                             "cables.c2.attachment", "winch.drum_radius", "nope.key", "cables.9.outlet"])
vary_values = st.one_of(st.sampled_from(["0.5,1", "1:2:2", "1e308", "nan", "a,b", "", "1:2:0", "-1,2", "[/x]",
                                         "1:2:99999999"]),
                        st.lists(st.floats(0.1, 3).map(lambda v: f"{v:.3g}"), min_size=1, max_size=2).map(",".join))


@fuzz(4)
@given(spec_data(), st.lists(st.tuples(vary_keys, vary_values), min_size=1, max_size=2),
       st.sampled_from([None, "fraction", "nope", "fraction:asc"]))
def test_sweep_job(work, data, vary, rank_by):
    from cdpr_design.jobs import sweep as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "sw")
    res, exc = outcome(job.sweep, design, job.SweepSettings([f"{k}={v}" for k, v in vary], workers=1, rank_by=rank_by,
                                                          step=0.25, picture=False, out=out))
    check_folder(out, exc is not None)
    if res is not None:
        strict_json(res.summary)


@pytest.mark.slow
@fuzz(6)
@given(spec_data(), option_floats(1e-3, 0.05), st.sampled_from(["sq", "pl", "nope"]))
def test_trajectory_job(work, data, cycle_time, name):
    from cdpr_design.jobs import motion as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "tr")
    res, exc = outcome(job.trajectory, design, name, cycle_time, out)
    check_folder(out, exc is not None)
    if res is not None:
        strict_json(res.summary)
        s = res.samples  # a feasible sample has its tensions (infeasible ones may keep out-of-bounds ones)
        assert not np.any(s.feasible & ~np.all(np.isfinite(s.tensions), axis=1))


@fuzz(8)
@given(spec_data(), st.sampled_from(["sq", "pl", "nope"]), option_floats(0.0, 0.2), option_floats(1e-4, 1e-3),
       option_floats(10.0, 500.0))
def test_simulate_job_options(work, data, name, delay, timestep, bandwidth):
    """The simulation's options are checked before it runs; valid runs are left to test_simulation.py
    (MuJoCo runs take seconds)."""
    from cdpr_design.jobs import motion as job

    design = load_design(data)
    assume(design is not None)
    delay = 0.0 if delay is None else delay
    timestep = 5e-4 if timestep is None else timestep
    bandwidth = 300.0 if bandwidth is None else bandwidth
    ok = name in design.trajectories and 0 <= delay <= 10 and 1e-6 <= timestep <= 0.01 and 1e-3 <= bandwidth <= 1e6
    assume(not ok)
    out = fresh(work, "sim")
    res, exc = outcome(job.simulate, design, name,
                       job.SimulateSettings(delay=delay, timestep=timestep, servo_bandwidth=bandwidth), out)
    assert exc is not None
    check_folder(out, True)


@fuzz(8)
@given(spec_data(), option_floats(1e-3, 0.1), option_floats(0.1, 2.0), st.integers(-3, 3))
def test_bridge_job_options(work, data, cycle_time, duration, reconnect):
    """The gateway's options and spec are checked before it connects (valid runs: test_bridge.py)."""
    from cdpr_design.jobs import bridge as job

    design = load_design(data)
    assume(design is not None)  # no plc: section (or a bad option): refused before any connection
    out = fresh(work, "br")
    res, exc = outcome(job.bridge, design, None, duration, cycle_time, 0.05, reconnect, out=out)
    assert exc is not None
    check_folder(out, True)


cells = st.one_of(st.floats(-10, 10).map(lambda v: f"{v:.6g}"), st.sampled_from(["", "nan", "inf", "-0", "x",
                                                                                   "1e308", "[/x]", " "]))


@st.composite
def logs(draw):
    """Two CSV logs of a motion, often broken: missing or unsorted time, empty and text cells,
    NaN columns, duplicate names."""
    names = draw(st.lists(st.sampled_from(["x", "y", "L1", "time", "t", "segment", "x"]), min_size=1, max_size=4))
    n = draw(st.integers(0, 40))
    out = []
    for _ in range(2):
        rows = [",".join(names)]
        t0 = draw(st.floats(0, 1))
        for i in range(n):
            row = []
            for c in names:
                if c in ("time", "t") and draw(st.integers(0, 9)):
                    row.append(f"{t0 + 0.01 * i:.6g}")
                elif draw(st.integers(0, 3)):
                    row.append(f"{np.sin(0.1 * i):.6g}")
                else:
                    row.append(draw(cells))
            rows.append(",".join(row))
        out.append("\n".join(rows) + "\n")
    return out


@fuzz(80)
@given(logs(), st.one_of(st.none(), st.sampled_from(["x", "y,x", "nope", "", ","])),
       st.one_of(st.none(), st.lists(st.sampled_from(["x=y", "y=x", "=", "a=b=c", "x="]), max_size=2)),
       option_floats(0.001, 0.2))
def test_compare_job(work, texts, columns, rename, max_delay):
    from cdpr_design.jobs import motion as job

    a, b = fresh(work, "a").with_suffix(".csv"), fresh(work, "b").with_suffix(".csv")
    a.write_text(texts[0])
    b.write_text(texts[1])
    res, exc = outcome(job.compare, a, b, columns, rename, max_delay)
    if res is not None:
        strict_json(res.summary)


@fuzz(200)
@given(hostile_values)
def test_hostile_documents_at_the_top(work, value):
    """A document that is not a mapping (a number, a string, a list, nesting) is refused cleanly."""
    from cdpr_design.model import spec

    p = fresh(work, "top").with_suffix(".yaml")
    p.write_text(yaml.safe_dump(value))
    res, exc = outcome(spec.load, p, limit=LOAD_LIMIT)
    assert exc is not None


# ----------------------------------------------------------------------------
# Cable models, the hanging pose, optimize, table formats (merged after issue 19)
# ----------------------------------------------------------------------------


def check_cable_models(design) -> None:
    """A loaded design's cables have what their model needs (EA > 0; sagging: a density > 0)."""
    for c in design.cables:
        p = c.props
        assert p.model in ("ideal", "elastic", "sagging"), p.model
        if p.model != "ideal":
            assert p.axial_stiffness is not None and 0 < p.axial_stiffness < np.inf, (c.name, p)
        if p.model == "sagging":
            assert 0 < p.mass_per_length < np.inf, (c.name, p)
    assert design.effector.orientation in ("fixed", "free")
    tilt = design.requirements.max_tilt
    assert tilt is None or (0 <= tilt <= 180 and design.effector.orientation == "free")


@fuzz(100)
@given(feature_spec_data())
def test_random_feature_specs_load(data):
    from cdpr_design.model import spec

    check_cable_models(spec.from_dict(data))


@pytest.mark.slow
@fuzz(400)
@given(mutated_feature_data())
def test_mutated_feature_keys_load_or_are_refused(work, data):
    res = load_both(work, "feat", data)
    if res is not None:
        check_cable_models(res)


def pose_entry(design, at: str, kind: str) -> dict:
    """What ``pose --at`` computes (cli/pose.py's branches, through the library)."""
    from cdpr_design.cli.common import parse_numbers, parse_pose
    from cdpr_design.jobs import hanging as hjob
    from cdpr_design.jobs import pose as job
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.pose import evaluate_pose

    robot = resolve(design, Analysis(command="pose", kind=kind))
    if robot.orientation.free:
        return hjob.free_pose_data(robot, parse_numbers(at, "--at", design.motion.dim))
    p = parse_pose(design, at)
    data = job.pose_data(design, evaluate_pose(robot, p))
    if robot.underconstrained and robot.cables.rigid and not robot.outlets.pulleys:
        data.update(hjob.hanging_fields(design, p[: design.motion.dim]))
    return data


@fuzz(60)
@given(feature_spec_data(), st.lists(st.one_of(st.floats(0.1, 0.9), st.sampled_from([0.0, 1.0, -1.0, 2.0])),
                                     min_size=3, max_size=3),
       st.sampled_from(["static", "static", "wrench-feasible", "wrench-closure"]))
def test_pose_with_cable_models_and_free_orientation(data, where, kind):
    design = load_design(data)
    assume(design is not None)
    g = design.workspace.grid
    pose = [lo + f * (hi - lo) for lo, hi, f in zip(g.lower, g.upper, where)]
    from cdpr_design.statics.robot import facts

    if not facts(design).orientation.free:
        pose += list(design.workspace.orientation)
    res, exc = outcome(pose_entry, design, ",".join(f"{v:.6g}" for v in pose), kind)
    if res is not None:
        strict_json(res)
        if res["feasible"] and kind != "wrench-closure":  # every tension, within its bounds (closure: unbounded)
            t = np.array([res["tensions"][c.name] for c in design.cables], dtype=float)
            assert np.all(np.isfinite(t))
            assert np.all(t >= design.tension_min - 1e-6) and np.all(t <= design.tension_max + 1e-6), t


@pytest.mark.slow
@fuzz(12)  # an elastic fk with no equilibrium takes 10-20 s to give up: more examples in the long run
@given(feature_spec_data(), st.lists(st.floats(0.2, 0.8), min_size=3, max_size=3),
       st.one_of(st.none(), st.lists(st.one_of(st.floats(0, 10), st.sampled_from([0.0, 1e-9, 1e-6, 1e4, 0.5])),
                                     min_size=4, max_size=4)))
def test_fk_with_cable_models_and_free_orientation(data, where, lengths):
    """``fk``'s library entry points (hanging for ideal cables, cable_fk for elastic and sagging ones) on
    lengths of a pose or lengths the command line accepts (finite, 0 to 10 km): a pose whose residual
    says it was reached, or a clean refusal."""
    from cdpr_design.jobs import hanging as hjob
    from cdpr_design.jobs import pose as job
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.reach import reached

    design = load_design(data)
    assume(design is not None)
    g = design.workspace.grid
    pose = [lo + f * (hi - lo) for lo, hi, f in zip(g.lower, g.upper, where)] + list(design.workspace.orientation)
    L = list(kin.inverse_kinematics(design, pose)) if lengths is None else lengths[: design.m]
    if cable_model(design).rigid:
        res, exc = outcome(lambda d, lengths: hjob.fk_data(resolved(d, "fk"), lengths), design, L)
    else:
        res, exc = outcome(lambda d, lengths: job.cable_fk_data(resolved(d, "fk"), lengths), design, L)
    if res is not None:
        strict_json(res)
        assert reached(res["residual"], np.asarray(L, float)), f"a pose {res['residual']:.3g} m off reported"


formats = st.sampled_from(["csv", "csv", "parquet", "xls"])
tilts = st.one_of(st.none(), st.floats(0, 180), st.sampled_from([-1.0, 180.5, 500.0, math.nan, math.inf, 1e308]))


@pytest.mark.slow
@fuzz(10)
@given(feature_spec_data(), steps, st.sampled_from(["static", "static", "wrench-feasible", "nope"]), formats,
       st.booleans(), tilts)
def test_workspace_job_formats_html_and_tilt(work, data, step, kind, fmt, html, max_tilt):
    from cdpr_design.jobs import workspace as job

    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "wsf")
    res, exc = outcome(job.workspace, design, job.WorkspaceSettings(Analysis(kind=kind, max_tilt=max_tilt), step=step,
                                                                   format=fmt, html=html), out)
    check_folder(out, exc is not None)
    if res is not None:
        assert fmt in ("csv", "parquet") and (max_tilt is None or 0 <= max_tilt <= 180)
        strict_json(res[0].summary())
        assert (out / f"workspace.{fmt}").is_file() and (out / "report.html").is_file() == html


opt_vary = st.one_of(
    st.sampled_from(["effector.mass=0.5:2", "effector.mass=0.1:10:log", "tension.1=100:300", "cables.0.outlet.0=0:1",
                     "cable.model=ideal,elastic", "effector.mass=1,2,3", "effector.mass=2:1", "effector.mass=0:1:log",
                     "effector.mass=nan:1", "effector.mass=1:1e308", "nope=0:1", "effector.mass", "=", "",
                     "effector.mass=1:2:3:4", "[/x]=0:1", "name=a,b", "effector.orientation=fixed,free",
                     "requirements.max_tilt=0:500", "cables.9.outlet.0=0:1", "workspace.grid.step=1e-9:1e-8",
                     "effector.mass=1,1"]),
    st.text(max_size=12))
opt_figures = st.one_of(st.sampled_from(["task_min_margin", "task_fraction", "fraction", "min_margin",
                                         "max_tension", "peak_tension_c1", "nope", "", "[/x]", "fraction>=1"]),
                        st.text(max_size=8))
opt_requires = st.one_of(st.sampled_from(["task_min_margin>=1", "fraction<=2", "fraction>=nan", "fraction>=1e308",
                                          "fraction=1", ">=1", "fraction>=", "nope>=1", "task_fraction>=-inf"]),
                         st.text(max_size=10))


@pytest.mark.slow
@fuzz(12)
@given(spec_data(), st.tuples(st.sampled_from([["effector.mass=0.5:2"], ["tension.1=100:300"], []]),
                              st.lists(opt_vary, max_size=1)).map(lambda t: t[0] + t[1]),
       st.tuples(st.sampled_from([["task_min_margin"], ["task_fraction"], []]),
                 st.lists(opt_figures, max_size=1)).map(lambda t: t[0] + t[1]),
       st.one_of(st.just([]), st.lists(opt_figures, max_size=1)),
       st.one_of(st.just([]), st.lists(opt_requires, max_size=2)),
       st.sampled_from([2, 2, 2, 3, 1, 0, -1, 10 ** 7]), st.sampled_from([None, None, None, 1, 0, -1, 10 ** 6]),
       st.sampled_from([None, None, 0, 7, -1, 2 ** 32 - 1, 2 ** 32, 2 ** 64]),
       st.one_of(st.none(), st.sampled_from([30.0, 0.0, -1.0, math.nan, math.inf, 1e308])), st.booleans())
def test_optimize_job(work, data, vary, maximize, minimize, require, trials, workers, seed, timeout, hostile):
    """``optimize`` (small trial counts, one worker, task-box evaluations) with hostile --vary, --maximize,
    --minimize, --require, --trials, --workers, --seed and --timeout: a result, or a clean refusal
    before anything is written."""
    from cdpr_design.jobs import optimize as job
    from cdpr_design.model import spec

    assume("requirements" in data)  # a task box
    data["requirements"].pop("max_speed")  # trials sweep only the task box
    data["requirements"].pop("max_acceleration")
    if not hostile:  # half the examples run: the first key and objective, two trials
        vary, maximize, minimize, require = vary[:1] or ["effector.mass=0.5:2"], maximize[:1] or ["task_fraction"], [], []
        trials, workers, seed, timeout = 2, None, 1, None
    design = load_design(data)
    assume(design is not None)
    out = fresh(work, "opt")
    res, exc = outcome(job.optimize, design, job.OptimizeSettings(vary, maximize, minimize, require, trials, workers,
                                                                  seed, timeout, picture=False, out=out))
    check_folder(out, exc is not None)
    if res is not None:
        strict_json(res.summary)
        assert (out / "optimize.csv").is_file() and res.summary["trials_done"] == trials
        if res.best is not None:
            spec.load(out / "best.yaml")


# ----------------------------------------------------------------------------
# Cases the fuzz runs found in the entry points (the spec-level ones are files in the corpus)
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("step", [100.0, 1e30])
def test_found_a_grid_of_one_row_draws_its_pictures(tmp_path, planar2, step):
    # a step larger than the frame leaves one pose (or one row): the outline contour raised a TypeError
    from cdpr_design.jobs import workspace as job

    res, out = job.workspace(planar2, job.WorkspaceSettings(step=step), tmp_path / "o")
    assert res.poses == 1 and (tmp_path / "o" / "workspace.png").stat().st_size > 0
    d = planar2.replace(workspace=planar2.workspace.__class__(
        grid=planar2.workspace.grid.__class__((0.0, 0.5), (1.5, 0.5), (0.1, 0.1)), orientation=(),
        external_wrench=None, orientation_set=None, orientation_range=None))
    res, out = job.workspace(d, out=tmp_path / "row")
    assert res.grid.shape == (16, 1) and (tmp_path / "row" / "tension_map.png").stat().st_size > 0


def test_found_a_refused_kind_leaves_no_folder(tmp_path, planar2):
    # the workspace.csv stream used to create the folder before the sweep checked --kind
    from cdpr_design.errors import SpecError
    from cdpr_design.jobs import workspace as job

    with pytest.raises(SpecError, match="--kind"):
        job.workspace(planar2, job.WorkspaceSettings(Analysis(kind="nope")), tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_found_a_table_format_outside_the_list_is_bad_input(tmp_path, planar2):
    # format="xls" through the library was a ValueError (a crash); the command line's enum hid it
    from cdpr_design.errors import InputError
    from cdpr_design.jobs import workspace as job

    with pytest.raises(InputError, match="--format"):
        job.workspace(planar2, job.WorkspaceSettings(step=0.5, format="xls"), tmp_path / "o")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("options, option", [
    ({"seed": 2 ** 32}, "--seed"), ({"seed": 2 ** 64}, "--seed"), ({"workers": 10 ** 6}, "--workers"),
    ({"trials": 10 ** 7}, "--trials")])
def test_found_optimize_options_out_of_range_are_refused_before_any_work(tmp_path, planar2, options, option):
    # a seed >= 2**32 was numpy's ValueError after optimize.db was created; a million workers or ten
    # million trials were started
    from cdpr_design.errors import InputError
    from cdpr_design.jobs import optimize as job

    kwargs = {"trials": 2, **options}
    with pytest.raises(InputError, match=option):
        job.optimize(planar2, job.OptimizeSettings(["cables.0.outlet.0=-0.5:0.5"], ["task_min_margin"],
                                                   out=tmp_path / "o", picture=False, **kwargs))
    assert not (tmp_path / "o").exists()


def test_found_a_resumed_seed_near_the_top_stays_a_seed(tmp_path):
    # the sampler's seed is the run's seed plus the trials already done (and plus the worker's number):
    # --seed 4294967295 on a resumed study was numpy's ValueError
    from cdpr_design.optimize.study import make_sampler

    assert make_sampler(2 ** 32 - 1 + 5) is not None


def test_found_check_of_a_held_three_cable_body_skips_the_tilt():
    # a 3-cable 3T body with a size: under-constrained and held, so every sweep also solved the tilt
    # it would hang with (a figure only) -- twice in `check` (workspace and sizing envelope), 113 s at
    # this 99,750-pose grid; the evaluation never uses the tilt and now skips it
    from cdpr_design.jobs import sizing as job
    from cdpr_design.model import spec

    design = spec.from_dict({
        "name": "fz", "motion": "3T", "frame": {"lower": [0.0, 0.0, 0.0], "upper": [0.93, 3.47298, 3.72752]},
        "effector": {"mass": 5.99069, "size": [0.212162, 0.0636041, 0.217465]}, "tension": [3.07262, 225.044],
        "cables": [{"name": "c1", "outlet": [0.920118, 1.1044, 3.72752], "attachment": [-0.0701782, 0.010774, -0.0248456]},
                   {"name": "c2", "outlet": [1.39897e-59, 2.21296, 1.53864],
                    "attachment": [0.0115591, 0.00745506, 1.49373e-244]},
                   {"name": "c3", "outlet": [0.04, 1.30734, 2.13765], "attachment": [0.101763, 0.00731415, -0.0134948]}],
        "workspace": {"grid": {"step": 0.621253}}})
    res, exc = outcome(job.check, design, None, None, None, None, 0.05)
    assert exc is None and res.evaluation.row["poses"] == 99750


def test_found_cable_models_picture_skips_the_tilt(tmp_path):
    # a held 4-cable 3T body with sagging cables: cable_models.png sweeps the grid again with ideal
    # cables, and that sweep solved the hanging tilt of all 27,720 poses (100 s) for a picture that
    # compares feasible cells only
    from cdpr_design.jobs import workspace as job
    from cdpr_design.model import spec

    design = spec.from_dict({
        "name": "fz", "motion": "3T", "frame": {"lower": [0.0, 0.0, 0.0], "upper": [3.55878, 3.84512, 3.30068]},
        "effector": {"mass": 6.61985, "size": [0.0493498, 5e-206, 1e-08]}, "tension": [0.178797, 265.15],
        "cables": [{"name": "c1", "outlet": [2.74967, 3.16376, 1.8238], "attachment": [0.0, 1e-300, 4.51592e-09]},
                   {"name": "c2", "outlet": [0.520182, 1.42119, 1.54758], "attachment": [0.0, 0.0, -3.12716e-09]},
                   {"name": "c3", "outlet": [6.07044e-290, 2.72754, 0.645148], "attachment": [-0.000201246, 0.0, 0.0],
                    "model": "elastic", "axial_stiffness": 1000.0},
                   {"name": "c4", "outlet": [1.04371, 2.92235, 0.160674], "attachment": [-1.17549e-38, 0.0, 1e-10]}],
        "workspace": {"grid": {"step": 0.640853}},
        "cable": {"model": "sagging", "axial_stiffness": 1015150.0, "mass_per_length": 0.436277}})
    (res, _), exc = outcome(job.workspace, design, job.WorkspaceSettings(step=0.11935492729705242), tmp_path / "o")
    assert exc is None and res.poses == 27720 and (tmp_path / "o" / "cable_models.png").stat().st_size > 0
