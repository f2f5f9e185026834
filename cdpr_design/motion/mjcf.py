"""The MuJoCo model of a design (MJCF text) and its massive cables.

:func:`build_xml` writes the model :mod:`cdpr_design.motion.simulation`
describes: the effector, one spatial tendon and one pull-only position
actuator per cable.  A cable whose model is ``sagging`` (with a mass per
length) is in addition a *massive cable*: a 1-D flex of ``segments`` elastic
segments between point masses (:class:`Chains`).

Why a low-level ``<flex dim="1">`` and not ``<flexcomp>`` or a chain of bodies
------------------------------------------------------------------------------
MuJoCo's old ``composite type="cable"`` is gone from MuJoCo 4; its 1-D
deformables are flexes.  ``flexcomp`` generates its vertex bodies under one
parent and can pin vertices only to that parent, whereas a robot's cable runs
from the frame (the world) to the moving effector.  ``flexcomp`` is a macro
for the ``<flex>`` element, so the model writes that element directly: one
vertex on the world at the outlet, ``segments - 1`` vertex bodies (point
masses on slide joints) and one vertex on the effector body at the
attachment.  A 1-D flex edge is a linear spring-damper along the segment
(``edge stiffness``, ``damping``); its rest length ``flexedge_length0`` is a
model parameter that MuJoCo reads at every step, so the winch sets it: each
of the N segments rests at q/N when the axis has paid out the unstretched
length q.  A chain of capsule bodies on ball joints cannot change its length
without a slide joint and a spring in every link, which the flex edge already
is.  The flex has no bending stiffness, like the elastic catenary.

Per step (:meth:`Chains.update`), for an axis at q [m] paying out at dq/dt:

- segment stiffness k = EA N / q (the cable's EA / q in series N times);
- segment damping c = N 2 zeta sqrt((EA / q) M) (M: the effector's mass),
  capped at MAX_DAMPING_STEP m / h for a vertex of mass m and a sub-step h
  (MuJoCo 4.0 steps flex edge dampers explicitly); the rest length is
  q/N + (c / k) (dq/dt) / N so that the damper acts on the segment's stretch
  rate relative to the winch, not on the pay-out itself.  The axial mode of
  the effector is damped by the cable's actuator instead (a dashpot on the
  chord, :meth:`cdpr_design.motion.simulation.Simulator._drive_chains`);
- physics sub-steps h <= SUBSTEP_OMEGA_DT / (2 sqrt(k / m)) (explicit springs);
- every inner vertex weighs mu q / N (mu: mass per length) and the half
  segments at the ends put mu q / (2N) on the outlet (the frame) and on the
  effector (an applied force at the attachment).  This is exactly the
  lumped-mass chain of the catenary tests: the midpoint rule applied to the
  catenary's closure, so the chain's end forces and shape differ from the
  continuous cable's by O((L/N)^2).

A flex edge also resists compression, unlike a cable.  A chain of segments
without bending stiffness buckles under compression (its vertices move
sideways), so it cannot hold the effector up by pushing; a compressed last
segment can still push for an instant in a fast transient.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cdpr_design.model.design import Design


#: Largest segment frequency times sub-step (explicit springs are stable below 2; half that).
SUBSTEP_OMEGA_DT = 1.0
#: Largest segment damping times sub-step over a vertex's mass (a vertex between two edges moving
#: against its neighbours feels 4 c: stable explicit dampers need 4 c h / m < 2).
MAX_DAMPING_STEP = 0.1


def massive_cables(design: Design) -> list[int]:
    """Indices of the cables simulated with mass: model ``sagging`` and a mass per length > 0."""
    return [i for i, c in enumerate(design.cables)
            if c.props.model == "sagging" and (c.props.mass_per_length or 0.0) > 0]


def _fmt(v) -> str:
    return " ".join(f"{x:.10g}" for x in v)


def build_xml(design: Design, timestep: float = 5e-4, force_limit: float = 1e6, segments: int = 0) -> str:
    """MJCF text of the design's robot (see :mod:`cdpr_design.motion.simulation` for the model).

    Parameters
    ----------
    design : Design
    timestep : float
        Physics step [s].
    force_limit : float
        Largest cable tension the actuator can exert [N] (not a design bound:
        tension bounds are checked by the analysis, not enforced by physics).
    segments : int
        Segments of each massive cable (:func:`massive_cables`); 0: none.
    """
    eff = design.effector
    planar = design.motion.planar
    I = np.array(eff.inertia_matrix, float)
    I = 0.5 * (I + I.T)
    d = np.maximum(np.diag(I), 1e-9 * max(eff.mass, 1e-9))
    if planar:
        # only the hinge about z moves: Ixx, Iyy do not enter the motion, but MuJoCo
        # requires the triangle inequality (a planar spec's scalar inertia gives Izz alone)
        d[0], d[1] = max(d[0], d[2]), max(d[1], d[2])
    full = [d[0], d[1], d[2], I[0, 1], I[0, 2], I[1, 2]]
    size = np.maximum(np.asarray(eff.size, float) / 2, 1e-3)
    lines = [
        f'<mujoco model="{design.name}">',
        '  <compiler inertiafromgeom="false" angle="radian"/>',
        f'  <option timestep="{timestep:.10g}" gravity="{_fmt(design.gravity)}" integrator="implicitfast">',
        '    <flag contact="disable"/>',
        '  </option>',
        '  <worldbody>',
    ]
    for c in design.cables:
        pos = _fmt(c.outlet)
        if c.pulley is not None and c.pulley.radius > 0:
            # the free cable leaves the pulley's tangent point: a mocap body the
            # simulator moves there every step (module notes, "Swivel pulleys")
            lines.append(f'    <body name="pulley_{c.name}" mocap="true" pos="{pos}">'
                         f'<site name="outlet_{c.name}" pos="0 0 0" size="0.005"/></body>')
        else:
            lines.append(f'    <site name="outlet_{c.name}" pos="{pos}" size="0.005"/>')
    lines.append('    <body name="effector" pos="0 0 0">')
    if planar:
        lines += [
            '      <joint name="x" type="slide" axis="1 0 0"/>',
            '      <joint name="y" type="slide" axis="0 1 0"/>',
            '      <joint name="phi" type="hinge" axis="0 0 1"/>',
        ]
    else:
        lines.append('      <freejoint name="free"/>')
    lines.append(f'      <inertial pos="{_fmt(eff.center_of_mass)}" mass="{eff.mass:.10g}" '
                 f'fullinertia="{_fmt(full)}"/>')
    lines.append(f'      <geom type="box" size="{_fmt(size)}" contype="0" conaffinity="0"/>')
    for c in design.cables:
        lines.append(f'      <site name="attach_{c.name}" pos="{_fmt(c.attachment)}" size="0.005"/>')
    lines.append('    </body>')
    chains = massive_cables(design) if segments > 0 else []
    lines += _chain_bodies(design, chains, segments)
    lines += ['  </worldbody>', '  <tendon>']
    for c in design.cables:
        lines.append(f'    <spatial name="{c.name}" width="0.002">'
                     f'<site site="outlet_{c.name}"/><site site="attach_{c.name}"/></spatial>')
    lines += ['  </tendon>', '  <actuator>']
    for c in design.cables:
        lines.append(f'    <position name="{c.name}" tendon="{c.name}" kp="1" '
                     f'forcelimited="true" forcerange="{-force_limit:.10g} 0"/>')
    lines.append('  </actuator>')
    lines += _chain_flexes(design, chains, segments)
    lines.append('</mujoco>')
    return "\n".join(lines)


def _straight(design: Design, i: int, segments: int) -> np.ndarray:
    """(segments + 1, 3) points from the outlet to the attachment at the identity pose [m]."""
    c = design.cables[i]
    A, B = np.asarray(c.outlet, float), np.asarray(c.attachment, float)
    f = np.linspace(0.0, 1.0, segments + 1)[:, None]
    return A[None, :] + f * (B - A)[None, :]


def _chain_bodies(design: Design, chains, segments: int) -> list[str]:
    """The inner vertices of each massive cable: point masses on slide joints (x, y; and z in space)."""
    axes = ("x", "y") if design.motion.planar else ("x", "y", "z")
    unit = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}
    lines = []
    for i in chains:
        c = design.cables[i]
        P = _straight(design, i, segments)
        mass = max(c.props.mass_per_length * float(np.linalg.norm(P[-1] - P[0])) / segments, 1e-9)
        for k in range(1, segments):
            joints = "".join(f'<joint name="{c.name}_v{k}_{a}" type="slide" axis="{unit[a]}"/>' for a in axes)
            lines.append(f'    <body name="{c.name}_v{k}" pos="{_fmt(P[k])}">{joints}'
                         f'<inertial pos="0 0 0" mass="{mass:.10g}" diaginertia="1e-9 1e-9 1e-9"/></body>')
    return lines


def _chain_flexes(design: Design, chains, segments: int) -> list[str]:
    """One 1-D flex per massive cable: world vertex at the outlet, effector vertex at the attachment."""
    if not chains:
        return []
    lines = ['  <deformable>']
    for i in chains:
        c = design.cables[i]
        bodies = " ".join(["world"] + [f"{c.name}_v{k}" for k in range(1, segments)] + ["effector"])
        vert = " ".join([_fmt(c.outlet)] + ["0 0 0"] * (segments - 1) + [_fmt(c.attachment)])
        elem = " ".join(f"{k} {k + 1}" for k in range(segments))
        radius = max(0.5 * (c.props.diameter or 0.0), 1e-3)
        lines.append(f'    <flex name="cable_{c.name}" dim="1" body="{bodies}" vertex="{vert}" element="{elem}" '
                     f'radius="{radius:.10g}"><edge stiffness="1" damping="0"/></flex>')
    lines.append('  </deformable>')
    return lines


class Chains:
    """The massive cables of a compiled model, driven by their winch positions.

    Parameters
    ----------
    model : mujoco.MjModel
        Built by :func:`build_xml` with ``segments`` > 0.
    design : Design
    segments : int
    EA : (m,) array
        Axial stiffness of every cable [N].
    zeta : float
        Damping ratio of each cable's axial mode with the effector's mass.
    """

    def __init__(self, model, design: Design, segments: int, EA, zeta: float):
        self.idx = np.array(massive_cables(design), dtype=int)
        self.N = int(segments)
        self.mu = np.array([design.cables[i].props.mass_per_length for i in self.idx], float)
        self.EA = np.asarray(EA, float)[self.idx]
        self.zeta = float(zeta)
        self.mass = float(design.effector.mass)
        self.g = np.asarray(design.gravity, float)
        self.ndim = 2 if design.motion.planar else 3
        names = [design.cables[i].name for i in self.idx]
        self.flex = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, f"cable_{n}") for n in names],
                             dtype=int)
        self.vertadr = model.flex_vertadr[self.flex].astype(int)
        self.edges = np.empty((len(names), self.N), dtype=int)
        for j, f in enumerate(self.flex):
            adr = int(model.flex_edgeadr[f])
            for e in range(adr, adr + int(model.flex_edgenum[f])):
                self.edges[j, int(min(model.flex_edge[e]))] = e
        self.vbody = np.array([[model.body(f"{n}_v{k}").id for k in range(1, self.N)] for n in names], dtype=int)
        self.qadr = model.jnt_qposadr[model.body_jntadr[self.vbody]].astype(int)
        self.dofs = (model.body_dofadr[self.vbody][:, :, None] + np.arange(self.ndim)).reshape(len(names), -1)
        self.eff = model.body("effector").id
        self.sites = np.array([model.site(f"attach_{n}").id for n in names], dtype=int)
        self.half = np.zeros(len(names))

    def update(self, model, data, q, qdot, dt: float) -> int:
        """Set stiffness, damping, rest lengths and masses for axes at ``q`` [m] moving at ``qdot`` [m/s]
        (see the module notes), and the half segments' weight on the effector; the physics step
        ``model.opt.timestep`` for a step of ``dt`` [s] made of the returned number of sub-steps."""
        qs = np.maximum(np.asarray(q, float)[self.idx], 1e-6)
        K = self.EA / qs
        ks = K * self.N
        m_seg = np.maximum(self.mu * qs / self.N, 1e-12)
        # MuJoCo 4.0 steps the edge springs and dampers as explicit forces: sub-steps keep the
        # fastest segment mode (2 sqrt(k / m_seg) rad/s) below SUBSTEP_OMEGA_DT per sub-step
        sub = max(1, int(np.ceil(dt * float(np.max(2.0 * np.sqrt(ks / m_seg))) / SUBSTEP_OMEGA_DT)))
        h = dt / sub
        model.opt.timestep = h
        # ... and the damping below what an explicit step of h damps stably
        cs = np.minimum(self.N * 2.0 * self.zeta * np.sqrt(K * self.mass), MAX_DAMPING_STEP * m_seg / h)
        model.flex_edgestiffness[self.flex] = ks
        model.flex_edgedamping[self.flex] = cs
        model.flexedge_length0[self.edges] = ((qs + cs / ks * np.asarray(qdot, float)[self.idx]) / self.N)[:, None]
        model.body_mass[self.vbody] = m_seg[:, None]
        self.half = 0.5 * m_seg
        F = self.half[:, None] * self.g[None, :]
        r = data.site_xpos[self.sites] - data.xipos[self.eff]
        data.xfrc_applied[self.eff, :3] = F.sum(axis=0)
        data.xfrc_applied[self.eff, 3:] = np.cross(r, F).sum(axis=0)
        return sub

    def place(self, model, data, points) -> None:
        """Put the inner vertices of chain j at ``points[j]`` ((N + 1, 3) from the outlet, [m])."""
        for j, P in enumerate(points):
            base = model.body_pos[self.vbody[j]]
            for k in range(1, self.N):
                a = self.qadr[j, k - 1]
                data.qpos[a:a + self.ndim] = (P[k] - base[k - 1])[: self.ndim]

    def end_tensions(self, model, data):
        """(effector-end, outlet) tensions [N] of every chain: the end segments' forces plus the
        half segments' weights (the chain's discrete ends of the catenary's T_B and T_A)."""
        ks = model.flex_edgestiffness[self.flex][:, None]
        cs = model.flex_edgedamping[self.flex][:, None]
        T = ks * (data.flexedge_length[self.edges] - model.flexedge_length0[self.edges]) \
            + cs * data.flexedge_velocity[self.edges]
        X = data.flexvert_xpos
        W = self.half[:, None] * self.g[None, :]

        def end(v_end, v_next, t):
            d = X[v_next] - X[v_end]
            return np.linalg.norm(t[:, None] * d / np.linalg.norm(d, axis=1)[:, None] + W, axis=1)

        v = self.vertadr
        return end(v + self.N, v + self.N - 1, T[:, -1]), end(v, v + 1, T[:, 0])

    def settle_damping(self, model, data, damp) -> None:
        """Extra damping on the vertices while settling (about critical for each chain's
        first transverse mode, pi sqrt(T / mu) / L, from the current end-segment tension)."""
        tB, _ = self.end_tensions(model, data)
        for j in range(self.idx.size):
            L = self.N * float(np.mean(model.flexedge_length0[self.edges[j]]))
            T = max(float(tB[j]), self.mu[j] * L * float(np.linalg.norm(self.g)), 1e-9)
            omega = np.pi * np.sqrt(T / self.mu[j]) / max(L, 1e-6)
            damp[self.dofs[j]] = 2.0 * float(model.body_mass[self.vbody[j, 0]]) * omega
