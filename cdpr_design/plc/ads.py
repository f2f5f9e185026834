"""ADS link to a TwinCAT runtime (or the test PLC) with pyads: :class:`AdsTransport`.

It implements the bridge's :class:`~cdpr_design.plc.transport.Transport`
over Beckhoff's ADS protocol (TwinCAT 3, the controller of the seed paper,
Rivera et al., "Environment for the Design and Automation of New CDPR
Architectures", Sec. 3 and Fig. 4).

Each cycle is two ADS round trips: one *sum read* (index group
``ADSIGRP_SUMUP_READ``, 0xF080) of every set-point symbol and one *sum
write* (``ADSIGRP_SUMUP_WRITE``, 0xF081) of every output symbol.  The index
group, offset and size of each symbol are looked up once, at connection,
which is also where a missing or mistyped symbol is refused
(:class:`~cdpr_design.plc.symbols.SymbolError`, naming it).  Every request
has a timeout, so a PLC that stops answering raises
:class:`~cdpr_design.plc.transport.PlcLinkError` instead of hanging.
"""

from __future__ import annotations

import struct
from typing import Sequence

import numpy as np

from cdpr_design.plc.symbols import (ADSERR_SYMBOLNOTFOUND, ADST_BIT, ADST_REAL64, ADST_UINT32, PlcLayout,
                                     SymbolError, check_symbol_info)
from cdpr_design.plc.transport import PlcLinkError, Transport

#: ADS index groups of the sum commands (ADSIGRP_SUMUP_READ / _WRITE).
SUMUP_READ = 0xF080
SUMUP_WRITE = 0xF081


class AdsTransport(Transport):
    """ADS link to a TwinCAT runtime (or the test PLC) with pyads.

    Parameters
    ----------
    layout : PlcLayout
    ams_net_id : str
        AMS net id of the PLC.
    port : int
        AMS port of the PLC runtime (851: TwinCAT 3 PLC runtime 1).
    host : str
        IP address of the PLC.
    timeout : float
        Timeout of every ADS request [s].
    local_net_id : str, optional
        AMS net id of this computer (the route the PLC knows us by); set once
        per process before the first connection.
    mode : {"sum", "handles"}
        ``sum``: one sum read and one sum write per cycle (two round trips).
        ``handles``: one request per symbol through variable handles (for
        comparison in the benchmark).
    """

    def __init__(self, layout: PlcLayout, ams_net_id: str, port: int, host: str, *,
                 timeout: float = 0.05, local_net_id: str | None = None, mode: str = "sum"):
        if mode not in ("sum", "handles"):
            raise ValueError(f"mode must be 'sum' or 'handles', got {mode!r}")
        self.layout = layout
        self.ams_net_id = ams_net_id
        self.port = int(port)
        self.host = host
        self.timeout = float(timeout)
        self.local_net_id = local_net_id
        self.mode = mode
        self._conn = None
        self._info: dict[str, tuple[int, int, int]] = {}
        self._handles: dict[str, int] = {}
        n_out = len(layout.outputs)
        self.round_trips = 2 if mode == "sum" else len(layout.inputs) + n_out

    # -- connection ----------------------------------------------------------
    def connect(self) -> None:
        import pyads

        self._pyads = pyads
        if self.local_net_id:
            _set_local_address(self.local_net_id)
        conn = pyads.Connection(self.ams_net_id, self.port, self.host)
        try:
            conn.open()
            conn.set_timeout(max(1, int(round(self.timeout * 1000))))
        except Exception as err:  # ADSError, RuntimeError from the router
            _safe_close(conn)
            raise PlcLinkError(f"cannot open an ADS connection to {self.ams_net_id}:{self.port} "
                               f"at {self.host}: {err}") from None
        self._conn = conn
        problems = self._check_symbols()
        if problems:
            self.close()
            raise SymbolError(problems)
        self._prepare()

    def _check_symbols(self) -> list[tuple[str, str]]:
        """Look every symbol up (index group, offset, size); the (name, problem) of the bad ones."""
        pyads = self._pyads
        from pyads import constants
        from pyads.structs import SAdsSymbolEntry

        problems = []
        for sym in self.layout.symbols:
            try:
                info = self._conn.read_write(constants.ADSIGRP_SYM_INFOBYNAMEEX, 0, SAdsSymbolEntry,
                                             sym.name, pyads.PLCTYPE_STRING)
            except pyads.ADSError as err:
                if getattr(err, "err_code", None) == ADSERR_SYMBOLNOTFOUND:
                    problems.append((sym.name, f"not found in the PLC ({sym.role}, "
                                     f"expected {sym.plc_type})"))
                    continue
                self.close()
                raise PlcLinkError(f"PLC {self.ams_net_id}:{self.port} at {self.host} does not "
                                   f"answer ({err})") from None
            why = check_symbol_info(sym, info.dataType, info.size, info.symbol_type)
            if why:
                problems.append((sym.name, why))
            self._info[sym.name] = (info.iGroup, info.iOffs, info.size)
        return problems

    def _prepare(self) -> None:
        from pyads.structs import SAdsSumRequest

        ins, outs = self.layout.inputs, self.layout.outputs
        n = len(ins)
        req = (SAdsSumRequest * n)()
        for i, s in enumerate(ins):
            g, o, size = self._info[s.name]
            req[i].iGroup, req[i].iOffset, req[i].size = g, o, size
        self._read_req = req
        self._read_n = n
        self._read_fmt = "<" + "I" * n + "".join(s.fmt for s in ins)
        head = b"".join(struct.pack("<III", *self._info[s.name]) for s in outs)
        self._write_head = len(head)
        self._write_buf = bytearray(head) + bytearray(sum(s.size for s in outs))
        self._write_fmt = "<" + "".join(s.fmt for s in outs)
        self._write_n = len(outs)
        if self.mode == "handles":
            for s in self.layout.symbols:
                self._handles[s.name] = self._conn.get_handle(s.name)

    def _fail(self, what: str, err: Exception) -> PlcLinkError:
        return PlcLinkError(f"PLC {self.ams_net_id}:{self.port} at {self.host}: {what} failed ({err})")

    # -- cyclic exchange -----------------------------------------------------
    def read_setpoints(self) -> np.ndarray:
        read = self._sum_read if self.mode == "sum" else self._handle_read
        return self._exchange("reading the set-points", read)

    def _exchange(self, what: str, action, *args):
        """``action(*args)`` on the open link; any ADS or socket failure becomes PlcLinkError."""
        pyads = self._pyads
        if self._conn is None:
            raise PlcLinkError("not connected")
        try:
            return action(*args)
        except (pyads.ADSError, OSError, struct.error, ValueError) as err:
            raise self._fail(what, err) from None

    def _handle_read(self) -> np.ndarray:
        """Every set-point [m], one read request per symbol through its variable handle."""
        return np.array([self._conn.read_by_name("", self._pyads.PLCTYPE_LREAL, handle=self._handles[s.name])
                         for s in self.layout.inputs], dtype=float)

    def _sum_read(self) -> np.ndarray:
        """Every set-point [m] in one sum read; PlcLinkError naming the symbols the PLC refused."""
        raw = self._conn.read_write(SUMUP_READ, self._read_n, None, self._read_req, None,
                                    return_ctypes=False, check_length=False)
        vals = struct.unpack(self._read_fmt, bytes(raw))
        _check_refused("reading", self.layout.inputs, vals[: self._read_n])
        return np.array(vals[self._read_n:], dtype=float)

    def write_outputs(self, values: Sequence) -> None:
        write = self._sum_write if self.mode == "sum" else self._handle_write
        self._exchange("writing the outputs", write, values)

    def _sum_write(self, values: Sequence) -> None:
        """Every output in one sum write; PlcLinkError naming the symbols the PLC refused."""
        struct.pack_into(self._write_fmt, self._write_buf, self._write_head, *values)
        raw = self._conn.read_write(SUMUP_WRITE, self._write_n, None, self._write_buf, None,
                                    return_ctypes=False, check_length=False)
        _check_refused("writing", self.layout.outputs, struct.unpack("<" + "I" * self._write_n, bytes(raw)))

    def _handle_write(self, values: Sequence) -> None:
        """One write request per output symbol, through its variable handle."""
        pyads = self._pyads
        ctypes = {ADST_REAL64: pyads.PLCTYPE_LREAL, ADST_UINT32: pyads.PLCTYPE_UDINT,
                  ADST_BIT: pyads.PLCTYPE_BOOL}
        i = 0
        for s in self.layout.outputs:
            ctype = ctypes[s.ads_type]
            if s.count > 1:
                self._conn.write_by_name("", list(values[i: i + s.count]), ctype * s.count,
                                         handle=self._handles[s.name])
            else:
                self._conn.write_by_name("", values[i], ctype, handle=self._handles[s.name])
            i += s.count

    def raise_fault(self) -> bool:
        sym = self.layout.fault
        if sym is None or self._conn is None or sym.name not in self._info:
            return False
        g, o, _ = self._info[sym.name]
        try:
            self._conn.write(g, o, True, self._pyads.PLCTYPE_BOOL)
            return True
        except Exception:  # best effort: the link may be gone
            return False

    def close(self) -> None:
        conn, self._conn = self._conn, None
        if conn is not None:
            for h in self._handles.values():
                try:
                    conn.release_handle(h)
                except Exception:
                    pass
            self._handles.clear()
            _safe_close(conn)


def _check_refused(verb: str, symbols, errs) -> None:
    """PlcLinkError naming the symbols whose ADS error code in a sum response is not 0."""
    if any(errs):
        bad = [s.name for s, e in zip(symbols, errs) if e]
        raise PlcLinkError(f"PLC refused {verb} {', '.join(bad)} (ADS error {max(errs):#x})")


_LOCAL_NET_ID: list[str] = []


def _set_local_address(net_id: str) -> None:
    """Set this process's AMS net id once (AdsLib keeps one router per process)."""
    import pyads

    if _LOCAL_NET_ID and _LOCAL_NET_ID[0] == net_id:
        return
    pyads.open_port()
    pyads.set_local_address(net_id)
    pyads.close_port()
    _LOCAL_NET_ID[:] = [net_id]


def _safe_close(conn) -> None:
    try:
        conn.close()
    except Exception:
        pass


__all__ = ["AdsTransport", "SUMUP_READ", "SUMUP_WRITE"]
