"""The arrays the kernels take for a design's swivel pulleys and interference checks (effector box,
cable radii, frame box, cable planes), built once per design."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Design


@dataclass(frozen=True)
class HardwareArrays:
    """Kernel arrays for pulleys and interference of one design (contiguous float64)."""

    axes: np.ndarray      # (m, 3) unit swivel axes (z where there is no pulley)
    eref: np.ndarray      # (m, 3) reference perpendiculars
    radii: np.ndarray     # (m,) pulley radii [m] (0: point outlet)
    half: np.ndarray      # (3,) effector half extents [m]
    rho: np.ndarray       # (m,) cable radii [m]
    frame_lower: np.ndarray
    frame_upper: np.ndarray
    dim: int
    tol: float
    zoff: np.ndarray      # (m,) planar designs: each cable's plane_offset [m] (zeros for spatial ones)


def hardware_arrays(design: Design) -> HardwareArrays:
    """Pulley and interference arrays of ``design`` for the kernels."""
    from cdpr_design.statics.pulley import reference_perpendicular

    m = design.m
    axes = np.zeros((m, 3))
    eref = np.zeros((m, 3))
    radii = np.zeros(m)
    for i, c in enumerate(design.cables):
        ax = np.asarray(c.pulley.axis if c.pulley is not None else (0.0, 0.0, 1.0), float)
        axes[i] = ax / np.linalg.norm(ax)
        eref[i] = reference_perpendicular(axes[i])
        radii[i] = c.pulley.radius if c.pulley is not None else 0.0
    lo, hi = np.asarray(design.frame_lower, float), np.asarray(design.frame_upper, float)
    scale = max(1.0, float(np.max(hi - lo)))
    return HardwareArrays(
        axes=axes, eref=eref, radii=radii,
        half=np.asarray(design.effector.size, float) / 2.0,
        rho=np.array([c.props.diameter / 2.0 for c in design.cables]),
        frame_lower=lo.copy(), frame_upper=hi.copy(), dim=design.motion.dim, tol=1e-9 * scale,
        zoff=np.array([c.plane_offset for c in design.cables], dtype=float),
    )


def in_cable_planes(points, zoff) -> np.ndarray:
    """``points`` (m, 3) [m] (a planar design's, in the z = 0 plane) moved to their cables'
    planes, z = ``zoff`` [m]: the free segments' 3-D places for the interference check."""
    out = np.array(points, dtype=float)
    out[:, 2] += zoff
    return out
