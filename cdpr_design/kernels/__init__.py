"""Every numba kernel of cdpr-design, split by topic.

Kernels take contiguous float64 arrays in SI units and never model objects;
the jit options are set once in :mod:`cdpr_design.kernels._jit`.  Importing
this package imports numba (about 0.4 s): the layers above import it on first
use only.

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
``sweep``          grid and point sweeps, per-chunk statistics
``hanging``        hanging orientation of a planar two-cable body; statics at per-pose orientations
=================  ==========================================================
"""

from cdpr_design.kernels.geometry import (fill_column, pulley_exit, rotate_attachments, rotation,
                                          structure_matrix, structure_matrix_pulley)
from cdpr_design.kernels.hsm import (CLOSURE_TOL, basis_factor, facet_normal, hsm_enumerate, hsm_factored,
                                     hsm_margin, make_scratch, square_eval)
from cdpr_design.kernels.hsm_small import hsm_one, hsm_two
from cdpr_design.kernels.interference import (HIT_CABLE_CABLE, HIT_CABLE_EFFECTOR, HIT_CABLE_FRAME,
                                              HIT_EFFECTOR_FRAME, cable_cable_dist, cable_effector_chord,
                                              interference_pose, seg_seg_dist2, segment_box_chord)
from cdpr_design.kernels.linalg import RANK_TOL, det_small, householder_qr, inverse_small
from cdpr_design.kernels.pose import KIND_STATIC, KIND_WRENCH_CLOSURE, KIND_WRENCH_FEASIBLE, eval_general, eval_pose
from cdpr_design.kernels.sweep import chunk_stats, sweep_grid, sweep_grid_planar2, sweep_points
from cdpr_design.kernels.tension_qp import QP_TOL, goldfarb_idnani, min_norm_tensions, null_space_setup
