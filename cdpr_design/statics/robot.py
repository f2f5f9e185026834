"""The resolved robot: what a design *is* for one analysis, decided once.

A :class:`~cdpr_design.model.design.Design` is the spec as data.  Before any
computation a command calls :func:`resolve` once with the :class:`Analysis` it
runs (its kind, its options); the :class:`Robot` it gets back holds

- the arrays every computation reads (outlets, attachments, tension bounds,
  the balanced wrench rows, the cables' weight and stiffness, the effector's
  mass), built once;
- the strategies, as objects every layer below asks without asking the design again
  (:mod:`cdpr_design.statics.strategies`):

  ``cables``       :class:`~cdpr_design.statics.strategies.CableModel`: ``ideal`` | ``elastic`` |
                   ``sagging`` (the heaviest of the cables' models)
  ``outlets``      :class:`~cdpr_design.statics.strategies.Outlets`: ``points`` | ``pulleys``
                   (swivel pulleys of positive radius)
  ``orientation``  :class:`~cdpr_design.statics.strategies.Orientation`: ``commanded`` (the
                   command fixes it) | ``held`` (an under-constrained effector held at the
                   commanded orientation, the tilt it would hang with reported beside) |
                   ``hanging`` (``effector.orientation: free``: it hangs where the cables and
                   gravity put it, within ``tilt_limit``)
  ``engine``       ``numpy`` (the closed form of two cables and two wrench rows, vectorised:
                   the one implementation of that case) | ``numba`` (the kernels: every other case)

Every combination of a design and an analysis that is not computed is refused
here, by the one table :data:`REFUSALS`, with its reason: nowhere else in the
package decides it (docs/architecture.md).  A row is keyed on what the analysis
needs (:data:`NEEDS`: the hanging solver, straight cables, a fixed orientation...),
not on the command that asks it.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.errors import InputError, SpecError
from cdpr_design.model.design import Design, has_weight, is_point_mass, is_underconstrained
from cdpr_design.statics.pulley import has_pulleys
from cdpr_design.statics import strategies as S
from cdpr_design.statics.strategies import CableModel, Orientation, Outlets

#: Cable models, lightest first (docs/cable-models.md): their names.
CABLE_MODELS = tuple(c.name for c in S.CABLE_MODELS)
#: How the cables leave the frame.
OUTLETS = (S.POINTS.name, S.PULLEYS.name)
#: How the effector's orientation is decided (see the module doc).
ORIENTATIONS = (S.COMMANDED.name, S.HELD.name, S.HANGING.name)
#: Engines of a grid sweep, as asked: ``auto`` and ``numba`` sweep with the implementation the
#: robot has (:func:`resolve`), ``numpy`` also refuses a robot the closed form does not cover.
ENGINES = ("auto", "numba", "numpy")
#: Kinds of workspace and their kernel codes (= ``kernels.KIND_*``; a test checks).  ``dynamic`` is
#: tested as ``wrench-feasible`` is, on a larger set of required wrenches: every vertex of the external
#: wrench box plus every vertex of the inertial wrenches of ``requirements.acceleration``
#: (:func:`cdpr_design.statics.wrenches.wrench_vertices`).
KINDS = {"static": 0, "wrench-feasible": 1, "wrench-closure": 2, "dynamic": 1}
#: Commands that analyse a design (``Analysis.command``).
COMMANDS = ("workspace", "pose", "fk", "certify", "size-motors", "motion", "check", "report", "statics")
#: What an analysis needs of the robot, the capabilities the rows of :data:`REFUSALS` are keyed on:
#: ``hanging-solver`` it runs the hanging solver (a free effector's orientation found at its poses;
#: point outlets); ``hanging-statics`` it reports a free effector's statics where it hangs (rigid
#: cables, its weight alone: static); ``tension-choice`` it distributes the tensions by an objective
#: or weights; ``cable-fk`` it solves the pose of given unstretched lengths of elastic or sagging
#: cables (point outlets); ``tension-bounds`` it checks the tension bounds (the cable-frequency
#: floor of straight cables); ``interval-tests`` it proves the workspace by interval tests
#: (straight cables from point outlets, one fixed orientation, constant tension bounds).
CAPABILITIES = ("hanging-solver", "hanging-statics", "tension-choice", "cable-fk", "tension-bounds",
                "interval-tests")
#: What each command needs (:data:`CAPABILITIES`).
NEEDS: dict[str, frozenset[str]] = {
    "workspace": frozenset({"hanging-solver", "hanging-statics", "tension-bounds"}),
    "pose": frozenset({"hanging-solver", "hanging-statics", "tension-choice", "tension-bounds"}),
    "fk": frozenset({"hanging-solver", "cable-fk"}),
    "certify": frozenset({"hanging-solver", "tension-bounds", "interval-tests"}),
    "size-motors": frozenset({"tension-bounds"}),
    "motion": frozenset({"tension-bounds"}),
    "check": frozenset({"hanging-solver", "tension-bounds"}),
    "report": frozenset({"hanging-solver", "tension-bounds"}),
    "statics": frozenset({"hanging-solver", "tension-bounds"}),
}
#: Commands that hold the effector at commanded poses and never run the hanging solver (motor
#: sizing over the task poses; trajectories and their simulation, in which a free effector hangs
#: on the simulated cables): the hanging solver's limits do not refuse them.
COMMANDED_POSES = tuple(c for c in COMMANDS if "hanging-solver" not in NEEDS[c])


@dataclass(frozen=True)
class Analysis:
    """What a command asks of a design: the options that decide how the robot is modelled.

    ``command`` one of :data:`COMMANDS` (``statics``: a library call that evaluates commanded poses); ``kind`` one of :data:`KINDS`; ``collisions`` the
    interference checks; ``orientations`` ``total`` | ``range`` (orientation workspaces) or
    None; ``max_tilt`` [deg] a tilt limit asked on the command line; ``objective`` and
    ``weights`` the tension distribution of ``pose``; ``engine`` one of :data:`ENGINES`;
    ``stiffness`` the sweep adds the least stiffness and the lowest natural frequency of every
    feasible pose; ``accelerations`` the sweep adds the acceleration radius of every pose
    (:mod:`cdpr_design.statics.acceleration`), asked for by ``accelerations_by`` (an option or a
    spec key: what a refusal of them names); ``time_optimal`` a path is timed as fast as the robot
    allows (:mod:`cdpr_design.motion.time_optimal`); ``hold`` the orientation is commanded at every pose, also of a free effector
    (one pose's statics, :meth:`one_pose`).
    """

    command: str = "workspace"
    kind: str = "static"
    collisions: bool = False
    orientations: str | None = None
    max_tilt: float | None = None
    objective: str = "min-norm"
    weights: bool = False
    engine: str = "auto"
    stiffness: bool = False
    hold: bool = False
    accelerations: bool = False
    time_optimal: bool = False
    #: what asks for the accelerations, the name a refusal gives: the option ``--accelerations``,
    #: or the spec's ``requirements.min_acceleration`` (``check``, ``report``, ``sweep``, ``optimize``)
    accelerations_by: str = "--accelerations"

    @property
    def needs(self) -> frozenset[str]:
        """What the analysis needs of the robot (:data:`NEEDS` of its command; nothing for an unknown one)."""
        return NEEDS.get(self.command, frozenset())

    def one_pose(self, engine: str) -> Analysis:
        """This analysis at one commanded pose, on ``engine``: its statics only (the pose fixes the
        orientation a free effector would find; no interference mask, orientation set, tilt
        limit or stiffness columns)."""
        return dataclasses.replace(self, collisions=False, orientations=None, max_tilt=None, stiffness=False,
                                   accelerations=False, hold=True, engine=engine)


@dataclass(frozen=True)
class Facts:
    """What :func:`resolve` decides about a design before it checks the analysis against
    :data:`REFUSALS` (the strategies of a :class:`Robot`)."""

    cables: CableModel
    outlets: Outlets
    orientation: Orientation
    underconstrained: bool
    weight: bool
    rotational: bool
    closed_form: bool
    motion: str
    #: why the stiffness is not defined (None: it is; :func:`stiffness_reason`)
    stiffness: str | None = None
    #: ``requirements.min_cable_frequency`` bounds a cable with a mass per length from below
    string_floor: bool = False
    #: the spec gives ``requirements.acceleration`` (the box of a ``dynamic`` workspace)
    acceleration_box: bool = False
    #: why the acceleration capability is not computed (None: it is; :func:`acceleration_reason`)
    acceleration: str | None = None
    #: why a hanging effector's statics under ``workspace.external_wrench`` are not computed (None:
    #: they are, or nothing hangs; :func:`hanging_load_reason`)
    hanging_load: str | None = None


#: Why a combination is refused (:attr:`Refusal.cause`): the spec lacks data the analysis needs
#: (the message names the key to give) ...
MISSING_DATA = "missing data"
#: ... the analysis has no meaning for this design or this option value (an orientation set for a
#: translational motion, a tilt limit for a held effector, a value outside an option's domain) ...
MEANINGLESS = "meaningless"
#: ... or it has one, and the package does not compute it (yet).
CAPABILITY = "capability"
#: The causes of :data:`REFUSALS`' rows (docs/cli.md's table of combinations says which is which).
CAUSES = (MISSING_DATA, MEANINGLESS, CAPABILITY)


@dataclass(frozen=True)
class Refusal:
    """One row of :data:`REFUSALS`: when ``applies(facts, analysis)``, the analysis is refused
    with ``option: reason`` (``option`` names the option or spec field the user changes, a
    format string of the analysis ``a``).  ``cause``: one of :data:`CAUSES`, or a function of the
    facts and the analysis giving one (a row whose reason is the facts')."""

    option: str
    reason: str
    applies: Callable[[Facts, Analysis], bool]
    cause: str | Callable[[Facts, Analysis], str]

    def message(self, facts: Facts, analysis: Analysis) -> str:
        """``option: reason``, formatted with the facts and the analysis (``{a.kind}``, ``{f.stiffness}``)."""
        return f"{self.option.format(a=analysis)}: {self.reason.format(f=facts)}"

    def cause_of(self, facts: Facts, analysis: Analysis) -> str:
        """Why this row refuses ``analysis`` of a design with ``facts``: one of :data:`CAUSES`."""
        return self.cause(facts, analysis) if callable(self.cause) else self.cause


def check_kind(kind: str) -> None:
    """Raise a :class:`SpecError` naming ``--kind`` unless ``kind`` is one of :data:`KINDS`."""
    if kind not in KINDS:
        raise SpecError([("--kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")])


def _free(f: Facts) -> bool:
    return f.orientation.free


def _kind_cause(f: Facts, a: Analysis) -> str:
    """A hanging effector under a kind other than static or wrench-feasible: wrench closure asks
    the cables alone to resist every wrench, which an effector whose orientation they leave free
    cannot (meaningless); the hanging orientation under each inertial wrench is not computed
    (capability)."""
    return MEANINGLESS if a.kind == "wrench-closure" else CAPABILITY


def _stiffness_cause(f: Facts, a: Analysis) -> str:
    """Missing data where the stiffness lacks the cables' ``axial_stiffness`` (the reason names the
    key to give), a capability otherwise (:func:`stiffness_reason`)."""
    return MISSING_DATA if "give axial_stiffness" in (f.stiffness or "") else CAPABILITY


#: Every combination that is not computed, and why: the one table (see the module doc).
REFUSALS: tuple[Refusal, ...] = (
    Refusal("engine", "expected one of auto, numba, numpy", lambda f, a: a.engine not in ENGINES, MEANINGLESS),
    Refusal("--orientations", "expected total or range",
            lambda f, a: a.orientations is not None and a.orientations not in ("total", "range"), MEANINGLESS),
    Refusal("--cable-model", "cable model 'sagging' assumes point outlets, and this design has swivel pulleys "
                             "(cables[].pulley): the catenaries start at the outlet points; use --cable-model "
                             "elastic or ideal",
            lambda f, a: not f.cables.straight and f.outlets.pulleys, CAPABILITY),
    Refusal("effector.orientation", "free: the hanging solver models point outlets, and this design has swivel "
                                    "pulleys (cables[].pulley)",
            lambda f, a: _free(f) and f.outlets.pulleys and "hanging-solver" in a.needs, CAPABILITY),
    Refusal("--orientations", "an under-constrained design with effector.orientation: free does not command "
                              "its orientation (it hangs); use effector.orientation: fixed to sweep commanded "
                              "orientations",
            lambda f, a: _free(f) and a.orientations is not None, MEANINGLESS),
    Refusal("--orientations", "this motion has a fixed orientation (orientation workspaces are for "
                              "1R2T and 3R3T)",
            lambda f, a: a.orientations is not None and not f.rotational, MEANINGLESS),
    Refusal("--kind {a.kind}", "an under-constrained design with effector.orientation: free hangs under gravity and "
                               "the external wrenches (static or wrench-feasible)",
            lambda f, a: _free(f) and a.kind not in ("static", "wrench-feasible") and "hanging-statics" in a.needs,
            _kind_cause),
    Refusal("workspace.external_wrench", "{f.hanging_load}",
            lambda f, a: _free(f) and a.kind == "wrench-feasible" and f.hanging_load is not None
            and "hanging-statics" in a.needs, CAPABILITY),
    Refusal("--max-tilt", "a tilt limit applies to an under-constrained design with effector.orientation: free "
                          "(this one's orientation is commanded or held)",
            lambda f, a: a.max_tilt is not None and not _free(f), MEANINGLESS),
    Refusal("--max-tilt", "expected an angle in [0, 180] degrees",
            lambda f, a: a.max_tilt is not None and not (0.0 <= a.max_tilt <= 180.0), MEANINGLESS),
    Refusal("--weights", "a hanging effector's tensions are unique (they balance its weight, force and moment)",
            lambda f, a: _free(f) and "tension-choice" in a.needs and a.weights, MEANINGLESS),
    Refusal("--objective", "a hanging effector's tensions are unique (they balance its weight, force and "
                           "moment)",
            lambda f, a: _free(f) and "tension-choice" in a.needs and a.objective != "min-norm", MEANINGLESS),
    Refusal("fk", "the forward kinematics of elastic and sagging cables takes point outlets, not swivel "
                  "pulleys; use --cable-model ideal for this design",
            lambda f, a: "cable-fk" in a.needs and not f.cables.rigid and f.outlets.pulleys, CAPABILITY),
    Refusal("--stiffness", "{f.stiffness}",
            lambda f, a: a.stiffness and f.stiffness is not None, _stiffness_cause),
    Refusal("--stiffness", "an orientation workspace's rows stand for a set of orientations, not one pose "
                           "the cables hold: the stiffness is reported at one orientation (leave out "
                           "--orientations)",
            lambda f, a: a.stiffness and a.orientations is not None, MEANINGLESS),
    Refusal("requirements.acceleration", "--kind dynamic tests the accelerations of this box from rest at every "
                                         "pose: give lower and upper, one value per motion coordinate "
                                         "[m/s^2, rad/s^2]",
            lambda f, a: a.kind == "dynamic" and not f.acceleration_box, MISSING_DATA),
    Refusal("requirements.min_acceleration", "{f.acceleration}",
            lambda f, a: a.accelerations and a.accelerations_by == "requirements.min_acceleration"
            and f.acceleration is not None, CAPABILITY),
    Refusal("--accelerations", "{f.acceleration}",
            lambda f, a: a.accelerations and f.acceleration is not None, CAPABILITY),
    Refusal("--accelerations", "an orientation workspace's rows stand for a set of orientations: the "
                               "acceleration radius is reported at one orientation (leave out --orientations)",
            lambda f, a: a.accelerations and a.orientations is not None, MEANINGLESS),
    Refusal("--time-optimal", "cable model 'sagging': the time-optimal constraints take the tensions of straight "
                              "cables (a catenary's wrench is not linear in its tension); use --cable-model "
                              "elastic or ideal",
            lambda f, a: a.time_optimal and not f.cables.straight, CAPABILITY),
    Refusal("engine=numpy", "the numpy engine covers two cables with two wrench rows (static or wrench-feasible) "
                            "from point outlets, at the workspace's orientation; use auto or numba for this design",
            lambda f, a: a.engine == "numpy" and not _numpy_covers(f, a), MEANINGLESS),
    Refusal("requirements.min_cable_frequency", "cable model 'sagging': the lower tension bound 4 f^2 L^2 mu "
                                                "is a taut straight cable's, and a sagging cable's own modes are "
                                                "not modelled; use --cable-model elastic or ideal",
            lambda f, a: f.string_floor and not f.cables.straight and "tension-bounds" in a.needs, CAPABILITY),
    Refusal("requirements.min_cable_frequency", "certify: the interval tests hold constant tension bounds, and "
                                                "this bound grows with the cable's length (4 f^2 L^2 mu); leave "
                                                "it out to certify the workspace of the other bounds",
            lambda f, a: f.string_floor and "interval-tests" in a.needs, CAPABILITY),
    Refusal("certify", "cable model 'sagging': the interval tests assume straight cables (ideal or elastic); "
                       "use --cable-model ideal or elastic",
            lambda f, a: "interval-tests" in a.needs and not f.cables.straight, CAPABILITY),
    Refusal("certify", "swivel pulleys (cables[].pulley): the interval tests take point outlets",
            lambda f, a: "interval-tests" in a.needs and f.outlets.pulleys, CAPABILITY),
    Refusal("certify", "effector.orientation: free: the hanging orientation changes with the position, and the "
                       "interval tests hold one fixed orientation",
            lambda f, a: "interval-tests" in a.needs and _free(f), CAPABILITY),
)


def _numpy_covers(f: Facts, a: Analysis) -> bool:
    """Whether the numpy closed form sweeps this analysis: two cables, two wrench rows, not wrench
    closure, straight cables from point outlets, no interference checks, one orientation."""
    return (f.closed_form and a.kind != "wrench-closure" and f.cables.straight and not f.outlets.pulleys
            and not a.collisions and a.orientations is None and not _free(f))


def refusal(facts: Facts, analysis: Analysis) -> Refusal | None:
    """The first row of :data:`REFUSALS` that refuses ``analysis`` of a design with ``facts``, or None."""
    for r in REFUSALS:
        if r.applies(facts, analysis):
            return r
    return None


@dataclass(frozen=True)
class CableArrays:
    """What the kernels need of the cables: ``w`` (m,) weight per length [N/m] (0 unless the
    cable sags), ``EA`` (m,) axial stiffness [N] (inf for an ideal cable), ``up`` (3,) unit
    vector against gravity."""

    w: np.ndarray
    EA: np.ndarray
    up: np.ndarray


@dataclass(frozen=True, eq=False)
class Robot:
    """A design resolved for one :class:`Analysis` (see the module doc).

    Arrays (SI, float64, C-contiguous; never modified): ``outlets`` and ``attachments`` (m, 3)
    [m], ``tension_min`` and ``tension_max`` (m,) [N], ``rows`` (n,) int64 the balanced rows of
    the full wrench, ``combos`` the (C(m, n-1), n-1) cable subsets of hyperplane shifting,
    ``cable`` the :class:`CableArrays`, ``mass`` [kg], ``center_of_mass`` (3,) [m] in the
    effector's frame, ``gravity`` (3,) [m/s^2], ``tension_floor`` (m,) [N/m^2] the coefficients
    c_i of the lower tension bound c_i L_i^2 at free length L_i [m] of
    ``requirements.min_cable_frequency`` (zeros without it; :attr:`Design.string_floor
    <cdpr_design.model.design.Design.string_floor>`): every evaluation bounds cable i from
    below by max(tension_min_i, c_i L_i^2) (:func:`tension_lower`).
    """

    design: Design
    analysis: Analysis
    cables: CableModel
    outlets: Outlets
    orientation: Orientation
    underconstrained: bool
    engine: str
    tilt_limit: float | None
    outlet_points: np.ndarray = field(repr=False)
    attachments: np.ndarray = field(repr=False)
    tension_min: np.ndarray = field(repr=False)
    tension_max: np.ndarray = field(repr=False)
    rows: np.ndarray = field(repr=False)
    combos: np.ndarray = field(repr=False)
    cable: CableArrays = field(repr=False)
    mass: float = 0.0
    center_of_mass: np.ndarray = field(default_factory=lambda: np.zeros(3), repr=False)
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3), repr=False)
    tension_floor: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    @property
    def m(self) -> int:
        """Number of cables."""
        return self.design.m

    @property
    def n(self) -> int:
        """Degrees of freedom (rows of the structure matrix)."""
        return self.design.n

    @property
    def kind(self) -> str:
        return self.analysis.kind

    @property
    def kcode(self) -> int:
        """The kernels' code of the analysis's kind."""
        return KINDS[self.analysis.kind]

    @property
    def every_vertex(self) -> bool:
        """Whether every vertex of the required wrench set must be feasible (``wrench-feasible``,
        ``dynamic``), not only the first (``static``) or none (``wrench-closure``)."""
        return self.kcode == KINDS["wrench-feasible"]

    @property
    def planar(self) -> bool:
        return self.design.motion.planar

    @property
    def straight(self) -> bool:
        """Whether the statics take straight cables (ideal or elastic)."""
        return self.cables.straight

    @property
    def hangs(self) -> bool:
        """Whether the effector's orientation is found by hanging (held: beside the commanded one)."""
        return self.orientation.free or self.orientation.tilt_beside

    def one_pose(self) -> Robot:
        """The robot of this design for one commanded pose of this analysis
        (:meth:`Analysis.one_pose`, on this robot's engine), resolved."""
        return resolve(self.design, self.analysis.one_pose(self.engine))


def cable_model(design: Design) -> CableModel:
    """The design's cable model: the heaviest of its cables' models (:data:`CABLE_MODELS`)."""
    return S.CABLE_MODELS[max(CABLE_MODELS.index(c.props.model) for c in design.cables)]


def underconstrained(design: Design) -> bool:
    """Whether the cables leave the effector's orientation free
    (:func:`~cdpr_design.model.design.is_underconstrained`)."""
    return is_underconstrained(design.m, design.attachments, design.motion.planar)


def cable_arrays(design: Design) -> CableArrays:
    """The :class:`CableArrays` of a design (gravity from ``design.gravity`` [m/s^2])."""
    g = np.asarray(design.gravity, float)
    gn = float(np.linalg.norm(g))
    up = -g / gn if gn > 0 else np.array([0.0, 0.0, 1.0])
    w = np.array([c.props.mass_per_length * gn if c.props.model == "sagging" else 0.0 for c in design.cables])
    EA = np.array([np.inf if c.props.model == "ideal" else float(c.props.axial_stiffness)
                   for c in design.cables])
    return CableArrays(np.ascontiguousarray(w), np.ascontiguousarray(EA), np.ascontiguousarray(up))


def combinations(m: int, n: int) -> np.ndarray:
    """All subsets of n-1 of the m cables, as a (C(m, n-1), n-1) int64 array (hyperplane shifting)."""
    k = max(n - 1, 0)
    c = list(itertools.combinations(range(m), k))
    return np.array(c, dtype=np.int64).reshape(len(c), k)


def facts(design: Design, hold: bool = False) -> Facts:
    """The strategies of ``design`` (see the module doc); ``hold``: the orientation commanded at
    every pose, also of a free effector (:attr:`Analysis.hold`)."""
    cables = cable_model(design)
    outlets = S.PULLEYS if has_pulleys(design) else S.POINTS
    under = underconstrained(design)
    weight = has_weight(design.effector.mass, design.gravity)
    if under and design.effector.orientation == "free" and not hold:
        orientation: Orientation = S.HANGING
    elif under and design.effector.orientation == "free":
        orientation = S.COMMANDED
    elif under and weight and not outlets.pulleys and cables.rigid:
        orientation = S.HELD  # the tilt it would hang with is reported beside the commanded orientation
    else:
        orientation = S.COMMANDED
    return Facts(cables, outlets, orientation, under, weight, design.motion.rotational,
                 design.m == 2 and design.n == 2, design.motion.name,
                 stiffness_reason(design, cables, outlets, orientation), bool(np.any(design.string_floor > 0)),
                 design.requirements.acceleration is not None, acceleration_reason(cables, orientation),
                 hanging_load_reason(design, orientation))


def hanging_load_reason(design: Design, orientation: Orientation) -> str | None:
    """Why a hanging effector's statics under the vertices of ``workspace.external_wrench`` are not
    computed, or None (they are: forces at the reference point; or the effector does not hang).
    A moment is not: a constant moment about a tilting axis has no potential, so the hanging pose's
    stability is not a minimum of energy, and a planar body's moment is refused with it (its
    balance is not the closed form's).  Nor a force on a spatial point mass attached away from its
    reference point (:func:`cdpr_design.statics.hanging.at_positions.unit_geometry`)."""
    box = design.workspace.external_wrench
    if not orientation.free or box is None:
        return None
    rows = np.asarray(design.rows)
    moment = rows >= 3
    if np.any(np.asarray(box.lower)[moment] != 0) or np.any(np.asarray(box.upper)[moment] != 0):
        return ("a moment on a hanging effector (effector.orientation: free) is not modelled: give its moment "
                "rows 0 (the forces act at the platform origin)")
    A = np.asarray(design.attachments, float)
    if not design.motion.planar and is_point_mass(A) and np.any(A[0]):
        return ("a force on a spatial point-mass effector attached away from the platform origin is not modelled "
                "(effector.orientation: free): attach it at the origin")
    return None


def acceleration_reason(cables: CableModel, orientation: Orientation) -> str | None:
    """Why the acceleration capability of a design's effector (:mod:`cdpr_design.statics.acceleration`)
    is not computed, or None (it is: straight cables, the orientation commanded or held)."""
    if not cables.straight:
        return ("sagging cables: the wrench of a catenary is not linear in its tension, so the accelerations "
                "it allows are not modelled (use --cable-model elastic or ideal)")
    if orientation.free:
        return "effector.orientation: free: the hanging effector's accelerations are not modelled"
    return None


def stiffness_reason(design: Design, cables: CableModel, outlets: Outlets, orientation: Orientation) -> str | None:
    """Why the stiffness of the design's effector on its cables is not defined, or None (it is:
    straight or sagging cables from point outlets, each with an axial stiffness, the orientation
    commanded or held, :mod:`cdpr_design.statics.stiffness`; or a hanging effector, whose pulleys
    are refused before: :mod:`cdpr_design.statics.hanging.compliance` and
    :mod:`cdpr_design.statics.hanging.sagging`)."""
    if orientation.free:  # on rigid cables too: it swings on them (cdpr_design.statics.hanging.compliance)
        return None
    if outlets.pulleys:
        return "swivel pulleys: the stiffness of a cable over a pulley is not modelled"
    missing = [c.name for c in design.cables if not c.props.axial_stiffness]
    if missing:
        return ("ideal cables without cable.axial_stiffness are inextensible, so the robot is rigid along "
                f"them (infinite stiffness): give axial_stiffness for {', '.join(missing)}")
    return None


def resolve(design: Design, analysis: Analysis | None = None, **options) -> Robot:
    """The :class:`Robot` of ``design`` for ``analysis`` (or an :class:`Analysis` of ``options``).

    Raises
    ------
    SpecError
        When the kind is not one of :data:`KINDS`.
    InputError
        When :data:`REFUSALS` refuses the combination: the message names the option or
        spec field and says why.
    """
    a = analysis if analysis is not None else Analysis(**options)
    check_kind(a.kind)
    f = facts(design, a.hold)
    r = refusal(f, a)
    if r is not None:
        raise InputError(r.message(f, a))
    return Robot(
        design=design, analysis=a, cables=f.cables, outlets=f.outlets, orientation=f.orientation,
        underconstrained=f.underconstrained, engine=_engine(f, a), tilt_limit=_tilt_limit(design, f, a),
        outlet_points=np.ascontiguousarray(design.outlets), attachments=np.ascontiguousarray(design.attachments),
        tension_min=design.tension_min, tension_max=design.tension_max, rows=design.rows,
        combos=combinations(design.m, design.n), cable=cable_arrays(design), mass=float(design.effector.mass),
        center_of_mass=np.asarray(design.effector.center_of_mass, float), gravity=np.asarray(design.gravity, float),
        tension_floor=np.ascontiguousarray(design.string_floor))


def tension_lower(tension_min, tension_floor, free_lengths) -> np.ndarray:
    """The lower tension bounds [N] at cable free lengths ``free_lengths`` (..., m) [m]:
    max(``tension_min``, ``tension_floor`` L^2) (:class:`Robot`); ``tension_min`` itself where a
    cable has no floor.  The kernels' per-pose bound is the same expression (``kernels.pose.raise_floor``)."""
    L = np.asarray(free_lengths, float)
    c = np.asarray(tension_floor, float)
    return np.where(c > 0.0, np.maximum(tension_min, c * L * L), tension_min)


def _engine(f: Facts, a: Analysis) -> str:
    """``numpy`` where the closed form of two cables covers the analysis (:func:`_numpy_covers`),
    ``numba`` otherwise: each case has one implementation, whatever the process has loaded."""
    return "numpy" if _numpy_covers(f, a) else "numba"


def _tilt_limit(design: Design, f: Facts, a: Analysis) -> float | None:
    """The tilt limit [deg] of a hanging effector: ``--max-tilt``, else ``requirements.max_tilt``."""
    if not f.orientation.free:
        return None
    return float(a.max_tilt) if a.max_tilt is not None else design.requirements.max_tilt
