"""Workspace sweeps with real hardware geometry: swivel pulleys and interference.

:func:`run_hardware` is what :func:`cdpr_design.workspaces.run` does when a
design has swivel pulleys or interference is checked: the same chunked grid
sweep, through :func:`cdpr_design.kernels.sweep_points` (pulley-aware
structure matrix, interference mask per pose).  :class:`Evaluator` evaluates
explicit positions at one orientation; the orientation workspaces
(:mod:`cdpr_design.workspaces.orientation`) call it once per orientation.

Results are data: chunks go to ``on_chunk``, nothing touches files.
"""

from __future__ import annotations

import time

import numpy as np

from cdpr_design import kernels as K
from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.interference import HIT_NAMES, hardware_arrays, in_cable_planes
from cdpr_design.statics.pose import KINDS, combinations, wrench_vertices
from cdpr_design.workspaces.grid import CHUNK, Chunk, Maps, chunk_poses, positions3


class Evaluator:
    """Evaluates explicit positions at one orientation (pulleys and interference included)."""

    def __init__(self, design: Design, kind: str, interference: bool):
        self.design = design
        self.kind = kind
        self.kcode = KINDS[kind]
        self.interference = bool(interference)
        self.hw = hardware_arrays(design)
        self.A = np.ascontiguousarray(design.outlets)
        self.Bp = np.ascontiguousarray(design.attachments)
        self.Bp_planes = np.ascontiguousarray(in_cable_planes(design.attachments, self.hw.zoff))  # interference
        self.rows = design.rows
        self.tmin, self.tmax = design.tension_min, design.tension_max
        self.combos = combinations(design.m, design.n)
        self._wreq = {}

    def wrench(self, ori) -> np.ndarray:
        key = tuple(float(x) for x in ori)
        if key not in self._wreq:
            self._wreq[key] = wrench_vertices(self.design, self.kind, np.asarray(ori, float))
        return self._wreq[key]

    def __call__(self, P: np.ndarray, ori, full: bool = True):
        """(feasible uint8, margin, tensions, lengths, mask uint8) at positions ``P`` (k, 3).

        ``feasible`` is the statics result only; ``mask`` the interference bits
        (zero when interference is not checked).
        """
        ori = np.asarray(ori, float)
        R = np.ascontiguousarray(kin.rotation_matrix(*ori))
        Rb = np.ascontiguousarray(self.Bp @ R.T)
        k, m = P.shape[0], self.design.m
        feas = np.empty(k, dtype=np.uint8)
        marg = np.empty(k)
        ten = np.empty((k, m))
        L = np.empty((k, m))
        mask = np.empty(k, dtype=np.uint8)
        hw = self.hw
        K.sweep_points(np.ascontiguousarray(P, dtype=float), Rb, R, self.A, hw.axes, hw.eref,
                       hw.radii, self.rows, self.wrench(ori), self.tmin, self.tmax, self.combos,
                       self.kcode, self.interference, self.Bp_planes, hw.half, hw.rho, hw.frame_lower,
                       hw.frame_upper, hw.dim, hw.tol, full, hw.zoff, feas, marg, ten, L, mask)
        return feas, marg, ten, L, mask

def chunk_stats(feas, marg, ten, tpeak):
    """(feasible count, min margin [N], max margin [N]) of a chunk; raises ``tpeak`` [N] in place."""
    return K.chunk_stats(np.ascontiguousarray(feas), np.ascontiguousarray(marg),
                         np.ascontiguousarray(ten), feas.shape[0], tpeak)


def kind_counts(mask: np.ndarray, counts: dict) -> None:
    for bit, name in HIT_NAMES.items():
        counts[name] += int(np.count_nonzero(mask & bit))


def run_hardware(design: Design, kind: str, g, ori, *, on_chunk=None, progress=None,
                 chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False):
    """Sweep grid ``g`` at orientation ``ori`` (3,) [rad] with pulleys and interference.

    With ``interference`` the ``feasible`` flag is statics-feasible and
    collision free; tensions are blanked (NaN) where a pose collides; the
    margin stays the capacity margin.  Summary extras: ``interference``,
    ``collision_free`` (collision-free poses), ``feasible_statics`` (feasible
    before the interference checks), ``collisions_by_kind`` (poses hit by
    each kind of interference), ``pulleys``.
    """
    t0 = time.perf_counter()
    ev = Evaluator(design, kind, interference)
    total = g.size
    chunk = max(1, min(chunk, total))
    maps = Maps(g, design.m, keep_maps)
    n_free = n_stat = 0
    counts = {name: 0 for name in HIT_NAMES.values()}
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        P = positions3(g, done, cnt)
        feas, marg, ten, L, mask = ev(P, ori)
        cfree = None
        if interference:
            n_stat += int(np.count_nonzero(feas))
            cfree = (mask == 0).astype(np.uint8)
            n_free += int(np.count_nonzero(cfree))
            kind_counts(mask, counts)
            feas &= cfree
            ten[cfree == 0] = np.nan
        maps.add(done, chunk_stats(feas, marg, ten, maps.tpeak), feas, marg, ten)
        if on_chunk is not None:
            on_chunk(Chunk(done, chunk_poses(design, P, ori), feas, marg, ten, L, collision_free=cfree))
        done += cnt
        if progress is not None:
            progress(done, total)
    extra = {"pulleys": bool(kin.has_pulleys(design)), "interference": bool(interference)}
    if interference:
        extra.update(collision_free=n_free, feasible_statics=n_stat, collisions_by_kind=counts)
    return maps.result(design, kind, ori, t0, extra)
