"""MuJoCo cross-check: an effector released at its computed hanging pose stays there.

The simulator (cdpr_design.motion.simulation) builds the robot independently of the
statics: a rigid body with the spec's mass, centre of mass and inertia, free to move
in all its degrees of freedom (planar: x, y and the tilt phi; spatial: a free joint),
hung from pull-only elastic tendons.  Each winch holds its cable's length with the
stretch T/k of the computed tension taken up, so at the computed pose every tendon pulls
with exactly the computed tension; gravity and the tendon forces are MuJoCo's own.

Tolerances.  The computed pose balances force and moment to ~1e-12 N (N m): released there
with no initial velocity, the body starts with an acceleration of that order and stays put
to ~1e-9 m over the run (rounding in the integrator).  We allow 1e-6 m and 1e-6 rad.  The
check has teeth: one degree of orientation error on planar2 leaves a moment of
m g (0.06 m) sin 1 deg ~ 0.01 N m on an inertia of 0.0024 kg m^2, an angular acceleration of
~4 rad/s^2 - the body would swing by far more than 1e-6 rad within milliseconds.  Stability
is checked by releasing the body 0.01 rad (and 5 mm) off the pose with light joint damping:
a stable equilibrium swings back to within 1e-4 of it; the unstable alternative equilibrium
of the same lengths runs away.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cdpr_design.model import spec
from cdpr_design.motion.simulation import Simulator
from cdpr_design.statics import hanging as H
from tests.helpers import DESIGNS, PLANAR2, resolved


def release(design, position, R, lengths, tensions, duration, *, kick=0.0, damping=0.0):
    """Simulate the body released at (position, R) with the axes holding ``lengths`` and
    the stretch of ``tensions`` taken up; return the largest position [m] and rotation [rad]
    deviation over the last half of the run."""
    sim = Simulator(resolved(design, "motion"), servo_bandwidth=np.inf, joint_damping=damping)
    planar = design.motion.planar
    sim.reset(np.asarray(position)[: len(design.motion.coords)] if not design.motion.rotational else None, settle=0)
    sim.q = np.asarray(lengths, float).copy()  # the axes already hold the lengths: no velocity step
    rot = Rotation.from_matrix(R) * Rotation.from_rotvec([0.0, 0.0, kick] if planar else [kick, -kick, 0.0])
    q = sim.data.qpos
    pos = np.asarray(position, float) + (0.005 * np.sign(kick) if kick else 0.0)
    if planar:
        q[0], q[1], q[2] = pos[0], pos[1], rot.as_euler("xyz")[2]
    else:
        q[:3] = pos
        x, y, z, w = rot.as_quat()
        q[3:7] = [w, x, y, z]
    sim.data.qvel[:] = 0.0
    mujoco.mj_forward(sim.model, sim.data)
    dev_p = dev_r = 0.0
    steps = 20
    for k in range(steps):
        sim.advance(lengths, duration / steps, velocity=np.zeros(design.m), tension=tensions)
        if k >= steps // 2:
            s = sim.state()
            p = s.pose[: design.motion.dim]
            Q = Rotation.from_euler("XYZ", s.orientation).as_matrix()
            dev_p = max(dev_p, float(np.linalg.norm(p - np.asarray(position)[: design.motion.dim])))
            dev_r = max(dev_r, float(Rotation.from_matrix(Q @ R.T).magnitude()))
    return dev_p, dev_r


def rotation3(at):
    return np.asarray(at.rotation, float)


@pytest.mark.parametrize("name,position", [
    ("planar2", [0.3, 0.5]),
    ("crane4", [1.5, 1.5, 2.0]),   # all four cables pulling, off the symmetry planes
    ("crane4", [1.0, 1.0, 2.0]),   # three pulling, c2 just slack
])
def test_released_at_the_hanging_pose_it_stays(name, position):
    d = spec.load(DESIGNS / f"{name}.yaml")
    at = H.hanging_pose(d, position, nominal=H.nominal_rotation(d))
    assert at.feasible and at.tilt_deg > 10  # a real tilt, not the level pose
    dev_p, dev_r = release(d, position, rotation3(at), at.lengths, at.tensions, 1.0)
    assert dev_p < 1e-6 and dev_r < 1e-6
    # one degree off, it swings away (measured ~0.03 rad): the tolerance above has teeth
    off = Rotation.from_rotvec(np.radians([0, 0, 1] if d.motion.planar else [1, 0, 0])).as_matrix()
    _, dev_r = release(d, position, off @ rotation3(at), at.lengths, at.tensions, 1.0)
    assert dev_r > 1e-2


def test_stable_pose_comes_back_unstable_one_runs_away():
    d = spec.load(PLANAR2)
    at = H.hanging_pose(d, [0.3, 0.5])
    _, dev_r = release(d, [0.3, 0.5], rotation3(at), at.lengths, at.tensions, 6.0, kick=0.01, damping=0.02)
    assert dev_r < 1e-4  # it swings back and settles on the pose (measured ~4e-6 rad)
    # the same lengths' unstable equilibrium (upside down, both cables pulling)
    unstable = [a for a in at.alternatives if not a[2]]
    assert unstable
    phi, t, _ = unstable[0]
    R = Rotation.from_rotvec([0, 0, phi]).as_matrix()
    _, dev_r = release(d, [0.3, 0.5], R, at.lengths, t, 6.0, kick=0.01, damping=0.02)
    assert dev_r > 0.5


def test_point_mass_rests_where_fk_puts_it():
    """pointmass3 with lengths whose trilateration point needs a pushing cable: released where
    fk puts it (cable c slack), the pod stays."""
    d = spec.load(DESIGNS / "pointmass3.yaml")
    L = np.linalg.norm(d.outlets - [5.0, -1.5, 3.0], axis=1)
    e = H.equilibrium(d, L)
    assert e.slack == (2,)
    dev_p, dev_r = release(d, e.position, e.rotation, L, e.tensions, 1.0)
    assert dev_p < 1e-6 and dev_r < 1e-6
    # the trilateration point (the old kinematic answer) is no rest: the pod falls away from it
    dev_p, _ = release(d, [5.0, -1.5, 3.0], e.rotation, L, e.tensions, 1.0)
    assert dev_p > 0.1
