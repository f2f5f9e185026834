"""Set-points of real cables along a sampled path: sag and stretch compensation.

With ideal cables a winch commands the chord length L from outlet to
attachment.  A real cable is stretched by its tension and, when heavy, hangs
below its chord, so the length the winch must pay out is the cable's
*unstretched* length L0 at that sample (docs/cable-models.md):

- ``elastic``: straight cables, L0 = L / (1 + T/EA) with the sample's
  tensions T (gravity and the effector's inertia);
- ``sagging``: Irvine's elastic catenary, L0 from the sagging statics of the
  sample (:func:`cdpr_design.statics.cables.sagging_samples`) under the same
  required wrench; the tensions become the effector-end ones.

The error an ideal set-point would cause is ``L - L0`` [m] per cable and
sample (positive: the chord pays out too much cable, as a stretched cable
does; negative: too little, as a slack, sagging cable needs more than its
chord).  Samples where the cable model has no solution carry NaN and a
status, never a number.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.statics import cables
from cdpr_design.statics.robot import Robot


@dataclass(frozen=True)
class CableSamples:
    """The cable model's per-sample results (k samples, m cables; NaN where there is no solution).

    Attributes
    ----------
    model : str
        ``elastic`` or ``sagging``.
    unstretched : (k, m) array
        Unstretched lengths L0 [m]: the set-points a winch must command.
    setpoint_error : (k, m) array
        Chord length minus L0 [m]: the error of an ideal set-point.
    outlet_tensions : (k, m) array
        Tensions at the outlet [N] (the winch side; the effector-end ones for straight cables).
    sag : (k, m) array
        Largest distance of each cable from its chord [m] (0 for straight cables).
    status : (k,) int array or None
        Sagging: index into :data:`cdpr_design.statics.cables.STATUS` (0 = solved).
    """

    model: str
    unstretched: np.ndarray
    setpoint_error: np.ndarray
    outlet_tensions: np.ndarray
    sag: np.ndarray
    status: np.ndarray | None = None

    @property
    def solved(self) -> np.ndarray:
        """(k,) bool: every cable has a set-point (L0 finite)."""
        return np.all(np.isfinite(self.unstretched), axis=1)

    def columns(self, names) -> dict[str, np.ndarray]:
        """Table columns, after the straight model's: ``outlet_tension_<c>`` [N],
        ``unstretched_length_<c>`` [m], ``sag_<c>`` [m], ``setpoint_error_<c>`` [m], and
        ``cable_status`` (sagging)."""
        out: dict[str, np.ndarray] = {}
        for key, arr in (("outlet_tension", self.outlet_tensions), ("unstretched_length", self.unstretched),
                         ("sag", self.sag), ("setpoint_error", self.setpoint_error)):
            for i, c in enumerate(names):
                out[f"{key}_{c}"] = arr[:, i]
        if self.status is not None:
            out["cable_status"] = self.status.astype(np.int64)
        return out

    def summary(self, names) -> dict:
        """JSON keys: ``cable_model``, ``max_setpoint_error`` [m] (largest |L - L0| per cable),
        ``max_outlet_tension`` [N] per cable (None where no sample has a number), ``unsolved_samples``."""
        def per_cable(values):
            out = {}
            for i, c in enumerate(names):
                v = values[:, i]
                v = v[np.isfinite(v)]
                out[c] = float(v.max()) if v.size else None
            return out

        return {"cable_model": self.model, "max_setpoint_error": per_cable(np.abs(self.setpoint_error)),
                "max_outlet_tension": per_cable(self.outlet_tensions),
                "unsolved_samples": int(np.count_nonzero(~self.solved))}


def cable_samples(robot: Robot, positions, Rb, wreq, lengths, tensions, feasible):
    """The cable model of ``robot`` (resolved for ``motion``) along a path: (CableSamples, tensions (k, m) [N], feasible (k,)).

    ``positions`` (k, 3) [m], ``Rb`` (k, m, 3) rotated attachments [m],
    ``wreq`` (k, n) the wrench the cables exert [N, N m], ``lengths`` (k, m)
    chords [m], ``tensions`` and ``feasible`` the straight model's.  Elastic
    cables keep the straight tensions (a pushing cable has no length: NaN);
    sagging cables replace them by the catenaries' effector-end tensions and
    the feasibility by the whole-cable bounds.  None for ideal designs (``robot.cables``: the
    heaviest of the cables' models).
    """
    model = robot.cables
    if model.rigid:
        return None, tensions, feasible
    if model.stretches:
        t = np.where(tensions >= 0.0, tensions, np.nan)
        L0 = cables.elastic_unstretched(lengths, t, robot.cable.EA)
        sag = np.where(np.isfinite(t), 0.0, np.nan)
        return CableSamples(model.name, L0, lengths - L0, t, sag), tensions, feasible
    s = cables.sagging_samples(robot, positions, Rb, wreq)
    res = CableSamples(model.name, s.unstretched_lengths, lengths - s.unstretched_lengths, s.outlet_tensions, s.sag,
                       s.status.astype(np.int64))
    return res, s.tensions, s.feasible
