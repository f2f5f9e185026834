"""Every numba kernel of cdpr-design, split by topic.

Kernels take contiguous float64 arrays in SI units and never model objects;
the jit options are set once in :mod:`cdpr_design.kernels._jit`.  Importing
a kernel imports numba (slow to import); this package itself is cheap and loads
each submodule the first time one of its names is used
(``from cdpr_design import kernels as K; K.sweep_grid``), so the layers above
can import it at the top and :mod:`cdpr_design.kernels.parallel` (the thread
count) needs no numba.

=================  ==========================================================
module             what
=================  ==========================================================
``geometry``       rotations, structure matrix columns, swivel-pulley exits
``linalg``         small determinants, inverses, Householder QR
``hsm``            wrench feasibility / capacity margin (hyperplane shifting)
``hsm_small``      the same in closed form for one or two redundant cables
``tension_qp``     exact minimum-2-norm tensions (Goldfarb-Idnani)
``pose``           one pose for any m, n: feasibility, margin, tensions
``interference``   cable / effector / frame contacts
``codes``          the bit codes kernels return (no numba: the layers above name them freely)
``sweep``          grid and point sweeps, per-chunk statistics
``parallel``       blocks of rows on threads (every parallel kernel)
``hanging``        statics at per-pose orientations (a hanging effector's)
``catenary``       Irvine's elastic catenary of one cable: its ends, flexibility and shape from its forces
``catenary_inv``   the catenary's forces from its ends (the inverse problem)
``cable_shape``    one heavy elastic cable at a given tension: its shape, its least tension
``sag_shapes``     sagging cables' shapes and structure matrix at given tensions
``sag_fixed``      the sagging cables' fixed point (tensions = minimum-norm tensions of their shapes)
``sagging``        statics of a pose with sagging cables; the sagging grid sweep
``sag_path``       sagging statics along a sampled trajectory
``sag_clearance``  interference of sagging cables: the catenaries as polylines of bounded error
``stiffness``      the effector's least stiffness and lowest natural frequency at many poses
``cache``          where numba caches the kernels: a folder per version of their sources (no numba)
``acceleration``   the accelerations an effector at rest can reach; the available wrench set's facets
=================  ==========================================================
"""

import importlib

#: name -> submodule, for the names used as ``kernels.<name>``
_EXPORTS = {
    **dict.fromkeys(("fill_column", "pulley_exit", "rotate_attachments", "rotation", "structure_matrix",
                     "structure_matrix_pulley"), "geometry"),
    **dict.fromkeys(("CLOSURE_TOL", "basis_factor", "facet_normal", "hsm_enumerate", "hsm_factored",
                     "make_scratch"), "hsm"),
    **dict.fromkeys(("hsm_one", "hsm_two"), "hsm_small"),
    **dict.fromkeys(("HIT_CABLE_CABLE", "HIT_CABLE_EFFECTOR", "HIT_CABLE_FRAME", "HIT_EFFECTOR_FRAME", "HIT_UNKNOWN"),
                   "codes"),
    **dict.fromkeys(("cable_cable_dist", "cable_effector_chord", "interference_pose", "seg_seg_dist2",
                     "segment_box_chord"), "interference"),
    **dict.fromkeys(("RANK_TOL", "det_small", "householder_qr"), "linalg"),
    **dict.fromkeys(("KIND_STATIC", "KIND_WRENCH_CLOSURE", "KIND_WRENCH_FEASIBLE", "Outputs", "Statics", "eval_general",
                     "eval_pose", "eval_square"), "pose"),
    **dict.fromkeys(("GridPoses", "Interference", "Pulleys", "sweep_grid", "sweep_points"),
                    "sweep"),
    **dict.fromkeys(("QP_TOL", "Reduction", "goldfarb_idnani", "min_norm_tensions", "min_norm_tensions_square",
                     "null_space", "project_null", "project_one", "project_two", "qp_tolerance", "reduction",
                     "square_projection"), "tension_qp"),
}

_SUBMODULES = {"acceleration", "cable_shape", "cache", "catenary", "catenary_inv", "codes", "geometry", "hanging", "hsm",
               "hsm_small", "interference", "linalg", "parallel", "pose", "sag_clearance", "sag_fixed", "sag_path", "sag_shapes",
               "sagging", "stiffness", "sweep", "tension_qp"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS) | _SUBMODULES)
