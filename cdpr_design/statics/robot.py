"""The resolved robot: what a design *is* for one analysis, decided once.

A :class:`~cdpr_design.model.design.Design` is the spec as data.  Before any
computation a command calls :func:`resolve` once with the :class:`Analysis` it
runs (its kind, its options); the :class:`Robot` it gets back holds

- the arrays every computation reads (outlets, attachments, tension bounds,
  the balanced wrench rows, the cables' weight and stiffness, the effector's
  mass), built once;
- the strategies, as plain fields every layer below takes without asking the
  design again:

  ``cables``       ``ideal`` | ``elastic`` | ``sagging`` (the heaviest of the cables' models)
  ``outlets``      ``points`` | ``pulleys`` (swivel pulleys of positive radius)
  ``orientation``  ``commanded`` (the command fixes it) | ``held`` (an under-constrained
                   effector held at the commanded orientation, the tilt it would hang with
                   reported beside) | ``hanging`` (``effector.orientation: free``: it hangs
                   where the cables and gravity put it, within ``tilt_limit``)
  ``engine``       ``numpy`` (the closed form of two cables and two wrench rows, vectorised)
                   | ``numba`` (the kernels)

Every combination of a design and an analysis that is not computed is refused
here, by the one table :data:`REFUSALS`, with its reason: nowhere else in the
package decides it (docs/architecture.md).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.errors import InputError, SpecError
from cdpr_design.model.design import Design, has_weight, is_underconstrained

#: Cable models, lightest first (docs/cable-models.md).
CABLE_MODELS = ("ideal", "elastic", "sagging")
#: How the cables leave the frame.
OUTLETS = ("points", "pulleys")
#: How the effector's orientation is decided (see the module doc).
ORIENTATIONS = ("commanded", "held", "hanging")
#: Engines of a grid sweep, as asked (``auto`` is decided by :func:`resolve`).
ENGINES = ("auto", "numba", "numpy")
#: Kinds of workspace and their kernel codes (= ``kernels.KIND_*``; a test checks).
KINDS = {"static": 0, "wrench-feasible": 1, "wrench-closure": 2}
#: Commands that analyse a design (``Analysis.command``).
COMMANDS = ("workspace", "pose", "fk", "certify", "size-motors", "motion", "check", "report", "statics")
#: Largest closed-form grid ``auto`` gives to numpy: numpy is slower a pose than the kernels but
#: pays no numba start-up; the crossover, measured on planar2's whole ``workspace`` command, is
#: between 63,001 and 74,529 poses (docs/performance.md).
NUMPY_MAX_POSES = 70_000
#: Commands that hold the effector at commanded poses and never run the hanging solver (motor
#: sizing over the task poses; trajectories and their simulation, in which a free effector hangs
#: on the simulated cables): the hanging solver's limits do not refuse them.
COMMANDED_POSES = ("size-motors", "motion")


@dataclass(frozen=True)
class Analysis:
    """What a command asks of a design: the options that decide how the robot is modelled.

    ``command`` one of :data:`COMMANDS` (``statics``: a library call that evaluates commanded poses); ``kind`` one of :data:`KINDS`; ``collisions`` the
    interference checks; ``orientations`` ``total`` | ``range`` (orientation workspaces) or
    None; ``max_tilt`` [deg] a tilt limit asked on the command line; ``objective`` and
    ``weights`` the tension distribution of ``pose``; ``engine`` one of :data:`ENGINES`;
    ``poses`` the size of the grid to sweep (the engine's choice); ``stiffness`` the sweep adds
    the least stiffness and the lowest natural frequency of every feasible pose.
    """

    command: str = "workspace"
    kind: str = "static"
    collisions: bool = False
    orientations: str | None = None
    max_tilt: float | None = None
    objective: str = "min-norm"
    weights: bool = False
    engine: str = "auto"
    poses: int = 1
    stiffness: bool = False


@dataclass(frozen=True)
class Facts:
    """What :func:`resolve` decides about a design before it checks the analysis against
    :data:`REFUSALS` (the strategies of a :class:`Robot`)."""

    cables: str
    outlets: str
    orientation: str
    underconstrained: bool
    weight: bool
    rotational: bool
    closed_form: bool
    motion: str
    #: why the stiffness is not defined (None: it is; :func:`stiffness_reason`)
    stiffness: str | None = None
    #: ``requirements.min_cable_frequency`` bounds a cable with a mass per length from below
    string_floor: bool = False


@dataclass(frozen=True)
class Refusal:
    """One row of :data:`REFUSALS`: when ``applies(facts, analysis)``, the analysis is refused
    with ``option: reason`` (``option`` names the option or spec field the user changes, a
    format string of the analysis ``a``)."""

    option: str
    reason: str
    applies: Callable[[Facts, Analysis], bool]

    def message(self, facts: Facts, analysis: Analysis) -> str:
        """``option: reason``, formatted with the facts and the analysis (``{a.kind}``, ``{f.stiffness}``)."""
        return f"{self.option.format(a=analysis)}: {self.reason.format(f=facts)}"


def check_kind(kind: str) -> None:
    """Raise a :class:`SpecError` naming ``--kind`` unless ``kind`` is one of :data:`KINDS`."""
    if kind not in KINDS:
        raise SpecError([("--kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")])


def _free(f: Facts) -> bool:
    return f.orientation == "hanging"


#: Every combination that is not computed, and why: the one table (see the module doc).
REFUSALS: tuple[Refusal, ...] = (
    Refusal("engine", "expected one of auto, numba, numpy", lambda f, a: a.engine not in ENGINES),
    Refusal("--orientations", "expected total or range",
            lambda f, a: a.orientations is not None and a.orientations not in ("total", "range")),
    Refusal("--cable-model", "cable model 'sagging' assumes point outlets, and this design has swivel pulleys "
                             "(cables[].pulley): the catenaries start at the outlet points; use --cable-model "
                             "elastic or ideal",
            lambda f, a: f.cables == "sagging" and f.outlets == "pulleys"),
    Refusal("--collisions", "cable model 'sagging': the interference checks assume straight cables; use "
                            "--cable-model elastic or ideal for this analysis",
            lambda f, a: f.cables == "sagging" and a.collisions),
    Refusal("--orientations", "cable model 'sagging': orientation workspaces assume straight cables; use "
                              "--cable-model elastic or ideal for this analysis",
            lambda f, a: f.cables == "sagging" and a.orientations is not None),
    Refusal("effector.orientation", "free: the hanging solver models point outlets, and this design has swivel "
                                    "pulleys (cables[].pulley)",
            lambda f, a: _free(f) and f.outlets == "pulleys" and a.command not in COMMANDED_POSES),
    Refusal("--cable-model", "an effector with effector.orientation: free hangs on ideal cables (the hanging "
                             "solver models rigid, weightless cables); use --cable-model ideal",
            lambda f, a: _free(f) and f.cables != "ideal" and a.command in ("workspace", "pose")),
    Refusal("--orientations", "an under-constrained design with effector.orientation: free does not command "
                              "its orientation (it hangs); use effector.orientation: fixed to sweep commanded "
                              "orientations",
            lambda f, a: _free(f) and a.orientations is not None),
    Refusal("--orientations", "this motion has a fixed orientation (orientation workspaces are for "
                              "1R2T and 3R3T)",
            lambda f, a: a.orientations is not None and not f.rotational),
    Refusal("--kind {a.kind}", "an under-constrained design with effector.orientation: free hangs under gravity alone "
                      "(static only)",
            lambda f, a: _free(f) and a.kind != "static" and a.command in ("workspace", "pose")),
    Refusal("--collisions", "an under-constrained design with effector.orientation: free is swept without "
                            "interference checks (interference at the hanging pose is not modelled)",
            lambda f, a: _free(f) and a.collisions),
    Refusal("--max-tilt", "a tilt limit applies to an under-constrained design with effector.orientation: free "
                          "(this one's orientation is commanded or held)",
            lambda f, a: a.max_tilt is not None and not _free(f)),
    Refusal("--max-tilt", "expected an angle in [0, 180] degrees",
            lambda f, a: a.max_tilt is not None and not (0.0 <= a.max_tilt <= 180.0)),
    Refusal("--weights", "a hanging effector's tensions are unique (they balance its weight, force and moment)",
            lambda f, a: _free(f) and a.command == "pose" and a.weights),
    Refusal("--objective", "a hanging effector's tensions are unique (they balance its weight, force and "
                           "moment)",
            lambda f, a: _free(f) and a.command == "pose" and a.objective != "min-norm"),
    Refusal("fk", "the forward kinematics of elastic and sagging cables takes point outlets, not swivel "
                  "pulleys; use --cable-model ideal for this design",
            lambda f, a: a.command == "fk" and f.cables != "ideal" and f.outlets == "pulleys"),
    Refusal("--stiffness", "{f.stiffness}",
            lambda f, a: a.stiffness and f.stiffness is not None),
    Refusal("--stiffness", "an orientation workspace's rows stand for a set of orientations, not one pose "
                           "the cables hold: the stiffness is reported at one orientation (leave out "
                           "--orientations)",
            lambda f, a: a.stiffness and a.orientations is not None),
    Refusal("engine=numpy", "the numpy engine covers two cables with two wrench rows (static or wrench-feasible) "
                            "from point outlets, at the workspace's orientation; use auto or numba for this design",
            lambda f, a: a.engine == "numpy" and not _numpy_covers(f, a)),
    Refusal("requirements.min_cable_frequency", "cable model 'sagging': the lower tension bound 4 f^2 L^2 mu "
                                                "is a taut straight cable's, and a sagging cable's own modes are "
                                                "not modelled; use --cable-model elastic or ideal",
            lambda f, a: f.string_floor and f.cables == "sagging" and a.command != "fk"),
    Refusal("requirements.min_cable_frequency", "certify: the interval tests hold constant tension bounds, and "
                                                "this bound grows with the cable's length (4 f^2 L^2 mu); leave "
                                                "it out to certify the workspace of the other bounds",
            lambda f, a: f.string_floor and a.command == "certify"),
    Refusal("certify", "cable model 'sagging': the interval tests assume straight cables (ideal or elastic); "
                       "use --cable-model ideal or elastic",
            lambda f, a: a.command == "certify" and f.cables == "sagging"),
    Refusal("certify", "swivel pulleys (cables[].pulley): the interval tests take point outlets",
            lambda f, a: a.command == "certify" and f.outlets == "pulleys"),
    Refusal("certify", "effector.orientation: free: the hanging orientation changes with the position, and the "
                       "interval tests hold one fixed orientation",
            lambda f, a: a.command == "certify" and _free(f)),
)


def _numpy_covers(f: Facts, a: Analysis) -> bool:
    """Whether the numpy closed form sweeps this analysis: two cables, two wrench rows, not wrench
    closure, straight cables from point outlets, no interference checks, one orientation."""
    return (f.closed_form and a.kind != "wrench-closure" and f.cables != "sagging" and f.outlets == "points"
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
    cables: str
    outlets: str
    orientation: str
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
    def planar(self) -> bool:
        return self.design.motion.planar

    @property
    def straight(self) -> bool:
        """Whether the statics take straight cables (ideal or elastic)."""
        return self.cables != "sagging"

    @property
    def hangs(self) -> bool:
        """Whether the effector's orientation is found by hanging (held: beside the commanded one)."""
        return self.orientation in ("held", "hanging")


def robot_of(design: Design | Robot, command: str) -> Robot:
    """``design`` resolved for ``command`` (an :class:`Analysis` of its defaults, :func:`resolve`),
    or the :class:`Robot` a caller already resolved: the public functions of a command take either,
    so the command resolves its design once and hands the robot down."""
    return design if isinstance(design, Robot) else resolve(design, Analysis(command=command))


def design_of(design: Design | Robot) -> Design:
    """The :class:`~cdpr_design.model.design.Design` of a design or of a robot (its spec as data)."""
    return design.design if isinstance(design, Robot) else design


def cable_model(design: Design) -> str:
    """The design's cable model: the heaviest of its cables' models (:data:`CABLE_MODELS`)."""
    return CABLE_MODELS[max(CABLE_MODELS.index(c.props.model) for c in design.cables)]


def has_pulleys(design: Design) -> bool:
    """Whether any cable leaves its outlet over a swivel pulley of positive radius."""
    return any(c.pulley is not None and c.pulley.radius > 0 for c in design.cables)


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


def facts(design: Design) -> Facts:
    """The strategies of ``design`` that do not depend on the analysis (see the module doc)."""
    cables = cable_model(design)
    outlets = "pulleys" if has_pulleys(design) else "points"
    under = underconstrained(design)
    weight = has_weight(design.effector.mass, design.gravity)
    if under and design.effector.orientation == "free":
        orientation = "hanging"
    elif under and weight and outlets == "points" and cables == "ideal":
        orientation = "held"  # the tilt it would hang with is reported beside the commanded orientation
    else:
        orientation = "commanded"
    return Facts(cables, outlets, orientation, under, weight, design.motion.rotational,
                 design.m == 2 and design.n == 2, design.motion.name,
                 stiffness_reason(design, cables, outlets, orientation), bool(np.any(design.string_floor > 0)))


def stiffness_reason(design: Design, cables: str, outlets: str, orientation: str) -> str | None:
    """Why the stiffness of the design's effector on its cables is not defined, or None (it is:
    straight cables from point outlets, each with an axial stiffness, the orientation commanded
    or held; :mod:`cdpr_design.statics.stiffness`)."""
    if cables == "sagging":
        return "sagging cables: the elastic catenary's stiffness is not modelled (use --cable-model elastic)"
    if outlets == "pulleys":
        return "swivel pulleys: the stiffness of a cable over a pulley is not modelled"
    if orientation == "hanging":
        return "effector.orientation: free: the hanging effector's stiffness is not modelled"
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
    f = facts(design)
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
    """``numpy`` where the closed form covers the analysis and is asked for, or chosen by ``auto``
    for a grid of at most :data:`NUMPY_MAX_POSES` poses (numba's start-up would cost more than
    the sweep; a process that has loaded the kernels for many sweeps asks for ``numba``);
    ``numba`` otherwise."""
    if a.engine == "numpy":
        return "numpy"
    if a.engine == "auto" and _numpy_covers(f, a) and a.poses <= NUMPY_MAX_POSES:
        return "numpy"
    return "numba"


def _tilt_limit(design: Design, f: Facts, a: Analysis) -> float | None:
    """The tilt limit [deg] of a hanging effector: ``--max-tilt``, else ``requirements.max_tilt``."""
    if f.orientation != "hanging":
        return None
    return float(a.max_tilt) if a.max_tilt is not None else design.requirements.max_tilt
