"""What the bridge loop needs from a controller link: the :class:`Transport` interface.

The bridge loop (:mod:`cdpr_design.plc.bridge`) talks to a controller only
through this small interface: connect and check the symbols, read the axis
set-points, write back the simulated state, raise a fault flag, close.
:class:`cdpr_design.plc.ads.AdsTransport` implements it over Beckhoff's ADS
protocol; another PLC protocol or another simulator link is a new subclass,
and the loop does not change.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cdpr_design.errors import CdprError
from cdpr_design.plc.symbols import PlcLayout


class PlcLinkError(CdprError):
    """The PLC cannot be reached or stopped answering (timeout, reset, refused)."""


class Transport:
    """What the bridge loop needs from a controller link.

    Subclasses implement :meth:`connect`, :meth:`read_setpoints`,
    :meth:`write_outputs` and :meth:`close`; :meth:`raise_fault` has a
    default built on :meth:`write_outputs`.  ``round_trips`` is the number of
    request/response exchanges one :meth:`read_setpoints` plus one
    :meth:`write_outputs` cost.
    """

    layout: PlcLayout
    round_trips: int = 2

    def connect(self) -> None:
        """Open the link and check every symbol.

        Raises
        ------
        SymbolError
            A symbol is missing or declared with the wrong type (names it).
        PlcLinkError
            The controller cannot be reached.
        """
        raise NotImplementedError

    def read_setpoints(self) -> np.ndarray:
        """The axis set-points (cable lengths [m], cable order). Raises PlcLinkError."""
        raise NotImplementedError

    def write_outputs(self, values: Sequence) -> None:
        """Write :meth:`PlcLayout.pack_outputs` values. Raises PlcLinkError."""
        raise NotImplementedError

    def raise_fault(self) -> bool:
        """Best effort: set the fault flag; True when the controller took it."""
        return False

    def close(self) -> None:
        raise NotImplementedError


__all__ = ["PlcLinkError", "Transport"]
