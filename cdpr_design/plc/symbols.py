"""The PLC symbols of a ``plc:`` section: names, IEC types, ADS type codes and packing.

The bridge reads one LREAL set-point per cable and writes back, in this
order, the actual lengths, the tensions, the pose, a heartbeat and a fault
flag (the optional ones only when the spec names them).  The layout is built
from the design alone (no pyads needed), and :func:`check_symbol_info`
compares it with what a PLC declares.
"""

from __future__ import annotations

from dataclasses import dataclass

from cdpr_design.errors import InputError

#: ADS error code "symbol not found" (ADSERR_DEVICE_SYMBOLNOTFOUND).
ADSERR_SYMBOLNOTFOUND = 0x710

# ADS data type codes (pyads.constants.ADST_*), kept here so the layout can be
# built without importing pyads.
ADST_REAL64 = 5
ADST_UINT32 = 19
ADST_BIT = 33

#: Size [bytes] of one element of each ADS data type.
ELEM_SIZE = {ADST_REAL64: 8, ADST_UINT32: 4, ADST_BIT: 1}
#: struct format character of each ADS data type (little endian, no padding).
STRUCT_CODE = {ADST_REAL64: "d", ADST_UINT32: "I", ADST_BIT: "?"}


class SymbolError(InputError):
    """A PLC symbol named in ``plc:`` is missing or has the wrong type (exit 2).

    Parameters
    ----------
    problems : list of (symbol, message)
    """

    def __init__(self, problems):
        self.problems = [(str(s), str(m)) for s, m in problems]
        lines = [f"plc symbol {s}: {m}" for s, m in self.problems]
        super().__init__(lines[0] if len(lines) == 1 else
                         f"{len(lines)} PLC symbol problems\n" + "\n".join("  " + x for x in lines))


@dataclass(frozen=True)
class Symbol:
    """One PLC variable the bridge reads or writes.

    Attributes
    ----------
    name : str
        The PLC's symbol name (``MAIN.fCableLen1``).
    plc_type : str
        IEC 61131-3 type: ``LREAL``, ``UDINT`` or ``BOOL``; arrays are
        ``ARRAY [0..k-1] OF LREAL``.
    ads_type : int
        ADS data type code of the element.
    count : int
        Number of elements (1 for a scalar).
    role : str
        ``setpoints``, ``actuals``, ``tensions``, ``pose``, ``heartbeat`` or ``fault``.
    """

    name: str
    plc_type: str
    ads_type: int
    count: int
    role: str

    @property
    def elem_size(self) -> int:
        return ELEM_SIZE[self.ads_type]

    @property
    def size(self) -> int:
        """Size in bytes."""
        return self.elem_size * self.count

    @property
    def fmt(self) -> str:
        """struct format of the value (little endian, no padding)."""
        return STRUCT_CODE[self.ads_type] * self.count


def _lreal(name, role):
    return Symbol(name, "LREAL", ADST_REAL64, 1, role)


@dataclass(frozen=True)
class PlcLayout:
    """The symbols of a ``plc:`` section with their expected PLC types.

    ``inputs`` are read each cycle (the set-points, one LREAL per cable in
    cable order); ``outputs`` are written each cycle in this order: actual
    lengths, tensions, pose, heartbeat, fault (the optional ones only when
    the spec names them).
    """

    inputs: tuple[Symbol, ...]
    outputs: tuple[Symbol, ...]

    @classmethod
    def from_design(cls, design) -> "PlcLayout":
        plc = design.plc
        if plc is None:
            raise InputError("the spec has no plc: section (needed by bridge)")
        outs = [_lreal(n, "actuals") for n in plc.actuals]
        outs += [_lreal(n, "tensions") for n in (plc.tensions or ())]
        if plc.pose:
            k = len(design.motion.coords)
            outs.append(Symbol(plc.pose, f"ARRAY [0..{k - 1}] OF LREAL", ADST_REAL64, k, "pose"))
        if plc.heartbeat:
            outs.append(Symbol(plc.heartbeat, "UDINT", ADST_UINT32, 1, "heartbeat"))
        if plc.fault:
            outs.append(Symbol(plc.fault, "BOOL", ADST_BIT, 1, "fault"))
        return cls(tuple(_lreal(n, "setpoints") for n in plc.setpoints), tuple(outs))

    @property
    def symbols(self) -> tuple[Symbol, ...]:
        return self.inputs + self.outputs

    def role(self, role: str) -> list[Symbol]:
        return [s for s in self.outputs if s.role == role]

    @property
    def fault(self) -> Symbol | None:
        f = self.role("fault")
        return f[0] if f else None

    def pack_outputs(self, actuals, tensions, pose, heartbeat: int, fault: bool) -> list:
        """The output values as a flat list in the order of :attr:`outputs`."""
        vals: list = []
        vals.extend(float(v) for v in actuals)
        if self.role("tensions"):
            vals.extend(float(v) for v in tensions)
        if self.role("pose"):
            vals.extend(float(v) for v in pose)
        if self.role("heartbeat"):
            vals.append(int(heartbeat) & 0xFFFFFFFF)
        if self.role("fault"):
            vals.append(bool(fault))
        return vals


def check_symbol_info(sym: Symbol, data_type: int, size: int, type_name: str) -> str | None:
    """Why the PLC's declaration of ``sym`` does not fit, or None when it does."""
    type_name = (type_name or "").strip()
    if size == sym.size and (data_type == sym.ads_type or
                             (sym.count > 1 and type_name.upper().endswith("OF " + "LREAL"))):
        return None
    got = f"{type_name or 'type ' + str(data_type)} ({size} bytes)"
    return f"expected {sym.plc_type} ({sym.size} bytes), the PLC declares {got}"


__all__ = ["ADSERR_SYMBOLNOTFOUND", "ADST_BIT", "ADST_REAL64", "ADST_UINT32", "ELEM_SIZE", "PlcLayout",
           "STRUCT_CODE", "Symbol", "SymbolError", "check_symbol_info"]
