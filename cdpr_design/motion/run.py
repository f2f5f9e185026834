"""A sampled trajectory run on the simulated robot (:class:`cdpr_design.motion.simulation.Simulator`).

The set-points of sample k are issued at ``time[k]`` and held as a ramp for one
cycle; the state is recorded at every sample time.  With ideal cables the
set-points are the chord lengths, with their speeds as feed-forward and the
trajectory's inertial tensions as stretch compensation.  With elastic or
sagging cables they are the cable model's unstretched lengths
(:mod:`cdpr_design.motion.setpoints`), or, without stretch compensation, the
chord lengths (to see the error ideal set-points cause).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.statics.robot import Robot


@dataclass(frozen=True)
class SimulationResult:
    """A simulated run of a sampled trajectory (k samples).

    Attributes
    ----------
    time : (k,) array [s]
    target_pose, pose : (k, ncoords) arrays
        Set-point pose and simulated effector pose.
    orientation : (k, 3) array
        Simulated (rx, ry, rz) [rad] (the tilt of a planar effector is column 2).
    target_lengths, lengths, axis, tensions : (k, m) arrays
        Set-point lengths, simulated cable lengths, winch positions [m] and tensions [N].
    segment : (k,) int array
        Straight-segment id of each sample (-1: not a straight line).
    cable_model : str
        The design's cable model (:mod:`cdpr_design.statics.cables`).
    setpoints, outlet_tensions : (k, m) arrays or None
        With elastic or sagging cables: the axis set-points commanded
        (unstretched lengths, or the chords without stretch compensation) [m]
        and the simulated outlet tensions [N]; ``target_lengths`` are then the
        target pose's chords and ``tensions`` the effector-end ones.
    """

    name: str
    coords: tuple[str, ...]
    cable_names: tuple[str, ...]
    time: np.ndarray
    target_pose: np.ndarray
    pose: np.ndarray
    orientation: np.ndarray
    target_lengths: np.ndarray
    lengths: np.ndarray
    axis: np.ndarray
    tensions: np.ndarray
    segment: np.ndarray
    settings: dict = field(default_factory=dict)
    cable_model: str = "ideal"
    setpoints: np.ndarray | None = None
    outlet_tensions: np.ndarray | None = None

    def columns(self) -> dict[str, np.ndarray]:
        """The ``simulation.csv`` columns of the CLI contract, in order (extra ones last)."""
        out: dict[str, np.ndarray] = {"time": self.time}
        for j, c in enumerate(self.coords):
            out[f"{c}_target"] = self.target_pose[:, j]
        for j, c in enumerate(self.coords):
            out[c] = self.pose[:, j]
        for i, c in enumerate(self.cable_names):
            out[f"length_{c}_target"] = self.target_lengths[:, i]
        for i, c in enumerate(self.cable_names):
            out[f"length_{c}"] = self.lengths[:, i]
        for i, c in enumerate(self.cable_names):
            out[f"tension_{c}"] = self.tensions[:, i]
        for i, c in enumerate(self.cable_names):
            out[f"axis_{c}"] = self.axis[:, i]
        for j, c in enumerate(("rx", "ry", "rz")):
            if c not in self.coords and not (c == "rz" and "phi" in self.coords):
                out[f"tilt_{c}"] = self.orientation[:, j]
        out["segment"] = self.segment
        if self.setpoints is not None:
            for i, c in enumerate(self.cable_names):
                out[f"setpoint_{c}"] = self.setpoints[:, i]
            for i, c in enumerate(self.cable_names):
                out[f"outlet_tension_{c}"] = self.outlet_tensions[:, i]
        return out

    def comparison(self, max_delay: float | None = None):
        """Delay, errors and the per-segment table of target vs simulated (see :mod:`compare`)."""
        from cdpr_design.motion.compare import compare

        tgt, act = {}, {}
        for j, c in enumerate(self.coords):
            tgt[c], act[c] = self.target_pose[:, j], self.pose[:, j]
        for i, c in enumerate(self.cable_names):
            tgt[f"length_{c}"], act[f"length_{c}"] = self.target_lengths[:, i], self.lengths[:, i]
        return compare(self.time, tgt, self.time, act, segment_ids=self.segment, max_delay=max_delay)

    def summary(self, max_delay: float | None = None) -> dict:
        """JSON summary: ``rms_error``, ``max_error`` [m], ``delay`` [s] per column, ``segments``."""
        cmp = self.comparison(max_delay)
        out = cmp.to_json()
        out = {"name": self.name, **out}
        out["max_tension"] = {c: float(np.max(self.tensions[:, i])) for i, c in enumerate(self.cable_names)}
        out["min_tension"] = {c: float(np.min(self.tensions[:, i])) for i, c in enumerate(self.cable_names)}
        out["max_tilt"] = float(np.max(np.abs(self.orientation))) if not self.design_rotational else None
        out["samples"] = int(self.time.size)
        out["settings"] = dict(self.settings)
        if self.setpoints is not None:
            out["cable_model"] = self.cable_model
            out["max_outlet_tension"] = {c: float(np.max(self.outlet_tensions[:, i]))
                                         for i, c in enumerate(self.cable_names)}
        return out

    @property
    def design_rotational(self) -> bool:
        return any(c in self.coords for c in ("phi", "rx", "ry", "rz"))


def cable_setpoints(samples, compensate_stretch: bool = True):
    """(set-points (k, m) [m], speeds (k, m) [m/s], real-cable model or None) of a sampled path:
    what a winch is commanded, by ``simulate`` and by the gateway's test PLC alike.
    Ideal cables (or ``compensate_stretch`` off): the chord lengths; elastic or sagging
    cables: the cable model's unstretched lengths.

    The speeds are the chord speeds in every case: the unstretched lengths follow them but for
    their stretch and sag, which step with the tensions where the path's acceleration does.

    Raises ValueError when a sample has no set-point (its cable model has no solution).
    """
    cs = getattr(samples, "cables", None)
    if cs is None or not compensate_stretch:
        return samples.lengths, samples.cable_speed, cs
    sp = cs.unstretched
    bad = ~np.all(np.isfinite(sp), axis=1)
    if np.any(bad):
        j = int(np.argmax(bad))
        raise ValueError(f"{int(bad.sum())} samples have no {cs.model} cable set-points (the cable model has "
                         f"no solution there), the first at t = {samples.time[j]:.6g} s")
    return sp, samples.cable_speed, cs


def simulate(robot: Robot, samples, *, timestep: float = 5e-4, servo_bandwidth: float = 300.0,
             delay: float = 0.0, cable_damping: float = 0.7, joint_damping: float = 0.05,
             feedforward: bool = True, compensate_stretch: bool = True, settle: float = 3.0,
             progress=None, cable_segments: int | None = None) -> SimulationResult:
    """Run a sampled trajectory on the simulated robot.

    Set-point k (lengths, their speeds as feed-forward, the trajectory's
    inertial tensions as stretch compensation) is issued at ``time[k]`` and
    held as a ramp for one cycle; the state is recorded at every sample time.
    Add hold time to the trajectory (``trajectory.sample(..., hold_end=...)``)
    to see a delayed robot finish its motion.  With elastic or sagging cables
    the set-points are the samples' unstretched lengths (``samples.cables``;
    ValueError where one has none), or the chords if ``compensate_stretch``
    is off.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``motion`` (:func:`~cdpr_design.statics.robot.resolve`).
    samples : trajectory.Samples
    progress : callable, optional
        Called as ``progress(done, total)`` every few hundred samples.
    cable_segments : int, optional
        Segments of each massive cable (default
        :data:`cdpr_design.motion.simulation.DEFAULT_CABLE_SEGMENTS`).
    Other parameters: see :class:`cdpr_design.motion.simulation.Simulator`.
    """
    from cdpr_design.motion.simulation import DEFAULT_CABLE_SEGMENTS, Simulator

    sp, vel, cs = cable_setpoints(samples, compensate_stretch)
    sim = Simulator(robot, timestep=timestep, servo_bandwidth=servo_bandwidth, delay=delay,
                    cable_damping=cable_damping, joint_damping=joint_damping,
                    feedforward=feedforward, compensate_stretch=compensate_stretch,
                    cable_segments=cable_segments or DEFAULT_CABLE_SEGMENTS)
    k = samples.time.size
    dt = samples.cycle_time
    sim.reset(samples.pose[0], settle=settle, setpoints=None if cs is None else sp[0])
    nc, m = samples.pose.shape[1], sim.m
    pose = np.empty((k, nc))
    ori = np.empty((k, 3))
    lengths, axis, tens, outlet = (np.empty((k, m)) for _ in range(4))

    def record(j, s):
        pose[j], ori[j], lengths[j], axis[j], tens[j] = s.pose, s.orientation, s.lengths, s.axis, s.tensions
        outlet[j] = s.outlet_tensions

    record(0, sim.state())
    T = samples.tensions
    for j in range(k - 1):
        s = sim.advance(sp[j], dt, velocity=vel[j], tension=T[j] if np.all(np.isfinite(T[j])) else None)
        record(j + 1, s)
        if progress is not None and (j % 500 == 0 or j == k - 2):
            progress(j + 1, k - 1)
    settings = {"timestep": timestep, "servo_bandwidth": servo_bandwidth, "delay": delay,
                "cable_damping": cable_damping, "joint_damping": joint_damping,
                "feedforward": feedforward, "compensate_stretch": compensate_stretch,
                "cycle_time": dt, "axial_stiffness": [float(v) for v in sim.EA]}
    if sim.cable_segments:
        settings["cable_segments"] = sim.cable_segments
    extra = {} if cs is None else {"cable_model": cs.model, "setpoints": np.array(sp, float),
                                   "outlet_tensions": outlet}
    return SimulationResult(samples.name, tuple(samples.coords), tuple(samples.cable_names),
                            samples.time.copy(), samples.pose.copy(), pose, ori,
                            samples.lengths.copy(), lengths, axis, tens, _line_segments(samples), settings,
                            **extra)


def _line_segments(samples) -> np.ndarray:
    """Straight-segment id of each sample while its target moves (holds at the ends excluded), else -1."""
    seg = samples.segment.copy()
    kinds = {s.index: s.kind for s in samples.segments}
    seg = np.array([v if kinds.get(int(v)) == "line" else -1 for v in seg], dtype=np.int64)
    for sgm in samples.segments:
        sel = samples.segment == sgm.index
        sel[: sgm.first] = False
        sel[sgm.last + 1:] = False
        seg[(samples.segment == sgm.index) & ~sel] = -1
    return seg


__all__ = ["SimulationResult", "simulate"]
