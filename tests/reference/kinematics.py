"""Cable lengths and speeds computed pose by pose: the references of the vectorised forms
(trajectory sampling, the pulley geometry's batches).  Units: SI (m, m/s, rad)."""

from __future__ import annotations

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import has_pulleys


def lengths_many(design: Design, poses) -> np.ndarray:
    """Cable lengths for many poses, (k, ncoords) -> (k, m) [m]."""
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    full = np.zeros((poses.shape[0], 6))
    full[:, list(design.motion.pose_index)] = poses
    A, B = design.outlets, design.attachments
    if not design.motion.rotational:
        Rb = B  # orientation fixed at identity
        if has_pulleys(design):
            return kin.outlet_points(design, full[:, None, :3] + Rb[None, :, :])[1]
        vec = A[None, :, :] - full[:, None, :3] - Rb[None, :, :]
    else:
        out = np.empty((poses.shape[0], design.m))
        for k in range(poses.shape[0]):
            out[k] = kin.inverse_kinematics(design, poses[k])
        return out
    return np.linalg.norm(vec, axis=2)


def length_rates(design: Design, pose, velocity) -> np.ndarray:
    """Cable speeds dL/dt [m/s] for a pose velocity in the motion's coordinates.

    dL_i/dt = -u_i . (v + omega x R b_i) = -W_full[:, i] . [v; omega].
    For the rotational motions the angular velocity is taken as the rates of
    the pose angles mapped through the xyz Euler kinematics.  With swivel
    pulleys u_i is the free segment's direction: the arc + free length has
    gradient -u_i with respect to the attachment point (the tangent point
    moves along the pulley without changing the length to first order).
    """
    mot = design.motion
    g = kin.cable_geometry(design, pose)
    vel = np.zeros(6)
    vel[list(mot.pose_index)] = np.asarray(velocity, dtype=float)
    v = vel[:3]
    omega = kin.euler_rates_to_omega(design.full_pose(pose)[3:], vel[3:])
    pt = v[None, :] + np.cross(omega, g.attachments)
    return -np.einsum("ij,ij->i", np.nan_to_num(g.directions), pt)
