"""Physics simulation of a cable robot with MuJoCo (headless).

The model, built from the design alone:

- **Effector**: a rigid body with the spec's mass, centre of mass and inertia.
  Planar designs move in the z = 0 plane on three joints (slide x, slide y,
  hinge z), so the under-constrained planar robot can swing and *tilt* as the
  real one does even for motion ``2T``; spatial designs have a free joint.
  No contacts.
- **Cables**: one spatial tendon per cable from a site at the outlet a_i to a
  site at the attachment b_i, driven by a position actuator whose force is
  limited to [-F, 0]: the cable pulls (tension = -force) but never pushes, so
  a slack cable carries exactly zero tension.  Its gain is the cable's axial
  stiffness k_i = EA / L0_i with L0_i the unstretched length paid out, updated
  every step, and its damping k_v,i = 2 zeta sqrt(k_i m) (``cable_damping`` =
  zeta).  Cable mass is not modelled here.
- **Massive cables** (cable model ``sagging`` with a mass per length): a
  1-D flex of ``cable_segments`` elastic segments between point masses from
  the outlet to the attachment, whose rest lengths the winch sets
  (:mod:`cdpr_design.motion.mjcf`); its tendon and actuator only measure the
  chord.
- **Swivel pulleys** (``cables[i].pulley``, :mod:`cdpr_design.statics.pulley`): the
  arc wrapped on the pulley is not a MuJoCo wrapping object.  The tendon runs
  from a mocap site that the simulator moves, before every physics step, to
  the pulley's tangent point C_i for the current attachment point, and the
  actuator's length is the tendon's (free segment) plus the arc r beta_i, so
  the cable's length, its stretch and the direction it pulls (from the
  attachment towards C_i) are those of the analysis (arc + free segment;
  the tendon's velocity, the attachment's velocity along u_i, is dL/dt
  because the mocap site carries no degree of freedom).  The pulley's
  inertia and friction and the cable's bending on it are not modelled.
- **Winch axes**: each axis position q_i (the unstretched cable length it has
  paid out, m) follows its set-point r_i through a first-order position loop
  with velocity feed-forward, dq/dt = v_ff + omega_c (r - q) (``servo_bandwidth``
  = omega_c in rad/s), where the set-point is held as a ramp with the
  set-point velocity between cycles.  An optional transport delay puts the
  set-points through a FIFO (the seed paper's communication path added
  110-150 ms, its Table 1).
- **Command to the cable actuator**: q_i - T_ff,i / k_i + (k_v,i / k_i) dq_i/dt,
  i.e. the expected static stretch T_ff / k is taken up (``compensate_stretch``)
  and the actuator damping acts on the cable's velocity *relative to the
  winch*, so it does not make the effector lag (MuJoCo cable modelling notes
  in the project's algorithms reference).
- **Real cables** (``elastic`` or ``sagging``): the set-points are the cable
  model's unstretched lengths (:mod:`cdpr_design.motion.setpoints`), which
  already hold the stretch, so T_ff / k is taken up only on ideal cables.

Lengths reported by :meth:`Simulator.state` are the geometric (stretched)
cable lengths from outlet to attachment (with a pulley: arc + free segment);
``axis`` holds the winch positions q.

Typical use (the PLC bridge does the same, one cycle at a time)::

    sim = Simulator(resolve(design, Analysis(command="motion")), delay=0.13)
    sim.reset([0.65, 0.75])                  # at rest, settled under gravity
    for k in range(n):
        s = sim.advance(setpoint_lengths[k], 0.001)   # -> SimState
        print(s.time, s.pose, s.lengths, s.tensions)

References
----------
Rivera, Garrido, Riveiro, Silva: "Environment for the Design and Automation
of New CDPR Architectures" (seed paper): section 3 (simulated model: prismatic
joint free in compression, locked in traction), section 4 and Table 1 (delays).
MuJoCo documentation: spatial tendons, position actuators, ``forcerange``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from cdpr_design.motion.mjcf import Chains, build_xml, massive_cables
from cdpr_design.statics import cables as cm
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import pulley as pl
from cdpr_design.statics.robot import Robot

#: Segments of each massive cable (``cable_segments``): the chain's end forces
#: differ from the catenary's by O((L/N)^2) (tests/test_simulation_cables.py).
DEFAULT_CABLE_SEGMENTS = 16

DEFAULT_AXIAL_STIFFNESS = 1.0e5
"""EA [N] used when the spec gives no ``cable.axial_stiffness``."""

_BAD_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
                 mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADCTRL)


class SimulationError(RuntimeError):
    """The physics became unstable (MuJoCo reported NaN/huge values and reset the state)."""


@dataclass(frozen=True)
class SimState:
    """State of the simulated robot at one instant.

    Attributes
    ----------
    time : float
        Simulated time [s] since :meth:`Simulator.reset`.
    pose : (ncoords,) array
        Effector pose in the motion's coordinates [m, rad].
    orientation : (3,) array
        Actual (rx, ry, rz) [rad], xyz Euler (R = Rx Ry Rz), whatever the
        motion type (the tilt of a 2T effector is ``orientation[2]``).
    velocity : (6,) array
        Linear [m/s] and angular [rad/s] velocity of the platform origin (frame).
    lengths : (m,) array
        Geometric cable lengths outlet to attachment [m].
    tensions : (m,) array
        Cable tensions [N], >= 0 (0 when slack).
    axis : (m,) array
        Winch positions q: unstretched length paid out [m].
    setpoints : (m,) array
        Set-points the axes are following now (after the delay) [m].
    outlet_tensions : (m,) array or None
        Tensions at the outlet [N]: those of the massive cables' first
        segments with half its weight, the ``tensions`` of the others.
    """

    time: float
    pose: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    lengths: np.ndarray
    tensions: np.ndarray
    axis: np.ndarray
    setpoints: np.ndarray
    outlet_tensions: np.ndarray | None = None


@dataclass
class _Entry:
    t: float
    sp: np.ndarray
    vel: np.ndarray
    tension: np.ndarray


class Simulator:
    """The design's robot in MuJoCo, driven by cable-length set-points.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``motion`` (:func:`~cdpr_design.statics.robot.resolve`).
    timestep : float
        Physics step [s] (default 0.5 ms; keep sqrt(sum k_i / m) * timestep well
        below 1).
    servo_bandwidth : float
        Position-loop bandwidth omega_c of each winch axis [rad/s]; ``inf``
        makes the axis follow the set-point exactly.
    delay : float
        Transport delay of the set-points [s] (FIFO), >= 0.
    cable_damping : float
        Damping ratio zeta of the axial cable mode with the effector's mass.
    joint_damping : float
        Viscous damping on the effector's joints [N s/m, N m s/rad] (air, joints).
    feedforward : bool
        Velocity feed-forward in the servo loop (without it the axis lags by
        v / omega_c).
    compensate_stretch : bool
        Take up the expected static stretch T/k of each cable.  The expected
        tensions are those passed to :meth:`advance`, else the static tensions
        at the pose the set-points stand for (forward kinematics).
        Cables whose model is elastic or sagging are commanded their unstretched
        lengths, which hold the stretch already: no T/k on them.
    axial_stiffness : float, optional
        EA [N] for every cable; default: the spec's, else 1e5 N.
    cable_segments : int
        Segments of each massive (``sagging``) cable, >= 2.
    """

    def __init__(self, robot: Robot, *, timestep: float = 5e-4, servo_bandwidth: float = 300.0,
                 delay: float = 0.0, cable_damping: float = 0.7, joint_damping: float = 0.05,
                 feedforward: bool = True, compensate_stretch: bool = True,
                 axial_stiffness: float | None = None, cable_segments: int = DEFAULT_CABLE_SEGMENTS):
        if not timestep > 0:
            raise ValueError(f"timestep must be > 0, got {timestep}")
        if not delay >= 0:
            raise ValueError(f"delay must be >= 0, got {delay}")
        if not servo_bandwidth > 0:
            raise ValueError(f"servo_bandwidth must be > 0, got {servo_bandwidth}")
        massive = massive_cables(robot.design)
        if massive and not (int(cable_segments) == cable_segments and cable_segments >= 2):
            raise ValueError(f"cable_segments must be an integer >= 2, got {cable_segments}")
        #: the design resolved for ``motion`` (refused where the catenaries cannot start)
        self.robot = robot
        self.design = design = self.robot.design
        self.timestep = float(timestep)
        self.servo_bandwidth = float(servo_bandwidth)
        self.delay = float(delay)
        self.cable_damping = float(cable_damping)
        self.joint_damping = float(joint_damping)
        self.feedforward = bool(feedforward)
        self.compensate_stretch = bool(compensate_stretch)
        ea = []
        for c in design.cables:
            v = axial_stiffness if axial_stiffness is not None else c.props.axial_stiffness
            ea.append(float(v) if v else DEFAULT_AXIAL_STIFFNESS)
        self.EA = np.array(ea)
        self.cable_segments = int(cable_segments) if massive else 0
        self.xml = build_xml(design, timestep, segments=self.cable_segments)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        self.model.dof_damping[:] = self.joint_damping
        self._chains = Chains(self.model, design, self.cable_segments, self.EA, cable_damping) if massive else None
        self._rest_damping()
        # stretch taken up by T/k on ideal cables only (real cables are commanded unstretched lengths)
        self._real = np.array([c.props.model != "ideal" for c in design.cables])
        self._comp = ~self._real & self.compensate_stretch
        self.m = design.m
        self._planar = design.motion.planar
        self._fifo: deque[_Entry] = deque()
        self._last_issue: _Entry | None = None
        self.q = np.zeros(self.m)
        self.qdot = np.zeros(self.m)
        self._current = None
        self.time = 0.0
        tmax = np.asarray(design.tension_max, float)
        self._t_cap = np.where(np.isfinite(tmax), tmax, 1e6)
        # per-step constants: kv = 2 zeta sqrt(k m), so kv / k = 2 zeta sqrt(m) / sqrt(k)
        self._kv_per_sqrt_k = 2.0 * self.cable_damping * np.sqrt(design.effector.mass)
        self._decay = None if np.isinf(self.servo_bandwidth) else float(np.exp(-self.servo_bandwidth * self.timestep))
        self._gainprm = self.model.actuator_gainprm
        self._ff_cache = None
        self._biasprm = self.model.actuator_biasprm
        # swivel pulleys: tangent exit points (mocap sites) and wrapped arc lengths r beta
        self._arc = np.zeros(self.m)
        self._pulley = None
        if self.robot.outlets.pulleys:
            A, axes, radii = pl.design_pulleys(design)
            idx = np.flatnonzero(radii > 0)
            names = [design.cables[i].name for i in idx]
            mocap = np.array([self.model.body(f"pulley_{n}").mocapid[0] for n in names])
            sites = np.array([self.model.site(f"attach_{n}").id for n in names])
            self._pulley = (idx, [tuple(map(float, v)) for v in A[idx]],
                            [tuple(map(float, v)) for v in axes[idx]], [float(v) for v in radii[idx]],
                            [int(v) for v in mocap], [int(v) for v in sites])

    # ------------------------------------------------------------------
    # set-up
    # ------------------------------------------------------------------
    def _set_pose(self, pose) -> None:
        full = self.design.full_pose(pose)
        qpos = self.data.qpos
        if self._planar:
            qpos[0], qpos[1], qpos[2] = full[0], full[1], full[5]
        else:
            qpos[:3] = full[:3]
            x, y, z, w = Rotation.from_euler("XYZ", full[3:]).as_quat()
            qpos[3:7] = [w, x, y, z]
        self.data.qvel[:] = 0.0
        mujoco.mj_forward(self.model, self.data)
        if self._pulley is not None:
            self._update_pulleys()
            mujoco.mj_forward(self.model, self.data)

    def _update_pulleys(self) -> None:
        """Move each pulley cable's outlet site to its tangent point and store r beta.

        Uses the attachment points of the last kinematics pass (one physics
        step old inside :meth:`_step`): the total length r beta + |B - C| is
        stationary in C at the tangent point, so the lag costs a length error
        of second order in the step's motion.
        """
        idx, A, axes, radii, mocap, sites = self._pulley
        xpos, mpos, arc = self.data.site_xpos, self.data.mocap_pos, self._arc
        for j in range(len(idx)):
            C, beta = pl.exit_point(A[j], axes[j], radii[j], xpos[sites[j]])
            if C is not None:  # inside the pulley circle: keep the last exit point
                mpos[mocap[j]] = C
                arc[idx[j]] = radii[j] * beta

    def static_tensions(self, pose) -> np.ndarray:
        """Tensions [N] holding the effector at rest at a pose (gravity only), NaN if singular."""
        from cdpr_design.motion.trajectory import states

        x = np.atleast_2d(np.asarray(pose, float))
        z = np.zeros_like(x)
        return states(self.robot, x, z, z)["tensions"][0]

    def reset(self, pose=None, *, settle: float = 3.0, setpoints=None) -> SimState:
        """Put the robot at rest at a pose, with the axes holding its cable lengths.

        Parameters
        ----------
        pose : array, optional
            Pose in the motion's coordinates; default: the centre of the
            workspace grid at the workspace orientation.
        settle : float
            Simulated time [s] to let the body find its equilibrium under
            gravity with extra damping (the rigid body of an under-constrained
            robot tilts until the cable lines and gravity meet); 0 to skip.
            The clock restarts at 0 afterwards.
        setpoints : (m,) array, optional
            Axis positions to hold [m]; default: the chord lengths of ideal
            cables, the cable model's unstretched lengths at the pose for real
            ones (the chords where the model has no solution).  Massive cables
            start on their catenary for these lengths.
        """
        d = self.design
        if pose is None:
            grid = d.workspace.grid
            pose = [(lo + hi) / 2 for lo, hi in zip(grid.lower, grid.upper)] + list(d.workspace.orientation)
        pose = np.asarray(pose, float)
        mujoco.mj_resetData(self.model, self.data)
        self._set_pose(pose)
        L = self._hold_lengths(pose) if setpoints is None else np.asarray(setpoints, float).reshape(-1).copy()
        if L.size != self.m or not np.all(np.isfinite(L)):
            raise ValueError(f"expected {self.m} finite set-points, got {L}")
        T = self.static_tensions(pose)
        T = np.where(np.isfinite(T) & self._comp, np.clip(T, 0.0, self._t_cap), 0.0)
        self.q = L.copy()
        self.qdot = np.zeros(self.m)
        self._fifo.clear()
        entry = _Entry(0.0, L.copy(), np.zeros(self.m), T)
        self._current = entry
        self._last_issue = entry
        self.time = 0.0
        if self._chains is not None:
            self._place_chains(L)
        if settle > 0:
            self._settle(settle)
        self.time = 0.0
        self.data.time = 0.0
        return self.state()

    def _hold_lengths(self, pose) -> np.ndarray:
        """Axis positions [m] holding a pose: chords, or the cable model's unstretched lengths."""
        L = kin.inverse_kinematics(self.design, pose)
        if self.robot.cables.rigid:
            return L
        from cdpr_design.statics.robot import Analysis, resolve
        from cdpr_design.workspaces.pose import evaluate_pose

        L0 = evaluate_pose(resolve(self.design, Analysis(command="statics")), pose).cable_state.unstretched_lengths
        return np.where(np.isfinite(L0), L0, L)

    def _place_chains(self, lengths) -> None:
        """Massive cables on their catenaries for unstretched ``lengths`` (straight where none exists)."""
        ch = self._chains
        arr = self.robot.cable
        pts = []
        for j, i in enumerate(ch.idx):
            A, B = self.data.site_xpos[self.model.site(f"outlet_{self.design.cables[i].name}").id], \
                self.data.site_xpos[ch.sites[j]]
            shape = cm.cable_shape(A, B, float(lengths[i]), float(arr.w[i]), float(ch.EA[j]), arr.up, ch.N)
            f = np.linspace(0.0, 1.0, ch.N + 1)[:, None]
            pts.append(shape[0] if shape is not None else A[None, :] + f * (B - A)[None, :])
        ch.place(self.model, self.data, pts)
        ch.update(self.model, self.data, lengths, np.zeros(self.m), self.timestep)
        mujoco.mj_forward(self.model, self.data)

    def _settle(self, settle: float) -> None:
        """Let the robot come to rest for up to ``settle`` [s] with extra damping."""
        d = self.design
        # extra damping while settling: about critical for a 1 m pendulum of the effector
        mass = d.effector.mass
        arm = 0.5 * float(np.max(d.effector.size)) + 0.1
        ne = 3 if self._planar else 6  # the effector's dofs come first
        damp = np.full(self.model.nv, 4.0 * mass)
        if self._planar:
            damp[2] = 4.0 * mass * arm * arm
        else:
            damp[3:ne] = 4.0 * mass * arm * arm
        if self._chains is not None:
            self._chains.settle_damping(self.model, self.data, damp)
        self.model.dof_damping[:] = np.maximum(damp, self.joint_damping)
        steps = int(np.ceil(settle / self.timestep))
        min_steps = int(np.ceil(0.2 / self.timestep))
        for j in range(steps):
            self._step()
            # at rest: stop early (velocities below 1 um/s, 1 urad/s)
            if j >= min_steps and j % 50 == 0 and np.max(np.abs(self.data.qvel)) < 1e-6:
                break
        self._check_stable()
        self._rest_damping()
        self.data.qvel[:] = 0.0
        mujoco.mj_forward(self.model, self.data)

    # ------------------------------------------------------------------
    # stepping
    # ------------------------------------------------------------------
    def _reference(self, t: float):
        """Set-point entry the axes follow at time t (after the delay), and its ramp value."""
        horizon = t - self.delay
        while self._fifo and self._fifo[0].t <= horizon + 1e-12:
            self._current = self._fifo.popleft()
        e = self._current
        tau = max(horizon - e.t, 0.0)
        return e, e.sp + e.vel * tau

    def _step(self) -> None:
        dt = self.timestep
        e, r = self._reference(self.time)
        # exact discretisation of dq/dt = vff + wc (r(t) - q) with r a ramp of slope e.vel
        if self._decay is None:  # infinite bandwidth: the axis is the set-point
            q_new = r + e.vel * dt
        else:
            a = self._decay
            q_new = r + e.vel * dt + (self.q - r) * a
            if not self.feedforward:
                q_new -= e.vel * ((1 - a) / self.servo_bandwidth)
        self.qdot = (q_new - self.q) / dt
        self.q = q_new
        k = self.EA / np.maximum(q_new, 1e-6)
        c = self._kv_per_sqrt_k / np.sqrt(k)  # kv / k
        # the damper acts relative to the winch; on real cables relative to the commanded cable
        # speed, so that the steps of their set-points (stretch and sag follow the tensions, which
        # jump with the path's acceleration) are not damped away
        rate = np.where(self._real, e.vel, self.qdot) if self._real.any() else self.qdot
        ctrl = q_new + c * rate
        if self._pulley is not None:
            # the tendon spans the free segment only: the winch's length minus the wrapped arc
            self._update_pulleys()
            ctrl -= self._arc
        if self.compensate_stretch:
            ctrl -= e.tension / k  # e.tension is 0 where the set-points are unstretched lengths
        gp, bp = self._gainprm, self._biasprm
        gp[:, 0] = k
        bp[:, 1] = -k
        bp[:, 2] = -c * k
        if self._chains is None:
            self.data.ctrl[:] = ctrl
            mujoco.mj_step(self.model, self.data)
        else:
            sub = self._drive_chains(q_new, rate, c * k, ctrl)
            self.data.ctrl[:] = ctrl
            mujoco.mj_step(self.model, self.data, sub)
        self.time += dt

    def _drive_chains(self, q, rate, kv, ctrl) -> int:
        """Massive cables for axes at ``q`` [m] paying out at ``rate`` [m/s]: the flexes
        (:meth:`Chains.update`), and each cable's actuator as a dashpot on its chord relative to the
        winch, force kv (rate - dL/dt) with kv [N s/m] as for straight cables (integrated implicitly,
        unlike the flex's own dampers), pulling only like every cable actuator.
        Returns the physics sub-steps."""
        ch = self._chains
        sub = ch.update(self.model, self.data, q, rate, self.timestep)
        i = ch.idx
        self._gainprm[i, 0] = kv[i]
        self._biasprm[i, 1] = 0.0
        self._biasprm[i, 2] = -kv[i]
        ctrl[i] = rate[i]
        return sub

    def _rest_damping(self) -> None:
        """``joint_damping`` on the effector; none on the massive cables' vertices (their flex damps them)."""
        self.model.dof_damping[:] = self.joint_damping
        if self._chains is not None:
            self.model.dof_damping[self._chains.dofs.ravel()] = 0.0

    def _check_stable(self) -> None:
        if self._unstable():
            raise SimulationError(
                f"the simulation became unstable near t = {self.time:.4g} s (MuJoCo reset it); "
                "use a smaller timestep or check the set-points")

    def _unstable(self) -> bool:
        w = self.data.warning
        return any(w[int(k)].number > 0 for k in _BAD_WARNINGS)

    def advance(self, setpoints, duration: float, *, velocity=None, tension=None) -> SimState:
        """Issue cable-length set-points now and simulate for ``duration`` seconds.

        Parameters
        ----------
        setpoints : (m,) array
            Cable lengths the axes must reach [m] (rigid-cable geometry, as a
            PLC computes them by inverse kinematics).
        duration : float
            Simulated time to advance [s] (rounded to whole physics steps).
        velocity : (m,) array, optional
            Set-point velocities [m/s] for the feed-forward; default: the
            finite difference with the previous set-points.
        tension : (m,) array, optional
            Expected tensions [N] for the stretch compensation; default: the
            static tensions at the pose the set-points stand for.

        Returns
        -------
        SimState
            The state at the end.
        """
        sp = np.asarray(setpoints, float).reshape(-1)
        if sp.size != self.m:
            raise ValueError(f"expected {self.m} set-points, got {sp.size}")
        if not np.all(np.isfinite(sp)):
            raise ValueError("set-points must be finite")
        if velocity is None:
            prev = self._last_issue
            span = self.time - prev.t if prev is not None else 0.0
            vel = (sp - prev.sp) / span if prev is not None and span > 0 else np.zeros(self.m)
        else:
            vel = np.asarray(velocity, float).reshape(-1)
        if tension is None:
            if self.compensate_stretch:
                T = self._tension_for_lengths(sp)
            else:
                T = np.zeros(self.m)
        else:
            T = np.asarray(tension, float).reshape(-1)
        # a feed-forward near a singular pose can be huge: never more than a cable's bound
        T = np.where(np.isfinite(T) & self._comp, np.clip(T, 0.0, self._t_cap), 0.0)
        entry = _Entry(self.time, sp.copy(), vel.copy(), T)
        self._fifo.append(entry)
        self._last_issue = entry
        steps = max(int(round(duration / self.timestep)), 0)
        for _ in range(steps):
            self._step()
        self._check_stable()
        return self.state()

    def _tension_for_lengths(self, lengths) -> np.ndarray:
        # the expected tension changes by ~0.1 N per mm of motion, i.e. nanometres of
        # stretch: recompute (forward kinematics + statics) only after 1 mm of set-point change
        cache = self._ff_cache
        if cache is not None and np.max(np.abs(lengths - cache[0])) < 1e-3:
            return cache[1]
        T = self._tension_for_lengths_uncached(lengths)
        self._ff_cache = (np.array(lengths, float), T)
        return T

    def _tension_for_lengths_uncached(self, lengths) -> np.ndarray:
        try:
            guess = self.state().pose
            fk = kin.forward_kinematics(self.design, lengths, guess=guess)
            if fk.residual > 1e-6:
                return np.zeros(self.m)
            return self.static_tensions(fk.pose)
        except Exception:  # noqa: BLE001 - no compensation where the lengths fit no pose
            return np.zeros(self.m)

    # ------------------------------------------------------------------
    # read-out
    # ------------------------------------------------------------------
    def state(self) -> SimState:
        """The current :class:`SimState`."""
        d = self.design
        qpos, qvel = self.data.qpos, self.data.qvel
        if self._planar:
            full = np.array([qpos[0], qpos[1], 0.0, 0.0, 0.0, qpos[2]])
            vel = np.array([qvel[0], qvel[1], 0.0, 0.0, 0.0, qvel[2]])
        else:
            w, x, y, z = qpos[3:7]
            ang = Rotation.from_quat([x, y, z, w]).as_euler("XYZ")
            full = np.concatenate([qpos[:3], ang])
            R = Rotation.from_quat([x, y, z, w]).as_matrix()
            vel = np.concatenate([qvel[:3], R @ qvel[3:6]])  # free joint: body-frame angular velocity
        pose = full[list(d.motion.pose_index)]
        # the actuator's force range [-F, 0] makes these >= 0 (0 when slack); + 0.0 turns -0.0 into 0.0
        tensions = -np.asarray(self.data.actuator_force, float) + 0.0
        outlet = tensions.copy()
        if self._chains is not None:
            # the flex's end forces plus the pull of the chord's dashpot (0 at rest)
            i = self._chains.idx
            tB, tA = self._chains.end_tensions(self.model, self.data)
            tensions[i], outlet[i] = tB + tensions[i], tA + tensions[i]
        sp = self._current.sp if self._current is not None else np.full(self.m, np.nan)
        return SimState(self.time, pose, full[3:].copy(), vel,
                        np.array(self.data.ten_length, float) + self._arc, tensions, self.q.copy(), sp.copy(),
                        outlet)


__all__ = ["SimState", "SimulationError", "Simulator", "build_xml"]
