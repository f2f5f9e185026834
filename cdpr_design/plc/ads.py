"""PLC transports for the ``bridge`` gateway (the seed paper's loop A).

The bridge loop (:mod:`cdpr_design.plc.bridge`) talks to a controller only
through the small :class:`Transport` interface: connect and check the
symbols, read the axis set-points, write back the simulated state, raise a
fault flag, close.  :class:`AdsTransport` implements it over Beckhoff's ADS
protocol with pyads (TwinCAT 3, the controller of the seed paper, Rivera et
al., "Environment for the Design and Automation of New CDPR Architectures",
Sec. 3 and Fig. 4).  Another PLC protocol or another simulator link is a new
subclass; the loop does not change.

Each cycle is two ADS round trips: one *sum read* (index group
``ADSIGRP_SUMUP_READ``, 0xF080) of every set-point symbol and one *sum
write* (``ADSIGRP_SUMUP_WRITE``, 0xF081) of every output symbol.  The index
group, offset and size of each symbol are looked up once, at connection,
which is also where a missing or mistyped symbol is refused
(:class:`SymbolError`, naming it).  Every request has a timeout, so a PLC that
stops answering raises :class:`PlcLinkError` instead of hanging.

:class:`TestPlc` is a stand-in controller for runs without hardware: pyads'
ADS test server (``pyads.testserver``) on the loopback address, in a child
process, with every symbol of the ``plc:`` section declared with its PLC type,
and a PLC task that plays a trajectory as set-points and logs the actual axis
positions the bridge writes back (as TwinCAT's scope does in the paper).
"""

from __future__ import annotations

import multiprocessing as mp
import struct
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from cdpr_design.errors import CdprError, InputError

#: ADS error code "symbol not found" (ADSERR_DEVICE_SYMBOLNOTFOUND).
ADSERR_SYMBOLNOTFOUND = 0x710
#: The loopback address the test PLC binds (never any other address).
LOOPBACK = "127.0.0.1"
#: AMS net id of the test PLC and of the bridge's side in --test-plc runs.
TEST_PLC_NET_ID = "127.0.0.1.1.1"
TEST_LOCAL_NET_ID = "127.0.0.1.1.2"

# ADS data type codes (pyads.constants.ADST_*), kept here so the layout can be
# built without importing pyads.
ADST_REAL64 = 5
ADST_UINT32 = 19
ADST_BIT = 33


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


class PlcLinkError(CdprError):
    """The PLC cannot be reached or stopped answering (timeout, reset, refused)."""


# ----------------------------------------------------------------------------
# The symbol layout of a ``plc:`` section
# ----------------------------------------------------------------------------


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
        return {ADST_REAL64: 8, ADST_UINT32: 4, ADST_BIT: 1}[self.ads_type]

    @property
    def size(self) -> int:
        """Size in bytes."""
        return self.elem_size * self.count

    @property
    def fmt(self) -> str:
        """struct format of the value (little endian, no padding)."""
        return {ADST_REAL64: "d", ADST_UINT32: "I", ADST_BIT: "?"}[self.ads_type] * self.count


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


# ----------------------------------------------------------------------------
# The transport interface
# ----------------------------------------------------------------------------


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
        from pyads import constants
        from pyads.structs import SAdsSymbolEntry

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
        problems = []
        for sym in self.layout.symbols:
            try:
                info = conn.read_write(constants.ADSIGRP_SYM_INFOBYNAMEEX, 0, SAdsSymbolEntry,
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
        if problems:
            self.close()
            raise SymbolError(problems)
        self._prepare()

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
        pyads = self._pyads
        conn = self._conn
        if conn is None:
            raise PlcLinkError("not connected")
        try:
            if self.mode == "sum":
                raw = conn.read_write(0xF080, self._read_n, None, self._read_req, None,
                                      return_ctypes=False, check_length=False)
                vals = struct.unpack(self._read_fmt, bytes(raw))
                errs = vals[: self._read_n]
                if any(errs):
                    bad = [s.name for s, e in zip(self.layout.inputs, errs) if e]
                    raise PlcLinkError(f"PLC refused reading {', '.join(bad)} (ADS error "
                                       f"{max(errs):#x})")
                return np.array(vals[self._read_n:], dtype=float)
            return np.array([conn.read_by_name("", pyads.PLCTYPE_LREAL, handle=self._handles[s.name])
                             for s in self.layout.inputs], dtype=float)
        except (pyads.ADSError, OSError, struct.error, ValueError) as err:
            raise self._fail("reading the set-points", err) from None

    def write_outputs(self, values: Sequence) -> None:
        pyads = self._pyads
        conn = self._conn
        if conn is None:
            raise PlcLinkError("not connected")
        try:
            if self.mode == "sum":
                struct.pack_into(self._write_fmt, self._write_buf, self._write_head, *values)
                raw = conn.read_write(0xF081, self._write_n, None, self._write_buf, None,
                                      return_ctypes=False, check_length=False)
                errs = struct.unpack("<" + "I" * self._write_n, bytes(raw))
                if any(errs):
                    bad = [s.name for s, e in zip(self.layout.outputs, errs) if e]
                    raise PlcLinkError(f"PLC refused writing {', '.join(bad)} (ADS error "
                                       f"{max(errs):#x})")
                return
            i = 0
            for s in self.layout.outputs:
                ctype = {ADST_REAL64: pyads.PLCTYPE_LREAL, ADST_UINT32: pyads.PLCTYPE_UDINT,
                         ADST_BIT: pyads.PLCTYPE_BOOL}[s.ads_type]
                if s.count > 1:
                    conn.write_by_name("", list(values[i: i + s.count]), ctype * s.count,
                                       handle=self._handles[s.name])
                else:
                    conn.write_by_name("", values[i], ctype, handle=self._handles[s.name])
                i += s.count
        except (pyads.ADSError, OSError, struct.error, ValueError) as err:
            raise self._fail("writing the outputs", err) from None

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


# ----------------------------------------------------------------------------
# The test PLC: pyads' ADS test server on loopback, in a child process
# ----------------------------------------------------------------------------


def _test_plc_main(pipe, symbols, initial, setpoint_names, actual_names, times, lengths,
                   task_cycle, ip, port):
    """Body of the test PLC process (see :class:`TestPlc`)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops us
    from pyads.testserver import AdsTestServer, AdvancedHandler, PLCVariable
    from pyads.testserver.handler import AmsResponseData

    class Handler(AdvancedHandler):
        frozen = False

        def handle_request(self, request):
            if self.frozen:
                return None  # no answer at all: the client times out
            try:
                return super().handle_request(request)
            except KeyError:  # unknown symbol name / handle / index
                state = struct.unpack("<H", request.ams_header.state_flags)[0] | 0x0001
                return AmsResponseData(struct.pack("<H", state), request.ams_header.error_code,
                                       struct.pack("<II", ADSERR_SYMBOLNOTFOUND, 0))

    handler = Handler()
    vars_ = {}
    for (name, plc_type, ads_type, count), value in zip(symbols, initial):
        v = PLCVariable(name, value, ads_type, plc_type)
        handler.add_variable(v)
        vars_[name] = v
    try:
        server = AdsTestServer(handler=handler, ip_address=ip, port=port, logging=False)
    except OSError as err:
        pipe.send(("error", f"cannot bind {ip}:{port}: {err}"))
        return
    server.request_history = deque(maxlen=16)  # bounded memory on long runs
    server.start()

    sp_vars = [vars_[n] for n in setpoint_names]
    act_vars = [vars_[n] for n in actual_names if n in vars_]
    hb_var = None
    m = len(sp_vars)
    times = np.asarray(times, dtype=float)
    lengths = np.asarray(lengths, dtype=float).reshape(len(times), m) if len(times) else None
    max_rows = 2_000_000
    log = []
    rows = 0
    run = threading.Event()
    run.set()
    started = [None]
    stats = {"ticks": 0}
    hb_name = [s[0] for s in symbols if s[1] == "UDINT"]
    if hb_name:
        hb_var = vars_[hb_name[0]]

    def setpoint_at(tau):
        if lengths is None:
            return None
        return np.array([np.interp(tau, times, lengths[:, j]) for j in range(m)])

    def task():
        nonlocal rows
        nxt = time.perf_counter()
        while run.is_set():
            now = time.perf_counter()
            if started[0] is None and hb_var is not None and \
                    struct.unpack("<I", hb_var.value)[0] != 0:
                started[0] = now
            tau = 0.0 if started[0] is None else now - started[0]
            sp = setpoint_at(tau)
            if sp is not None:
                for var, val in zip(sp_vars, sp):
                    var.value = struct.pack("<d", val)
                if started[0] is not None and rows < max_rows:
                    act = [struct.unpack("<d", v.value)[0] for v in act_vars]
                    log.append((tau, *sp, *act))
                    rows += 1
            stats["ticks"] += 1
            nxt += task_cycle
            delay = nxt - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            else:
                nxt = time.perf_counter()

    t = threading.Thread(target=task, daemon=True)
    t.start()
    pipe.send(("ready", None))
    try:
        while True:
            if not pipe.poll(0.5):
                continue
            cmd = pipe.recv()
            if cmd == "freeze":
                handler.frozen = True
                pipe.send(("ok", None))
            elif cmd == "stop_server":
                server.close()
                pipe.send(("ok", None))
            elif cmd == "log":
                pipe.send(("log", np.array(log, dtype=float).reshape(-1, 1 + m + len(act_vars))))
            elif cmd == "values":
                pipe.send(("values", {n: v.value for n, v in vars_.items()}))
            elif cmd == "quit":
                break
    except (EOFError, OSError):
        pass
    finally:
        run.clear()
        t.join(1.0)
        server.close()
        try:
            pipe.send(("bye", None))
        except Exception:
            pass


class TestPlc:
    """A stand-in PLC on loopback: pyads' ADS test server in a child process.

    Every symbol of ``layout`` is declared with its PLC type (LREAL, an
    ARRAY OF LREAL for the pose, UDINT, BOOL).  A PLC task (period
    ``task_cycle``) writes the trajectory's cable lengths to the set-point
    symbols, starting when the bridge's heartbeat first becomes non-zero
    (holding the first sample before, the last after), and logs
    ``(tau, set-points..., actuals...)`` each period, as TwinCAT's scope
    does in the paper.

    It binds the fixed ADS port 48898 of 127.0.0.1 (AdsLib always connects to
    that port), so only one test PLC runs at a time on a machine.

    Parameters
    ----------
    layout : PlcLayout
        The symbols to declare.
    times : (k,) array [s], lengths : (k, m) array [m]
        The set-point trajectory; empty for constant set-points ``initial_setpoints``.
    task_cycle : float
        Period of the PLC task [s].
    omit : sequence of str
        Symbol names *not* to declare (tests of the symbol check).
    retype : dict
        Symbol name -> (plc_type, ads_type, count) declared instead (tests).
    """

    __test__ = False  # not a pytest class

    def __init__(self, layout: PlcLayout, times=(), lengths=(), *, task_cycle: float = 0.001,
                 initial_setpoints=None, omit: Sequence[str] = (), retype: dict | None = None,
                 ip: str = LOOPBACK, port: int = 48898):
        if ip != LOOPBACK:
            raise ValueError("the test PLC binds the loopback address only")
        self.layout = layout
        self.times = np.asarray(times, dtype=float)
        self.lengths = np.asarray(lengths, dtype=float)
        self.task_cycle = float(task_cycle)
        self.omit = set(omit)
        self.retype = dict(retype or {})
        self.ip, self.port = ip, int(port)
        self.initial_setpoints = initial_setpoints
        self._proc = None
        self._pipe = None
        self.net_id = TEST_PLC_NET_ID

    def _declarations(self):
        syms, init = [], []
        m = len(self.layout.inputs)
        if self.initial_setpoints is not None:
            sp0 = list(self.initial_setpoints)
        elif self.lengths.size:
            sp0 = list(self.lengths.reshape(len(self.times), m)[0])
        else:
            sp0 = [0.0] * m
        for s in self.layout.symbols:
            if s.name in self.omit:
                continue
            plc_type, ads_type, count = self.retype.get(s.name, (s.plc_type, s.ads_type, s.count))
            size = {ADST_REAL64: 8, ADST_UINT32: 4, ADST_BIT: 1}.get(ads_type, 4) * count
            if s.role == "setpoints" and (plc_type, ads_type, count) == (s.plc_type, s.ads_type, s.count):
                value = struct.pack("<d", sp0[self.layout.inputs.index(s)])
            else:
                value = bytes(size)
            syms.append((s.name, plc_type, ads_type, count))
            init.append(value)
        return syms, init

    def start(self, timeout: float = 20.0) -> "TestPlc":
        syms, init = self._declarations()
        ctx = mp.get_context("spawn")
        parent, child = ctx.Pipe()
        sp_names = [s.name for s in self.layout.inputs if s.name not in self.omit
                    and s.name not in self.retype]
        act_names = [s.name for s in self.layout.role("actuals")]
        self._proc = ctx.Process(
            target=_test_plc_main, daemon=True,
            args=(child, syms, init, sp_names, act_names, self.times, self.lengths,
                  self.task_cycle, self.ip, self.port))
        self._proc.start()
        self._pipe = parent
        msg = self._recv(timeout)
        if msg[0] != "ready":
            self.stop()
            raise PlcLinkError(f"the test PLC did not start: {msg[1]}")
        return self

    def _recv(self, timeout: float):
        if self._pipe is None or not self._pipe.poll(timeout):
            return ("error", "no answer from the test PLC process")
        try:
            return self._pipe.recv()
        except (EOFError, OSError) as err:
            return ("error", str(err))

    def _ask(self, cmd: str, timeout: float = 10.0):
        if self._pipe is None:
            return None
        try:
            self._pipe.send(cmd)
        except (BrokenPipeError, OSError):
            return None
        msg = self._recv(timeout)
        return msg[1] if msg[0] != "error" else None

    def freeze(self) -> None:
        """Stop answering requests (the connection stays open): a hung PLC."""
        self._ask("freeze")

    def stop_server(self) -> None:
        """Close the server and its connections: a PLC that went away."""
        self._ask("stop_server")

    def log(self) -> np.ndarray:
        """The PLC task's log: columns tau [s], set-points (m), actuals (m)."""
        out = self._ask("log", timeout=30.0)
        m = len(self.layout.inputs)
        return out if out is not None else np.zeros((0, 1 + m + len(self.layout.role("actuals"))))

    def values(self) -> dict:
        """The raw bytes of every declared symbol (name -> bytes)."""
        return self._ask("values") or {}

    def value(self, name: str):
        """One symbol's current value, decoded with its declared type."""
        raw = self.values().get(name)
        if raw is None:
            return None
        sym = next(s for s in self.layout.symbols if s.name == name)
        vals = struct.unpack("<" + sym.fmt, raw)
        return vals[0] if sym.count == 1 else list(vals)

    def stop(self) -> None:
        """End the child process (never blocks for more than a few seconds)."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.is_alive() and self._pipe is not None:
            try:
                self._pipe.send("quit")
                self._recv(3.0)
            except (BrokenPipeError, OSError):
                pass
        proc.join(3.0)
        if proc.is_alive():
            proc.terminate()
            proc.join(2.0)
        if proc.is_alive():
            proc.kill()
            proc.join(1.0)
        if self._pipe is not None:
            self._pipe.close()
            self._pipe = None

    def __enter__(self) -> "TestPlc":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
