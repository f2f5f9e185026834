"""Bit codes the kernels return, in a module without numba: the layers above name them
(``kernels.HIT_CABLE_CABLE``) without loading a compiled kernel or numba itself (the picture
process unpickles results that carry these names, and forks only without numba)."""

#: Bits of the interference mask returned by :func:`cdpr_design.kernels.interference.interference_pose`.
HIT_CABLE_CABLE = 1
HIT_CABLE_EFFECTOR = 2
HIT_EFFECTOR_FRAME = 4
HIT_CABLE_FRAME = 8
#: The mask of a pose whose sagging cables' shapes did not converge: not checked, so not known to be
#: collision free (:mod:`cdpr_design.kernels.sag_clearance`).
HIT_UNKNOWN = 16
