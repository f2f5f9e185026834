"""The design model: frozen dataclasses built by :mod:`cdpr_design.model.spec`.

Everything is stored in SI units and in *three-dimensional* form so that one
code path serves every motion type: planar designs live in the z = 0 plane,
poses are always the 6-vector ``[x, y, z, rx, ry, rz]`` and the wrench is the
6-vector ``[fx, fy, fz, mx, my, mz]``.  A :class:`Motion` says which pose
coordinates move and which wrench rows are balanced.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# ----------------------------------------------------------------------------
# Motion types
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Motion:
    """A motion type of the spec format.

    Attributes
    ----------
    name : str
        ``2T``, ``1R2T``, ``3T`` or ``3R3T``.
    dim : int
        Dimension of positions and geometry vectors in the spec (2 or 3).
    coords : tuple of str
        The pose coordinates in spec order (``x, y[, z][, phi | rx, ry, rz]``).
    pose_index : tuple of int
        Where each pose coordinate goes in the full pose ``[x, y, z, rx, ry, rz]``.
    wrench_rows : tuple of int
        Rows of the full wrench ``[fx, fy, fz, mx, my, mz]`` that are balanced.
    wrench_names : tuple of str
        Names of those rows.
    """

    name: str
    dim: int
    coords: tuple[str, ...]
    pose_index: tuple[int, ...]
    wrench_rows: tuple[int, ...]
    wrench_names: tuple[str, ...]

    @property
    def n(self) -> int:
        """Degrees of freedom = rows of the structure matrix."""
        return len(self.wrench_rows)

    @property
    def position_coords(self) -> tuple[str, ...]:
        return self.coords[: self.dim]

    @property
    def rotation_coords(self) -> tuple[str, ...]:
        return self.coords[self.dim:]

    @property
    def rotational(self) -> bool:
        return len(self.coords) > self.dim

    @property
    def planar(self) -> bool:
        return self.dim == 2


MOTIONS: dict[str, Motion] = {
    "2T": Motion("2T", 2, ("x", "y"), (0, 1), (0, 1), ("fx", "fy")),
    "1R2T": Motion("1R2T", 2, ("x", "y", "phi"), (0, 1, 5), (0, 1, 5), ("fx", "fy", "mz")),
    "3T": Motion("3T", 3, ("x", "y", "z"), (0, 1, 2), (0, 1, 2), ("fx", "fy", "fz")),
    "3R3T": Motion(
        "3R3T", 3, ("x", "y", "z", "rx", "ry", "rz"), (0, 1, 2, 3, 4, 5),
        (0, 1, 2, 3, 4, 5), ("fx", "fy", "fz", "mx", "my", "mz"),
    ),
}


def pad3(v, dim: int | None = None) -> np.ndarray:
    """A 2- or 3-vector as a float64 3-vector (z = 0 for planar vectors)."""
    a = np.asarray(v, dtype=float).reshape(-1)
    out = np.zeros(3)
    out[: a.size] = a
    return out


def default_gravity(dim: int) -> list[float]:
    """The spec's gravity when it gives none [m/s^2]: -9.81 along the last of ``dim`` axes."""
    return [0.0] * (dim - 1) + [-9.81]


def min_string_tension(lengths, mass_per_length, frequency: float) -> np.ndarray:
    """The least tension [N] that keeps a cable's first transverse (string) mode at or above
    ``frequency`` [Hz]: T_min = 4 f^2 L^2 mu (``lengths`` L [m], ``mass_per_length`` mu [kg/m];
    0 for a massless cable), from f_1 = sqrt(T / mu) / (2 L) (docs/algorithms.md, "The cables'
    own vibration")."""
    L, mu = np.asarray(lengths, float), np.asarray(mass_per_length, float)
    return 4.0 * float(frequency) ** 2 * L * L * mu


#: The least weight [N] an effector hangs under (:func:`has_weight`).  The balance of a hanging
#: effector is solved scaled by its weight (forces) and its weight times its size (moments, the
#: size at least 1 mm), and the squared scaled structure matrix overflows below about 1e-150 N
#: (a 1e-300 kg effector gave infinities and a "balanced" pose with 1e-300 N tensions).  1e-12 N,
#: a tenth of a nanogram at 1 g, is far below any effector a cable robot carries and far above that.
MIN_WEIGHT = 1e-12


def weight(mass: float, g) -> float:
    """The weight [N] of ``mass`` [kg] under gravity ``g`` [m/s^2]."""
    return float(mass) * float(np.linalg.norm(np.asarray(g, float)))


def has_weight(mass: float, g) -> bool:
    """Whether an effector of ``mass`` [kg] under gravity ``g`` [m/s^2] has a weight to hang under:
    at least :data:`MIN_WEIGHT`."""
    return bool(weight(mass, g) >= MIN_WEIGHT)


def weight_problem(mass: float, g) -> str | None:
    """Why an under-constrained effector of ``mass`` [kg] under gravity ``g`` [m/s^2] cannot hang from
    its cables (None when it has a weight, :func:`has_weight`): the message of both refusals."""
    if has_weight(mass, g):
        return None
    gn = float(np.linalg.norm(np.asarray(g, float)))
    return (f"an under-constrained effector hangs from its cables under its weight, so it needs a weight "
            f"(effector.mass x |gravity|) of at least {MIN_WEIGHT:g} N (got {mass:g} kg and |gravity| = "
            f"{gn:g} m/s^2)")


def is_point_mass(B, tol: float = 1e-12) -> bool:
    """True when every attachment (rows of ``B`` [m]) is the same point: rotations change no length."""
    B = np.atleast_2d(np.asarray(B, float))
    return bool(np.all(np.linalg.norm(B - B[0], axis=1) <= tol))


def is_underconstrained(m: int, B, planar: bool) -> bool:
    """Fewer cables (``m``) than the free degrees of freedom they would have to fix, with
    attachments ``B`` [m]: a planar rigid body < 3, a spatial one < 6, a point mass < its
    dimension (its orientation then hangs: docs/spec-format.md, under-constrained designs)."""
    if is_point_mass(B):
        return m < (2 if planar else 3)
    return m < (3 if planar else 6)


# ----------------------------------------------------------------------------
# Components
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Winch:
    """Winch of one cable: drum, gearbox and (optionally) a catalogue motor.

    ``drum_radii`` and ``gear_ratios`` hold the candidate values: one value
    for a fixed design, several when sizing should search them.
    """

    drum_radii: tuple[float, ...] = (0.02,)
    gear_ratios: tuple[float, ...] = (1.0,)
    efficiency: float = 1.0
    drum_inertia: float = 0.0
    motor: str | None = None

    @property
    def drum_radius(self) -> float:
        """The drum radius [m] used where one value is needed (the first)."""
        return self.drum_radii[0]

    @property
    def gear_ratio(self) -> float:
        """Motor turns per drum turn used where one value is needed (the first)."""
        return self.gear_ratios[0]


@dataclass(frozen=True)
class Pulley:
    """Swivel pulley at a cable outlet: radius [m] and swivel axis (unit, frame)."""

    radius: float
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class CableProps:
    """Physical cable: model, diameter [m], axial stiffness EA [N], mass per length [kg/m].

    ``model``: ``ideal`` (massless, inextensible, straight), ``elastic``
    (straight, stretched by T/EA) or ``sagging`` (elastic catenary).
    """

    model: str = "ideal"
    diameter: float = 0.0
    axial_stiffness: float | None = None
    mass_per_length: float = 0.0


@dataclass(frozen=True)
class Cable:
    """One cable: outlet a_i (frame), attachment b_i (platform), bounds and hardware."""

    name: str
    outlet: tuple[float, float, float]
    attachment: tuple[float, float, float]
    tension_min: float
    tension_max: float
    winch: Winch = field(default_factory=Winch)
    pulley: Pulley | None = None
    props: CableProps = field(default_factory=CableProps)
    #: planar designs: the cable's plane is z = plane_offset [m] (interference only; 0 for spatial ones)
    plane_offset: float = 0.0


@dataclass(frozen=True)
class Effector:
    """Rigid end effector: mass [kg], box size [m], COM and inertia about the COM.

    ``orientation``: ``fixed`` (held at the commanded orientation) or ``free``
    (hangs where gravity puts it; :mod:`cdpr_design.statics.hanging`).
    """

    mass: float
    size: tuple[float, float, float]
    center_of_mass: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[tuple[float, float, float], ...] = ((0.0,) * 3,) * 3
    orientation: str = "fixed"

    @property
    def inertia_matrix(self) -> np.ndarray:
        return np.array(self.inertia, dtype=float)


@dataclass(frozen=True)
class Grid:
    """Axis-aligned grid of platform positions (dim entries each)."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    step: tuple[float, ...]

    def axes(self) -> list[np.ndarray]:
        """The sample values along each axis (bounds included when on the step)."""
        out = []
        for lo, hi, st in zip(self.lower, self.upper, self.step):
            count = int(np.floor((hi - lo) / st + 1e-9)) + 1
            out.append(lo + st * np.arange(count))
        return out

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(
            int(np.floor((hi - lo) / st + 1e-9)) + 1
            for lo, hi, st in zip(self.lower, self.upper, self.step)
        )

    @property
    def size(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64))

    @property
    def cell(self) -> float:
        """Area [m^2] or volume [m^3] that one grid sample stands for."""
        return float(np.prod(self.step))


@dataclass(frozen=True)
class WrenchBox:
    """Box of external wrench, one value per balanced wrench row [N, N m]."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]


@dataclass(frozen=True)
class OrientationSet:
    """``workspace.orientation_set``: sampled box of orientations (rotation coords [rad])."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    count: tuple[int, ...]


@dataclass(frozen=True)
class OrientationRange:
    """``workspace.orientation_range``: nested boxes nominal +- (k/levels) max [rad]."""

    max: tuple[float, ...]
    levels: int = 10
    count: int = 3


@dataclass(frozen=True)
class WorkspaceSpec:
    grid: Grid
    orientation: tuple[float, ...] = ()
    external_wrench: WrenchBox | None = None
    orientation_set: OrientationSet | None = None
    orientation_range: OrientationRange | None = None


@dataclass(frozen=True)
class Requirements:
    """What the design must achieve (``requirements:``); every field optional."""

    task_box: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    max_speed: float | None = None
    max_acceleration: float | None = None
    min_margin: float | None = None
    min_fraction: float | None = None
    safety_factor: float = 1.0
    #: largest hanging tilt [deg] of an under-constrained effector at a feasible pose
    max_tilt: float | None = None
    #: ``check`` proves the whole task box feasible (interval analysis, ``certify``)
    certified: bool = False
    #: least first string frequency of every cable [Hz] (a lower tension bound 4 f^2 L^2 mu)
    min_cable_frequency: float | None = None
    #: least stiffness [N/m] over the task box (``check``; :mod:`cdpr_design.workspaces.stiffness`)
    min_stiffness: float | None = None
    #: lowest natural frequency [Hz] allowed over the task box
    min_frequency: float | None = None
    #: largest force [N] a cable may put on the frame at its outlet over the feasible workspace grid
    max_frame_load: float | None = None
    #: the box of accelerations [m/s^2, rad/s^2] (lower, upper; one per motion coordinate) reachable from rest
    #: at every pose of a ``dynamic`` workspace
    acceleration: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    #: least acceleration radius [m/s^2] over the task box (:mod:`cdpr_design.statics.acceleration`)
    min_acceleration: float | None = None


@dataclass(frozen=True)
class Trajectory:
    """A named path of the ``trajectories:`` section (validated, not sampled)."""

    name: str
    type: str
    speed: float | None
    acceleration: float | None
    center: tuple[float, ...] | None = None
    side: float | None = None
    radius: float | None = None
    waypoints: tuple[tuple[float, ...], ...] | None = None
    file: str | None = None
    jerk: float | None = None
    cycle_time: float | None = None
    start: tuple[float, ...] | None = None
    laps: int = 1
    orientation: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Plc:
    """ADS link of the ``plc:`` section (names are the PLC's symbols)."""

    ams_net_id: str
    port: int = 851
    host: str | None = None
    cycle_time: float = 0.01
    setpoints: tuple[str, ...] = ()
    actuals: tuple[str, ...] = ()
    tensions: tuple[str, ...] = ()
    pose: str | None = None
    heartbeat: str | None = None
    fault: str | None = None


# ----------------------------------------------------------------------------
# The design
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Design:
    """A validated cable robot design. Build it with :func:`cdpr_design.model.spec.load`.

    ``raw`` keeps the validated spec as plain data (for sweeps, which vary keys
    of the spec and rebuild).
    """

    name: str
    motion: Motion
    gravity: tuple[float, float, float]
    frame_lower: tuple[float, float, float]
    frame_upper: tuple[float, float, float]
    effector: Effector
    cables: tuple[Cable, ...]
    workspace: WorkspaceSpec
    description: str = ""
    requirements: Requirements = field(default_factory=Requirements)
    trajectories: dict[str, Trajectory] = field(default_factory=dict)
    plc: Plc | None = None
    sweep: dict[str, Any] = field(default_factory=dict)
    raw: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    source: str | None = field(default=None, compare=False, repr=False)

    # --- arrays for the kernels (SI, float64, contiguous) -------------------
    @property
    def m(self) -> int:
        """Number of cables."""
        return len(self.cables)

    @property
    def n(self) -> int:
        """Degrees of freedom."""
        return self.motion.n

    @property
    def cable_names(self) -> list[str]:
        return [c.name for c in self.cables]

    @property
    def outlets(self) -> np.ndarray:
        """a_i as an (m, 3) array [m]."""
        return np.array([c.outlet for c in self.cables], dtype=float)

    @property
    def attachments(self) -> np.ndarray:
        """b_i as an (m, 3) array in platform coordinates [m]."""
        return np.array([c.attachment for c in self.cables], dtype=float)

    @property
    def tension_min(self) -> np.ndarray:
        return np.array([c.tension_min for c in self.cables], dtype=float)

    @property
    def tension_max(self) -> np.ndarray:
        return np.array([c.tension_max for c in self.cables], dtype=float)

    @property
    def string_floor(self) -> np.ndarray:
        """(m,) [N/m^2]: the coefficient c_i of the lower tension bound c_i L_i^2 that
        ``requirements.min_cable_frequency`` f sets on each cable of free length L_i
        (:func:`min_string_tension` at L = 1 m); zeros without the requirement or a mass per length."""
        f = self.requirements.min_cable_frequency
        mu = np.array([c.props.mass_per_length or 0.0 for c in self.cables], dtype=float)
        return min_string_tension(1.0, mu, 0.0 if f is None else f)

    @property
    def rows(self) -> np.ndarray:
        return np.array(self.motion.wrench_rows, dtype=np.int64)

    def full_pose(self, pose) -> np.ndarray:
        """A pose in the motion's coordinates as the 6-vector [x, y, z, rx, ry, rz].

        Coordinates the motion does not move take the workspace's fixed
        orientation (rotational motions) or zero.
        """
        pose = np.asarray(pose, dtype=float).reshape(-1)
        if pose.size != len(self.motion.coords):
            raise ValueError(
                f"expected {len(self.motion.coords)} pose coordinates "
                f"({','.join(self.motion.coords)}) for motion {self.motion.name}, got {pose.size}"
            )
        out = np.zeros(6)
        out[list(self.motion.pose_index)] = pose
        return out

    def default_orientation_full(self) -> np.ndarray:
        """The workspace's fixed orientation as (rx, ry, rz) [rad]."""
        out = np.zeros(3)
        ori = self.workspace.orientation
        if self.motion.name == "1R2T" and ori:
            out[2] = ori[0]
        elif self.motion.name == "3R3T" and ori:
            out[:] = ori
        return out

    def replace(self, **changes) -> "Design":
        return dataclasses.replace(self, **changes)
