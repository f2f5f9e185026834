"""A stand-in PLC for runs without hardware: :class:`TestPlc`.

pyads' ADS test server (``pyads.testserver``) on the loopback address, in a
child process, with every symbol of the ``plc:`` section declared with its
PLC type, and a PLC task that plays a trajectory as set-points and logs the
actual axis positions the bridge writes back (as TwinCAT's scope does in the
seed paper, Rivera et al., "Environment for the Design and Automation of New
CDPR Architectures", Sec. 4).
"""

from __future__ import annotations

import multiprocessing as mp
import struct
import threading
import time
from collections import deque
from typing import Sequence

import numpy as np

from cdpr_design.plc.symbols import ADSERR_SYMBOLNOTFOUND, ELEM_SIZE, PlcLayout
from cdpr_design.plc.transport import PlcLinkError

#: The loopback address the test PLC binds (never any other address).
LOOPBACK = "127.0.0.1"
#: AMS net id of the test PLC and of the bridge's side in --test-plc runs.
TEST_PLC_NET_ID = "127.0.0.1.1.1"
TEST_LOCAL_NET_ID = "127.0.0.1.1.2"

#: Most rows the PLC task logs (bounded memory on long runs).
MAX_LOG_ROWS = 2_000_000


# ----------------------------------------------------------------------------
# The child process: pyads' ADS test server on loopback and a PLC task
# ----------------------------------------------------------------------------


def _handler():
    """A pyads test-server handler that can freeze (answer nothing) and refuses unknown symbols."""
    from pyads.testserver import AdvancedHandler
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

    return Handler()


class _PlcTask:
    """The PLC task: plays the set-point trajectory and logs (tau, set-points, actuals).

    It starts when the heartbeat first becomes non-zero (holding the first
    sample before, the last after); ``tau`` [s] is the time since then.
    """

    def __init__(self, variables: dict, symbols, setpoint_names, actual_names, times, lengths,
                 task_cycle: float):
        self.sp_vars = [variables[n] for n in setpoint_names]
        self.act_vars = [variables[n] for n in actual_names if n in variables]
        hb_name = [s[0] for s in symbols if s[1] == "UDINT"]
        self.hb_var = variables[hb_name[0]] if hb_name else None
        self.m = len(self.sp_vars)
        self.times = np.asarray(times, dtype=float)
        self.lengths = (np.asarray(lengths, dtype=float).reshape(len(self.times), self.m)
                        if len(self.times) else None)
        self.task_cycle = task_cycle
        self.log: list = []
        self.started = None
        self.ticks = 0
        self.running = threading.Event()
        self.running.set()

    def setpoint_at(self, tau: float):
        if self.lengths is None:
            return None
        return np.array([np.interp(tau, self.times, self.lengths[:, j]) for j in range(self.m)])

    def tick(self, now: float) -> None:
        """One period: start on the heartbeat, write the set-points, log a row."""
        if self.started is None and self.hb_var is not None and \
                struct.unpack("<I", self.hb_var.value)[0] != 0:
            self.started = now
        tau = 0.0 if self.started is None else now - self.started
        sp = self.setpoint_at(tau)
        if sp is not None:
            for var, val in zip(self.sp_vars, sp):
                var.value = struct.pack("<d", val)
            if self.started is not None and len(self.log) < MAX_LOG_ROWS:
                act = [struct.unpack("<d", v.value)[0] for v in self.act_vars]
                self.log.append((tau, *sp, *act))
        self.ticks += 1

    def run(self) -> None:
        """Tick every ``task_cycle`` [s] against an absolute schedule until stopped."""
        nxt = time.perf_counter()
        while self.running.is_set():
            self.tick(time.perf_counter())
            nxt += self.task_cycle
            delay = nxt - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            else:
                nxt = time.perf_counter()

    def log_array(self) -> np.ndarray:
        return np.array(self.log, dtype=float).reshape(-1, 1 + self.m + len(self.act_vars))


def _serve(pipe, handler, server, variables: dict, task: _PlcTask) -> None:
    """Answer the parent's commands (freeze, stop_server, log, values, quit) until it quits."""
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
            pipe.send(("log", task.log_array()))
        elif cmd == "values":
            pipe.send(("values", {n: v.value for n, v in variables.items()}))
        elif cmd == "quit":
            break


def _test_plc_main(pipe, symbols, initial, setpoint_names, actual_names, times, lengths,
                   task_cycle, ip, port):
    """Body of the test PLC process (see :class:`TestPlc`)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops us
    from pyads.testserver import AdsTestServer, PLCVariable

    handler = _handler()
    variables = {}
    for (name, plc_type, ads_type, count), value in zip(symbols, initial):
        v = PLCVariable(name, value, ads_type, plc_type)
        handler.add_variable(v)
        variables[name] = v
    try:
        server = AdsTestServer(handler=handler, ip_address=ip, port=port, logging=False)
    except OSError as err:
        pipe.send(("error", f"cannot bind {ip}:{port}: {err}"))
        return
    server.request_history = deque(maxlen=16)  # bounded memory on long runs
    bound = server.server.getsockname()[1]  # the port the system chose when asked for 0
    server.start()
    task = _PlcTask(variables, symbols, setpoint_names, actual_names, times, lengths, task_cycle)
    thread = threading.Thread(target=task.run, daemon=True)
    thread.start()
    pipe.send(("ready", bound))
    try:
        _serve(pipe, handler, server, variables, task)
    except (EOFError, OSError):
        pass
    finally:
        task.running.clear()
        thread.join(1.0)
        server.close()
        try:
            pipe.send(("bye", None))
        except Exception:
            pass


# ----------------------------------------------------------------------------
# The parent's handle
# ----------------------------------------------------------------------------


class TestPlc:
    """A stand-in PLC on loopback: pyads' ADS test server in a child process.

    Every symbol of ``layout`` is declared with its PLC type (LREAL, an
    ARRAY OF LREAL for the pose, UDINT, BOOL).  A PLC task (period
    ``task_cycle``) writes the trajectory's cable lengths to the set-point
    symbols, starting when the bridge's heartbeat first becomes non-zero
    (holding the first sample before, the last after), and logs
    ``(tau, set-points..., actuals...)`` each period, as TwinCAT's scope
    does in the paper.

    It listens on 127.0.0.1 at ``port``; the default 0 lets the system choose a
    free port (read :attr:`port` or :attr:`address` once started), so any
    number of test PLCs run side by side on a machine. A client reaches it at
    :attr:`address`, ``"127.0.0.1:<port>"``, the ``host[:port]`` form AdsLib
    accepts (its default port is the ADS router port 48898), and by its own AMS
    net id :attr:`net_id`, ``127.0.0.1.<port / 256>.<port % 256>``.

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
    port : int
        TCP port to listen on; 0 (the default): a free one the system chooses.
    """

    __test__ = False  # not a pytest class

    def __init__(self, layout: PlcLayout, times=(), lengths=(), *, task_cycle: float = 0.001,
                 initial_setpoints=None, omit: Sequence[str] = (), retype: dict | None = None,
                 ip: str = LOOPBACK, port: int = 0):
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
            size = ELEM_SIZE.get(ads_type, 4) * count
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
        self.port = int(msg[1])
        # one AMS net id per test PLC: AdsLib keeps one route per net id in a process, so a route
        # left to an earlier test PLC's port can never be taken for this one's
        self.net_id = f"127.0.0.1.{self.port >> 8}.{self.port & 0xFF}"
        return self

    @property
    def address(self) -> str:
        """Where a client reaches the started test PLC: ``"127.0.0.1:<port>"`` (AdsLib's ``host:port``)."""
        return f"{self.ip}:{self.port}"

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


__all__ = ["LOOPBACK", "MAX_LOG_ROWS", "TEST_LOCAL_NET_ID", "TEST_PLC_NET_ID", "TestPlc"]
