"""The only YAML reader: read a design spec, validate it, build the frozen model.

Validation happens in two passes so that every message names the offending
key by its path and says what was expected and what was found:

1. :class:`~cdpr_design.model.schema.DesignSpec` (pydantic) checks structure
   and types: unknown keys, missing keys, non-numbers, non-finite numbers, signs.
2. :func:`~cdpr_design.model.spec_checks.check_semantics` checks what depends
   on other keys: vector lengths for the motion type, min <= max, duplicate
   names, trajectory fields.

Both collect every problem before raising one :class:`~cdpr_design.errors.SpecError`.
The motor catalogue files are read here too (:func:`load_catalogue`); their
format and the catalogue's dataclasses are :mod:`cdpr_design.model.catalogue`.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from cdpr_design.errors import InputError, SpecError, quote
from cdpr_design.io.inputs import read_text
from cdpr_design.model import limits
from cdpr_design.model.catalogue import Catalogue, catalogue_from_dict, shipped_catalogue_path
from cdpr_design.model.design import (  # noqa: I001
    MOTIONS, Cable, CableProps, Design, Effector, Grid, Motion, OrientationRange, OrientationSet, Plc, Pulley,
    Requirements, Trajectory, Winch, WorkspaceSpec, WrenchBox, default_gravity, pad3,
)
from cdpr_design.model.schema import (
    CablePhysSpec, DesignSpec, GridSpec, RequirementsSpec, WinchSpec, WorkspaceSpecModel, parse,
)
from cdpr_design.model.spec_checks import MODEL_NEEDS, cable_model_problems, check_semantics


# ----------------------------------------------------------------------------
# YAML
# ----------------------------------------------------------------------------


class _UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """``yaml.SafeLoader`` (libyaml's parser when PyYAML has it: the same documents, parsed
    in C) that refuses a key given twice in one mapping."""


def _construct_mapping(loader, node, deep=False):
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            hash(key)
        except TypeError:  # a list or mapping as a key (``? [a, b]``)
            raise yaml.constructor.ConstructorError(
                None, None, f"a key must be a name, got {quote(key)}", key_node.start_mark) from None
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"key {quote(key)} is given twice", key_node.start_mark)
        seen.add(key)
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
# YAML 1.1 (PyYAML) reads ``1e6`` and ``1.0e6`` as text: its floats need a dot and a signed exponent.
# YAML 1.2 and every other language read them as numbers, and so does a spec (strict types would
# refuse the text); quoted values (``"1.0e6"``) stay text and are refused where a number is meant.
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def read_yaml(path: str | Path) -> Any:
    """Read a YAML file with the safe loader; bad files raise :class:`SpecError`.

    Only a regular file of at most :data:`~cdpr_design.model.limits.MAX_SPEC_BYTES`
    is read, and its document must keep the depth and node limits of
    :func:`~cdpr_design.model.limits.check_yaml` (aliases expanded) before
    anything is constructed from it.
    """
    path = Path(path)
    try:
        text = read_text(path, limits.MAX_SPEC_BYTES)
    except InputError as exc:
        raise SpecError([("", str(exc))]) from None
    shape = limits.check_yaml(text)
    if shape is not None:
        raise SpecError([("", shape)], source=str(path))
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise SpecError([("", f"not valid YAML: {_short(str(exc))}")], source=str(path)) from None
    except RecursionError:  # not reached within MAX_YAML_DEPTH; a last guard
        raise SpecError([("", "the YAML nests too deeply")], source=str(path)) from None
    except MemoryError:
        raise
    except Exception as exc:  # noqa: BLE001 - PyYAML's constructors raise what the value gives them
        # an explicit tag the value does not fit (``!!float cables``, ``!!float`` with no value,
        # ``!!int twelve``, a bad ``!!timestamp``): ValueError, IndexError, TypeError ... inside PyYAML
        raise SpecError([("", f"not valid YAML: a tagged value cannot be read ({type(exc).__name__}: "
                              f"{_short(str(exc))})")], source=str(path)) from None


def _short(text: str, width: int = 400) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


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


def from_dict(data: Any, source: str | None = None) -> Design:
    """Validate plain data and build the design."""
    s = validate(data, source)
    return build(s, raw=data, source=source)


def with_cable_model(design: Design, model: str | None, option: str = "--cable-model") -> Design:
    """``design`` with every cable's model replaced by ``model`` (``None``: unchanged).

    The spec's ``cable.model`` and per-cable ``model`` keys are overridden (in
    ``design.raw`` too, so sweeps that rebuild the spec keep the override).
    Raises a :class:`SpecError` naming ``option`` for an unknown model, and the
    missing property's key when a cable lacks what the model needs.
    """
    if model is None:
        return design
    if model not in MODEL_NEEDS:
        raise SpecError([(option, f"expected one of {', '.join(MODEL_NEEDS)}, got {model!r}")], design.source)
    raw = copy.deepcopy(design.raw)
    raw["cable"] = dict(raw.get("cable") or {}, model=model)
    for c in raw.get("cables", []):
        if isinstance(c, dict):
            c.pop("model", None)
    problems = cable_model_problems(parse(DesignSpec, design.raw, design.source), model, option)
    if problems:
        raise SpecError(problems, design.source)
    cables = tuple(dataclasses.replace(c, props=dataclasses.replace(c.props, model=model)) for c in design.cables)
    return dataclasses.replace(design, cables=cables, raw=raw)


def validate(data: Any, source: str | None = None) -> DesignSpec:
    """Validate plain data (a parsed YAML document) against the spec format."""
    if not isinstance(data, dict):
        raise SpecError([("", f"expected a mapping of keys at the top of the spec, got {type(data).__name__}")], source)
    s = parse(DesignSpec, data, source)
    plain = s.model_dump(exclude_none=True)
    problems = limits.check_numbers(plain) + limits.check_orientation_samples(
        plain.get("workspace"), len(MOTIONS[s.motion].rotation_coords))
    if problems:  # the cross-key checks compute with these numbers: not past the limits
        raise SpecError(problems, source)
    problems = check_semantics(s)
    if problems:
        raise SpecError(problems, source)
    return s


def json_schema() -> dict:
    """The JSON Schema of the spec format (for editors' YAML validation)."""
    schema = DesignSpec.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "cdpr-design spec"
    return schema


def schema_text() -> str:
    """:func:`json_schema` as indented JSON text."""
    return json.dumps(json_schema(), indent=2)


def load_catalogue(path: str | Path | None = None) -> Catalogue:
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


# ----------------------------------------------------------------------------
# Building the model
# ----------------------------------------------------------------------------


def build(s: DesignSpec, raw: dict | None = None, source: str | None = None) -> Design:
    """Build the frozen :class:`~cdpr_design.model.design.Design` from a validated spec."""
    mot = MOTIONS[s.motion]
    d = mot.dim
    g = pad3(s.gravity if s.gravity is not None else default_gravity(d))
    frame_lo, frame_hi = pad3(s.frame.lower), pad3(s.frame.upper)
    return Design(
        name=s.name, motion=mot, gravity=_t3(g), frame_lower=_t3(frame_lo),
        frame_upper=_t3(frame_hi), effector=_effector(s, mot), cables=_cables(s),
        workspace=_workspace(s, mot, frame_lo, frame_hi),
        description=s.description, requirements=_requirements(s), trajectories=_trajectories(s), plc=_plc(s),
        sweep=dict(s.sweep or {}), raw=copy.deepcopy(raw) if raw is not None else s.model_dump(exclude_none=True),
        source=source,
    )


def _t3(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in pad3(v))


def _default_inertia(mass: float, size: np.ndarray) -> np.ndarray:
    """Inertia of a uniform box of the effector's size about its centre [kg m^2]."""
    a, b, c = size
    return np.diag([mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12])


def _effector(s: DesignSpec, mot: Motion) -> Effector:
    """Mass [kg], size [m], centre of mass [m] and inertia [kg m^2] (a box's by default; Izz alone when planar)."""
    size = pad3(s.effector.size)
    com = pad3(s.effector.center_of_mass) if s.effector.center_of_mass is not None else np.zeros(3)
    inertia = s.effector.inertia
    if inertia is None:
        I = _default_inertia(s.effector.mass, size)
    elif isinstance(inertia, float):
        I = np.diag([0.0, 0.0, inertia])
    else:
        I = np.array(inertia, dtype=float)
        if I.shape == (3,):
            I = np.diag(I)
    return Effector(mass=s.effector.mass, size=_t3(size), center_of_mass=_t3(com),
                    inertia=tuple(tuple(float(x) for x in row) for row in I), orientation=s.effector.orientation)


def _winch(default: WinchSpec | None, override: WinchSpec | None) -> Winch:
    """The design-wide winch with one cable's keys on top."""
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


def _cables(s: DesignSpec) -> tuple[Cable, ...]:
    """Every cable with its tension bounds [N], winch, pulley and physical properties resolved."""
    phys = s.cable or CablePhysSpec()
    cables = []
    for c in s.cables:
        t = c.tension if c.tension is not None else s.tension
        props = CableProps(
            model=next(v for v in (c.model, phys.model, "ideal") if v is not None),
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
            pulley=pulley, props=props, plane_offset=float(c.plane_offset or 0.0),
        ))
    return tuple(cables)


def _grid(gs: GridSpec, d: int, frame_lo: np.ndarray, frame_hi: np.ndarray) -> Grid:
    """The workspace grid [m]: the frame's box by default, step = largest extent / 150 (planar) or / 30."""
    lo = tuple(gs.lower) if gs.lower is not None else tuple(frame_lo[:d])
    hi = tuple(gs.upper) if gs.upper is not None else tuple(frame_hi[:d])
    if gs.step is not None:
        step = tuple(gs.step) * d if len(gs.step) == 1 else tuple(gs.step)
    else:
        per_axis = 150 if d == 2 else 30
        ext = max(h - l for l, h in zip(lo, hi)) or 1.0
        step = (float(ext / per_axis),) * d
    return Grid(lower=lo, upper=hi, step=step)


def _workspace(s: DesignSpec, mot: Motion, frame_lo: np.ndarray, frame_hi: np.ndarray) -> WorkspaceSpec:
    """Grid, fixed orientation [rad], external wrench box, orientation set and range."""
    ws = s.workspace or WorkspaceSpecModel()
    grid = _grid(ws.grid or GridSpec(), mot.dim, frame_lo, frame_hi)
    ext = None
    if ws.external_wrench is not None:
        ext = WrenchBox(tuple(ws.external_wrench.lower), tuple(ws.external_wrench.upper))
    nrot = len(mot.rotation_coords)
    ori = tuple(ws.orientation) if ws.orientation is not None else (0.0,) * nrot
    oset = orng = None
    if ws.orientation_set is not None:
        cnt = list(ws.orientation_set.count)
        oset = OrientationSet(tuple(ws.orientation_set.lower), tuple(ws.orientation_set.upper),
                              tuple(int(c) for c in (cnt * nrot if len(cnt) == 1 else cnt)))
    if ws.orientation_range is not None:
        mx = list(ws.orientation_range.max)
        orng = OrientationRange(tuple(mx * nrot if len(mx) == 1 else mx),
                                ws.orientation_range.levels, ws.orientation_range.count)
    return WorkspaceSpec(grid=grid, orientation=ori, external_wrench=ext,
                         orientation_set=oset, orientation_range=orng)


def _requirements(s: DesignSpec) -> Requirements:
    """Task box, speed, acceleration, margin, fraction and safety factor (1 by default)."""
    req = s.requirements or RequirementsSpec()
    return Requirements(
        task_box=(tuple(req.task_box.lower), tuple(req.task_box.upper)) if req.task_box else None,
        max_speed=req.max_speed, max_acceleration=req.max_acceleration,
        min_margin=req.min_margin, min_fraction=req.min_fraction,
        safety_factor=req.safety_factor if req.safety_factor is not None else 1.0, max_tilt=req.max_tilt,
        certified=bool(req.certified), min_cable_frequency=req.min_cable_frequency,
        min_stiffness=req.min_stiffness, min_frequency=req.min_frequency, max_frame_load=req.max_frame_load,
        acceleration=(tuple(req.acceleration.lower), tuple(req.acceleration.upper)) if req.acceleration else None,
        min_acceleration=req.min_acceleration,
    )


def _trajectories(s: DesignSpec) -> dict[str, Trajectory]:
    """The named trajectories, in the spec's order."""
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
    return trajs


def _plc(s: DesignSpec) -> Plc | None:
    """The PLC connection and symbol names, or None."""
    if s.plc is None:
        return None
    return Plc(ams_net_id=s.plc.ams_net_id, port=s.plc.port, host=s.plc.host,
               cycle_time=s.plc.cycle_time, setpoints=tuple(s.plc.setpoints),
               actuals=tuple(s.plc.actuals), tensions=tuple(s.plc.tensions or ()),
               pose=s.plc.pose, heartbeat=s.plc.heartbeat, fault=s.plc.fault)
