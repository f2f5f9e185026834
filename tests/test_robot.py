"""The resolved robot (statics/robot.py): its strategies, and the one table of refusals.

Every row of REFUSALS is reached here through ``resolve`` with a design and an analysis that
trigger it and no earlier row, and the message is the row's (the option named first).  The
commands' exit status and wording for these combinations are checked by the combination matrix
(tests/test_combinations.py) and the commands' own tests."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cdpr_design.errors import InputError, SpecError
from cdpr_design.model import spec
from cdpr_design.model.design import Pulley
from cdpr_design.statics import robot as R
from cdpr_design.statics.robot import Analysis, resolve

from .helpers import DESIGNS, PLANAR2


def _with(d, *, model=None, pulleys=False, orientation=None, mass=None, cable_frequency=None, acceleration=None):
    if acceleration is not None:  # requirements.acceleration: a box of this half-width [m/s^2, rad/s^2]
        box = (tuple([-acceleration] * len(d.motion.coords)), tuple([acceleration] * len(d.motion.coords)))
        d = d.replace(requirements=dataclasses.replace(d.requirements, acceleration=box))
    if cable_frequency is not None:  # requirements.min_cable_frequency [Hz]
        d = d.replace(requirements=dataclasses.replace(d.requirements, min_cable_frequency=cable_frequency))
    if model is not None:
        d = spec.with_cable_model(d, model)
    if pulleys:
        d = d.replace(cables=tuple(dataclasses.replace(c, pulley=Pulley(0.05)) for c in d.cables))
    if orientation is not None or mass is not None:
        eff = d.effector
        eff = dataclasses.replace(eff, orientation=orientation or eff.orientation,
                                  mass=eff.mass if mass is None else mass)
        d = d.replace(effector=eff)
    return d


@pytest.fixture(scope="module")
def planar2():
    return spec.load(PLANAR2)


@pytest.fixture(scope="module")
def ipanema3():
    return spec.load(DESIGNS / "ipanema3.yaml")


@pytest.fixture(scope="module")
def cogiro():
    return spec.load(DESIGNS / "cogiro.yaml")


def test_strategies_of_the_shipped_designs(planar2, ipanema3):
    """planar2 is under-constrained and held (its tilt reported beside), ideal, from points;
    IPAnema 3 fully constrained; the arrays are the design's, built once."""
    r = resolve(planar2)
    assert (r.cables.name, r.outlets.name, r.orientation.name, r.underconstrained) == ("ideal", "points", "held", True)
    assert r.engine == "numpy" and r.tilt_limit is None
    np.testing.assert_array_equal(r.outlet_points, planar2.outlets)
    np.testing.assert_array_equal(r.tension_max, planar2.tension_max)
    assert r.combos.shape == (2, 1)
    r = resolve(ipanema3)
    assert (r.cables.name, r.outlets.name, r.orientation.name, r.underconstrained) == ("ideal", "points", "commanded", False)
    assert r.engine == "numba"
    assert resolve(_with(planar2, orientation="free"), max_tilt=10.0).tilt_limit == 10.0
    assert resolve(_with(planar2, orientation="free")).orientation.name == "hanging"
    # a held effector needs a weight, ideal cables and point outlets to hang: else commanded
    assert resolve(_with(planar2, mass=0.0)).orientation.name == "commanded"
    assert resolve(_with(planar2, model="elastic")).orientation.name == "commanded"
    assert resolve(_with(planar2, pulleys=True)).outlets.name == "pulleys"


def _free_with_moment():
    """A planar body hanging from two cables (1R2T, ``free``) under a box of external moments."""
    from .helpers import random_planar_data

    data = random_planar_data(np.random.default_rng(3), m=2, motion="1R2T")
    data["effector"]["orientation"] = "free"
    data["workspace"]["external_wrench"] = {"lower": [0.0, 0.0, -1.0], "upper": [0.0, 0.0, 1.0]}
    return spec.from_dict(data)


def _cases(planar2, ipanema3, cogiro):
    """(row's option and reason start, design, analysis) for every row of the table."""
    free = _with(planar2, orientation="free")
    return [
        ("engine: expected one of", planar2, Analysis(engine="fortran")),
        ("--orientations: expected total or range", ipanema3, Analysis(orientations="half")),
        ("--cable-model: cable model 'sagging' assumes point outlets", _with(planar2, model="sagging", pulleys=True),
         Analysis()),
        ("effector.orientation: free: the hanging solver models point outlets", _with(free, pulleys=True), Analysis()),
        ("--orientations: an under-constrained design with effector.orientation: free", free,
         Analysis(orientations="total")),
        ("--orientations: this motion has a fixed orientation", planar2, Analysis(orientations="range")),
        ("--kind wrench-closure: an under-constrained design", free, Analysis(kind="wrench-closure")),
        ("workspace.external_wrench: a moment on a hanging effector", _free_with_moment(),
         Analysis(kind="wrench-feasible")),
        ("--max-tilt: a tilt limit applies", planar2, Analysis(max_tilt=5.0)),
        ("--max-tilt: expected an angle", free, Analysis(max_tilt=200.0)),
        ("--weights: a hanging effector's tensions are unique", free, Analysis(command="pose", weights=True)),
        ("--objective: a hanging effector's tensions are unique", free, Analysis(command="pose", objective="min-max")),
        ("fk: the forward kinematics of elastic and sagging cables takes point outlets",
         _with(cogiro, model="elastic", pulleys=True), Analysis(command="fk")),
        ("--stiffness: ideal cables without cable.axial_stiffness", ipanema3, Analysis(stiffness=True)),
        ("--stiffness: an orientation workspace's rows", cogiro, Analysis(stiffness=True, orientations="total")),
        ("requirements.acceleration: --kind dynamic tests", planar2, Analysis(kind="dynamic")),
        ("--accelerations: sagging cables", _with(planar2, model="sagging"), Analysis(accelerations=True)),
        ("requirements.min_acceleration: sagging cables", _with(planar2, model="sagging"),
         Analysis(accelerations=True, accelerations_by="requirements.min_acceleration")),
        ("--accelerations: an orientation workspace's rows", cogiro, Analysis(accelerations=True,
                                                                              orientations="total")),
        ("--time-optimal: cable model 'sagging'", _with(planar2, model="sagging"),
         Analysis(command="motion", time_optimal=True)),
        ("engine=numpy: the numpy engine covers two cables", ipanema3, Analysis(engine="numpy")),
        ("requirements.min_cable_frequency: cable model 'sagging'",
         _with(cogiro, model="sagging", cable_frequency=5.0), Analysis(command="pose")),
        ("requirements.min_cable_frequency: certify: the interval tests hold constant tension bounds",
         _with(cogiro, cable_frequency=5.0), Analysis(command="certify")),
        ("certify: cable model 'sagging'", _with(cogiro, model="sagging"), Analysis(command="certify")),
        ("certify: swivel pulleys", _with(ipanema3, pulleys=True), Analysis(command="certify")),
        ("certify: effector.orientation: free", free, Analysis(command="certify")),
    ]


def test_every_row_of_the_table_is_reached_with_its_reason(planar2, ipanema3, cogiro):
    cases = _cases(planar2, ipanema3, cogiro)
    assert len(cases) == len(R.REFUSALS)  # a new row needs its case here
    reached = set()
    for start, design, analysis in cases:
        with pytest.raises(InputError) as err:
            resolve(design, analysis)
        msg = str(err.value)
        assert msg.startswith(start), (start, msg)
        row = R.refusal(R.facts(design), analysis)
        assert row is not None and msg == row.message(R.facts(design), analysis)
        reached.add(id(row))
    assert len(reached) == len(R.REFUSALS)  # each case reaches its own row


def test_every_refusal_has_a_cause_and_a_line_in_the_docs(planar2, ipanema3, cogiro):
    """Each row says why it refuses (missing data, meaningless, capability; the causes that depend on
    the facts: the stiffness's missing axial stiffness against the models not built, a hanging
    effector's closure against its dynamic workspace), and docs/cli.md's table of
    combinations has a line for each option a row names."""
    causes = {}
    for start, design, analysis in _cases(planar2, ipanema3, cogiro):
        f = R.facts(design)
        row = R.refusal(f, analysis)
        causes[start] = row.cause_of(f, analysis)
        assert causes[start] in R.CAUSES
    assert causes["--stiffness: ideal cables without cable.axial_stiffness"] == R.MISSING_DATA
    assert causes["--orientations: this motion has a fixed orientation"] == R.MEANINGLESS
    assert causes["requirements.acceleration: --kind dynamic tests"] == R.MISSING_DATA
    free = _with(planar2, orientation="free")
    kind_row = R.refusal(R.facts(free), Analysis(kind="wrench-closure"))
    assert kind_row.cause_of(R.facts(free), Analysis(kind="wrench-closure")) == R.MEANINGLESS
    assert kind_row.cause_of(R.facts(free), Analysis(kind="dynamic")) == R.CAPABILITY
    assert R.refusal(R.facts(free), Analysis(kind="wrench-feasible")) is None  # computed: hung at each vertex
    table = (DESIGNS.parent / "docs" / "cli.md").read_text().split("**Combinations that are refused.**")[1]
    table = table.split("\n\n**")[0]
    for row in R.REFUSALS:
        option = row.option.split(" ")[0]
        assert any(line.startswith("| `") and f"`{option}`" in line.split("|")[1] for line in table.splitlines()), option


def test_an_unknown_kind_names_the_option(planar2):
    with pytest.raises(SpecError, match="--kind"):
        resolve(planar2, Analysis(kind="kinematic"))


def test_what_the_table_allows_resolves(planar2, cogiro):
    """Combinations the table does not refuse resolve (the matrix test computes them)."""
    for model in R.CABLE_MODELS:
        for kind in R.KINDS:
            resolve(_with(cogiro, model=model, acceleration=1.0), Analysis(kind=kind))
            resolve(_with(planar2, model=model, acceleration=1.0), Analysis(kind=kind))
    resolve(_with(cogiro, model="elastic"), Analysis(orientations="total", collisions=True))
    resolve(_with(planar2, orientation="free"), Analysis(command="fk"))
    resolve(_with(planar2, orientation="free", model="sagging"), Analysis(command="fk"))
    # a hanging effector on straight cables: its workspace with interference at the hanging pose and its
    # stiffness (on rigid cables too: it swings on them)
    for model in R.CABLE_MODELS:
        resolve(_with(planar2, orientation="free", model=model), Analysis(collisions=True, stiffness=True))
        resolve(_with(planar2, orientation="free", model=model), Analysis(command="pose"))
        resolve(_with(planar2, orientation="free", model=model), Analysis(stiffness=True))
    # the cable-frequency floor: straight cables compute it, fk does not use tension bounds
    r = resolve(_with(cogiro, cable_frequency=5.0), Analysis(kind="wrench-feasible", collisions=True))
    np.testing.assert_allclose(r.tension_floor, 4 * 5.0**2 * 0.061)  # 4 f^2 mu [N/m^2]
    resolve(_with(cogiro, model="sagging", cable_frequency=5.0), Analysis(command="fk"))
    # without the requirement, or without a mass per length, no floor
    assert not np.any(resolve(cogiro).tension_floor)
    assert not np.any(resolve(_with(spec.load(DESIGNS / "planar4.yaml"), cable_frequency=5.0)).tension_floor)


def test_commands_at_commanded_poses_take_a_free_effector_over_pulleys(planar2):
    """Motor sizing and motion hold the effector at commanded poses: the hanging solver's limit
    (point outlets) refuses the commands that run it, not these; the catenaries' limit (point
    outlets) refuses every command."""
    free_pulleys = _with(planar2, orientation="free", pulleys=True)
    for command in R.COMMANDED_POSES:
        r = resolve(free_pulleys, Analysis(command=command))
        assert (r.outlets.name, r.orientation.name) == ("pulleys", "hanging")
        with pytest.raises(InputError, match="^--cable-model: cable model 'sagging' assumes point outlets"):
            resolve(_with(free_pulleys, model="sagging"), Analysis(command=command))
    for command in ("workspace", "pose", "fk", "statics"):
        with pytest.raises(InputError, match="^effector.orientation: free: the hanging solver"):
            resolve(free_pulleys, Analysis(command=command))


def test_strategies_answer_what_the_layers_below_ask(planar2, cogiro):
    """Each strategy object answers for its model: straight, rigid, stretching, sagging under a
    kind, the cable columns; its name is what the outputs report."""
    names = ("c1", "c2")
    for model, straight, rigid, stretches, cols in (("ideal", True, True, False, 0), ("elastic", True, False, True, 6),
                                                    ("sagging", False, False, False, 7)):
        c = resolve(_with(cogiro, model=model)).cables
        assert (c.name, str(c), c.straight, c.rigid, c.stretches) == (model, model, straight, rigid, stretches)
        assert len(c.state_columns(names)) == cols
        assert c.sags("static") == c.sags("wrench-feasible") == (model == "sagging") and not c.sags("wrench-closure")
        assert c.chords("wrench-closure") == (model == "sagging") and not c.chords("static")
    assert not resolve(planar2).outlets.pulleys and resolve(_with(planar2, pulleys=True)).outlets.pulleys
    held, free = resolve(planar2).orientation, resolve(_with(planar2, orientation="free")).orientation
    assert (held.tilt_beside, held.free, free.tilt_beside, free.free) == (True, False, False, True)


def test_one_pose_is_a_new_resolution_of_the_pose_statics(planar2, cogiro):
    """A pose's robot: the same design resolved for one commanded pose (a free effector's
    orientation commanded; no collisions, orientation set, tilt limit or stiffness), on the one
    implementation of that case (two cables at a commanded pose: the closed form); the robot
    asked is left as it was."""
    free = resolve(_with(planar2, orientation="free"), Analysis(command="pose", max_tilt=20.0))
    one = free.one_pose()
    assert one is not free and one.design is free.design
    assert (free.engine, one.engine) == ("numba", "numpy")
    assert (free.orientation.name, one.orientation.name) == ("hanging", "commanded")
    assert one.tilt_limit is None and free.tilt_limit == 20.0 and one.analysis.max_tilt is None
    r = resolve(_with(cogiro, model="elastic"), Analysis(collisions=True, orientations="total"))
    one = r.one_pose()
    assert not one.analysis.collisions and one.analysis.orientations is None and one.engine == r.engine
    assert (r.analysis.collisions, r.analysis.orientations) == (True, "total")
    np.testing.assert_array_equal(one.outlet_points, r.outlet_points)


def test_every_command_says_what_it_needs():
    """The refusal rows are keyed on capabilities: every command states its needs, from the known set."""
    assert set(R.NEEDS) == set(R.COMMANDS)
    for command, needs in R.NEEDS.items():
        assert needs <= set(R.CAPABILITIES), command
        assert Analysis(command=command).needs == needs
    assert set(R.COMMANDED_POSES) == {"size-motors", "motion"}
