"""The checks of a spec that depend on several keys (the second validation pass).

:class:`~cdpr_design.model.schema.DesignSpec` has checked structure and
types; :func:`check_semantics` checks vector lengths for the motion type,
min <= max, duplicate names, trajectory and PLC fields, the sweep section.
Every problem is a ``(key path, message)`` pair saying what was expected and
what was found; all of them are collected before the caller raises one
:class:`~cdpr_design.errors.SpecError`.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.errors import quote
from cdpr_design.model.design import MOTIONS, default_gravity, is_underconstrained, weight_problem
from cdpr_design.model.limits import net_id_problem
from cdpr_design.model.schema import DesignSpec, WorkspaceSpecModel

Problems = list[tuple[str, str]]


def check_semantics(s: DesignSpec) -> Problems:
    """Every cross-key problem of a structurally valid spec (empty when it is sound)."""
    p: Problems = []
    _check_frame_effector(p, s)
    _check_bounds(p, "tension", s.tension)
    _check_cables(p, s)
    if s.workspace is not None:
        _check_workspace(p, s, s.workspace)
    r = s.requirements
    if r is not None and r.task_box is not None:
        a = _motion_vec(p, s, "requirements.task_box.lower", r.task_box.lower)
        b = _motion_vec(p, s, "requirements.task_box.upper", r.task_box.upper)
        if a and b:
            _check_ordered(p, "requirements.task_box", r.task_box.lower, r.task_box.upper)
    for key in ("min_stiffness", "min_frequency"):
        if r is not None and getattr(r, key, None) is not None and r.task_box is None:
            p.append((f"requirements.{key}", "is checked over requirements.task_box, which the spec does not "
                                             "give: add the task box, or remove the requirement"))
    if r is not None and r.acceleration is not None:
        coords = MOTIONS[s.motion].coords
        what = f"numbers ({', '.join(coords)}) for motion {s.motion}"
        a = _vec(p, "requirements.acceleration.lower", r.acceleration.lower, len(coords), what)
        b = _vec(p, "requirements.acceleration.upper", r.acceleration.upper, len(coords), what)
        if a and b:
            _check_ordered(p, "requirements.acceleration", r.acceleration.lower, r.acceleration.upper)
    _check_hanging_weight(p, s)
    if r is not None and r.max_tilt is not None and s.effector.orientation != "free":
        p.append(("requirements.max_tilt", "a tilt limit needs effector.orientation: free (a fixed effector is "
                                           "held at its commanded orientation and does not tilt)"))
    _check_trajectories(p, s)
    if s.plc is not None:
        if (problem := net_id_problem(s.plc.ams_net_id)) is not None:
            p.append(("plc.ams_net_id", problem))
        m = len(s.cables)
        for key in ("setpoints", "actuals", "tensions"):
            v = getattr(s.plc, key)
            if v is not None and len(v) != m:
                p.append((f"plc.{key}", f"expected {m} symbol names (one per cable), got {len(v)}"))
    if s.sweep is not None:
        _check_sweep(p, s.sweep)
    if s.tolerance is not None and not isinstance(s.tolerance, (int, float)):
        for key in ("outlets", "attachments"):
            v = getattr(s.tolerance, key)
            if isinstance(v, list) and len(v) != len(s.cables):
                p.append((f"tolerance.{key}", f"expected one value or {len(s.cables)} (one per cable), got {len(v)}"))
    return p


# ----------------------------------------------------------------------------
# Helpers
# ----------------------------------------------------------------------------


def _vec(p: Problems, path: str, v, n: int, what: str = "numbers") -> bool:
    """Whether ``v`` (None counts as fine) has ``n`` entries; a problem when not."""
    if v is not None and len(v) != n:
        p.append((path, f"expected {n} {what}, got {len(v)}"))
        return False
    return True


def _motion_vec(p: Problems, s: DesignSpec, path: str, v) -> bool:
    """:func:`_vec` with one entry per position coordinate of the motion."""
    return _vec(p, path, v, MOTIONS[s.motion].dim, f"numbers for motion {s.motion}")


def _check_ordered(p: Problems, base: str, lower, upper, lower_name: str = "lower") -> None:
    """``base.upper[k]`` >= ``base.lower[k]`` for every k."""
    for k, (lo, hi) in enumerate(zip(lower, upper)):
        if lo > hi:
            p.append((f"{base}.upper[{k}]", f"expected a value >= {lower_name}[{k}] = {lo}, got {hi}"))


def _check_bounds(p: Problems, path: str, t) -> None:
    """A tension range [min, max] [N]: two numbers, 0 <= min <= max."""
    if t is None:
        return
    if len(t) != 2:
        p.append((path, f"expected [min, max] (2 numbers), got {len(t)}"))
    elif t[0] > t[1]:
        p.append((path, f"expected min <= max, got min {t[0]} > max {t[1]}"))
    elif t[0] < 0:
        p.append((path, f"expected min >= 0 (cables can only pull), got {t[0]}"))


# ----------------------------------------------------------------------------
# Sections
# ----------------------------------------------------------------------------


def _check_frame_effector(p: Problems, s: DesignSpec) -> None:
    """gravity, frame (lower < upper), effector size, centre of mass and inertia."""
    _motion_vec(p, s, "gravity", s.gravity)
    if _motion_vec(p, s, "frame.lower", s.frame.lower) & _motion_vec(p, s, "frame.upper", s.frame.upper):
        for k, (lo, hi) in enumerate(zip(s.frame.lower, s.frame.upper)):
            if lo >= hi:
                p.append((f"frame.upper[{k}]", f"expected a value above frame.lower[{k}] = {lo}, got {hi}"))
    _motion_vec(p, s, "effector.size", s.effector.size)
    if any(x < 0 for x in s.effector.size):
        p.append(("effector.size", "expected non-negative extents"))
    _motion_vec(p, s, "effector.center_of_mass", s.effector.center_of_mass)
    _check_inertia(p, s.effector.inertia, MOTIONS[s.motion].dim)


def _check_hanging_weight(p: Problems, s: DesignSpec) -> None:
    """An under-constrained design with ``effector.orientation: free`` hangs under its weight: it
    needs a weight (:func:`~cdpr_design.model.design.has_weight`; a fully constrained one is held either way)."""
    mot = MOTIONS[s.motion]
    B = [c.attachment for c in s.cables]
    gravity = s.gravity if s.gravity is not None else default_gravity(mot.dim)
    if s.effector.orientation != "free" or any(len(b) != mot.dim for b in B) or len(gravity) != mot.dim:
        return
    if not is_underconstrained(len(B), B, mot.planar):
        return
    why = weight_problem(s.effector.mass, gravity)
    if why:
        p.append(("effector.mass", f"effector.orientation: free: {why}"))


def _check_inertia(p: Problems, inertia, dim: int) -> None:
    """effector.inertia [kg m^2]: a scalar Izz (planar), 3 diagonal values or a symmetric PSD 3x3."""
    if inertia is None:
        return
    if isinstance(inertia, float):
        if inertia < 0:
            p.append(("effector.inertia", f"expected a non-negative number, got {inertia}"))
        elif dim == 3:
            p.append(("effector.inertia", "expected a 3x3 matrix (or 3 diagonal values) for a spatial motion, got a scalar"))
        return
    if any(isinstance(row, list) for row in inertia) and not all(
            isinstance(row, list) and len(row) == 3 for row in inertia):
        p.append(("effector.inertia", "expected a 3x3 matrix: 3 rows of 3 numbers each"))
        return
    arr = np.array(inertia, dtype=float)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3):
        p.append(("effector.inertia", f"expected a 3x3 matrix, 3 diagonal values or a scalar Izz, got shape {arr.shape}"))
    elif not np.allclose(arr, arr.T, atol=1e-12):
        p.append(("effector.inertia", "expected a symmetric matrix"))
    elif np.linalg.eigvalsh(arr).min() < -1e-12:
        p.append(("effector.inertia", "expected a positive semi-definite matrix"))


def _check_cables(p: Problems, s: DesignSpec) -> None:
    """Unique names, outlet/attachment lengths, tension ranges, pulley axes, plane offsets (planar
    motions only), winch motor names."""
    dim = MOTIONS[s.motion].dim
    seen: dict[str, int] = {}
    for i, c in enumerate(s.cables):
        base = f"cables[{i}]"
        if c.name in seen:
            p.append((f"{base}.name", f"duplicate cable name {quote(c.name)} (also cables[{seen[c.name]}])"))
        seen.setdefault(c.name, i)
        _motion_vec(p, s, f"{base}.outlet", c.outlet)
        _motion_vec(p, s, f"{base}.attachment", c.attachment)
        _check_bounds(p, f"{base}.tension", c.tension)
        if c.tension is None and s.tension is None:
            p.append((f"{base}.tension", "required: no design-wide tension is given"))
        if c.pulley is not None:
            if len(c.pulley.axis) != 3:
                p.append((f"{base}.pulley.axis", f"expected 3 numbers, got {len(c.pulley.axis)}"))
            elif np.linalg.norm(c.pulley.axis) == 0:
                p.append((f"{base}.pulley.axis", "expected a non-zero vector"))
            elif dim == 2 and c.pulley.radius > 0 and c.pulley.axis[2] != 0:
                p.append((f"{base}.pulley.axis", "a planar design needs a swivel axis in the x-y plane "
                          f"(z = 0; the direction the cable runs into the pulley), got {list(c.pulley.axis)}"))
        if c.plane_offset is not None and dim != 2:
            p.append((f"{base}.plane_offset", "only for planar motions (a spatial cable's outlet and "
                      "attachment give its height)"))
    _check_cable_models(p, s)
    for path, w in [("winch", s.winch)] + [(f"cables[{i}].winch", c.winch) for i, c in enumerate(s.cables)]:
        if w is not None and w.motor is not None and not w.motor.strip():
            p.append((f"{path}.motor", "expected a motor name, got an empty string"))


#: What each cable model needs (docs/cable-models.md).
MODEL_NEEDS = {"ideal": (), "elastic": ("axial_stiffness",), "sagging": ("axial_stiffness", "mass_per_length")}


def cable_model_problems(s: DesignSpec, override: str | None = None, option: str | None = None) -> Problems:
    """The properties each cable's model needs and does not have.

    ``override`` replaces every cable's model (the ``--cable-model`` option,
    named ``option`` in the messages).  ``mass_per_length`` must be > 0 for a
    sagging cable.
    """
    phys = s.cable
    out: Problems = []
    seen = set()
    for i, c in enumerate(s.cables):
        model = override or next((v for v in (c.model, phys.model if phys else None) if v is not None), "ideal")
        for key in MODEL_NEEDS[model]:
            own, shared = getattr(c, key), getattr(phys, key) if phys else None
            value = own if own is not None else shared
            path = f"cables[{i}].{key}" if own is not None else f"cable.{key}"
            why = f"cable model {model!r}" + (f" (from {option})" if override else "")
            if path in seen:
                continue
            if value is None:
                seen.add(path)
                out.append((path, f"required by {why}: give cable.{key} (or {key} on each cable)"))
            elif key == "mass_per_length" and value <= 0:
                seen.add(path)
                out.append((path, f"expected a positive mass per length [kg/m] for {why}, got {value}"))
    return out


def _check_cable_models(p: Problems, s: DesignSpec) -> None:
    """Each cable's model has the properties it needs."""
    p.extend(cable_model_problems(s))


def _check_workspace(p: Problems, s: DesignSpec, ws: WorkspaceSpecModel) -> None:
    """workspace: grid, orientation, orientation set/range, external wrench box."""
    mot = MOTIONS[s.motion]
    g = ws.grid
    if g is not None:
        ok = _motion_vec(p, s, "workspace.grid.lower", g.lower) & _motion_vec(p, s, "workspace.grid.upper", g.upper)
        if ok and g.lower is not None and g.upper is not None:
            _check_ordered(p, "workspace.grid", g.lower, g.upper, "workspace.grid.lower")
        if g.step is not None and len(g.step) not in (1, mot.dim):
            p.append(("workspace.grid.step",
                      f"expected a scalar or {mot.dim} numbers for motion {s.motion}, got {len(g.step)}"))
    nrot = len(mot.rotation_coords)
    if ws.orientation is not None and len(ws.orientation) != nrot:
        if nrot == 0:
            p.append(("workspace.orientation", f"motion {s.motion} has a fixed orientation: remove this key"))
        else:
            p.append(("workspace.orientation", f"expected {nrot} numbers ({', '.join(mot.rotation_coords)}) for motion {s.motion}, got {len(ws.orientation)}"))
    _check_orientations(p, s, ws)
    if ws.external_wrench is not None:
        box = ws.external_wrench
        what = f"numbers ({', '.join(mot.wrench_names)}) for motion {s.motion}"
        a = _vec(p, "workspace.external_wrench.lower", box.lower, mot.n, what)
        b = _vec(p, "workspace.external_wrench.upper", box.upper, mot.n, what)
        if a and b:
            _check_ordered(p, "workspace.external_wrench", box.lower, box.upper)


def _check_orientations(p: Problems, s: DesignSpec, ws: WorkspaceSpecModel) -> None:
    """workspace.orientation_set and workspace.orientation_range: one entry per rotation coordinate."""
    mot = MOTIONS[s.motion]
    nrot = len(mot.rotation_coords)
    what = f"numbers ({', '.join(mot.rotation_coords)}) for motion {s.motion}"
    for key in ("orientation_set", "orientation_range"):
        if getattr(ws, key) is not None and nrot == 0:
            p.append((f"workspace.{key}", f"motion {s.motion} has a fixed orientation: remove this key"))
    if nrot == 0:
        return
    o = ws.orientation_set
    if o is not None:
        a = _vec(p, "workspace.orientation_set.lower", o.lower, nrot, what)
        b = _vec(p, "workspace.orientation_set.upper", o.upper, nrot, what)
        if len(o.count) not in (1, nrot):
            p.append(("workspace.orientation_set.count", f"expected a scalar or {nrot} counts, got {len(o.count)}"))
        if a and b:
            _check_ordered(p, "workspace.orientation_set", o.lower, o.upper)
    r = ws.orientation_range
    if r is not None:
        if len(r.max) not in (1, nrot):
            p.append(("workspace.orientation_range.max", f"expected a scalar or {nrot} {what}, got {len(r.max)}"))
        elif not any(v > 0 for v in r.max):
            p.append(("workspace.orientation_range.max", "expected at least one positive half-width"))


#: The keys each path type needs.
_PATH_KEYS = {"square": ("center", "side"), "circle": ("center", "radius"),
              "polyline": ("waypoints",), "csv": ("file",)}


def _check_trajectories(p: Problems, s: DesignSpec) -> None:
    """trajectories: the keys each path type needs, point lengths, orientation length."""
    mot = MOTIONS[s.motion]
    d, ncoords = mot.dim, len(mot.coords)
    for name, t in (s.trajectories or {}).items():
        base = f"trajectories.{name}"
        for key in _PATH_KEYS[t.type]:
            if getattr(t, key) is None:
                p.append((f"{base}.{key}", f"required for a {t.type} path"))
        _motion_vec(p, s, f"{base}.center", t.center)
        _motion_vec(p, s, f"{base}.start", t.start)
        if t.waypoints is not None:
            if len(t.waypoints) < 2:
                p.append((f"{base}.waypoints", f"expected at least 2 waypoints, got {len(t.waypoints)}"))
            for k, wp in enumerate(t.waypoints):
                if len(wp) not in (d, ncoords):
                    p.append((f"{base}.waypoints[{k}]", f"expected {d} (position) or {ncoords} (pose) numbers for motion {s.motion}, got {len(wp)}"))
        if t.orientation is not None and len(t.orientation) != len(mot.rotation_coords):
            p.append((f"{base}.orientation", f"expected {len(mot.rotation_coords)} numbers for motion {s.motion}, got {len(t.orientation)}"))


def _check_sweep(p: Problems, sweep: dict) -> None:
    """sweep: known keys, ``vary`` a mapping of dotted keys to values, ``workers`` >= 1, ``rank_by`` a name."""
    for key in sweep:
        if key not in ("vary", "rank_by", "workers"):
            p.append((f"sweep.{key}", "unknown key (expected vary, rank_by or workers)"))
    vary = sweep.get("vary")
    if vary is not None and not isinstance(vary, dict):
        p.append(("sweep.vary", f"expected a mapping of dotted keys to values, got {quote(vary)}"))
    elif vary:
        for key, v in vary.items():
            ok = (isinstance(v, str) or (isinstance(v, list) and len(v) > 0)
                  or (isinstance(v, (int, float)) and not isinstance(v, bool)))
            if not ok:
                p.append((f"sweep.vary.{key}", f"expected a list of values or 'start:stop:count', got {quote(v)}"))
    workers = sweep.get("workers")
    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool) or workers < 1):
        p.append(("sweep.workers", f"expected a whole number >= 1, got {quote(workers)}"))
    rank_by = sweep.get("rank_by")
    if rank_by is not None and not isinstance(rank_by, str):
        p.append(("sweep.rank_by", f"expected a figure name such as fraction, got {quote(rank_by)}"))
