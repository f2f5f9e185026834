"""The Python API, for notebooks and scripts: load a design, analyse it, size it, sweep it.

Every function takes and returns data: a design from :func:`load`, result
objects whose fields are numpy arrays and numbers, convertible to a table
(``to_dict()``, ``to_arrow()``).  Nothing here writes files; the command line
(``cdpr-design ...``) is the same library plus the files and pictures.
Units are SI throughout: m, kg, N, s, rad.

    import cdpr_design as cd
    d = cd.load("designs/planar2.yaml")
    r = cd.workspace(d)                      # every grid pose
    r.feasible.sum(), r.feasible.size        # (18421, 22801)
    p = cd.pose(d, [0.75, 0.75])             # tensions, margin, W at one pose
    f = cd.fk(d, p.lengths)                  # back to the pose
    s = cd.size_motors(d)                    # motors, gears, drums
"""

from __future__ import annotations

from pathlib import Path

from cdpr_design.model.design import Design


def load(path: str | Path) -> Design:
    """Read and validate a design spec (YAML); errors name the offending key (:class:`SpecError`)."""
    from cdpr_design.model import spec

    return spec.load(path)


def workspace(design: Design, kind: str = "static", *, step: float | None = None, grid=None,
              orientation=None, orientations: str | None = None, interference: bool = False,
              engine: str = "auto", max_poses: int | None = None, force: bool = False,
              max_tilt: float | None = None):
    """Sweep the workspace grid and keep every pose: a :class:`~cdpr_design.workspaces.table.WorkspaceTable`.

    Parameters
    ----------
    design : Design
    kind : {'static', 'wrench-feasible', 'wrench-closure', 'dynamic'}
    step : float, optional
        Grid step [m] (default ``workspace.grid.step``).
    grid : Grid, optional
        Sweep this grid instead of the design's.
    orientation : (3,) array, optional
        Fixed orientation (rx, ry, rz) [rad] (default ``workspace.orientation``).
    orientations : {'total', 'range'}, optional
        Orientation workspaces of rotational motions (extra columns).
    interference : bool
        Intersect feasibility with the interference checks (column ``collision_free``).
    engine : {'auto', 'numba', 'numpy'}
    max_poses : int, optional
        Refuse grids with more poses than this (default 5,000,000; each pose
        holds about (k + 2 + 2 m) x 8 bytes); stream larger ones with
        :func:`cdpr_design.workspaces.run` and ``on_chunk``.
    force : bool
        Allow grids over the command line's sane-size limit (20 M poses).
    max_tilt : float, optional
        Largest hanging tilt [deg] of a feasible pose (an under-constrained design with
        ``effector.orientation: free``; default ``requirements.max_tilt``).

    Under-constrained designs add the columns ``tilt`` [deg] and ``orientation_*`` [rad]
    (``extra``): the orientation their effector hangs in (:mod:`cdpr_design.workspaces.hanging`).
    The result has ``feasible`` (bool, one per grid pose), ``margin`` [N],
    ``tensions`` [N], ``lengths`` [m], ``poses``, ``shape`` (the grid's),
    ``summary()`` and ``to_dict()`` / ``to_arrow()`` (the ``workspace.csv`` columns).
    """
    from cdpr_design.statics.robot import Analysis
    from cdpr_design.workspaces import table

    analysis = Analysis(kind=kind, collisions=interference, orientations=orientations, max_tilt=max_tilt,
                        engine=engine)
    return table.collect(design, analysis, step=step, grid=grid, orientation=orientation, force=force,
                         max_poses=table.MAX_COLLECT if max_poses is None else max_poses)


def pose(design: Design, at, kind: str = "static", *, objective: str = "min-norm", weights=None):
    """One pose ``at`` (the motion's coordinates [m, rad]): a :class:`~cdpr_design.statics.pose.PoseResult`
    (:func:`cdpr_design.workspaces.pose.evaluate_pose` of the design resolved for ``kind``).

    Lengths [m], tensions [N] (minimum 2-norm, or ``objective`` 'min-max' /
    'min-sum' with optional per-cable ``weights``; NaN where infeasible),
    ``feasible``, capacity ``margin`` [N], structure matrix ``W``, ``collisions``.
    """
    from cdpr_design.statics.robot import Analysis, resolve
    from cdpr_design.workspaces.pose import evaluate_pose

    robot = resolve(design, Analysis(command="statics", kind=kind, objective=objective, weights=weights is not None))
    return evaluate_pose(robot, at, weights)


def fk(design: Design, lengths, guess=None):
    """Forward kinematics: the pose for cable ``lengths`` [m] (a ``FKResult``: ``pose``,
    ``residual`` [m], ``method``).  Closed form for two planar cables, Levenberg-Marquardt
    from ``guess`` otherwise."""
    from cdpr_design.statics.kinematics import forward_kinematics

    return forward_kinematics(design, lengths, guess=guess)


def hanging_pose(design: Design, position):
    """The orientation an under-constrained design's effector hangs in at ``position`` [m]
    (a :class:`~cdpr_design.statics.hanging.HangingPose`: ``feasible``, ``reason``,
    ``orientation`` [rad], ``tilt_deg``, ``tensions`` [N], ``lengths`` [m], ``stable``),
    searched about ``workspace.orientation``."""
    from cdpr_design.statics import hanging

    return hanging.hanging_pose(design, position, nominal=hanging.nominal_rotation(design))


def size_motors(design: Design, catalogue=None, *, step: float | None = None, trajectory: str | None = None,
                safety_factor: float | None = None, motor: str | None = None):
    """Motor, gearbox and drum sizing: a :class:`~cdpr_design.design.sizing.SizingResult`.

    ``catalogue``: a ``Catalogue`` or the path of a catalogue YAML extending
    the shipped one (default: the shipped one).  ``trajectory``: the name of a
    spec trajectory whose duty cycle gives the RMS torque.  ``motor``: size
    every axis with this catalogue motor.  ``to_dict()`` gives the
    ``motor_sizing.csv`` columns.
    """
    from cdpr_design.design import sizing
    from cdpr_design.model import spec
    from cdpr_design.model.catalogue import Catalogue

    from cdpr_design.jobs.motion import design_samples
    from cdpr_design.statics.robot import Analysis, resolve

    cat = catalogue if isinstance(catalogue, Catalogue) else spec.load_catalogue(catalogue)
    samples = design_samples(design, trajectory)  # None without a trajectory
    sizing.check_options(design, cat, safety_factor, motor)  # the options first, then the robot
    robot = resolve(design, Analysis(command="size-motors"))
    return sizing.size_motors(robot, cat, step=step, samples=samples, safety_factor=safety_factor, motor=motor)


def certify(design: Design, kind: str = "static", **options):
    """Prove the workspace between grid samples by interval analysis: a
    :class:`~cdpr_design.workspaces.certify.CertifyResult` of ``design`` resolved for ``certify``
    and ``kind`` (``static`` or ``wrench-feasible``); ``options`` as for
    :func:`cdpr_design.workspaces.certify.certify` (``resolution`` [m], ``box``, ``min_margin`` [N],
    ``max_boxes``, ``time_limit`` [s], ``tolerance_outlets``, ``tolerance_attachments`` [m]...)."""
    from cdpr_design.workspaces import certify as cert

    return cert.certify(cert.check_certifiable(design, kind), **options)


def sweep(design: Design, vary: dict, *, step: float | None = None, workers: int = 1,
          scheduler: str | None = None, trajectory: str | None = None, safety_factor: float | None = None,
          motor: str | None = None, catalogue=None):
    """Evaluate variants of ``design``: a :class:`~cdpr_design.batch.results.SweepTable`.

    ``vary`` maps dotted spec keys to values, e.g. ``{"effector.mass": [0.5, 1, 2],
    "cables.0.outlet.0": "0:0.3:4"}`` (a list, or the command line's text
    ``a,b,c`` / ``start:stop:count``); every combination is one variant,
    evaluated like ``cdpr-design report`` (``step``, ``trajectory``,
    ``safety_factor``, ``motor``, ``catalogue`` as for :func:`size_motors`).
    ``workers`` processes (1: in this process), or a Dask ``scheduler``
    (``"local"`` or an address).  A variant that fails keeps its row with the
    reason in ``error``.
    """
    from cdpr_design import batch as sw
    from cdpr_design.batch.results import SweepTable
    from cdpr_design.model import spec

    pairs = [(k, sw.parse_values(v) if isinstance(v, str) else tuple(v)) for k, v in vary.items()]
    plan = sw.make_plan(design, pairs)
    cat = catalogue if catalogue is None or not isinstance(catalogue, (str, Path)) else spec.load_catalogue(catalogue)
    options = sw.Options(step=step, safety_factor=safety_factor, motor=motor, trajectory=trajectory, catalogue=cat)
    records: list[dict] = []
    sw.run(plan, options, workers=workers, scheduler=scheduler, on_record=records.append)
    return SweepTable(*sw.table(plan, records))
