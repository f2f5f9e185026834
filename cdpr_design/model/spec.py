"""The only YAML reader: validate a design spec, then build the model.

Validation happens in two passes so that every message names the offending
key by its path and says what was expected and what was found:

1. :class:`DesignSpec` (pydantic) checks structure and types: unknown keys,
   missing keys, non-numbers, non-finite numbers, signs.
2. :func:`_check_semantics` checks what depends on other keys: vector lengths
   for the motion type, min <= max, duplicate names, trajectory fields.

Both collect every problem before raising one :class:`~cdpr_design.errors.SpecError`.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError
from pydantic.types import FiniteFloat

from cdpr_design.errors import SpecError
from cdpr_design.model.design import (  # noqa: I001
    MOTIONS, Cable, CableProps, Design, Effector, Grid, OrientationRange, OrientationSet, Plc, Pulley, Requirements,
    Trajectory, Winch, WorkspaceSpec, WrenchBox, pad3,
)

# ----------------------------------------------------------------------------
# pydantic models of the YAML format (structure and types only)
# ----------------------------------------------------------------------------


def _as_list(v):
    """Accept a scalar where a list of values is allowed (``step: 0.01``)."""
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return [v]
    return v


Vec = list[FiniteFloat]
PosFloat = Annotated[FiniteFloat, Field(gt=0)]
NonNegFloat = Annotated[FiniteFloat, Field(ge=0)]
ScalarOrList = Annotated[list[PosFloat], BeforeValidator(_as_list)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class WinchSpec(_Strict):
    drum_radius: ScalarOrList | None = Field(None, description="Drum radius [m]; a list to search candidates")
    gear_ratio: ScalarOrList | None = Field(None, description="Motor turns per drum turn; a list to search candidates")
    efficiency: Annotated[FiniteFloat, Field(gt=0, le=1)] | None = Field(None, description="Gearbox efficiency (0, 1]")
    drum_inertia: NonNegFloat | None = Field(None, description="Drum inertia about its axis [kg m^2]")
    motor: str | None = Field(None, description="Motor name from the catalogue")


class PulleySpec(_Strict):
    radius: NonNegFloat = Field(description="Pulley radius [m]")
    axis: Vec = Field([0.0, 0.0, 1.0], description="Swivel axis (frame coordinates)")


class CablePhysSpec(_Strict):
    diameter: NonNegFloat | None = Field(None, description="Cable diameter [m]")
    axial_stiffness: PosFloat | None = Field(None, description="Axial stiffness EA [N]")
    mass_per_length: NonNegFloat | None = Field(None, description="Linear density [kg/m]")


class CableSpec(_Strict):
    name: str = Field(min_length=1)
    outlet: Vec = Field(description="a_i: where the cable leaves the frame (frame coordinates) [m]")
    attachment: Vec = Field(description="b_i: where it meets the effector (platform coordinates) [m]")
    tension: Vec | None = Field(None, description="[min, max] tension [N]; overrides the design-wide bounds")
    winch: WinchSpec | None = None
    pulley: PulleySpec | None = None
    diameter: NonNegFloat | None = None
    axial_stiffness: PosFloat | None = None
    mass_per_length: NonNegFloat | None = None


class EffectorSpec(_Strict):
    mass: NonNegFloat = Field(description="Mass [kg]")
    size: Vec = Field(description="Box extents [m], centred on the platform origin")
    center_of_mass: Vec | None = Field(None, description="Platform coordinates [m]")
    inertia: FiniteFloat | list[FiniteFloat] | list[list[FiniteFloat]] | None = Field(
        None, description="Inertia about the COM [kg m^2]: 3x3 (spatial) or Izz (planar)")


class FrameSpec(_Strict):
    lower: Vec
    upper: Vec


class GridSpec(_Strict):
    lower: Vec | None = None
    upper: Vec | None = None
    step: ScalarOrList | None = Field(None, description="Grid step [m]: a scalar or one value per axis")


class BoxSpec(_Strict):
    lower: Vec
    upper: Vec


class OrientationSetSpec(_Strict):
    lower: Vec = Field(description="Lowest orientation, rotation coordinates [rad]")
    upper: Vec = Field(description="Highest orientation, rotation coordinates [rad]")
    count: Annotated[list[Annotated[int, Field(ge=1)]], BeforeValidator(_as_list)] = Field(
        [5], description="Samples per coordinate (both ends included): a scalar or one per coordinate")


class OrientationRangeSpec(_Strict):
    max: Annotated[list[NonNegFloat], BeforeValidator(_as_list)] = Field(
        description="Largest half-width tested around workspace.orientation [rad]: a scalar or one per coordinate (0: held)")
    levels: Annotated[int, Field(ge=1)] = Field(10, description="Nested boxes tested (half-width k/levels * max)")
    count: Annotated[int, Field(ge=2)] = Field(3, description="Samples per coordinate of each box (both ends included)")


class WorkspaceSpecModel(_Strict):
    grid: GridSpec | None = None
    orientation: Vec | None = None
    external_wrench: BoxSpec | None = None
    orientation_set: OrientationSetSpec | None = Field(
        None, description="Total orientation workspace: feasible for every orientation of this sampled box")
    orientation_range: OrientationRangeSpec | None = Field(
        None, description="Orientation range per position around workspace.orientation")


class RequirementsSpec(_Strict):
    task_box: BoxSpec | None = None
    max_speed: NonNegFloat | None = Field(None, description="Effector speed in any direction [m/s]")
    max_acceleration: NonNegFloat | None = Field(None, description="Effector acceleration [m/s^2]")
    min_margin: FiniteFloat | None = Field(None, description="Capacity margin at every task pose [N]")
    min_fraction: Annotated[FiniteFloat, Field(ge=0, le=1)] | None = Field(
        None, description="Least feasible fraction of the workspace grid")
    safety_factor: Annotated[FiniteFloat, Field(ge=1)] | None = Field(
        None, description="Factor on required motor torque and speed when sizing")


class TrajectorySpec(_Strict):
    type: Literal["square", "polyline", "circle", "csv"]
    speed: PosFloat = Field(description="Cruise speed [m/s]")
    acceleration: PosFloat = Field(description="Acceleration limit [m/s^2]")
    center: Vec | None = None
    side: PosFloat | None = None
    radius: PosFloat | None = None
    waypoints: list[Vec] | None = None
    file: str | None = None
    jerk: PosFloat | None = Field(None, description="Jerk limit [m/s^3] (optional)")
    cycle_time: PosFloat | None = Field(None, description="Sample period [s]; default 0.001")
    start: Vec | None = Field(None, description="Where the effector starts (default: the path's first point)")
    laps: Annotated[int, Field(ge=1)] = 1
    orientation: Vec | None = None


class PlcSpec(_Strict):
    ams_net_id: str
    port: Annotated[int, Field(ge=1, le=65535)] = 851
    host: str | None = None
    cycle_time: PosFloat = 0.01
    setpoints: list[str]
    actuals: list[str]
    tensions: list[str] | None = None
    pose: str | None = None
    heartbeat: str | None = None
    fault: str | None = None


class DesignSpec(_Strict):
    """A cable-driven parallel robot design (cdpr-design spec format)."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.+-]+$",
                      description="Design name; also the default output folder out/<name>/")
    description: str = ""
    motion: Literal["2T", "1R2T", "3T", "3R3T"]
    gravity: Vec | None = Field(None, description="m/s^2; default -9.81 along the last axis")
    frame: FrameSpec
    effector: EffectorSpec
    tension: Vec | None = Field(None, description="[min, max] N for every cable")
    cables: list[CableSpec] = Field(min_length=1)
    winch: WinchSpec | None = None
    cable: CablePhysSpec | None = None
    workspace: WorkspaceSpecModel | None = None
    trajectories: dict[str, TrajectorySpec] | None = None
    plc: PlcSpec | None = None
    requirements: RequirementsSpec | None = None
    sweep: dict[str, Any] | None = Field(None, description="Parameter sweep: vary: {dotted.key: values}")


# ----------------------------------------------------------------------------
# YAML
# ----------------------------------------------------------------------------


class _UniqueKeyLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping."""


def _construct_mapping(loader, node, deep=False):
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"key {key!r} is given twice", key_node.start_mark)
        seen.add(key)
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def read_yaml(path: str | Path) -> Any:
    """Read a YAML file with the safe loader; bad files raise :class:`SpecError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpecError([("", f"no such file: {path}")]) from None
    except IsADirectoryError:
        raise SpecError([("", f"{path} is a folder, expected a YAML file")]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError([("", f"cannot read {path}: {exc}")]) from None
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise SpecError([("", f"not valid YAML: {exc}")], source=str(path)) from None


# ----------------------------------------------------------------------------
# Validation
# ----------------------------------------------------------------------------


def format_loc(loc) -> str:
    """pydantic's error location as a key path: ``cables[1].outlet``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            part = str(part)
            # drop the union-member tags pydantic inserts (``float``, ``list[float]``)
            if part in ("float", "int", "str", "list[float]", "list[list[float]]") or part.startswith(
                    ("function-", "list[", "constrained-")):
                continue
            out += ("." if out else "") + part
    return out


def _pydantic_problems(err: ValidationError) -> list[tuple[str, str]]:
    problems: dict[str, str] = {}
    for e in err.errors(include_url=False):
        path = format_loc(e["loc"])
        kind = e["type"]
        got = e.get("input")
        if kind == "missing":
            msg = "required key is missing"
        elif kind == "extra_forbidden":
            msg = "unknown key (check its spelling against the spec format)"
        elif kind == "finite_number":
            msg = f"expected a finite number, got {got!r}"
        elif kind in ("float_type", "float_parsing", "int_type", "int_parsing"):
            msg = f"expected a number, got {got!r}"
        elif kind == "list_type":
            msg = f"expected a list, got {got!r}"
        elif kind == "literal_error":
            allowed = e.get("ctx", {}).get("expected", "")
            msg = f"expected one of {allowed}, got {got!r}"
        elif kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
            msg = f"{e['msg'].replace('Input should be', 'expected a value')}, got {got!r}"
        elif kind == "model_type" or kind == "dict_type":
            msg = f"expected a mapping of keys, got {got!r}"
        elif kind == "too_short":
            msg = f"expected at least {e.get('ctx', {}).get('min_length', 1)} entries, got {len(got) if hasattr(got, '__len__') else got!r}"
        elif kind == "string_pattern_mismatch":
            msg = f"expected letters, digits and _ . + - only, got {got!r}"
        else:
            msg = f"{e['msg']}, got {got!r}"
        # unions report once per member: keep the first message for a path
        problems.setdefault(path, msg)
    return list(problems.items())


def _vec(problems, path, v, n, what="numbers"):
    if v is not None and len(v) != n:
        problems.append((path, f"expected {n} {what}, got {len(v)}"))
        return False
    return True


def _check_semantics(s: DesignSpec) -> list[tuple[str, str]]:
    p: list[tuple[str, str]] = []
    mot = MOTIONS[s.motion]
    d = mot.dim
    dm = f"{d} numbers for motion {s.motion}"

    def vec(path, v, n=d, what=None):
        return _vec(p, path, v, n, what or (f"numbers for motion {s.motion}" if n == d else "numbers"))

    vec("gravity", s.gravity)
    if vec("frame.lower", s.frame.lower) & vec("frame.upper", s.frame.upper):
        for k, (lo, hi) in enumerate(zip(s.frame.lower, s.frame.upper)):
            if lo >= hi:
                p.append((f"frame.upper[{k}]", f"expected a value above frame.lower[{k}] = {lo}, got {hi}"))
    vec("effector.size", s.effector.size)
    if any(x < 0 for x in s.effector.size):
        p.append(("effector.size", "expected non-negative extents"))
    vec("effector.center_of_mass", s.effector.center_of_mass)
    inertia = s.effector.inertia
    if inertia is not None:
        if isinstance(inertia, float):
            if inertia < 0:
                p.append(("effector.inertia", f"expected a non-negative number, got {inertia}"))
            elif d == 3:
                p.append(("effector.inertia", "expected a 3x3 matrix (or 3 diagonal values) for a spatial motion, got a scalar"))
        else:
            arr = np.array(inertia, dtype=float)
            if arr.shape == (3,):
                arr = np.diag(arr)
            if arr.shape != (3, 3):
                p.append(("effector.inertia", f"expected a 3x3 matrix, 3 diagonal values or a scalar Izz, got shape {arr.shape}"))
            elif not np.allclose(arr, arr.T, atol=1e-12):
                p.append(("effector.inertia", "expected a symmetric matrix"))
            elif np.linalg.eigvalsh(arr).min() < -1e-12:
                p.append(("effector.inertia", "expected a positive semi-definite matrix"))

    def bounds(path, t):
        if t is None:
            return
        if len(t) != 2:
            p.append((path, f"expected [min, max] (2 numbers), got {len(t)}"))
        elif t[0] > t[1]:
            p.append((path, f"expected min <= max, got min {t[0]} > max {t[1]}"))
        elif t[0] < 0:
            p.append((path, f"expected min >= 0 (cables can only pull), got {t[0]}"))

    bounds("tension", s.tension)
    seen: dict[str, int] = {}
    for i, c in enumerate(s.cables):
        base = f"cables[{i}]"
        if c.name in seen:
            p.append((f"{base}.name", f"duplicate cable name {c.name!r} (also cables[{seen[c.name]}])"))
        seen.setdefault(c.name, i)
        vec(f"{base}.outlet", c.outlet)
        vec(f"{base}.attachment", c.attachment)
        bounds(f"{base}.tension", c.tension)
        if c.tension is None and s.tension is None:
            p.append((f"{base}.tension", "required: no design-wide tension is given"))
        if c.pulley is not None:
            if len(c.pulley.axis) != 3:
                p.append((f"{base}.pulley.axis", f"expected 3 numbers, got {len(c.pulley.axis)}"))
            elif np.linalg.norm(c.pulley.axis) == 0:
                p.append((f"{base}.pulley.axis", "expected a non-zero vector"))
            elif d == 2 and c.pulley.radius > 0 and c.pulley.axis[2] != 0:
                p.append((f"{base}.pulley.axis", "a planar design needs a swivel axis in the x-y plane "
                          f"(z = 0; the direction the cable runs into the pulley), got {list(c.pulley.axis)}"))
    for path, w in [("winch", s.winch)] + [(f"cables[{i}].winch", c.winch) for i, c in enumerate(s.cables)]:
        if w is not None and w.motor is not None and not w.motor.strip():
            p.append((f"{path}.motor", "expected a motor name, got an empty string"))

    ws = s.workspace
    if ws is not None:
        g = ws.grid
        if g is not None:
            ok = vec("workspace.grid.lower", g.lower) & vec("workspace.grid.upper", g.upper)
            if ok and g.lower is not None and g.upper is not None:
                for k, (lo, hi) in enumerate(zip(g.lower, g.upper)):
                    if lo > hi:
                        p.append((f"workspace.grid.upper[{k}]", f"expected a value >= workspace.grid.lower[{k}] = {lo}, got {hi}"))
            if g.step is not None and len(g.step) not in (1, d):
                p.append(("workspace.grid.step", f"expected a scalar or {dm}, got {len(g.step)}"))
        nrot = len(mot.rotation_coords)
        if ws.orientation is not None and len(ws.orientation) != nrot:
            if nrot == 0:
                p.append(("workspace.orientation", f"motion {s.motion} has a fixed orientation: remove this key"))
            else:
                p.append(("workspace.orientation", f"expected {nrot} numbers ({', '.join(mot.rotation_coords)}) for motion {s.motion}, got {len(ws.orientation)}"))
        for key in ("orientation_set", "orientation_range"):
            o = getattr(ws, key)
            if o is None:
                continue
            if nrot == 0:
                p.append((f"workspace.{key}", f"motion {s.motion} has a fixed orientation: remove this key"))
                continue
            what = f"numbers ({', '.join(mot.rotation_coords)}) for motion {s.motion}"
            if key == "orientation_set":
                a = _vec(p, "workspace.orientation_set.lower", o.lower, nrot, what)
                b = _vec(p, "workspace.orientation_set.upper", o.upper, nrot, what)
                if len(o.count) not in (1, nrot):
                    p.append(("workspace.orientation_set.count", f"expected a scalar or {nrot} counts, got {len(o.count)}"))
                if a and b:
                    for k, (lo, hi) in enumerate(zip(o.lower, o.upper)):
                        if lo > hi:
                            p.append((f"workspace.orientation_set.upper[{k}]", f"expected a value >= lower[{k}] = {lo}, got {hi}"))
            else:
                if len(o.max) not in (1, nrot):
                    p.append(("workspace.orientation_range.max", f"expected a scalar or {nrot} {what}, got {len(o.max)}"))
                elif not any(v > 0 for v in o.max):
                    p.append(("workspace.orientation_range.max", "expected at least one positive half-width"))
        if ws.external_wrench is not None:
            n = mot.n
            names = ", ".join(mot.wrench_names)
            a = _vec(p, "workspace.external_wrench.lower", ws.external_wrench.lower, n, f"numbers ({names}) for motion {s.motion}")
            b = _vec(p, "workspace.external_wrench.upper", ws.external_wrench.upper, n, f"numbers ({names}) for motion {s.motion}")
            if a and b:
                for k, (lo, hi) in enumerate(zip(ws.external_wrench.lower, ws.external_wrench.upper)):
                    if lo > hi:
                        p.append((f"workspace.external_wrench.upper[{k}]", f"expected a value >= lower[{k}] = {lo}, got {hi}"))

    r = s.requirements
    if r is not None and r.task_box is not None:
        a = vec("requirements.task_box.lower", r.task_box.lower)
        b = vec("requirements.task_box.upper", r.task_box.upper)
        if a and b:
            for k, (lo, hi) in enumerate(zip(r.task_box.lower, r.task_box.upper)):
                if lo > hi:
                    p.append((f"requirements.task_box.upper[{k}]", f"expected a value >= lower[{k}] = {lo}, got {hi}"))

    ncoords = len(mot.coords)
    for name, t in (s.trajectories or {}).items():
        base = f"trajectories.{name}"
        need = {"square": ("center", "side"), "circle": ("center", "radius"),
                "polyline": ("waypoints",), "csv": ("file",)}[t.type]
        for key in need:
            if getattr(t, key) is None:
                p.append((f"{base}.{key}", f"required for a {t.type} path"))
        if t.center is not None:
            vec(f"{base}.center", t.center)
        if t.start is not None:
            vec(f"{base}.start", t.start)
        if t.waypoints is not None:
            if len(t.waypoints) < 2:
                p.append((f"{base}.waypoints", f"expected at least 2 waypoints, got {len(t.waypoints)}"))
            for k, wp in enumerate(t.waypoints):
                if len(wp) not in (d, ncoords):
                    p.append((f"{base}.waypoints[{k}]", f"expected {d} (position) or {ncoords} (pose) numbers for motion {s.motion}, got {len(wp)}"))
        if t.orientation is not None and len(t.orientation) != len(mot.rotation_coords):
            p.append((f"{base}.orientation", f"expected {len(mot.rotation_coords)} numbers for motion {s.motion}, got {len(t.orientation)}"))

    if s.plc is not None:
        m = len(s.cables)
        for key in ("setpoints", "actuals", "tensions"):
            v = getattr(s.plc, key)
            if v is not None and len(v) != m:
                p.append((f"plc.{key}", f"expected {m} symbol names (one per cable), got {len(v)}"))
    if s.sweep is not None:
        for key in s.sweep:
            if key not in ("vary", "rank_by", "workers"):
                p.append((f"sweep.{key}", "unknown key (expected vary, rank_by or workers)"))
        vary = s.sweep.get("vary")
        if vary is not None and not isinstance(vary, dict):
            p.append(("sweep.vary", f"expected a mapping of dotted keys to values, got {vary!r}"))
        elif vary:
            for key, v in vary.items():
                ok = (isinstance(v, str) or (isinstance(v, list) and len(v) > 0)
                      or (isinstance(v, (int, float)) and not isinstance(v, bool)))
                if not ok:
                    p.append((f"sweep.vary.{key}", f"expected a list of values or 'start:stop:count', got {v!r}"))
        workers = s.sweep.get("workers")
        if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool) or workers < 1):
            p.append(("sweep.workers", f"expected a whole number >= 1, got {workers!r}"))
        rank_by = s.sweep.get("rank_by")
        if rank_by is not None and not isinstance(rank_by, str):
            p.append(("sweep.rank_by", f"expected a figure name such as fraction, got {rank_by!r}"))
    return p


def validate(data: Any, source: str | None = None) -> DesignSpec:
    """Validate plain data (a parsed YAML document) against the spec format."""
    if not isinstance(data, dict):
        raise SpecError([("", f"expected a mapping of keys at the top of the spec, got {type(data).__name__}")], source)
    try:
        s = DesignSpec.model_validate(data)
    except ValidationError as err:
        raise SpecError(_pydantic_problems(err), source) from None
    problems = _check_semantics(s)
    if problems:
        raise SpecError(problems, source)
    return s


# ----------------------------------------------------------------------------
# Building the model
# ----------------------------------------------------------------------------


def _t3(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in pad3(v))


def _winch(default: WinchSpec | None, override: WinchSpec | None) -> Winch:
    merged: dict[str, Any] = {}
    for w in (default, override):
        if w is not None:
            merged.update({k: v for k, v in w.model_dump().items() if v is not None})
    kw: dict[str, Any] = {}
    if "drum_radius" in merged:
        kw["drum_radii"] = tuple(merged["drum_radius"])
    if "gear_ratio" in merged:
        kw["gear_ratios"] = tuple(merged["gear_ratio"])
    for k in ("efficiency", "drum_inertia", "motor"):
        if k in merged:
            kw[k] = merged[k]
    return Winch(**kw)


def _default_inertia(mass: float, size: np.ndarray, planar: bool) -> np.ndarray:
    """Inertia of a uniform box of the effector's size about its centre [kg m^2]."""
    a, b, c = size
    return np.diag([mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12])


def build(s: DesignSpec, raw: dict | None = None, source: str | None = None) -> Design:
    """Build the frozen :class:`~cdpr_design.model.design.Design` from a validated spec."""
    mot = MOTIONS[s.motion]
    d = mot.dim
    g = pad3(s.gravity) if s.gravity is not None else pad3([0.0] * (d - 1) + [-9.81])
    frame_lo, frame_hi = pad3(s.frame.lower), pad3(s.frame.upper)
    size = pad3(s.effector.size)
    com = pad3(s.effector.center_of_mass) if s.effector.center_of_mass is not None else np.zeros(3)
    inertia = s.effector.inertia
    if inertia is None:
        I = _default_inertia(s.effector.mass, size, mot.planar)
    elif isinstance(inertia, float):
        I = np.diag([0.0, 0.0, inertia])
    else:
        I = np.array(inertia, dtype=float)
        if I.shape == (3,):
            I = np.diag(I)
    eff = Effector(mass=s.effector.mass, size=_t3(size), center_of_mass=_t3(com),
                   inertia=tuple(tuple(float(x) for x in row) for row in I))

    phys = s.cable or CablePhysSpec()
    cables = []
    for c in s.cables:
        t = c.tension if c.tension is not None else s.tension
        props = CableProps(
            diameter=next(v for v in (c.diameter, phys.diameter, 0.0) if v is not None),
            axial_stiffness=c.axial_stiffness if c.axial_stiffness is not None else phys.axial_stiffness,
            mass_per_length=next(v for v in (c.mass_per_length, phys.mass_per_length, 0.0) if v is not None),
        )
        pulley = None
        if c.pulley is not None:
            ax = np.asarray(c.pulley.axis, float)
            pulley = Pulley(radius=c.pulley.radius, axis=_t3(ax / np.linalg.norm(ax)))
        cables.append(Cable(
            name=c.name, outlet=_t3(c.outlet), attachment=_t3(c.attachment),
            tension_min=float(t[0]), tension_max=float(t[1]), winch=_winch(s.winch, c.winch),
            pulley=pulley, props=props,
        ))

    ws = s.workspace or WorkspaceSpecModel()
    gs = ws.grid or GridSpec()
    lo = tuple(gs.lower) if gs.lower is not None else tuple(frame_lo[:d])
    hi = tuple(gs.upper) if gs.upper is not None else tuple(frame_hi[:d])
    if gs.step is not None:
        step = tuple(gs.step) * d if len(gs.step) == 1 else tuple(gs.step)
    else:
        per_axis = 150 if d == 2 else 30
        ext = max(h - l for l, h in zip(lo, hi)) or 1.0
        step = (float(ext / per_axis),) * d
    grid = Grid(lower=lo, upper=hi, step=step)
    ext = None
    if ws.external_wrench is not None:
        ext = WrenchBox(tuple(ws.external_wrench.lower), tuple(ws.external_wrench.upper))
    ori = tuple(ws.orientation) if ws.orientation is not None else (0.0,) * len(mot.rotation_coords)
    oset = orng = None
    nrot = len(mot.rotation_coords)
    if ws.orientation_set is not None:
        cnt = list(ws.orientation_set.count)
        oset = OrientationSet(tuple(ws.orientation_set.lower), tuple(ws.orientation_set.upper),
                              tuple(int(c) for c in (cnt * nrot if len(cnt) == 1 else cnt)))
    if ws.orientation_range is not None:
        mx = list(ws.orientation_range.max)
        orng = OrientationRange(tuple(mx * nrot if len(mx) == 1 else mx),
                                ws.orientation_range.levels, ws.orientation_range.count)
    wspec = WorkspaceSpec(grid=grid, orientation=ori, external_wrench=ext,
                          orientation_set=oset, orientation_range=orng)

    req = s.requirements or RequirementsSpec()
    requirements = Requirements(
        task_box=(tuple(req.task_box.lower), tuple(req.task_box.upper)) if req.task_box else None,
        max_speed=req.max_speed, max_acceleration=req.max_acceleration,
        min_margin=req.min_margin, min_fraction=req.min_fraction,
        safety_factor=req.safety_factor if req.safety_factor is not None else 1.0,
    )
    trajs = {}
    for name, t in (s.trajectories or {}).items():
        trajs[name] = Trajectory(
            name=name, type=t.type, speed=t.speed, acceleration=t.acceleration,
            center=tuple(t.center) if t.center else None, side=t.side, radius=t.radius,
            waypoints=tuple(tuple(w) for w in t.waypoints) if t.waypoints else None,
            file=t.file, jerk=t.jerk, cycle_time=t.cycle_time,
            start=tuple(t.start) if t.start else None, laps=t.laps,
            orientation=tuple(t.orientation) if t.orientation else None,
        )
    plc = None
    if s.plc is not None:
        plc = Plc(ams_net_id=s.plc.ams_net_id, port=s.plc.port, host=s.plc.host,
                  cycle_time=s.plc.cycle_time, setpoints=tuple(s.plc.setpoints),
                  actuals=tuple(s.plc.actuals), tensions=tuple(s.plc.tensions or ()),
                  pose=s.plc.pose, heartbeat=s.plc.heartbeat, fault=s.plc.fault)
    return Design(
        name=s.name, motion=mot, gravity=_t3(g), frame_lower=_t3(frame_lo),
        frame_upper=_t3(frame_hi), effector=eff, cables=tuple(cables), workspace=wspec,
        description=s.description, requirements=requirements, trajectories=trajs, plc=plc,
        sweep=dict(s.sweep or {}), raw=copy.deepcopy(raw) if raw is not None else s.model_dump(exclude_none=True),
        source=source,
    )


def from_dict(data: Any, source: str | None = None) -> Design:
    """Validate plain data and build the design."""
    s = validate(data, source)
    return build(s, raw=data, source=source)


def load(path: str | Path) -> Design:
    """Read, validate and build a design spec file.

    Raises
    ------
    SpecError
        The file is missing, is not YAML, or breaks the spec format; the
        message names each offending key by its path.
    """
    data = read_yaml(path)
    return from_dict(data, source=str(path))


def json_schema() -> dict:
    """The JSON Schema of the spec format (for editors' YAML validation)."""
    schema = DesignSpec.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "cdpr-design spec"
    return schema


def schema_text() -> str:
    return json.dumps(json_schema(), indent=2)


def is_finite_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


# ----------------------------------------------------------------------------
# Motor catalogue (cdpr_design/data/motors.yaml and users' --catalogue files)
# ----------------------------------------------------------------------------


class DriveEntry(_Strict):
    name: str = Field(min_length=1)
    rated_current: PosFloat = Field(description="Rated current [A rms]")
    peak_current: PosFloat = Field(description="Peak current [A rms]")
    source: str = ""


class MotorEntry(_Strict):
    name: str = Field(min_length=1)
    rated_torque: PosFloat = Field(description="Rated (continuous) torque [N m]")
    peak_torque: PosFloat = Field(description="Peak torque [N m]")
    max_speed: PosFloat = Field(description="Speed limit checked by the sizing [rpm]")
    rotor_inertia: NonNegFloat = Field(description="Rotor inertia [kg m^2]")
    torque_constant: PosFloat | None = Field(None, description="[N m/A]")
    rated_current: PosFloat | None = None
    peak_current: PosFloat | None = None
    drive: str | None = Field(None, description="Name of a drive entry whose current limits apply")
    source: str = Field("", description="Where the figures come from")


class GearboxEntry(_Strict):
    name: str = Field(min_length=1)
    ratio: PosFloat = Field(description="Motor turns per drum turn")
    efficiency: Annotated[FiniteFloat, Field(gt=0, le=1)] = 1.0
    inertia: NonNegFloat = Field(0.0, description="Inertia at the motor shaft [kg m^2]")
    source: str = ""


class CatalogueSpec(_Strict):
    """A motor catalogue: motors, drives and gearboxes."""

    motors: list[MotorEntry] = []
    drives: list[DriveEntry] = []
    gearboxes: list[GearboxEntry] = []


def _check_catalogue(c: CatalogueSpec) -> list[tuple[str, str]]:
    p: list[tuple[str, str]] = []
    for key in ("motors", "drives", "gearboxes"):
        seen: dict[str, int] = {}
        for i, e in enumerate(getattr(c, key)):
            if e.name in seen:
                p.append((f"{key}[{i}].name", f"duplicate name {e.name!r} (also {key}[{seen[e.name]}])"))
            seen.setdefault(e.name, i)
    drives = {d.name for d in c.drives}
    for i, m in enumerate(c.motors):
        if m.peak_torque < m.rated_torque:
            p.append((f"motors[{i}].peak_torque", f"expected a value >= rated_torque = {m.rated_torque}, got {m.peak_torque}"))
        if m.drive is not None:
            if m.drive not in drives:
                p.append((f"motors[{i}].drive", f"no drive named {m.drive!r} in this catalogue's drives"))
            if m.torque_constant is None:
                p.append((f"motors[{i}].torque_constant", "required when a drive is given (its current limits become torque limits)"))
    for i, d in enumerate(c.drives):
        if d.peak_current < d.rated_current:
            p.append((f"drives[{i}].peak_current", f"expected a value >= rated_current = {d.rated_current}, got {d.peak_current}"))
    return p


def catalogue_from_dict(data: Any, source: str | None = None, base=None):
    """Validate a catalogue document and build a :class:`~cdpr_design.design.sizing.Catalogue`.

    Drives named by motors may also come from ``base`` (the shipped catalogue).
    """
    from cdpr_design.design.sizing import Catalogue, Drive, Gearbox, Motor

    if not isinstance(data, dict):
        raise SpecError([("", f"expected a mapping with motors, drives, gearboxes, got {type(data).__name__}")], source)
    try:
        c = CatalogueSpec.model_validate(data)
    except ValidationError as err:
        raise SpecError(_pydantic_problems(err), source) from None
    if base is not None:
        extra = [DriveEntry(name=d.name, rated_current=d.rated_current, peak_current=d.peak_current,
                            source=d.source) for d in base.drives if d.name not in {x.name for x in c.drives}]
        c_check = c.model_copy(update={"drives": list(c.drives) + extra})
    else:
        c_check = c
    problems = _check_catalogue(c_check)
    if problems:
        raise SpecError(problems, source)
    drives = {d.name: Drive(d.name, d.rated_current, d.peak_current, d.source) for d in c_check.drives}
    motors = tuple(Motor(
        name=m.name, rated_torque=m.rated_torque, peak_torque=m.peak_torque, max_speed=m.max_speed,
        rotor_inertia=m.rotor_inertia, torque_constant=m.torque_constant,
        rated_current=m.rated_current, peak_current=m.peak_current,
        drive=drives[m.drive] if m.drive is not None else None, source=m.source) for m in c.motors)
    gearboxes = tuple(Gearbox(g.name, g.ratio, g.efficiency, g.inertia, g.source) for g in c.gearboxes)
    return Catalogue(motors, gearboxes, tuple(drives[d.name] for d in c.drives))


def shipped_catalogue_path() -> Path:
    return Path(__file__).resolve().parents[1] / "data" / "motors.yaml"


def load_catalogue(path: str | Path | None = None):
    """The shipped motor catalogue, extended by the catalogue file ``path`` (if given).

    Entries of the user's file replace shipped entries of the same name.

    Raises
    ------
    SpecError
        The file is missing, is not YAML, or breaks the catalogue format; the
        message names each offending key by its path (``motors[2].peak_torque``).
    """
    base_path = shipped_catalogue_path()
    base = catalogue_from_dict(read_yaml(base_path), source=str(base_path))
    if path is None:
        return base
    user = catalogue_from_dict(read_yaml(path), source=str(path), base=base)
    return base.merged(user)
