"""Workspace sweeps with elastic and sagging cables (:mod:`cdpr_design.statics.cables`).

- ``elastic``: the straight-cable sweep's rows, with the unstretched lengths
  L / (1 + T/EA) added to each chunk (:func:`elastic_chunks`).
- ``sagging``: every pose solved with elastic catenaries by the batched
  kernel :func:`cdpr_design.kernels.sagging.sweep_grid_sagging`
  (:func:`sweep_sagging`); each chunk carries the outlet tensions, unstretched
  lengths, sag and a ``cable_status`` per pose.

Extra ``workspace.csv`` columns, per cable c: ``outlet_tension_<c>`` [N],
``unstretched_length_<c>`` [m], ``sag_<c>`` [m]; sagging sweeps add
``cable_status`` (:data:`cdpr_design.statics.cables.STATUS` index: 0 ok,
1 no tensions, 2 no catenary, 3 not converged, 4 singular).
"""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from cdpr_design.model.design import Design, Grid
from cdpr_design.statics import cables
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.pose import KINDS, combinations, pose_at, wrench_vertices
from cdpr_design.workspaces.grid import CHUNK, Chunk, Maps, WorkspaceResult, grid3, grid_positions


def _extra(design: Design, outlet, L0, sag, status=None) -> dict:
    out = {}
    for i, c in enumerate(design.cable_names):
        out[f"outlet_tension_{c}"] = outlet[:, i]
    for i, c in enumerate(design.cable_names):
        out[f"unstretched_length_{c}"] = L0[:, i]
    for i, c in enumerate(design.cable_names):
        out[f"sag_{c}"] = sag[:, i]
    if status is not None:
        out["cable_status"] = status
    return out


class ElasticColumns:
    """Wraps ``on_chunk`` of a straight-cable sweep: adds the elastic columns (outlet
    tension = tension, no sag, unstretched length L / (1 + T/EA))."""

    def __init__(self, design: Design, on_chunk: Callable[[Chunk], None] | None):
        self.design, self.on_chunk = design, on_chunk
        self.EA = cables.cable_arrays(design).EA

    def __call__(self, ch: Chunk) -> None:
        t = ch.tensions
        sag = np.where(np.isfinite(t), 0.0, np.nan)
        ch.extra.update(_extra(self.design, t, cables.elastic_unstretched(ch.lengths, t, self.EA), sag))
        if self.on_chunk is not None:
            self.on_chunk(ch)


class ChordColumns:
    """Wraps ``on_chunk`` of a straight-cable ``wrench-closure`` sweep of sagging cables: closure
    ignores the tensions (as they grow without bound every catenary straightens onto its chord),
    so the rows are the chords' and the cables have no shapes: the sagging columns are empty and
    ``cable_status`` is 0 (nothing was solved that could fail)."""

    def __init__(self, design: Design, on_chunk: Callable[[Chunk], None] | None):
        self.design, self.on_chunk = design, on_chunk

    def __call__(self, ch: Chunk) -> None:
        empty = np.full(ch.tensions.shape, np.nan)
        ch.extra.update(_extra(self.design, empty, empty, empty, np.zeros(len(empty), dtype=np.int8)))
        if self.on_chunk is not None:
            self.on_chunk(ch)


def cable_summary(design: Design, status_counts: np.ndarray | None, outlet_peak: np.ndarray | None) -> dict:
    """The keys a non-ideal cable model adds to the workspace summary."""
    out: dict = {"cable_model": cables.design_model(design)}
    if status_counts is not None:
        out["cable_status"] = {name: int(n) for name, n in zip(cables.STATUS, status_counts)}
    if outlet_peak is not None:
        out["max_outlet_tension_per_cable"] = {
            c: (float(v) if np.isfinite(v) else None) for c, v in zip(design.cable_names, outlet_peak)}
    return out


def sweep_sagging(design: Design, kind: str, g: Grid, ori: np.ndarray, *,
                  on_chunk: Callable[[Chunk], None] | None = None,
                  progress: Callable[[int, int], None] | None = None,
                  chunk: int = CHUNK, keep_maps: bool = True) -> WorkspaceResult:
    """Sweep grid ``g`` at orientation ``ori`` (3,) [rad] with sagging cables from point outlets.

    The caller (:func:`cdpr_design.workspaces.run`) has checked ``kind`` (not
    wrench closure, which takes the chords) and the grid's size.  Rows are
    independent of the chunking: every pose starts from its own straight
    solution.
    """
    from cdpr_design.kernels import chunk_stats
    from cdpr_design.kernels.sagging import sweep_grid_sagging

    t0 = time.perf_counter()
    arr = cables.cable_arrays(design)
    R = kin.rotation_matrix(*ori)
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    A = np.ascontiguousarray(design.outlets)
    wreq = wrench_vertices(design, kind, ori)
    combos = combinations(design.m, design.n)
    lower, step, shape = grid3(g)
    total, m = g.size, design.m
    ori_coords = pose_at(design, np.zeros(3), ori)[design.motion.dim:]
    maps = Maps(g, m, keep_maps)
    chunk = max(1, min(chunk, total))
    feas, marg = np.empty(chunk, dtype=np.uint8), np.empty(chunk)
    ten, lens, outlet, L0, sag = (np.empty((chunk, m)) for _ in range(5))
    status = np.empty(chunk, dtype=np.int8)
    counts = np.zeros(len(cables.STATUS), dtype=np.int64)
    opeak = np.full(m, -np.inf)
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        sweep_grid_sagging(done, cnt, lower, step, shape, Rb, A, design.rows, arr.up, arr.w, arr.EA, wreq,
                           design.tension_min, design.tension_max, combos, KINDS[kind], cables.MAX_ITERATIONS,
                           feas, marg, ten, lens, outlet, L0, sag, status)
        stats = chunk_stats(feas, marg, ten, cnt, maps.tpeak)
        maps.add(done, stats, feas[:cnt], marg[:cnt], ten[:cnt])
        counts += np.bincount(status[:cnt], minlength=len(cables.STATUS))
        f = feas[:cnt].astype(bool)
        if f.any():
            np.fmax(opeak, outlet[:cnt][f].max(axis=0), out=opeak)
        if on_chunk is not None:
            poses = np.empty((cnt, len(design.motion.coords)))
            poses[:, : design.motion.dim] = grid_positions(g, done, cnt)
            poses[:, design.motion.dim:] = ori_coords
            on_chunk(Chunk(done, poses, feas[:cnt].copy(), marg[:cnt].copy(), ten[:cnt].copy(),
                           lens[:cnt].copy(), extra=_extra(design, outlet[:cnt].copy(), L0[:cnt].copy(),
                                                           sag[:cnt].copy(), status[:cnt].copy())))
        done += cnt
        if progress is not None:
            progress(done, total)
    opeak[~np.isfinite(opeak)] = np.nan
    return maps.result(design, kind, ori, t0, extra=cable_summary(design, counts, opeak))
