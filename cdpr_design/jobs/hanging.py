"""The hanging effector in the ``pose`` and ``fk`` commands: their JSON objects (cli.md keys).

``fk`` is the geometrico-static forward problem for every design
(:func:`cdpr_design.statics.hanging.equilibrium`); ``pose --at`` of an
under-constrained design reports the orientation its effector hangs in
(``free``: and judges the pose there, :func:`cdpr_design.workspaces.hanging.free_pose`;
``fixed``: beside the held model's answer, under ``hanging``).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.errors import InputError


def _num(x):
    x = float(x) + 0.0  # + 0.0 turns -0.0 into 0.0
    return x if math.isfinite(x) else None


def _by_cable(design, values) -> dict:
    return {c: _num(v) for c, v in zip(design.cable_names, values)}


def _orientation(value):
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_num(v) for v in value]
    return _num(value)


def _motion_pose(design, position, orientation) -> list:
    """The pose in the motion's coordinates: the position, then the orientation if the motion has it."""
    pose = [float(v) for v in position]
    if design.motion.rotational:
        pose += [orientation] if design.motion.planar else list(orientation)
    return pose


def _equilibrium_data(design, e) -> dict:
    return {"pose": _motion_pose(design, e.position, e.orientation), "orientation": _orientation(e.orientation),
            "tilt": _num(e.tilt_deg), "tensions": _by_cable(design, e.tensions),
            "slack": [design.cable_names[i] for i in e.slack], "energy": float(e.energy), "stable": bool(e.stable)}


def fk_data(robot, lengths, guess=None) -> dict:
    """The ``fk --json`` object: where the effector rests for cable ``lengths`` [m].

    ``guess`` (motion coordinates) adds its orientation as a start of the
    search (rotational motions).  Designs with swivel pulleys take the
    kinematic solve (:func:`cdpr_design.statics.kinematics.forward_kinematics`):
    the geometrico-static solver models point outlets.  ``robot``: the
    :class:`~cdpr_design.statics.robot.Robot` the command resolved for ``fk``.
    """
    from cdpr_design.statics import hanging as H
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.reach import require_reached

    design = robot.design
    rho = np.asarray(lengths, float)
    if robot.outlets.pulleys:
        res = kin.forward_kinematics(design, rho, guess=guess)
        require_reached(res.residual, rho)  # lengths no pose has: exit 2 with the residual, never a pose
        return {"pose": [float(v) for v in res.pose], "residual": float(res.residual),
                "method": f"{res.method} (swivel pulleys: kinematic solution, tensions not solved)",
                "orientation": None, "tilt": None, "tensions": None, "slack": None, "stable": None,
                "equilibria": [], "effector_orientation": design.effector.orientation}
    options = {}
    if guess is not None and design.motion.rotational:
        options["nominal"] = kin.pose_rotation(design, guess)
    H.check_weight(design.effector.mass, design.gravity)  # the spec's fault, not the lengths'
    try:
        e = H.equilibrium(design, rho, **options)
    except InputError as exc:  # unreachable, too short or miscounted lengths
        raise (H.UnreachableLengths if isinstance(exc, H.UnreachableLengths) else InputError)(
            f"--lengths: {exc}") from None
    p = np.zeros(3)
    p[: e.position.size] = e.position
    L = np.linalg.norm(design.outlets - p - design.attachments @ e.rotation.T, axis=1)
    taut = np.zeros(design.m, bool)
    taut[[i for i in range(design.m) if i not in e.slack]] = True
    miss = np.where(taut, L - rho, np.maximum(L - rho, 0.0))
    data = _equilibrium_data(design, e)
    data.update(
        residual=float(np.linalg.norm(miss)), balance_residual=float(e.residual), method="geometrico-static",
        model=e.model, effector_orientation=design.effector.orientation, underconstrained=bool(e.underconstrained),
        indeterminate=bool(e.indeterminate), within_limits=e.within_limits,
        equilibria=[_equilibrium_data(design, q) for q in e.equilibria])
    return data


def hanging_fields(design, position) -> dict:
    """``pose --json``'s ``tilt`` and ``hanging`` keys for a ``fixed`` under-constrained design:
    the orientation the free body would hang in at ``position`` [m] (:func:`statics.hanging.hanging_pose`);
    both null for a weightless effector, which hangs in no particular orientation."""
    from cdpr_design.statics import hanging as H

    if not H.has_weight(design.effector.mass, design.gravity):
        return {"tilt": None, "hanging": None}
    at = H.hanging_pose(design, position, nominal=H.nominal_rotation(design))
    return {"tilt": _num(at.tilt_deg), "hanging": {
        "feasible": bool(at.feasible), "reason": at.reason, "orientation": _orientation(at.orientation),
        "tilt": _num(at.tilt_deg), "tensions": _by_cable(design, at.tensions), "lengths": _by_cable(design, at.lengths),
        "stable": bool(at.stable), "within_limits": at.within_limits}}


def free_pose_data(robot, position) -> dict:
    """The ``pose --json`` object of a hanging robot (``effector.orientation: free``) at
    ``position`` [m]: the hanging orientation and the statics there (the workspace's rows; cli.md keys)."""
    from cdpr_design.statics.hanging.results import REASONS, OK
    from cdpr_design.workspaces.hanging import free_pose

    design = robot.design
    r = free_pose(robot, position)
    h = r.hanging
    ok = h.status[0] == OK
    reason = REASONS[h.status[0]]
    if ok and not r.feasible[0]:
        reason = _infeasible_reason(r)
    ori = _orientation(h.orientation[0]) if ok else None
    W = None
    if ok:
        from cdpr_design.statics.hanging.geometry import euler_xyz
        from cdpr_design.statics.pose import structure

        full = np.concatenate([np.pad(np.asarray(position, float), (0, 3 - len(position))), euler_xyz(h.rotation[0])])
        Wm = structure(robot, full)[0] if r.cables is None else _catenary_structure(robot, full[:3], h.rotation[0],
                                                                                   r.cables)
        W = [[float(x) for x in row] for row in Wm]
    if ok:
        pose = _motion_pose(design, position, ori)
    else:
        pose = [float(v) for v in position] + [None] * len(design.motion.rotation_coords)
    return {
        "pose": pose,
        "orientation": ori, "tilt": _num(h.tilt_deg[0]), "lengths": _by_cable(design, r.lengths[0]),
        "tensions": _by_cable(design, r.tensions[0]), "feasible": bool(r.feasible[0]), "reason": reason,
        "stable": bool(ok), "margin": _num(r.margin[0]), "structure_matrix": W,
        "collisions": _loaded_collisions(robot, position, r) if ok else None,
        "effector_orientation": "free", "hanging_tensions": _by_cable(design, h.tensions[0]),
    } | ({"tilt_loaded": _num(r.extra["tilt_loaded"][0])} if "tilt_loaded" in r.extra else {}) \
        | _cable_model_data(robot, r) | free_stiffness_data(robot, position, r)


def _infeasible_reason(r) -> str:
    """Why a hanging pose whose effector hangs under gravity alone is infeasible: under gravity
    alone, else under the first vertex of the external wrench that fails (``pose``'s reason)."""
    from cdpr_design.statics.hanging.results import OK, REASONS

    for j, v in enumerate(r.vertices or [r]):
        if v.feasible[0]:
            continue
        h = v.hanging
        if h.status[0] != OK:
            why = REASONS[h.status[0]]
        elif not v.within[0]:
            why = "the hanging tensions are outside their bounds"
        elif v.collisions is not None and v.collisions[0] != 0:
            why = "it interferes"
        else:
            why = f"it hangs tilted by {h.tilt_deg[0]:.4g} deg, more than max_tilt"
        return why if j == 0 else f"under vertex {j} of workspace.external_wrench: {why}"
    return "it interferes"


def _loaded_collisions(robot, position, r) -> list | None:
    """The colliding pairs at the hanging pose of gravity alone and of every vertex of the external
    wrench where it hangs (:func:`_collisions`); None where a vertex does not hang on sagging
    cables (its catenaries unknown: not known to be collision free)."""
    from cdpr_design.statics.hanging.results import OK

    pairs = []
    for v in r.vertices or [r]:
        if v.hanging.status[0] != OK:
            if v.cables is not None:
                return None
            continue
        pairs += [p for p in _collisions(robot, position, v.hanging.rotation[0], v.cables) if p not in pairs]
    return pairs


def _catenary_structure(robot, p, R, cables) -> np.ndarray:
    """The structure matrix (n, m) of sagging cables at the hanging pose (platform origin ``p`` [m],
    rotation ``R``): each column the unit end force at the attachment, (H u + VB up) / T, and its
    moment about the platform origin, in the motion's wrench rows."""
    design = robot.design
    up = robot.cable.up
    Rb = design.attachments @ R.T
    l = design.outlets - p - Rb
    hor = l - (l @ up)[:, None] * up
    u = hor / np.maximum(np.linalg.norm(hor, axis=1), 1e-300)[:, None]
    F = cables.H[0][:, None] * u + cables.VB[0][:, None] * up
    d = F / np.linalg.norm(F, axis=1)[:, None]
    return np.concatenate([d, np.cross(Rb, d)], axis=1).T[list(design.motion.wrench_rows)]


def _collisions(robot, position, R, cables) -> list:
    """The colliding pairs at the hanging pose (cli.md names): along the catenaries of sagging
    ``cables`` (:class:`~cdpr_design.statics.hanging.sagging.SaggingCables` of the one position),
    else the straight cables'."""
    from cdpr_design.statics.interference import check_at, check_sagging_at

    p = np.zeros(3)
    p[: len(position)] = position
    if cables is None:
        return [list(pair) for pair in check_at(robot.design, p, R).pairs]
    shapes = np.column_stack([cables.H[0], cables.VB[0], cables.unstretched[0]])
    return [list(pair) for pair in check_sagging_at(robot, p, R, shapes).pairs]


def _cable_model_data(robot, r) -> dict:
    """The keys elastic and sagging cables add to a hanging robot's ``pose --json`` (as
    :func:`cdpr_design.jobs.pose.cable_model_data`): the outlet tensions, the unstretched lengths that
    hold it there and the sag (0 for elastic cables), empty where the pose is infeasible; none for
    ideal cables."""
    from cdpr_design.statics.cables import STATUS, straight_state

    if robot.cables.rigid:
        return {}
    design = robot.design
    if r.cables is None:
        s = straight_state(robot, r.lengths, r.tensions)
        outlet, L0, sag, status = s.outlet_tensions[0], s.unstretched_lengths[0], s.sag[0], 0
    else:
        ok = bool(r.feasible[0])
        c = r.cables
        outlet, L0, sag = (np.where(ok, v[0], np.nan) for v in (c.outlet_tensions, c.unstretched, c.sag))
        status = int(r.cable_status[0])
    return {"cable_model": robot.cables.name, "outlet_tensions": _by_cable(design, outlet),
            "unstretched_lengths": _by_cable(design, L0), "sag": _by_cable(design, sag),
            "cable_status": STATUS[status]}


#: The names of the hanging stiffness's coordinates, by degrees of freedom (statics.hanging.geometry).
_DOF_NAMES = ("x", "y", "z", "wx", "wy", "wz")


def free_stiffness_data(robot, position, r) -> dict:
    """The stiffness keys of a hanging robot's ``pose --json`` (cli.md) from its
    :class:`~cdpr_design.workspaces.hanging.FreeRows` of one ``position`` [m]: the stiffness and compliance of
    the hanging pose on the robot's cables (:mod:`cdpr_design.statics.hanging.compliance`), over the
    coordinates ``stiffness_coordinates`` (translations [m], then small rotations [rad] about the
    frame's axes through the platform origin)."""
    from cdpr_design.statics.hanging.compliance import translations
    from cdpr_design.statics.stiffness import string_frequencies
    from cdpr_design.workspaces.hanging import hanging_dofs, pose_stiffness, Hanger

    design = robot.design
    mu = np.array([c.props.mass_per_length or 0.0 for c in design.cables])
    strings = string_frequencies(r.lengths[0], r.hanging.tensions[0], mu)
    hanger = Hanger(robot, design.default_orientation_full())
    dofs = hanging_dofs(hanger.geo, hanger.planar)
    names = [_DOF_NAMES[j] for j in dofs]
    P = np.zeros((1, 3))
    P[0, : len(position)] = position
    out = {"stiffness_coordinates": names, "cable_frequencies": _by_cable(design, strings)}
    h = r.hanging
    if h.status[0] != 0:
        return out | dict.fromkeys(("stiffness_matrix", "compliance_matrix", "translational_stiffness",
                                    "min_stiffness", "min_rotational_stiffness", "natural_frequencies",
                                    "mode_shapes")) | {"stiffness_reason": "the effector cannot hang here"}
    s = r.stiffness
    if s is None:
        s = pose_stiffness(robot, hanger, P, h)
    nt = translations(dofs)
    C = s.compliance[0]
    rigid = bool(np.all(~np.isfinite(robot.cable.EA)))

    def mat(a):
        return None if a is None else [[_num(x) for x in row] for row in a]

    try:
        Ktt = np.linalg.inv(C[:nt, :nt])
    except np.linalg.LinAlgError:
        Ktt = None
    if Ktt is not None and not np.all(np.isfinite(Ktt)):
        Ktt = None
    freqs = s.frequencies[0]
    return out | {
        "stiffness_matrix": None if rigid else mat(s.matrix[0]), "compliance_matrix": mat(C),
        "translational_stiffness": None if rigid else mat(Ktt), "min_stiffness": _num(s.min_stiffness[0]),
        "min_rotational_stiffness": _num(s.min_rotational_stiffness[0]),
        "natural_frequencies": [_num(v) for v in freqs[np.isfinite(freqs)]] or None, "mode_shapes": None,
        "stiffness_reason": ("rigid cables (ideal): infinitely stiff along the taut cables; the stiffness is that "
                             "of the swinging effector (compliance_matrix)") if rigid else None}
