"""The results of the hanging-effector solvers (:mod:`cdpr_design.statics.hanging`).

:class:`Equilibrium` and :class:`HangingFK` (where the effector rests for
given cable lengths), :class:`HangingPose` (its hanging orientation at a
commanded position), :class:`HangingOrientations` (that orientation at many
positions, with a status code per position: :data:`OK`, ... and
:data:`REASONS`), and the two errors.  Units: SI (m, N, J, rad); ``tilt_deg`` in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.statics.hanging import geometry as hg


#: A stable equilibrium with every tension >= 0 was found.
OK = 0
#: Balanced orientations exist, but each needs a pushing (negative) cable.
PUSHING = 1
#: Balanced orientations with tensions >= 0 exist, but none is stable.
UNSTABLE = 2
#: No orientation balances the weight with the cables taut.
NO_BALANCE = 3
#: Degenerate input: a zero-length cable, or every orientation balances.
DEGENERATE = 4

#: Why a position has no hanging orientation, indexed by status code.
REASONS = (
    "ok",
    "every balanced orientation needs a pushing cable",
    "the balanced orientations with pulling cables are unstable",
    "no orientation balances the weight with the cables taut",
    "degenerate geometry (zero-length cable or indifferent balance)",
)


class UnreachableLengths(InputError):
    """No configuration has every |a_i - p - R b_i| <= rho_i (the reason is the message)."""


class NotUnderconstrained(InputError):
    """The design's cables can fix its orientation: it does not hang freely."""


# ----------------------------------------------------------------------------
# results
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Equilibrium:
    """One equilibrium of the hanging effector.

    Attributes
    ----------
    position : (d,) array
        Platform origin p [m] (d = 2 planar, 3 spatial).
    rotation : (3, 3) array
        R (rotation about z for planar bodies).
    tensions : (m,) array
        Cable tensions [N]; 0 for a slack cable.
    slack : tuple of int
        Indices of the cables that carry no tension.
    energy : float
        Potential energy -m g . (p + R c) [J].
    stable : bool
        Reduced Hessian positive definite (or the taut cables lock the pose).
        False with ``hessian_min`` ~ 0 is a neutral equilibrium: a continuum
        of poses of equal energy (e.g. a body free to turn about an axis
        through its taut attachments and its centre of mass).
    hessian_min : float
        Smallest eigenvalue of the reduced Hessian (inf when locked) [N/m and
        N m/rad mixed: the chart is (dp [m], w [rad])].
    residual : float
        Largest force [N] / moment [N m] imbalance after refinement.
    length_error : float
        Largest | |l_i| - rho_i | over the taut cables [m].
    indeterminate : bool
        More taut cables than the pose has degrees of freedom and they lock
        it: the tensions are not unique (the minimum-norm non-negative ones
        are reported, and ``slack`` lists the cables they leave at zero).
    planar : bool
    up : tuple
        -g / |g|, the frame's vertical (for ``tilt_deg``).
    within_limits : bool or None
        Tensions within the design's [tension_min, tension_max] (set by the
        Design-level functions; None for plain arrays or indeterminate tensions).
    """

    position: np.ndarray
    rotation: np.ndarray
    tensions: np.ndarray
    slack: tuple[int, ...]
    energy: float
    stable: bool
    hessian_min: float
    residual: float
    length_error: float = 0.0
    indeterminate: bool = False
    planar: bool = True
    up: tuple = (0.0, 0.0, 1.0)
    within_limits: bool | None = None

    @property
    def orientation(self):
        """phi [rad] about z (planar) or [rx, ry, rz] [rad], R = Rx Ry Rz (spatial)."""
        return orientation_of(self.rotation, self.planar)

    @property
    def tilt_deg(self) -> float:
        """Tilt away from level [deg]: the angle between the platform's vertical R up and
        the frame's up = -g/|g| (|phi| for planar bodies; a turn about the vertical is no tilt)."""
        return tilt_of(self.rotation, self.up)

    @property
    def pose(self) -> np.ndarray:
        """[x, y, phi] (planar) or [x, y, z, rx, ry, rz] (spatial) [m, rad]."""
        ori = self.orientation
        return np.concatenate([self.position, [ori] if self.planar else ori])

    def to_dict(self) -> dict:
        return {"position": self.position.tolist(), "orientation": self.orientation,
                "tilt_deg": self.tilt_deg, "tensions": self.tensions.tolist(),
                "slack": list(self.slack), "energy": self.energy, "stable": self.stable,
                "hessian_min": self.hessian_min, "residual": self.residual,
                "indeterminate": self.indeterminate, "within_limits": self.within_limits}


@dataclass(frozen=True)
class HangingFK(Equilibrium):
    """:func:`~cdpr_design.statics.hanging.forward.fk_arrays`: the lowest-energy equilibrium,
    plus every other stable one found.

    ``equilibria`` holds the other stable equilibria (each an
    :class:`Equilibrium` with its ``energy``), lowest energy first; ``model``
    is ``point``, ``held`` or ``rigid``; ``underconstrained`` whether the cables leave the
    orientation free (:func:`~cdpr_design.model.design.is_underconstrained`).
    """

    equilibria: tuple = ()
    model: str = "rigid"
    underconstrained: bool = True

    def to_dict(self) -> dict:
        d = super().to_dict()
        d.update(model=self.model, underconstrained=self.underconstrained,
                 equilibria=[e.to_dict() for e in self.equilibria])
        return d


@dataclass(frozen=True)
class HangingPose:
    """:func:`~cdpr_design.statics.hanging.design.hanging_pose`: the hanging orientation at a commanded position.

    ``feasible`` False comes with ``reason``; then orientation fields are NaN.
    ``lengths`` [m] are the cable lengths that put the effector there;
    ``alternatives`` the other balanced orientations found, as
    (orientation, tensions, stable) tuples; ``within_limits`` as for
    :class:`Equilibrium` (tension limits are not part of feasibility).
    """

    feasible: bool
    reason: str
    position: np.ndarray
    rotation: np.ndarray
    tensions: np.ndarray
    stable: bool
    hessian_min: float
    lengths: np.ndarray
    planar: bool = True
    alternatives: tuple = field(default=())
    up: tuple = (0.0, 0.0, 1.0)
    within_limits: bool | None = None

    @property
    def orientation(self):
        """phi [rad] (planar) or [rx, ry, rz] [rad] (spatial); NaN when infeasible."""
        if not self.feasible:
            return math.nan if self.planar else [math.nan] * 3
        return Equilibrium.orientation.fget(self)

    @property
    def tilt_deg(self) -> float:
        """Tilt from level [deg] as :attr:`Equilibrium.tilt_deg`; NaN when infeasible."""
        return tilt_of(self.rotation, self.up) if self.feasible else math.nan

    @property
    def pose(self) -> np.ndarray:
        """[x, y, phi] (planar) or [x, y, z, rx, ry, rz] (spatial) [m, rad]."""
        ori = self.orientation
        return np.concatenate([self.position, [ori] if self.planar else ori])

    def to_dict(self) -> dict:
        return {"feasible": self.feasible, "reason": self.reason, "position": self.position.tolist(),
                "orientation": self.orientation, "tilt_deg": self.tilt_deg,
                "tensions": self.tensions.tolist(), "stable": self.stable, "lengths": self.lengths.tolist(),
                "within_limits": self.within_limits}


@dataclass
class HangingOrientations:
    """The hanging orientation at k positions.

    ``rotation`` (k, 3, 3) and ``tensions`` (k, m) [N] are NaN where
    ``status`` (k,) is not :data:`OK`; ``hessian_min`` (k,) the smallest
    eigenvalue of the reduced Hessian there; ``up`` the frame's unit vertical
    (-g/|g|).  ``alternatives`` (when asked for) holds, per position, the
    other balanced orientations found with tensions >= 0, as (rotation,
    tensions, stable) tuples.
    """

    rotation: np.ndarray
    tensions: np.ndarray
    status: np.ndarray
    hessian_min: np.ndarray
    planar: bool
    up: np.ndarray
    alternatives: list = field(default_factory=list)

    @classmethod
    def joined(cls, parts: list["HangingOrientations"]) -> "HangingOrientations":
        """The answers of consecutive runs of positions (``parts`` in order) as one."""
        first = parts[0]
        return cls(*(np.concatenate([getattr(h, name) for h in parts])
                     for name in ("rotation", "tensions", "status", "hessian_min")),
                   first.planar, first.up, [a for h in parts for a in h.alternatives])

    @property
    def feasible(self) -> np.ndarray:
        return self.status == OK

    @property
    def tilt_deg(self) -> np.ndarray:
        """Angle [deg] between the platform's vertical R up and up; NaN where it cannot hang."""
        return hg.tilt_many(self.rotation, self.up)

    @property
    def orientation(self) -> np.ndarray:
        """phi (k,) [rad] about z (planar) or (k, 3) [rx, ry, rz] [rad], R = Rx Ry Rz (spatial)."""
        if self.planar:
            return np.arctan2(self.rotation[:, 1, 0], self.rotation[:, 0, 0])
        return hg.euler_xyz(self.rotation)


def orientation_of(R, planar: bool):
    """phi [rad] about z (planar) or [rx, ry, rz] [rad] with R = Rx Ry Rz (spatial)."""
    if planar:
        return float(math.atan2(R[1, 0], R[0, 0]))
    return [float(a) for a in hg.euler_xyz(R)]


def tilt_of(R, up) -> float:
    """The angle [deg] between R up and up (up a unit vector): the tilt from level."""
    return float(hg.tilt_many(np.asarray(R, float), up))
