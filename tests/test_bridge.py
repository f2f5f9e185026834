"""The PLC gateway (bridge) against pyads' ADS test server on 127.0.0.1.

Each test PLC listens on a free port of the loopback address that the system
chooses (``TestPlc.address``; the spec's ``plc.host`` names it as
``127.0.0.1:<port>``), so these tests run in parallel with anything, whatever
the number of workers. Each bridged run lasts a few seconds.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cdpr_design.plc import bridge as br
from cdpr_design.plc import delay, rows as plc_rows, stats, transport
from cdpr_design.model import spec
from cdpr_design.motion import trajectory
from cdpr_design.plc.ads import AdsTransport
from cdpr_design.plc.symbols import ADST_REAL64, PlcLayout, check_symbol_info
from cdpr_design.plc.testplc import LOOPBACK, TEST_LOCAL_NET_ID, TEST_PLC_NET_ID, TestPlc

from .helpers import invoke, subprocess_env, write_spec, resolved

PLC = {
    "ams_net_id": TEST_PLC_NET_ID, "port": 851, "host": LOOPBACK, "cycle_time": 0.01,
    "setpoints": ["MAIN.fCableLen1", "MAIN.fCableLen2"],
    "actuals": ["MAIN.fSimLen1", "MAIN.fSimLen2"],
    "tensions": ["MAIN.fSimT1", "MAIN.fSimT2"],
    "pose": "MAIN.aSimPose", "heartbeat": "MAIN.nSimHeartbeat", "fault": "MAIN.bSimFault",
}


@pytest.fixture
def loop_data(planar2_data) -> dict:
    """planar2 with its plc: section pointed at the loopback test PLC."""
    d = dict(planar2_data)
    d["plc"] = dict(PLC)
    d["trajectories"] = dict(d.get("trajectories") or {})
    d["trajectories"]["probe"] = {  # an L of 0.4 m at 0.3 m/s: ~1.6 s
        "type": "polyline", "waypoints": [[0.65, 0.75], [0.85, 0.75], [0.85, 0.95]],
        "speed": 0.3, "acceleration": 2.0}
    return d


@pytest.fixture
def design(loop_data):
    return spec.from_dict(loop_data)


def _spec_for(tmp_path, loop_data, address: str, net_id: str = TEST_PLC_NET_ID) -> Path:
    """The spec of ``loop_data`` with its ``plc.host`` at ``address`` (``host:port``), ``plc.ams_net_id``
    ``net_id``."""
    return write_spec(tmp_path, dict(loop_data, plc=dict(loop_data["plc"], host=address, ams_net_id=net_id)))


def _read_csv(path: Path):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [ln.split(",") for ln in lines[1:]]
    assert all(len(r) == len(header) for r in rows), "a truncated row in the log"
    data = np.array([[float(v) if v else np.nan for v in r] for r in rows]).reshape(-1, len(header))
    return header, data


# ----------------------------------------------------------------------------
# Pure parts (no server)
# ----------------------------------------------------------------------------


def test_stream_stats_match_numpy():
    rng = np.random.default_rng(1)
    x = rng.lognormal(mean=-7, sigma=1.0, size=20000)
    s = stats.StreamStats()
    for v in x:
        s.add(float(v))
    assert s.count == x.size
    assert s.summary()["mean"] == pytest.approx(x.mean(), rel=1e-12)
    assert s.max == x.max()
    # p99 within the 1 % bin width of numpy's (upper-edge convention)
    assert np.percentile(x, 99) * 0.99 <= s.percentile(99) <= np.percentile(x, 99) * 1.02


def test_layout_follows_the_spec(design):
    lay = PlcLayout.from_design(design)
    assert [s.name for s in lay.inputs] == PLC["setpoints"]
    assert [s.name for s in lay.outputs] == (PLC["actuals"] + PLC["tensions"]
                                            + [PLC["pose"], PLC["heartbeat"], PLC["fault"]])
    pose = lay.role("pose")[0]
    assert (pose.count, pose.size, pose.plc_type) == (2, 16, "ARRAY [0..1] OF LREAL")
    assert lay.role("heartbeat")[0].size == 4 and lay.fault.size == 1
    vals = lay.pack_outputs([1, 2], [3, 4], [5, 6], 2**32 + 7, True)
    assert vals == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7, True]  # the UDINT heartbeat wraps


def test_symbol_type_check_names_expected_and_declared():
    lay_sym = PlcLayout((), ())
    del lay_sym
    from cdpr_design.plc.symbols import Symbol

    lreal = Symbol("MAIN.f", "LREAL", ADST_REAL64, 1, "setpoints")
    assert check_symbol_info(lreal, ADST_REAL64, 8, "LREAL") is None
    msg = check_symbol_info(lreal, 4, 4, "REAL")
    assert "expected LREAL (8 bytes)" in msg and "REAL (4 bytes)" in msg
    arr = Symbol("MAIN.a", "ARRAY [0..2] OF LREAL", ADST_REAL64, 3, "pose")
    assert check_symbol_info(arr, 65, 24, "ARRAY [0..2] OF LREAL") is None
    assert check_symbol_info(arr, ADST_REAL64, 16, "ARRAY [0..1] OF LREAL") is not None


# ----------------------------------------------------------------------------
# The loop on a fake clock (deterministic: stalls injected, no server)
# ----------------------------------------------------------------------------


class FakeClock:
    """Wall clock that moves only when slept on, plus 20 us per reading."""

    def __init__(self):
        self.t = 0.0

    def __call__(self):
        self.t += 2e-5
        return self.t

    def sleep(self, s):
        self.t += max(s, 0.0)


class FakePlc(transport.Transport):
    """Plays the trajectory by the fake clock; the write of the cycle at each stall time hangs."""

    def __init__(self, design, samples, clock, stalls=()):
        self.layout = PlcLayout.from_design(design)
        self.samples, self.clock, self.stalls = samples, clock, sorted(stalls)

    def read_setpoints(self):
        s = self.samples
        return np.array([np.interp(self.clock.t, s.time, s.lengths[:, j])
                         for j in range(s.lengths.shape[1])])

    def write_outputs(self, values):
        if self.stalls and self.clock.t >= self.stalls[0][0]:
            self.clock.t += self.stalls.pop(0)[1]  # descheduled on a loaded machine


def test_stalls_degrade_timing_not_the_path(design):
    """A loaded machine (cycles hanging 120 ms, also near the corner) makes overruns, not detours.

    The loop used to run the last set-point ramp on through the stalled time
    and then step to the new set-point: 6.5 cm off the L here.
    """
    samples = trajectory.sample(resolved(design, "motion"), "probe")
    clock = FakeClock()
    stalls = [(t, 0.12) for t in (0.3, 0.8, 0.95, 1.1, 1.5)]
    sim = br.make_simulator(design, 0.01, samples.lengths[0])
    rows = plc_rows.RowMaker(design)
    log = []
    res = br.run(FakePlc(design, samples, clock, stalls), sim, br.Loop(0.01, samples.duration + 0.3, spin=0.0),
                 clock=clock, sleep=clock.sleep, on_row=lambda sp, st: log.append(rows.values(sp, st)))
    assert res.overruns == len(stalls) and res.slips == 0
    assert res.sim_time == pytest.approx(samples.duration + 0.3, abs=1e-6)
    log = np.array(log)
    assert log.shape[0] == res.cycles
    xy = log[:, 3:5]
    off_path = np.min(np.linalg.norm(xy[:, None, :] - samples.pose[None, :, :], axis=2), axis=1)
    assert off_path.max() < 0.01
    np.testing.assert_allclose(xy[-1], [0.85, 0.95], atol=2e-3)
    # the logged targets are the PLC's set-points at the rows' times
    on_path = np.min(np.linalg.norm(log[:, None, 5:7] - samples.lengths[None, :, :], axis=2), axis=1)
    assert on_path.max() < 1e-3


class RecordingSim:
    """A stand-in model that records what the loop asks of it (axes = reference)."""

    timestep = 5e-4

    def __init__(self, sp0):
        from types import SimpleNamespace

        self.t, self.ref, self.calls = 0.0, np.array(sp0, float), []
        self._ns = SimpleNamespace

    def advance(self, sp, duration, velocity=None, tension=None):
        sp, v = np.asarray(sp, float), np.asarray(velocity, float)
        self.calls.append((self.t, sp.copy(), v.copy(), duration))
        self.t += duration
        self.ref = sp + v * duration
        return self.state()

    def state(self):
        return self._ns(time=self.t, pose=np.zeros(2), lengths=self.ref.copy(),
                        tensions=np.zeros(2), setpoints=self.ref.copy())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_reference_is_continuous_and_never_overshoots(design, seed):
    """Whatever the timing, the axes' reference never steps and never leaves the set-points' hull."""
    samples = trajectory.sample(resolved(design, "motion"), "probe")
    clock = FakeClock()
    rng = np.random.default_rng(seed)
    stalls = sorted((float(t), float(rng.uniform(0.005, 0.2))) for t in rng.uniform(0, 2.0, 12))
    sim = RecordingSim(samples.lengths[0])
    res = br.run(FakePlc(design, samples, clock, stalls), sim, br.Loop(0.01, samples.duration + 0.2, spin=0.0),
                 clock=clock, sleep=clock.sleep)
    assert res.overruns >= 1 and res.cycles > 50
    ends = [sp + v * d for _, sp, v, d in sim.calls]
    assert len(sim.calls) > 50  # the continuity check below runs over many steps
    for (t, sp, v, d), prev in zip(sim.calls[1:], ends[:-1]):
        np.testing.assert_allclose(sp, prev, atol=1e-9)  # no step
    lo = samples.lengths.min(axis=0) - 1e-3   # extrapolation by one cycle stays within 1 mm
    hi = samples.lengths.max(axis=0) + 1e-3
    assert np.all(np.array(ends) >= lo) and np.all(np.array(ends) <= hi)


def test_delay_trace_sees_the_hold_of_the_written_values():
    """Values written every 10 ms, each standing for 20 ms before: the PLC sees 20 + 5 ms."""
    tr = delay.DelayTrace()
    dt, lag = 0.01, 0.02
    f = lambda t: np.array([0.9 + 0.1 * np.sin(2 * t), 0.8 - 0.05 * t * t])  # noqa: E731
    for k in range(300):
        t = k * dt + 1e-4 * np.sin(7 * k)  # jittered reads
        tr.read(t, f(t))
        tr.wrote(t + 0.004, f(t + 0.004 - lag), t)
    d = tr.delay(("c1", "c2"), dt)
    assert set(d) == {"length_c1", "length_c2"}  # the loop below checks every column
    for v in d.values():
        assert v == pytest.approx(lag + dt / 2, abs=5e-4)


# ----------------------------------------------------------------------------
# Against the test PLC (each on its own port of 127.0.0.1)
# ----------------------------------------------------------------------------


def test_setpoints_from_the_test_plc_move_the_effector(design):
    """The loop closes: PLC set-points -> simulated robot -> PLC actuals, heartbeat, pose."""
    samples = trajectory.sample(resolved(design, "motion"), "probe")
    lay = PlcLayout.from_design(design)
    with TestPlc(lay, samples.time, samples.lengths) as plc:
        tr = AdsTransport(lay, plc.net_id, 851, plc.address, timeout=0.1,
                          local_net_id=TEST_LOCAL_NET_ID)
        tr.connect()
        sp0 = tr.read_setpoints()
        np.testing.assert_allclose(sp0, samples.lengths[0], atol=1e-12)
        sim = br.make_simulator(design, 0.01, sp0)
        rows = plc_rows.RowMaker(design)
        log = []
        res = br.run(tr, sim, br.Loop(0.01, samples.duration + 0.3),
                     on_row=lambda sp, st: log.append(rows.values(sp, st)))
        final = sim.state()
        hb = plc.value(PLC["heartbeat"])
        pose = plc.value(PLC["pose"])
        act = [plc.value(n) for n in PLC["actuals"]]
        fault = plc.value(PLC["fault"])
        plc_log = plc.log()
        tr.close()
    assert res.stopped == "duration" and res.cycles == len(log) > 50
    assert res.sim_time == pytest.approx(samples.duration + 0.3, abs=1e-6)  # real time kept
    assert hb == res.cycles  # incremented once per completed cycle
    assert fault is False
    np.testing.assert_allclose(pose, final.pose, atol=1e-12)
    np.testing.assert_allclose(act, final.lengths, atol=1e-12)
    log = np.array(log)
    header = plc_rows.csv_header(design)
    col = {h: i for i, h in enumerate(header)}
    # the set-points the bridge read are the trajectory's lengths...
    tgt = log[:, [col["length_c1_target"], col["length_c2_target"]]]
    on_path = np.min(np.linalg.norm(tgt[:, None, :] - samples.lengths[None, ::5, :], axis=2), axis=1)
    assert on_path.max() < 5e-3
    # ...and the simulated effector went along the L (0.2 m each way) after them
    xy = log[:, [col["x"], col["y"]]]
    assert np.ptp(xy[:, 0]) > 0.19 and np.ptp(xy[:, 1]) > 0.19
    np.testing.assert_allclose(xy[-1], [0.85, 0.95], atol=2e-3)
    # on the path (distance to the nearest trajectory pose; the timing is the PLC's)
    off_path = np.min(np.linalg.norm(xy[:, None, :] - samples.pose[None, :, :], axis=2), axis=1)
    assert off_path.max() < 0.01
    # the PLC saw the simulated axes follow its set-points
    assert plc_log.shape[0] > 100
    d = delay.axis_delays(design.cable_names, plc_log[:, 0], plc_log[:, 1:3], plc_log[:, 3:5])
    assert len(d) == design.m  # one delay per axis: the checks below are not vacuous
    assert all(v is not None and abs(v) < 0.1 for v in d.values())
    # the gateway's own estimate (read -> written and held) agrees with the PLC's scope; the
    # PLC also sees its 1 ms task and the wait of a set-point before the read (< 1 cycle)
    gw = res.delay(design.cable_names)
    for k, v in d.items():
        assert gw[k] is not None and -0.003 < v - gw[k] < 0.01 + 0.003, (d, gw)


@pytest.mark.parametrize("case", ["missing", "mistyped"])
def test_bad_symbol_is_refused_at_start_naming_it(tmp_path, loop_data, design, case):
    lay = PlcLayout.from_design(design)
    if case == "missing":
        kw, name = {"omit": ["MAIN.fSimT2"]}, "MAIN.fSimT2"
    else:
        kw, name = {"retype": {"MAIN.nSimHeartbeat": ("LREAL", ADST_REAL64, 1)}}, "MAIN.nSimHeartbeat"
    with TestPlc(lay, **kw) as plc:
        p = _spec_for(tmp_path, loop_data, plc.address, plc.net_id)
        r = invoke("bridge", p, "--duration", "0.5", "--local-net-id", TEST_LOCAL_NET_ID, "--out", tmp_path / "o")
    assert r.exit_code == 2, r.output
    assert name in r.output
    assert "Traceback" not in r.output
    if case == "mistyped":
        assert "expected UDINT" in r.output
    assert not (tmp_path / "o" / "bridge.csv").exists()


@pytest.mark.parametrize("net_id", ["garbage", "1.2.3.4.5", "1.2.3.4.5.256", "1.2.3.4.5.-6", "1.2.3.4.5.6.7",
                                    "1.2.3.4.5.6 ", "1.2.3.4.5.0256", pytest.param("1" * 5000, id="long"),
                                    pytest.param("1.2.3.4.5." + "1" * 5000, id="long-number")])
def test_a_bad_net_id_is_refused_before_any_work(tmp_path, loop_data, net_id):
    """--local-net-id and the spec's plc.ams_net_id: six numbers 0-255 joined by dots, else exit 2 naming
    the option or the key and the spec file (the value shortened), no PLC started, nothing written."""
    p = write_spec(tmp_path, loop_data)
    r = invoke("bridge", p, "--test-plc", "probe", "--local-net-id", net_id, "--duration", "0.1",
               "--out", tmp_path / "o")
    assert r.exit_code == 2 and "--local-net-id" in r.output and "Traceback" not in r.output, r.output
    assert "1" * 100 not in r.output
    bad = dict(loop_data, plc=dict(PLC, ams_net_id=net_id))
    p = write_spec(tmp_path, bad, "bad_net_id.yaml")
    r = invoke("bridge", p, "--duration", "0.1", "--timeout", "0.05", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "Traceback" not in r.output, r.output
    assert "plc.ams_net_id" in r.output and "bad_net_id.yaml" in r.output and "1" * 100 not in r.output
    assert not (tmp_path / "o").exists()


def test_no_plc_at_all_is_a_clean_error(tmp_path, loop_data):
    with socket.socket() as taken:  # a port of our own that nothing listens on: the connection is refused
        taken.bind((LOOPBACK, 0))
        p = _spec_for(tmp_path, loop_data, f"{LOOPBACK}:{taken.getsockname()[1]}")
        t = time.monotonic()
        r = invoke("bridge", p, "--duration", "0.5", "--timeout", "0.05", "--local-net-id", TEST_LOCAL_NET_ID,
                   "--out", tmp_path / "o")
    assert r.exit_code == 3, r.output
    assert "Traceback" not in r.output
    assert time.monotonic() - t < 10


def _start_bridge(tmp_path, spec_path, *extra):
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "cdpr_design", "bridge", str(spec_path), "--out", str(out),
           "--json", *extra]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=subprocess_env(), cwd=tmp_path)
    return proc, out


def _wait_running(proc, out: Path, timeout=60.0):
    """Wait until the bridge has streamed some rows to its temporary log."""
    t = time.monotonic()
    while time.monotonic() - t < timeout:
        if proc.poll() is not None:
            raise AssertionError(f"bridge ended early: {proc.communicate()}")
        tmp = list(out.glob(".bridge.csv.*.tmp"))
        if tmp and tmp[0].stat().st_size > 2000:
            return
        time.sleep(0.05)
    raise AssertionError("bridge did not start")


@pytest.mark.slow
@pytest.mark.parametrize("how", ["stop_server", "freeze"])
def test_plc_that_stops_answering_ends_the_run_without_hanging(tmp_path, loop_data, design, how):
    lay = PlcLayout.from_design(design)
    samples = trajectory.sample(resolved(design, "motion"), "square_slow")
    with TestPlc(lay, samples.time, samples.lengths) as plc:
        p = _spec_for(tmp_path, loop_data, plc.address, plc.net_id)
        proc, out = _start_bridge(tmp_path, p, "--duration", "60", "--timeout", "0.05",
                                  "--local-net-id", TEST_LOCAL_NET_ID)
        try:
            _wait_running(proc, out)
            getattr(plc, how)()
            t = time.monotonic()
            stdout, stderr = proc.communicate(timeout=20)
            took = time.monotonic() - t
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    assert proc.returncode == 3, stderr
    # the run was asked for 60 s: ending well inside it means the loss ended it (a few
    # cycles of timeouts), not the duration; the bound leaves room for a loaded machine
    assert took < 20.0
    assert "PLC lost" in stderr and "Traceback" not in stderr
    summary = json.loads(stdout)
    assert summary["stopped"] == "plc_lost" and summary["missed"] >= 3
    header, data = _read_csv(out / "bridge.csv")  # what was logged is kept
    assert data.shape[0] == summary["cycles"] > 10
    assert json.loads((out / "bridge.json").read_text())["stopped"] == "plc_lost"


@pytest.mark.slow
def test_reconnect_retries_then_gives_up(tmp_path, loop_data, design):
    """--reconnect: the lost PLC is retried with back-off, then the run ends (exit 3)."""
    lay = PlcLayout.from_design(design)
    samples = trajectory.sample(resolved(design, "motion"), "probe")
    with TestPlc(lay, samples.time, samples.lengths) as plc:
        p = _spec_for(tmp_path, loop_data, plc.address, plc.net_id)
        proc, out = _start_bridge(tmp_path, p, "--duration", "60", "--reconnect", "2",
                                  "--local-net-id", TEST_LOCAL_NET_ID)
        try:
            _wait_running(proc, out)
            plc.stop_server()
            stdout, stderr = proc.communicate(timeout=30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    assert proc.returncode == 3, stderr
    assert stderr.count("reconnecting in") == 2
    assert "0.1 s" in stderr and "0.2 s" in stderr  # back-off doubles


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP], ids=lambda s: s.name)
def test_ctrl_c_stops_cleanly_with_the_log_intact(tmp_path, loop_data, sig):
    """Ctrl-C, and SIGTERM / SIGHUP the same way: exit 130, the summary printed, bridge.csv whole."""
    p = write_spec(tmp_path, loop_data)
    proc, out = _start_bridge(tmp_path, p, "--test-plc", "square_slow", "--duration", "60")
    try:
        _wait_running(proc, out)
        time.sleep(0.5)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr
    summary = json.loads(stdout)
    assert summary["stopped"] == "interrupted"
    header, data = _read_csv(out / "bridge.csv")
    assert header[:5] == ["time", "x_target", "y_target", "x", "y"]
    assert data.shape[0] == summary["cycles"] > 20
    assert np.all(np.diff(data[:, 0]) > 0)
    assert not list(out.glob(".bridge.csv.*"))  # no temporary file left behind


def test_test_plc_run_writes_compare_ready_log(tmp_path, loop_data):
    """--test-plc: bridge.csv has the simulation.csv columns; compare reads it."""
    p = write_spec(tmp_path, loop_data)
    out = tmp_path / "o"
    r = invoke("bridge", p, "--test-plc", "probe", "--duration", "2.5", "--out", out, "--json")
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    for key in ("cycles", "overruns", "cycle_time", "latency", "delay"):
        assert key in summary
    assert set(summary["latency"]) == {"mean", "p99", "max"}
    assert summary["latency"]["mean"] < summary["cycle_time"]
    header, data = _read_csv(out / "bridge.csv")
    assert header == plc_rows.csv_header(spec.from_dict(loop_data))
    assert data.shape[0] == summary["cycles"]
    assert set(summary["delay"]) == {"length_c1", "length_c2"}
    t = summary["timings"]  # the loop and its log's writing, apart
    assert set(t) == {"sweep_s", "write_s", "pictures_s", "total_s"}
    assert 0 < t["write_s"] < t["sweep_s"] <= t["total_s"] and t["pictures_s"] == 0
    assert json.loads((out / "bridge.json").read_text())["timings"] == t


def test_test_plc_plays_the_unstretched_lengths_of_elastic_cables(tmp_path, loop_data):
    """With elastic cables the test PLC commands what `simulate` commands: the unstretched lengths,
    which the simulated winches pay out (the chords would let the effector sink by the stretch)."""
    data = {**loop_data, "cable": {**loop_data["cable"], "model": "elastic"}}
    p = write_spec(tmp_path, data)
    d = spec.load(p)
    samples = trajectory.sample(resolved(d, "motion"), "probe")
    L0, chords = samples.cables.unstretched, samples.lengths
    assert np.all(chords - L0 > 1e-4)  # the stretch is there to see (planar2: EA = 2e4 N)
    out = tmp_path / "o"
    r = invoke("bridge", p, "--test-plc", "probe", "--out", out, "--json")
    assert r.exit_code == 0, r.output
    header, log = _read_csv(out / "bridge.csv")
    col = {h: i for i, h in enumerate(header)}
    targets = log[:, [col["length_c1_target"], col["length_c2_target"]]]
    # after the path the PLC holds its last set-point: L0 (to bridge.csv's 10 digits), not the chord
    np.testing.assert_allclose(targets[-1], L0[-1], rtol=1e-9, atol=0)
    # every set-point read lies on the played polyline of L0 (linear in time between samples)
    near = np.min(np.max(np.abs(targets[:, None, :] - L0[None, :, :]), axis=2), axis=1)
    assert near.max() < 0.3 * 0.01 + 1e-9  # at most one PLC cycle of travel (0.3 m/s, 10 ms) from a sample
    # and the robot ends where the path ends (within the ideal run's 2 mm: still settling there)
    np.testing.assert_allclose(log[-1, [col["x"], col["y"]]], [0.85, 0.95], atol=2e-3)
