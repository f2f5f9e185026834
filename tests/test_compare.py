"""compare: delay by cross-correlation with sub-sample resolution, error statistics,
the per-segment table (the seed paper's Table 2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from cdpr_design.motion import compare as C
from cdpr_design.motion import trajectory as tr

from .helpers import invoke, resolved


@pytest.fixture(scope="module")
def fast(planar2):
    return tr.sample(resolved(planar2, "motion"), "square_fast", hold_start=0.3, hold_end=0.5)


def smooth(t):
    return np.sin(2 * np.pi * 0.5 * t) + 0.3 * np.sin(2 * np.pi * 1.3 * t + 0.4)


@settings(max_examples=40, deadline=None)
@given(delay=st.floats(-0.3, 0.3), offset=st.floats(-0.01, 0.01))
def test_recovers_known_delay_of_smooth_signal(delay, offset):
    """A delayed copy (evaluated exactly, not shifted samples) with an offset: recovered
    far within the 1 ms the brief asks for, at 1 ms sampling."""
    dt = 1e-3
    t = np.arange(0, 5, dt)
    est = C.estimate_delay(dt, smooth(t), smooth(t - delay) + offset)
    assert abs(est - delay) < 1e-4


@pytest.mark.parametrize("delay", [0.0, 0.0004, 0.0305, 0.1304, 0.150])
def test_recovers_known_delay_on_the_square(fast, delay):
    """The paper's square at 1 m/s: y and cable lengths delayed by a known, sub-sample delay."""
    t = fast.time
    target = {"y": fast.pose[:, 1], "length_c1": fast.lengths[:, 0]}
    actual = {"y": np.interp(t - delay, t, fast.pose[:, 1]),
              "length_c1": np.interp(t - delay, t, fast.lengths[:, 0])}
    res = C.compare(t, target, t, actual)
    for col in target:
        assert abs(res.delay[col] - delay) < 1e-3, col
        assert abs(res.delay[col] - delay) < 2e-4, col  # in fact sub-sample


def test_different_time_bases(fast):
    """The actual log on its own 2 ms grid, offset by 0.7 ms (a scope export), delayed 25 ms."""
    t = fast.time
    ta = np.arange(t[0] + 0.0007, t[-1], 2e-3)
    act = {"x": np.interp(ta - 0.025, t, fast.pose[:, 0]), "y": np.interp(ta - 0.025, t, fast.pose[:, 1])}
    res = C.compare(t, {"x": fast.pose[:, 0], "y": fast.pose[:, 1]}, ta, act)
    assert abs(res.delay["x"] - 0.025) < 1e-3
    assert abs(res.delay["y"] - 0.025) < 1e-3


def test_known_offset_exactly(fast):
    """A constant offset of 2.5 mm on y: mean error, segment errors and max error are exact,
    and the delay stays zero."""
    t = fast.time
    tgt = {"x": fast.pose[:, 0], "y": fast.pose[:, 1]}
    act = {"x": fast.pose[:, 0].copy(), "y": fast.pose[:, 1] + 0.0025}
    res = C.compare(t, tgt, t, act)
    assert res.columns["y"]["mean"] == pytest.approx(0.0025, abs=1e-15)
    assert res.columns["x"]["mean"] == 0.0 and res.columns["x"]["max"] == 0.0
    assert res.rms_error == pytest.approx(0.0025, abs=1e-15)
    assert res.max_error == pytest.approx(0.0025, abs=1e-15)
    assert res.delay["y"] == pytest.approx(0.0, abs=1e-9)
    # the four sides are found; horizontal ones report y, vertical ones x
    assert [r.axis for r in res.segments] == ["y", "x", "y", "x"]
    for r in res.segments:
        assert r.error == pytest.approx(0.0025 if r.axis == "y" else 0.0, abs=1e-15)
    ys = sorted(r.mean_target for r in res.segments if r.axis == "y")
    np.testing.assert_allclose(ys, [0.7496, 0.9476], atol=1e-15)


def test_segment_table_is_the_papers_percentage():
    """Table 2 of the seed paper, simulated model at 100 mm/s: mean target 947.613 mm,
    mean simulated 946.016 mm, error 0.168 %; 749.578 -> 750.183 mm, 0.081 %."""
    n = 50
    tgt = np.zeros((2 * n, 2))
    act = np.zeros((2 * n, 2))
    tgt[:n, 0] = np.linspace(0.65, 0.85, n)
    tgt[:n, 1] = 0.947613
    act[:n, 0] = tgt[:n, 0]
    act[:n, 1] = 0.946016
    tgt[n:, 0] = np.linspace(0.85, 0.65, n)
    tgt[n:, 1] = 0.749578
    act[n:, 0] = tgt[n:, 0]
    act[n:, 1] = 0.750183
    ids = np.repeat([0, 1], n)
    rows = C.segment_table(tgt, act, ids, ("x", "y"))
    assert [round(r.error_pct, 3) for r in rows] == [0.169, 0.081]
    assert rows[0].error_pct == pytest.approx(0.1685, abs=5e-5)


def test_detect_segments_square_and_circle(fast):
    ids = C.detect_segments(fast.pose)
    assert sorted(set(ids.tolist())) == [-1, 0, 1, 2, 3]
    for sgm, k in zip(fast.segments, range(4)):
        sel = np.flatnonzero(ids == k)
        # a segment's run: from its start corner (unless the previous side claimed it) to its end corner
        assert sel[0] == (sgm.first if k == 0 else sgm.first + 1) and sel[-1] == sgm.last
    th = np.linspace(0, 2 * np.pi, 500)
    circle = np.stack([np.cos(th), np.sin(th)], axis=1)
    assert np.all(C.detect_segments(circle) == -1)


def test_constant_column_has_no_delay():
    t = np.arange(0, 1, 1e-3)
    res = C.compare(t, {"a": np.ones_like(t), "b": smooth(t)}, t, {"a": np.ones_like(t), "b": smooth(t)})
    assert np.isnan(res.delay["a"])
    js = res.to_json()
    assert js["delay"]["a"] is None and js["delay"]["b"] == pytest.approx(0.0, abs=1e-9)
    assert set(js) >= {"delay", "rms_error", "max_error", "segments"}


def test_bad_inputs():
    t = np.arange(0, 1, 1e-3)
    with pytest.raises(ValueError, match="no value column"):
        C.compare(t, {"a": t}, t, {"b": t})
    with pytest.raises(ValueError, match="overlap"):
        C.compare(t, {"a": t}, t + 5, {"a": t})


# ----------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------


def test_cli_compare_scope_export(tmp_path, fast):
    """A prototype-like log: 't' time column, its own names (--map), 30 ms late, 1 mm low."""
    import json

    t = fast.time
    tgt = tmp_path / "target.csv"
    tgt.write_text("time,x,y\n" + "\n".join(f"{a:.17g},{b:.17g},{c:.17g}" for a, b, c in zip(t, fast.pose[:, 0], fast.pose[:, 1])))
    ta = np.arange(0.0, t[-1], 2e-3)
    xa = np.interp(ta - 0.03, t, fast.pose[:, 0])
    ya = np.interp(ta - 0.03, t, fast.pose[:, 1]) - 0.001
    act = tmp_path / "scope.csv"
    act.write_text("t,PosX,PosY\n" + "\n".join(f"{a:.17g},{b:.17g},{c:.17g}" for a, b, c in zip(ta, xa, ya)))
    res = invoke("compare", tgt, act, "--map", "x=PosX", "--map", "y=PosY", "--json", "--out", tmp_path / "o")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["delay"]["x"] == pytest.approx(0.03, abs=1e-3)
    assert s["delay"]["y"] == pytest.approx(0.03, abs=1e-3)
    assert len(s["segments"]) == 4
    assert (tmp_path / "o" / "comparison.json").exists()
    res = invoke("compare", tgt, act)
    assert res.exit_code == 2 and "--map" in res.output  # no common column
    res = invoke("compare", tgt, tmp_path / "nothere.csv")
    assert res.exit_code == 2 and "Traceback" not in res.output
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n3,4\n")
    res = invoke("compare", tgt, bad)
    assert res.exit_code == 2 and "time" in res.output


# ----------------------------------------------------------------------------
# The searched window (--max-delay)
# ----------------------------------------------------------------------------


def _sines(delay: float, dt: float = 0.01):
    t = np.arange(0, 20, dt)
    return t, np.sin(t), np.sin(t - delay)


@pytest.mark.parametrize("delay", [0.5, -0.5, 0.3, -0.12])
@pytest.mark.parametrize("max_delay", [1e-6, 0.003, 0.1, 0.105, 0.11])
def test_a_delay_beyond_max_delay_is_flagged_not_reported(delay, max_delay):
    """sin(t) against sin(t - delay), |delay| > max_delay: no number (NaN), the column flagged; never a
    delay outside the window searched."""
    t, x, y = _sines(delay)
    assert np.isnan(C.estimate_delay(0.01, x, y, max_delay))
    res = C.compare(t, {"x": x}, t, {"x": y}, max_delay=max_delay)
    assert np.isnan(res.delay["x"]) and res.beyond == ("x",)
    assert res.to_json()["delay"]["x"] is None and res.to_json()["delay_beyond_window"] == ["x"]
    d, beyond = C.search_delay(0.01, x, y, max_delay)  # the window's edge, flagged
    assert beyond and abs(d) <= max_delay


@settings(max_examples=40, deadline=None)
@given(delay=st.floats(-0.6, 0.6), max_delay=st.floats(1e-6, 0.8))
@example(delay=0.5, max_delay=0.6)
@example(delay=0.098, max_delay=0.1)
@example(delay=-0.098, max_delay=0.1)
@example(delay=0.104, max_delay=0.105)
@example(delay=0.0, max_delay=1e-6)
@example(delay=0.002, max_delay=0.003)
def test_the_delay_never_exceeds_max_delay(delay, max_delay):
    """Whatever the window: a delay reported is within it (and right: within 1e-5 s when the true
    delay is inside), else it is flagged (NaN) and the true delay lies at most a sample inside."""
    _, x, y = _sines(delay)
    d = C.estimate_delay(0.01, x, y, max_delay)
    if np.isfinite(d):
        assert abs(d) <= max_delay and abs(d - delay) < (1e-5 if abs(delay) < max_delay else 0.01)
    else:
        assert abs(delay) > max_delay - 0.01


def test_cli_max_delay_flags_a_delay_beyond_it(tmp_path):
    import json

    t, x, y = _sines(0.5)
    for name, v in (("target.csv", x), ("actual.csv", y)):
        (tmp_path / name).write_text("time,x\n" + "\n".join(f"{a:.17g},{b:.17g}" for a, b in zip(t, v)))
    for max_delay, expect in (("0.1", None), ("1e-6", None), ("0.6", 0.5)):
        r = invoke("compare", tmp_path / "target.csv", tmp_path / "actual.csv", "--max-delay", max_delay, "--json")
        assert r.exit_code == 0, r.output
        s = json.loads(r.stdout)
        if expect is None:
            assert s["delay"]["x"] is None and s["delay_beyond_window"] == ["x"]
        else:
            assert s["delay"]["x"] == pytest.approx(expect, abs=1e-5) and s["delay_beyond_window"] == []


LONG = "a" * 5000


@pytest.mark.parametrize("args", [["--columns", LONG], ["--columns", "x," + LONG], ["--map", LONG],
                                  ["--map", LONG + "=x"], ["--map", "x=" + LONG]])
def test_cli_compare_shortens_long_values(tmp_path, args):
    """A 5,000-character column or --map item is quoted shortened, never whole."""
    t, x, y = _sines(0.0)
    for name, v in (("target.csv", x), ("actual.csv", y)):
        (tmp_path / name).write_text("time,x\n" + "\n".join(f"{a:.17g},{b:.17g}" for a, b in zip(t, v)))
    r = invoke("compare", tmp_path / "target.csv", tmp_path / "actual.csv", *args)
    assert r.exit_code == 2 and "Traceback" not in r.output
    assert "a" * 100 not in r.output and len(r.output) < 400, r.output
