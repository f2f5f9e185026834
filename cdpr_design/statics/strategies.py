"""The strategies of a resolved robot: its cable model, its outlets and how its effector's
orientation is decided, each an object bound once by :func:`cdpr_design.statics.robot.resolve`.

Every layer below the resolution asks the robot's strategy objects what it needs (a
predicate, a set of columns, a geometry) instead of comparing a name:

- :class:`CableModel` (``robot.cables``): :data:`IDEAL`, :data:`ELASTIC`, :data:`SAGGING`
  (docs/cable-models.md);
- :class:`Outlets` (``robot.outlets``): :data:`POINTS`, :data:`PULLEYS` (swivel pulleys of
  positive radius, :mod:`cdpr_design.statics.pulley`): the cables' lengths, free lengths,
  pulling directions and structure matrix;
- :class:`Orientation` (``robot.orientation``): :data:`COMMANDED`, :data:`HELD`,
  :data:`HANGING`.

Each has a ``name`` (the string the outputs report, e.g. ``cable_model`` in ``summary.json``);
``str()`` gives it too.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics.degenerate import MIN_CABLE_LENGTH

#: The kind of workspace under which sagging cables take their chords (tensions grow without bound).
CLOSURE = "wrench-closure"


class Strategy:
    """A named strategy (its ``name`` is what the outputs report)."""

    def __init__(self, name: str):
        self.name = name

    def __str__(self) -> str:
        return self.name

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"


class CableModel(Strategy):
    """How the cables carry their load (docs/cable-models.md).

    ``straight``: the cables are straight lines from outlet to attachment (ideal, elastic);
    ``rigid``: inextensible and weightless (ideal): the length is the chord, and the cables
    have no state beside their tension."""

    def __init__(self, name: str, straight: bool = True, rigid: bool = True):
        super().__init__(name)
        self.straight, self.rigid = straight, rigid

    def sags(self, kind: str) -> bool:
        """Whether the statics of ``kind`` solve each cable's catenary (sagging cables, every kind
        but wrench closure, under which they take their chords)."""
        return False

    def chords(self, kind: str) -> bool:
        """Whether the cables sag but ``kind`` takes their chords (no shapes: the cable-state
        columns are NaN)."""
        return False

    @property
    def stretches(self) -> bool:
        """Whether the statics are straight and the cables stretch (elastic): the ideal tensions,
        and the unstretched lengths beside."""
        return self.straight and not self.rigid

    def state_columns(self, names) -> list[str]:
        """The table columns of the cables' state, per cable c of ``names``: ``outlet_tension_<c>``
        [N], ``unstretched_length_<c>`` [m], ``sag_<c>`` [m] (none for rigid cables)."""
        if self.rigid:
            return []
        return ([f"outlet_tension_{c}" for c in names] + [f"unstretched_length_{c}" for c in names]
                + [f"sag_{c}" for c in names])


class _Sagging(CableModel):
    """Heavy elastic cables: each takes its catenary, but under wrench closure its chord."""

    def sags(self, kind: str) -> bool:
        return kind != CLOSURE

    def chords(self, kind: str) -> bool:
        return kind == CLOSURE

    def state_columns(self, names) -> list[str]:
        """As :meth:`CableModel.state_columns`, and ``cable_status`` (an index into
        :data:`cdpr_design.statics.cables.STATUS`)."""
        return super().state_columns(names) + ["cable_status"]


IDEAL, ELASTIC = CableModel("ideal"), CableModel("elastic", rigid=False)
SAGGING = _Sagging("sagging", straight=False, rigid=False)
#: Cable models, lightest first (docs/cable-models.md).
CABLE_MODELS: tuple[CableModel, ...] = (IDEAL, ELASTIC, SAGGING)


class Outlets(Strategy):
    """How the cables leave the frame: at points, or over swivel pulleys (``pulleys``).

    The geometry of straight cables at many poses, as the layers above take it: lengths L [m]
    (arc + free segment over a pulley), free lengths [m] (from the tangent point, else the
    outlet, to the attachment) and the free segments' unit pulling directions u (zero where a
    free length is at most :data:`~cdpr_design.statics.degenerate.MIN_CABLE_LENGTH`)."""

    pulleys = False

    def structure(self, robot, full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The structure matrix W (n, m) of ``robot``'s straight cables at a full pose [x, y, z,
        rx, ry, rz] [m, rad] and their free lengths (m,) [m] (the sweep kernels' geometry: true
        outlet points); W's columns are unspecified where a cable has zero length."""
        from cdpr_design import kernels as K  # numba, on first use
        from cdpr_design.statics import kinematics as kin

        Rb = np.ascontiguousarray(robot.attachments @ kin.rotation_matrix(*full[3:]).T)
        W, L = np.empty((robot.n, robot.m)), np.empty(robot.m)
        K.structure_matrix(full[0], full[1], full[2], Rb, robot.outlet_points, robot.rows, W, L)
        return W, L

    def envelope_paths(self, design, positions: np.ndarray, Rb: np.ndarray):
        """(L, free lengths, u, kappa) (k, m), (k, m), (k, m, 3), (k, m) with the effector at
        ``positions`` (k, 3) [m] and its attachments rotated to ``Rb`` (k or 1, m, 3) [m]: kappa
        [1/m] bounds each length's second derivative, |v^T H_i v| <= kappa_i |v|^2 (1 / L_i for a
        point outlet)."""
        vec = design.outlets[None, :, :] - positions[:, None, :] - Rb
        L = free = np.linalg.norm(vec, axis=2)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = vec / L[:, :, None]
            kappa = 1.0 / L
        u[L <= MIN_CABLE_LENGTH] = 0.0
        return L, free, u, kappa

    def motion_paths(self, design, positions: np.ndarray, Rb: np.ndarray, vB: np.ndarray, aB: np.ndarray):
        """(L, free lengths, u, dL/dt [m/s], d2L/dt2 [m/s^2]) of every cable with the effector at
        ``positions`` (k, 3) [m], its attachments rotated to ``Rb`` (k, m, 3) [m] and moving with
        velocities ``vB`` [m/s] and accelerations ``aB`` [m/s^2] (k, m, 3)."""
        from cdpr_design.statics.degenerate import directions

        vec = design.outlets[None, :, :] - positions[:, None, :] - Rb
        L = np.linalg.norm(vec, axis=2)
        u = directions(vec, L)  # zero for a cable of zero length: a degenerate sample
        Ld = -np.einsum("kmi,kmi->km", u, vB)
        with np.errstate(invalid="ignore", divide="ignore"):
            Ldd = (np.einsum("kmi,kmi->km", vB, vB) - Ld ** 2) / L - np.einsum("kmi,kmi->km", u, aB)
        return L, L, u, Ld, Ldd


class _Pulleys(Outlets):
    """Swivel pulleys: arc + free length, u along the free segment from the tangent point
    (:mod:`cdpr_design.statics.pulley`)."""

    pulleys = True

    def structure(self, robot, full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from cdpr_design import kernels as K  # numba, on first use
        from cdpr_design.statics import kinematics as kin
        from cdpr_design.statics.hardware import hardware_arrays

        Rb = np.ascontiguousarray(robot.attachments @ kin.rotation_matrix(*full[3:]).T)
        W, L = np.empty((robot.n, robot.m)), np.empty(robot.m)
        hw = hardware_arrays(robot.design)
        C = np.empty((robot.m, 3))
        K.structure_matrix_pulley(full[0], full[1], full[2], Rb, robot.outlet_points, hw.axes, hw.eref, hw.radii,
                                  robot.rows, W, L, C)
        return W, np.linalg.norm(full[:3] + Rb - C, axis=1)

    def envelope_paths(self, design, positions: np.ndarray, Rb: np.ndarray):
        """As :meth:`Outlets.envelope_paths`; kappa = max(1 / l_f, |kappa_t|)
        (:meth:`~cdpr_design.statics.pulley.CablePaths.max_curvature`)."""
        from cdpr_design.statics import pulley as pl

        paths = pl.design_cable_paths(design, positions[:, None, :] + Rb)
        u = paths.directions.copy()
        u[~(paths.free_lengths > MIN_CABLE_LENGTH)] = 0.0
        return paths.lengths, paths.free_lengths, u, paths.max_curvature()

    def motion_paths(self, design, positions: np.ndarray, Rb: np.ndarray, vB: np.ndarray, aB: np.ndarray):
        from cdpr_design.statics import pulley as pl

        cp = pl.design_cable_paths(design, positions[:, None, :] + Rb)
        u = np.nan_to_num(cp.directions)
        u[~(cp.free_lengths > MIN_CABLE_LENGTH)] = 0.0  # no direction: a degenerate sample
        Ld = -np.einsum("kmi,kmi->km", u, vB)
        Ldd = cp.second_derivative(vB) - np.einsum("kmi,kmi->km", u, aB)
        return cp.lengths, cp.free_lengths, u, Ld, Ldd


POINTS, PULLEYS = Outlets("points"), _Pulleys("pulleys")


class Orientation(Strategy):
    """How the effector's orientation is decided.

    ``commanded``: the command fixes it; ``held``: an under-constrained effector held at the
    commanded orientation, the tilt it would hang with reported beside (``tilt_beside``);
    ``hanging`` (``free``): ``effector.orientation: free``, it hangs where the cables and
    gravity put it, within the tilt limit.  ``free``: the orientation is found by hanging (the
    statics depend on it); ``tilt_beside``: the tilt the effector would hang with is reported
    beside the commanded orientation."""

    def __init__(self, name: str, free: bool = False, tilt_beside: bool = False):
        super().__init__(name)
        self.free, self.tilt_beside = free, tilt_beside


COMMANDED = Orientation("commanded")
HELD = Orientation("held", tilt_beside=True)
HANGING = Orientation("hanging", free=True)
