"""The pydantic models of the spec format (structure and types only), and their error messages.

:class:`DesignSpec` checks what one key can check alone: unknown keys,
missing keys, non-numbers, non-finite numbers, signs.  What depends on other
keys (vector lengths for the motion type, min <= max, ...) is checked by
:mod:`cdpr_design.model.spec_checks` on the validated model.
:func:`pydantic_problems` turns a pydantic ``ValidationError`` into
``(key path, message)`` pairs for :class:`~cdpr_design.errors.SpecError`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, TypeVar

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StringConstraints, ValidationError
from pydantic.types import FiniteFloat

from cdpr_design.errors import SpecError, quote
from cdpr_design.model.limits import MAX_CABLES, MAX_NAME_LENGTH, NAME_PATTERN


def _as_list(v):
    """Accept a scalar where a list of values is allowed (``step: 0.01``)."""
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return [v]
    return v


Vec = list[FiniteFloat]
PosFloat = Annotated[FiniteFloat, Field(gt=0)]
NonNegFloat = Annotated[FiniteFloat, Field(ge=0)]
ScalarOrList = Annotated[list[PosFloat], BeforeValidator(_as_list), Field(min_length=1)]
#: A design, cable or trajectory name (model.limits.NAME_PATTERN: never ".", ".." or a path)
Name = Annotated[str, StringConstraints(min_length=1, max_length=MAX_NAME_LENGTH, pattern=NAME_PATTERN)]


class StrictModel(BaseModel):
    """A frozen model that refuses unknown keys and values of the wrong type (strict: no ``true``
    or ``"1.0"`` where a number is meant; whole numbers are accepted where a float is)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class WinchSpec(StrictModel):
    drum_radius: ScalarOrList | None = Field(None, description="Drum radius [m]; a list to search candidates")
    gear_ratio: ScalarOrList | None = Field(None, description="Motor turns per drum turn; a list to search candidates")
    efficiency: Annotated[FiniteFloat, Field(gt=0, le=1)] | None = Field(None, description="Gearbox efficiency (0, 1]")
    drum_inertia: NonNegFloat | None = Field(None, description="Drum inertia about its axis [kg m^2]")
    motor: str | None = Field(None, description="Motor name from the catalogue")


class PulleySpec(StrictModel):
    radius: NonNegFloat = Field(description="Pulley radius [m]")
    axis: Vec = Field([0.0, 0.0, 1.0], description="Swivel axis (frame coordinates)")


CableModelName = Literal["ideal", "elastic", "sagging"]


class CablePhysSpec(StrictModel):
    model: CableModelName | None = Field(
        None, description="ideal (massless, inextensible, straight; the default), elastic (straight, stretches "
                          "by T/EA: needs axial_stiffness) or sagging (Irvine's elastic catenary: needs "
                          "axial_stiffness and mass_per_length)")
    diameter: NonNegFloat | None = Field(None, description="Cable diameter [m]")
    axial_stiffness: PosFloat | None = Field(None, description="Axial stiffness EA [N]")
    mass_per_length: NonNegFloat | None = Field(None, description="Linear density [kg/m]")


class CableSpec(StrictModel):
    name: Name
    outlet: Vec = Field(description="a_i: where the cable leaves the frame (frame coordinates) [m]")
    attachment: Vec = Field(description="b_i: where it meets the effector (platform coordinates) [m]")
    tension: Vec | None = Field(None, description="[min, max] tension [N]; overrides the design-wide bounds")
    winch: WinchSpec | None = None
    pulley: PulleySpec | None = None
    model: CableModelName | None = None
    diameter: NonNegFloat | None = None
    axial_stiffness: PosFloat | None = None
    mass_per_length: NonNegFloat | None = None
    plane_offset: FiniteFloat | None = Field(
        None, description="Planar motions: how far [m] the cable's plane lies from the motion plane (along z); "
                          "crossed cables run in offset planes.  Used by the interference check only")


class EffectorSpec(StrictModel):
    mass: NonNegFloat = Field(description="Mass [kg]")
    size: Vec = Field(description="Box extents [m], centred on the platform origin")
    center_of_mass: Vec | None = Field(None, description="Platform coordinates [m]")
    inertia: FiniteFloat | list[FiniteFloat] | list[list[FiniteFloat]] | None = Field(
        None, description="Inertia about the COM [kg m^2]: 3x3 (spatial) or Izz (planar)")
    orientation: Literal["fixed", "free"] = Field(
        "fixed", description="fixed: the effector is held at the commanded orientation; free: the cables do "
                             "not hold it and it hangs where gravity puts it (under-constrained robots)")


class FrameSpec(StrictModel):
    lower: Vec
    upper: Vec


class GridSpec(StrictModel):
    lower: Vec | None = None
    upper: Vec | None = None
    step: ScalarOrList | None = Field(None, description="Grid step [m]: a scalar or one value per axis")


class BoxSpec(StrictModel):
    lower: Vec
    upper: Vec


class OrientationSetSpec(StrictModel):
    lower: Vec = Field(description="Lowest orientation, rotation coordinates [rad]")
    upper: Vec = Field(description="Highest orientation, rotation coordinates [rad]")
    count: Annotated[list[Annotated[int, Field(ge=1)]], BeforeValidator(_as_list)] = Field(
        [5], description="Samples per coordinate (both ends included): a scalar or one per coordinate")


class OrientationRangeSpec(StrictModel):
    max: Annotated[list[NonNegFloat], BeforeValidator(_as_list)] = Field(
        description="Largest half-width tested around workspace.orientation [rad]: a scalar or one per coordinate (0: held)")
    levels: Annotated[int, Field(ge=1)] = Field(10, description="Nested boxes tested (half-width k/levels * max)")
    count: Annotated[int, Field(ge=2)] = Field(3, description="Samples per coordinate of each box (both ends included)")


class WorkspaceSpecModel(StrictModel):
    grid: GridSpec | None = None
    orientation: Vec | None = None
    external_wrench: BoxSpec | None = None
    orientation_set: OrientationSetSpec | None = Field(
        None, description="Total orientation workspace: feasible for every orientation of this sampled box")
    orientation_range: OrientationRangeSpec | None = Field(
        None, description="Orientation range per position around workspace.orientation")


class RequirementsSpec(StrictModel):
    task_box: BoxSpec | None = None
    max_speed: NonNegFloat | None = Field(None, description="Effector speed in any direction [m/s]")
    max_acceleration: NonNegFloat | None = Field(None, description="Effector acceleration [m/s^2]")
    min_margin: FiniteFloat | None = Field(None, description="Capacity margin at every task pose [N]")
    min_fraction: Annotated[FiniteFloat, Field(ge=0, le=1)] | None = Field(
        None, description="Least feasible fraction of the workspace grid")
    safety_factor: Annotated[FiniteFloat, Field(ge=1)] | None = Field(
        None, description="Factor on required motor torque and speed when sizing")
    max_tilt: Annotated[FiniteFloat, Field(ge=0, le=180)] | None = Field(
        None, description="Largest tilt [deg] an under-constrained effector may hang with at a feasible pose")
    certified: bool | None = Field(
        None, description="check proves every pose of the task box feasible by interval analysis")
    min_cable_frequency: PosFloat | None = Field(
        None, description="Least first transverse (string) frequency of every cable [Hz]: a lower tension "
                          "bound 4 f^2 L^2 mu per cable with a mass_per_length")
    min_stiffness: PosFloat | None = Field(
        None, description="Least stiffness [N/m] against a force at the reference point over the task box "
                          "(check; elastic or sagging cables, or ideal ones with axial_stiffness)")
    min_frequency: PosFloat | None = Field(
        None, description="Lowest natural frequency [Hz] of the effector on its cables allowed over the task box")
    max_frame_load: PosFloat | None = Field(
        None, description="Largest force [N] a cable may put on the frame at its outlet over the feasible "
                          "workspace grid (check)")
    acceleration: BoxSpec | None = Field(
        None, description="Accelerations the effector must reach from rest (workspace --kind dynamic): lower and "
                          "upper, one value per motion coordinate [m/s^2, rad/s^2]")
    min_acceleration: NonNegFloat | None = Field(
        None, description="Least acceleration radius [m/s^2] over the task box (check): every translational "
                          "acceleration of this size, in any direction, reachable from rest")


class TrajectorySpec(StrictModel):
    type: Literal["square", "polyline", "circle", "csv"]
    speed: PosFloat | None = Field(None, description="Cruise speed [m/s]; needed by the speed profile, an "
                                                      "upper limit of --time-optimal")
    acceleration: PosFloat | None = Field(None, description="Acceleration limit [m/s^2]; needed by the speed "
                                                             "profile, an upper limit of --time-optimal")
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


class PlcSpec(StrictModel):
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


class ToleranceSpec(StrictModel):
    outlets: NonNegFloat | list[NonNegFloat] | None = Field(
        None, description="Half-width [m] of the box each outlet may lie in (one value, or one per cable)")
    attachments: NonNegFloat | list[NonNegFloat] | None = Field(
        None, description="Half-width [m] of the box each attachment may lie in (one value, or one per cable)")


class DesignSpec(StrictModel):
    """A cable-driven parallel robot design (cdpr-design spec format)."""

    name: Name = Field(description="Design name; also the default output folder out/<name>/")
    description: str = ""
    motion: Literal["2T", "1R2T", "3T", "3R3T"]
    gravity: Vec | None = Field(None, description="m/s^2; default -9.81 along the last axis")
    frame: FrameSpec
    effector: EffectorSpec
    tension: Vec | None = Field(None, description="[min, max] N for every cable")
    cables: list[CableSpec] = Field(min_length=1, max_length=MAX_CABLES)
    winch: WinchSpec | None = None
    cable: CablePhysSpec | None = None
    workspace: WorkspaceSpecModel | None = None
    trajectories: dict[Name, TrajectorySpec] | None = None
    plc: PlcSpec | None = None
    requirements: RequirementsSpec | None = None
    sweep: dict[str, Any] | None = Field(None, description="Parameter sweep: vary: {dotted.key: values}")
    tolerance: NonNegFloat | ToleranceSpec | None = Field(
        None, description="Geometric tolerance [m] of every outlet and attachment (certify proves its boxes "
                          "for every geometry within it)")


# ----------------------------------------------------------------------------
# Error messages
# ----------------------------------------------------------------------------


M = TypeVar("M", bound=BaseModel)


def parse(model: type[M], data: dict, source: str | None = None) -> M:
    """``model`` validated from plain data; every problem in one :class:`SpecError` naming its key path."""
    try:
        return model.model_validate(data)
    except ValidationError as err:
        raise SpecError(pydantic_problems(err), source) from None


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


def pydantic_problems(err: ValidationError) -> list[tuple[str, str]]:
    """Every problem of a pydantic error as (key path, message), one per path."""
    problems: dict[str, str] = {}
    for e in err.errors(include_url=False):
        # unions report once per member: keep the first message for a path
        problems.setdefault(format_loc(e["loc"]), _message(e))
    return list(problems.items())


def _message(e: dict) -> str:
    """What one pydantic error says, in the spec's words: what was expected, what was found."""
    kind = e["type"]
    got = e.get("input")
    if kind == "missing":
        return "required key is missing"
    if kind == "extra_forbidden":
        return "unknown key (check its spelling against the spec format)"
    if kind == "finite_number":
        return f"expected a finite number, got {quote(got)}"
    if kind in ("int_type", "int_parsing", "int_from_float"):
        return f"expected a whole number, got {quote(got)}"
    if kind in ("float_type", "float_parsing"):
        return f"expected a number, got {quote(got)}"
    if kind == "list_type":
        return f"expected a list, got {quote(got)}"
    if kind == "literal_error":
        allowed = e.get("ctx", {}).get("expected", "")
        return f"expected one of {allowed}, got {quote(got)}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        return f"{e['msg'].replace('Input should be', 'expected a value')}, got {quote(got)}"
    if kind == "model_type" or kind == "dict_type":
        return f"expected a mapping of keys, got {quote(got)}"
    if kind == "too_short":
        least = e.get("ctx", {}).get("min_length", 1)
        return f"expected at least {least} {'entry' if least == 1 else 'entries'}, got {_count(got)}"
    if kind in ("string_pattern_mismatch", "string_too_long"):
        return (f"expected a name of 1 to {MAX_NAME_LENGTH} letters, digits and _ . + - not starting "
                f"with a dot, got {quote(got)}")
    if kind == "too_long":
        return f"expected at most {e.get('ctx', {}).get('max_length')} entries, got {_count(got)}"
    return f"{e['msg']}, got {quote(got)}"


def _count(got) -> str:
    return str(len(got)) if hasattr(got, "__len__") else quote(got)
