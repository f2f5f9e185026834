"""The motor catalogue: motors, drives and gearboxes the sizing chooses from.

The frozen dataclasses (:class:`Motor`, :class:`Drive`, :class:`Gearbox`,
:class:`Catalogue`) are what the sizing (:mod:`cdpr_design.design.sizing`)
reads; the pydantic models below are the catalogue file's format, and
:func:`catalogue_from_dict` validates a parsed document and builds a
:class:`Catalogue`.  Reading the YAML files (``cdpr_design/data/motors.yaml``
and users' ``--catalogue`` files) is :func:`cdpr_design.model.spec.load_catalogue`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from pydantic import Field
from pydantic.types import FiniteFloat

from cdpr_design.errors import SpecError
from cdpr_design.model.limits import check_numbers
from cdpr_design.model.schema import NonNegFloat, PosFloat, StrictModel, parse


@dataclass(frozen=True)
class Drive:
    """A servo drive (terminal): its current limits cap a motor's usable torque.

    Attributes: name, rated_current [A rms], peak_current [A rms], source.
    """

    name: str
    rated_current: float
    peak_current: float
    source: str = ""


@dataclass(frozen=True)
class Motor:
    """A catalogue motor.

    Attributes
    ----------
    rated_torque, peak_torque : float
        Continuous (rated or standstill) and peak torque [N m].
    max_speed : float
        Speed limit checked by the sizing [rpm].
    rotor_inertia : float
        [kg m^2].
    torque_constant : float, optional
        [N m / A]; with ``drive`` it caps the usable torque.
    drive : Drive, optional
        The drive the motor runs on; usable torque = min(motor torque,
        torque_constant x drive current).
    """

    name: str
    rated_torque: float
    peak_torque: float
    max_speed: float
    rotor_inertia: float
    torque_constant: float | None = None
    rated_current: float | None = None
    peak_current: float | None = None
    drive: Drive | None = None
    source: str = ""

    @property
    def usable_peak_torque(self) -> float:
        """Peak torque [N m] after the drive's peak current limit."""
        t = self.peak_torque
        if self.drive is not None and self.torque_constant is not None:
            t = min(t, self.torque_constant * self.drive.peak_current)
        return t

    @property
    def usable_rated_torque(self) -> float:
        """Continuous torque [N m] after the drive's rated current limit."""
        t = self.rated_torque
        if self.drive is not None and self.torque_constant is not None:
            t = min(t, self.torque_constant * self.drive.rated_current)
        return t


@dataclass(frozen=True)
class Gearbox:
    """A gearbox: ratio (motor turns per drum turn), efficiency (0, 1], inertia at the motor [kg m^2]."""

    name: str
    ratio: float
    efficiency: float = 1.0
    inertia: float = 0.0
    source: str = ""


@dataclass(frozen=True)
class Catalogue:
    """Motors, drives and gearboxes available to the sizing."""

    motors: tuple[Motor, ...] = ()
    gearboxes: tuple[Gearbox, ...] = ()
    drives: tuple[Drive, ...] = ()

    def motor(self, name: str) -> Motor | None:
        for m in self.motors:
            if m.name == name:
                return m
        return None

    def gearbox(self, ratio: float) -> Gearbox | None:
        """The gearbox with this ratio (relative tolerance 1e-9), or None."""
        for g in self.gearboxes:
            if abs(g.ratio - ratio) <= 1e-9 * max(1.0, abs(ratio)):
                return g
        return None

    def by_size(self) -> list[Motor]:
        """Motors from the smallest: usable rated torque, then usable peak torque, then inertia."""
        return sorted(self.motors, key=lambda m: (m.usable_rated_torque, m.usable_peak_torque,
                                                  m.rotor_inertia, m.name))

    def merged(self, other: "Catalogue") -> "Catalogue":
        """This catalogue extended by ``other``; entries of ``other`` replace same-named ones."""
        def merge(a, b):
            names = {x.name for x in b}
            return tuple(x for x in a if x.name not in names) + tuple(b)
        return Catalogue(merge(self.motors, other.motors), merge(self.gearboxes, other.gearboxes),
                         merge(self.drives, other.drives))

# ----------------------------------------------------------------------------
# The catalogue file's format
# ----------------------------------------------------------------------------


class DriveEntry(StrictModel):
    name: str = Field(min_length=1)
    rated_current: PosFloat = Field(description="Rated current [A rms]")
    peak_current: PosFloat = Field(description="Peak current [A rms]")
    source: str = ""


class MotorEntry(StrictModel):
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


class GearboxEntry(StrictModel):
    name: str = Field(min_length=1)
    ratio: PosFloat = Field(description="Motor turns per drum turn")
    efficiency: Annotated[FiniteFloat, Field(gt=0, le=1)] = 1.0
    inertia: NonNegFloat = Field(0.0, description="Inertia at the motor shaft [kg m^2]")
    source: str = ""


class CatalogueSpec(StrictModel):
    """A motor catalogue: motors, drives and gearboxes."""

    motors: list[MotorEntry] = []
    drives: list[DriveEntry] = []
    gearboxes: list[GearboxEntry] = []


def _check_catalogue(c: CatalogueSpec) -> list[tuple[str, str]]:
    """What depends on several entries: unique names, peak >= rated, drives that exist."""
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


def catalogue_from_dict(data: Any, source: str | None = None, base: Catalogue | None = None) -> Catalogue:
    """Validate a parsed catalogue document and build a :class:`Catalogue`.

    Drives named by motors may also come from ``base`` (the shipped catalogue).

    Raises
    ------
    SpecError
        The document breaks the catalogue format; the message names each
        offending key by its path (``motors[2].peak_torque``).
    """
    if not isinstance(data, dict):
        raise SpecError([("", f"expected a mapping with motors, drives, gearboxes, got {type(data).__name__}")], source)
    c = parse(CatalogueSpec, data, source)
    bounds = check_numbers(c.model_dump(exclude_none=True))  # magnitudes at most 1e12, texts bounded
    if bounds:
        raise SpecError(bounds, source)
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
    """``cdpr_design/data/motors.yaml``: the catalogue shipped with the package."""
    return Path(__file__).resolve().parents[1] / "data" / "motors.yaml"

