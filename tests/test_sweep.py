"""Batch parameter sweeps: definitions, validation, backends, resume, pictures, CI checks."""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

from cdpr_design.model import spec
from cdpr_design import batch as sw
from cdpr_design.batch import dask as bdask
from cdpr_design.errors import InputError, SpecError

from .helpers import PLANAR2, ROOT, invoke, planar2_raw, read_csv, subprocess_env, write_spec

STEP = "0.05"  # coarse grids keep the sweeps fast; report runs use the same step


# ----------------------------------------------------------------------------
# Definitions
# ----------------------------------------------------------------------------


def test_values_lists_and_linspace():
    assert sw.parse_values("0.5,1,2") == (0.5, 1, 2)
    assert sw.parse_values("AM8112-0F21-EL7211, AM8122") == ("AM8112-0F21-EL7211", "AM8122")
    # start:stop:count is an inclusive linspace, tidied to 12 significant digits
    assert sw.parse_values("0:1:11") == tuple(k / 10 for k in range(11))
    assert sw.parse_values("2:1:3") == (2.0, 1.5, 1.0)
    assert sw.parse_values("1.5:9:1") == (1.5,)
    for bad in ("", "1,,2", "0:1", "0:1:0", "0:1:2.5", "a:b:3", "0:inf:3", "1,nan"):
        with pytest.raises(ValueError):
            sw.parse_values(bad)


def test_vary_option_syntax():
    assert sw.parse_vary("effector.mass=1:2:3") == ("effector.mass", (1.0, 1.5, 2.0))
    for bad in ("effector.mass", "=1,2", "effector.mass=", "effector.mass=1:2"):
        with pytest.raises(InputError, match="--vary"):
            sw.parse_vary(bad)


def test_key_paths(planar2):
    raw = planar2.raw
    assert sw.parse_path("cables[1].outlet[0]") == ("cables", 1, "outlet", 0)
    assert sw.resolve(raw, sw.parse_path("cables.c2.outlet.0")) == ("cables", 1, "outlet", 0)
    assert sw.resolve(raw, sw.parse_path("cables.-1.outlet.0")) == ("cables", 1, "outlet", 0)
    # an optional key the base spec leaves out may be varied (validation decides)
    assert sw.resolve(raw, ("requirements", "min_fraction")) == ("requirements", "min_fraction")
    for bad in ("cables.2.outlet", "cables.c9.outlet", "frame.upper.0.1", "frame..upper",
                "effector.inertia.0"):
        with pytest.raises(ValueError):
            sw.resolve(raw, sw.parse_path(bad))


def test_with_value_copies_only_the_path(planar2):
    raw = planar2.raw
    new = sw.with_value(raw, ("cables", 1, "outlet", 0), 1.2)
    assert new["cables"][1]["outlet"] == [1.2, 1.5]
    assert raw["cables"][1]["outlet"] == [1.5, 1.5]  # the base is untouched
    assert new["cables"][0] is raw["cables"][0]  # the rest is shared
    assert new["frame"] is raw["frame"]


def test_grid_order_and_description(planar2):
    plan = sw.make_plan(planar2, [("effector.mass", (0.5, 1.0)), ("tension.1", (15, 20, 25))])
    assert len(plan) == 6
    got = list(plan.variants())
    assert [v for _, v in got] == [(0.5, 15), (0.5, 20), (0.5, 25), (1.0, 15), (1.0, 20), (1.0, 25)]
    assert all(plan.values(i) == v for i, v in got)
    assert list(plan.variants(skip={0, 4})) == [got[i] for i in (1, 2, 3, 5)]
    assert plan.describe(4) == "variant 4 (effector.mass=1, tension.1=20)"
    d = spec.from_dict(plan.data(plan.values(5)))
    assert d.effector.mass == 1.0 and all(c.tension_max == 25 for c in d.cables)


def test_bad_values_name_the_variant(planar2):
    with pytest.raises(SpecError) as e:
        sw.make_plan(planar2, [("tension.1", (20, 30)), ("effector.mass", (-1.0, 1.0, -2.0))])
    text = str(e.value)
    assert "variant 0 (tension.1=20, effector.mass=-1): effector.mass:" in text
    assert "variant 2 (tension.1=20, effector.mass=-2): effector.mass:" in text
    # the same problem again is counted, not repeated
    assert "variant 3 " not in text and "4 of 6 variants are rejected" in text
    # a joint problem: the frame's upper corner below its lower corner
    with pytest.raises(SpecError, match=r"variant 0 \(frame\.upper\.0=-1\): frame\.upper\[0\]"):
        sw.make_plan(planar2, [("frame.upper.0", (-1.0, 2.0))])
    # an unknown key is named once, not once per variant
    with pytest.raises(SpecError) as e:
        sw.make_plan(planar2, [("effector.masss", (1, 2, 3))])
    assert str(e.value).count("unknown key") == 1 and "3 of 3 variants" in str(e.value)
    with pytest.raises(SpecError, match="the same key"):
        sw.make_plan(planar2, [("cables.1.outlet.0", (1,)), ("cables.c2.outlet.0", (2,))])


def test_cli_bad_keys_exit_2(tmp_path):
    cases = [
        (["--vary", "effector.masss=1,2"], "unknown key"),
        (["--vary", "cables.7.outlet.0=1"], "out of range"),
        (["--vary", "effector.mass=-1,1"], "variant 0 (effector.mass=-1)"),
        (["--vary", "effector.mass=1:2"], "start:stop:count"),
        (["--vary", "tension.1=10,x"], "variant 1 (tension.1=x)"),
        (["--vary", "effector.mass=1", "--rank-by", "nonsense"], "--rank-by"),
        (["--vary", "effector.mass=1", "--workers", "0"], "--workers"),
        (["--vary", "effector.mass=1", "--check-against", tmp_path / "missing.csv"], "cannot read"),
        ([], "nothing to vary"),
    ]
    for extra, needle in cases:
        r = invoke("sweep", PLANAR2, "--out", tmp_path / "o", "--quiet", *extra)
        assert r.exit_code == 2, (extra, r.output)
        assert needle in r.output, (extra, r.output)
        assert "Traceback" not in r.output
    assert not (tmp_path / "o" / "sweep.csv").exists()


@pytest.mark.slow
def test_spec_sweep_section(tmp_path, planar2_data):
    data = dict(planar2_data)
    data["sweep"] = {"vary": {"effector.mass": [0.5, 1.5], "tension.1": "15:25:2"},
                     "rank_by": "peak_tension", "workers": 1}
    p = write_spec(tmp_path, data)
    r = invoke("sweep", p, "--step", STEP, "--out", tmp_path / "o", "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["keys"] == ["effector.mass", "tension.1"] and s["variants"] == 4
    assert s["rank_by"] == "peak_tension" and s["backend"] == "serial"
    header, rows = read_csv(tmp_path / "o" / "sweep.csv")
    assert header[:3] == ["variant", "effector.mass", "tension.1"] and header[-1] == "error"
    assert [r[:3] for r in rows] == [["0", "0.5", "15"], ["1", "0.5", "25"], ["2", "1.5", "15"], ["3", "1.5", "25"]]
    # best variants: passing ones, peak tension ascending (less is better)
    peaks = [b["peak_tension"] for b in s["best"]]
    assert peaks == sorted(peaks) and all(b["checks_passed"] for b in s["best"])
    # --vary on the command line replaces the spec's sweep.vary
    r = invoke("sweep", p, "--step", STEP, "--out", tmp_path / "o2", "--json", "--vary", "tension.1=18")
    assert json.loads(r.stdout)["keys"] == ["tension.1"]
    # a bad sweep section is refused by the spec format
    for bad, where in (({"vary": {"effector.mass": {}}}, "sweep.vary.effector.mass"),
                       ({"vary": {"effector.mass": [1]}, "workers": 0}, "sweep.workers"),
                       ({"vary": [1]}, "sweep.vary"), ({"speed": 1}, "sweep.speed")):
        data["sweep"] = bad
        r = invoke("sweep", write_spec(tmp_path, data, "bad.yaml"), "--out", tmp_path / "o3")
        assert r.exit_code == 2 and where in r.output, (bad, r.output)


# ----------------------------------------------------------------------------
# Each variant is a report run
# ----------------------------------------------------------------------------


@pytest.mark.slow
def test_rows_equal_individual_report_runs(tmp_path, planar2):
    """sweep.csv rows equal design_report.csv of ``report`` on each variant's own spec file."""
    out = tmp_path / "sweep"
    r = invoke("sweep", PLANAR2, "--vary", "effector.mass=0.6,1.4", "--vary", "cables.c2.outlet.0=1.3,1.5",
               "--step", STEP, "--workers", "1", "--out", out, "--quiet", "--no-picture")
    assert r.exit_code == 0, r.output
    header, rows = read_csv(out / "sweep.csv")
    assert len(rows) == 4
    plan = sw.make_plan(planar2, [("effector.mass", (0.6, 1.4)), ("cables.c2.outlet.0", (1.3, 1.5))])
    for i in (0, 3):
        variant_spec = write_spec(tmp_path, plan.data(plan.values(i)), f"variant{i}.yaml")
        rr = invoke("report", variant_spec, "--step", STEP, "--out", tmp_path / f"report{i}", "--quiet")
        assert rr.exit_code == 0, rr.output
        rh, rrows = read_csv(tmp_path / f"report{i}" / "design_report.csv")
        row = dict(zip(header, rows[i]))
        assert row["error"] == ""
        assert [row[k] for k in rh] == rrows[0], f"variant {i}"
    # the varied values are in the row and did change the figures
    assert rows[0][1:3] == ["0.6", "1.3"] and rows[3][1:3] == ["1.4", "1.5"]
    assert rows[0][header.index("peak_tension")] != rows[3][header.index("peak_tension")]


def test_failing_variant_is_recorded_and_the_sweep_goes_on(tmp_path):
    r = invoke("sweep", PLANAR2, "--vary", "winch.motor=AM8112-0F21-EL7211,NO-SUCH-MOTOR",
               "--vary", "workspace.grid.step=0.05,0.00001", "--workers", "1",
               "--out", tmp_path, "--json", "--no-picture")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["evaluated"] == 4 and s["errors"] == 3
    header, rows = read_csv(tmp_path / "sweep.csv")
    err = header.index("error")
    assert rows[0][err] == "" and rows[0][header.index("fraction")] != ""
    assert "NO-SUCH-MOTOR" in rows[2][err]
    assert "--force" in rows[1][err] and "--force" in rows[3][err]  # grid too large
    assert rows[1][header.index("fraction")] == ""


# ----------------------------------------------------------------------------
# Backends give the same rows
# ----------------------------------------------------------------------------


def _records(plan, options, **kw):
    got = []
    sw.run(plan, options, on_record=got.append, **kw)
    return sorted(got, key=lambda r: r["variant"])


@pytest.fixture(scope="module")
def small_plan(planar2):
    return sw.make_plan(planar2, [("effector.mass", (0.5, 1.0, 1.5, 2.0)), ("tension.1", (15, 25))])


@pytest.fixture(scope="module")
def serial_records(small_plan):
    return _records(small_plan, sw.Options(step=0.05), workers=1)


@pytest.mark.slow
def test_process_pool_equals_serial(small_plan, serial_records):
    """Spawned workers after this process ran numba's parallel kernels: same rows (fork would not be safe)."""
    seen = []
    stats = sw.run(small_plan, sw.Options(step=0.05), workers=2, chunk=3,
                   on_record=seen.append, progress=lambda d, t: None)
    assert stats.backend.startswith("processes") and stats.workers == 2 and stats.evaluated == 8
    assert sorted(seen, key=lambda r: r["variant"]) == serial_records
    assert all(not r["error"] for r in serial_records)


@pytest.mark.slow
def test_dask_local_cluster_equals_process_pool(small_plan, serial_records):
    pytest.importorskip("distributed")
    stats = sw.run(small_plan, sw.Options(step=0.05), workers=2, scheduler="local",
                   on_record=(got := []).append)
    assert stats.backend == "dask LocalCluster" and stats.chunk >= 10
    assert sorted(got, key=lambda r: r["variant"]) == serial_records


def test_dask_bad_address_is_bad_input(small_plan):
    pytest.importorskip("distributed")
    with pytest.raises(InputError, match="--scheduler: cannot connect to tcp://127.0.0.1:1"):
        sw.run(small_plan, sw.Options(step=0.05), scheduler="tcp://127.0.0.1:1", connect_timeout=1.0)


@pytest.mark.slow
def test_forked_workers_after_the_kernels_ran_here(small_plan, serial_records):
    """The kernels' threads (kernels/parallel.py) do not follow a fork: workers forked after a
    parallel sweep in this process evaluate like spawned ones (with numba's OpenMP layer they were
    terminated; workers are spawned by default all the same)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.kernels import parallel

    with parallel.threads_kept():
        parallel.set_threads(2)  # the pool runs here even on a one-core machine
        ws.run(spec.load("designs/ipanema3.yaml"), ws.Analysis(engine="numba"), step=0.3)
    got = []
    sw.run(small_plan, sw.Options(step=0.05, engine="numba"), workers=2, start_method="fork", on_record=got.append)
    assert sorted(got, key=lambda r: r["variant"]) == serial_records


# ----------------------------------------------------------------------------
# Resume
# ----------------------------------------------------------------------------

RESUME_VARY = ["--vary", "effector.mass=0.5:2:6", "--vary", "tension.1=15:30:8"]
N_RESUME = 48


@pytest.mark.slow
def test_resume_after_kill_gives_the_identical_csv(tmp_path):
    full = tmp_path / "full"
    r = invoke("sweep", PLANAR2, *RESUME_VARY, "--workers", "1", "--out", full, "--quiet", "--no-picture")
    assert r.exit_code == 0, r.output

    part = tmp_path / "part"
    journal = part / "sweep.journal.jsonl"
    env = subprocess_env()
    # the step is fine (slow variants) so the kill lands mid-sweep
    cmd = [sys.executable, "-m", "cdpr_design", "sweep", str(PLANAR2), *RESUME_VARY, "--workers", "1",
           "--out", str(part), "--quiet", "--no-picture"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if journal.exists() and journal.read_text().count("\n") >= 4:  # meta + 3 variants
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the sweep finished before it could be killed"
        os.killpg(proc.pid, signal.SIGKILL)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    assert not (part / "sweep.csv").exists()
    lines = journal.read_text().splitlines()
    done = len(lines) - 1
    assert 3 <= done < N_RESUME
    with journal.open("a") as fh:  # a line torn by the kill is dropped on resume
        fh.write('{"variant": 47, "values": [2.0, 30], "figu')

    r = invoke("sweep", PLANAR2, *RESUME_VARY, "--workers", "1", "--out", part, "--json", "--no-picture", "--resume")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["resumed"] == done and s["evaluated"] == N_RESUME - done
    assert (part / "sweep.csv").read_bytes() == (full / "sweep.csv").read_bytes()
    assert (part / "sweep_best.csv").read_bytes() == (full / "sweep_best.csv").read_bytes()

    # resuming a finished sweep evaluates nothing; another sweep's journal is refused
    r = invoke("sweep", PLANAR2, *RESUME_VARY, "--out", part, "--json", "--no-picture", "--resume")
    assert json.loads(r.stdout)["evaluated"] == 0
    assert (part / "sweep.csv").read_bytes() == (full / "sweep.csv").read_bytes()
    r = invoke("sweep", PLANAR2, "--vary", "effector.mass=1,2", "--out", part, "--resume", "--quiet")
    assert r.exit_code == 2 and "another sweep" in r.output


@pytest.mark.slow
def test_resume_with_a_pool_in_another_order(tmp_path, small_plan, serial_records):
    """Journal rows arrive in completion order; the final table is sorted and identical."""
    from cdpr_design.io.files import OutputDir
    from cdpr_design.io.journal import SweepJournal

    header, rows = sw.table(small_plan, serial_records)
    shuffled = [serial_records[i] for i in (5, 1, 7, 0, 3, 6, 2, 4)]
    assert sw.table(small_plan, shuffled) == (header, rows)
    out = OutputDir(tmp_path)
    j = SweepJournal(out)
    j.start({"journal": "cdpr-design sweep", "fingerprint": "x"}, shuffled[:3])
    for rec in shuffled[3:5]:
        j.append(rec)
    j.close()
    meta, recs = j.read()
    assert meta["fingerprint"] == "x" and recs == shuffled[:5]
    done = {r["variant"] for r in recs}
    rest = _records(small_plan, sw.Options(step=0.05), workers=1, skip=done)
    assert sorted(r["variant"] for r in rest) == sorted(set(range(8)) - done)
    assert sw.table(small_plan, recs + rest) == (header, rows)


# ----------------------------------------------------------------------------
# Best variants, pictures, CI regression checks
# ----------------------------------------------------------------------------


def test_best_ranking(small_plan, serial_records):
    header, rows = sw.table(small_plan, serial_records)
    name, desc = sw.parse_rank("fraction")
    assert desc
    bh, best = sw.best(header, rows, name, desc)
    ip, fr = header.index("checks_passed"), header.index("fraction")
    passing = [r for r in rows if r[ip]]
    assert 0 < len(best) == len(passing) < len(rows)
    assert [b[0] for b in best] == list(range(1, len(best) + 1))
    fracs = [b[1 + fr] for b in best]
    assert fracs == sorted(fracs, reverse=True)
    assert sw.parse_rank("peak_tension") == ("peak_tension", False)
    assert sw.parse_rank("peak_tension:desc") == ("peak_tension", True)
    assert sw.parse_rank("peak_tension_c1") == ("peak_tension_c1", False)


@pytest.mark.parametrize("vary", [
    ["effector.mass=0.5:2:4"],
    ["effector.mass=0.5:2:3", "tension.1=15,25"],
    ["effector.mass=0.5,2", "tension.1=15,25", "winch.drum_radius=0.03,0.036"],
])
def test_pictures(tmp_path, vary):
    args = [a for v in vary for a in ("--vary", v)]
    r = invoke("sweep", PLANAR2, *args, "--step", "0.1", "--workers", "1", "--out", tmp_path, "--quiet")
    assert r.exit_code == 0, r.output
    png = (tmp_path / "sweep.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    bh, brows = read_csv(tmp_path / "sweep_best.csv")
    assert bh[0] == "rank" and bh[1] == "variant"


def test_check_against_baseline(tmp_path):
    args = ["sweep", PLANAR2, "--vary", "effector.mass=0.8,1.2", "--step", "0.1", "--workers", "1",
            "--no-picture", "--quiet"]
    r = invoke(*args, "--out", tmp_path / "a")
    assert r.exit_code == 0, r.output
    base = tmp_path / "baseline.csv"
    shutil.copy(tmp_path / "a" / "sweep.csv", base)
    r = invoke(*args, "--out", tmp_path / "b", "--check-against", base, "--tolerance", "1e-9")
    assert r.exit_code == 0, r.output

    header, rows = read_csv(base)

    def write_baseline(col, value, row=1):
        rows2 = [list(x) for x in rows]
        rows2[row][header.index(col)] = value
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows([header] + rows2)
        p = tmp_path / f"edited_{col}.csv"
        p.write_text(buf.getvalue())
        return p

    frac = float(rows[1][header.index("fraction")])
    # the baseline was better: this run regressed -> exit 1, naming variant and figure
    r = invoke(*args, "--out", tmp_path / "c", "--json", "--check-against",
               write_baseline("fraction", repr(frac * 1.01)), "--tolerance", "1e-3")
    assert r.exit_code == 1, r.output
    reg = json.loads(r.stdout)["regressions"]
    assert reg == [{"variant": 1, "column": "fraction", "baseline": repr(frac * 1.01),
                    "current": rows[1][header.index("fraction")], "change": "worse"}]
    # within the tolerance: passes
    r = invoke(*args, "--out", tmp_path / "c", "--check-against",
               write_baseline("fraction", repr(frac * 1.0001)), "--tolerance", "1e-3")
    assert r.exit_code == 0, r.output
    # the baseline was worse: an improvement passes, unless --strict
    r = invoke(*args, "--out", tmp_path / "c", "--json", "--check-against",
               write_baseline("fraction", repr(frac * 0.9)))
    assert r.exit_code == 0 and json.loads(r.stdout)["improvements"][0]["change"] == "better"
    r = invoke(*args, "--out", tmp_path / "c", "--strict", "--check-against",
               write_baseline("fraction", repr(frac * 0.9)))
    assert r.exit_code == 1
    # lower is better for tensions: a lower baseline tension is a regression
    pt = float(rows[0][header.index("peak_tension")])
    r = invoke(*args, "--out", tmp_path / "c", "--json", "--check-against",
               write_baseline("peak_tension", repr(pt * 0.9), row=0))
    assert r.exit_code == 1 and json.loads(r.stdout)["regressions"][0]["change"] == "worse"
    # a figure without a direction (the chosen motor) must not change
    r = invoke(*args, "--out", tmp_path / "c", "--check-against", write_baseline("motor", "OTHER"))
    assert r.exit_code == 1
    # a baseline from another sweep is bad input
    r = invoke(*args, "--out", tmp_path / "c", "--check-against", write_baseline("effector.mass", "5"))
    assert r.exit_code == 2 and "another sweep" in r.output
    r = invoke("sweep", PLANAR2, "--vary", "tension.1=20", "--step", "0.1", "--workers", "1", "--quiet",
               "--no-picture", "--out", tmp_path / "d", "--check-against", base)
    assert r.exit_code == 2 and "another sweep" in r.output


CI_SWEEP = ("sweep designs/planar2.yaml --vary effector.mass=0.5:2:4 --vary tension.1=15,20,25 "
            "--step 0.05 --check-against tests/data/planar2_sweep_baseline.csv --tolerance 1e-6")


def test_committed_ci_baseline_matches(tmp_path):
    """The regression sweep of .ci/run passes against the committed baseline."""
    ci = ROOT / ".ci" / "run"
    if ci.exists():
        script = " ".join(ci.read_text().replace("\\\n", " ").split())  # continuation lines joined
        assert CI_SWEEP in script, ".ci/run must run the same regression sweep as this test"
    header, rows = read_csv(ROOT / "tests" / "data" / "planar2_sweep_baseline.csv")
    assert len(rows) == 12 and all(r[header.index("error")] == "" for r in rows)
    assert 0 < sum(r[header.index("checks_passed")] == "1" for r in rows) < 12
    args = [str(ROOT / a) if a.startswith(("designs/", "tests/")) else a for a in CI_SWEEP.split()]
    r = invoke(*args, "--out", tmp_path, "--quiet", "--workers", "1", "--no-picture")
    assert r.exit_code == 0, r.output


def _worker_settings():
    import dask

    return (os.environ.get("MALLOC_TRIM_THRESHOLD_"), os.environ.get("NUMBA_NUM_THREADS"),
            dask.config.get("distributed.worker.profile.enabled"),
            dask.config.get("distributed.admin.tick.interval"))


@pytest.mark.slow
def test_local_cluster_workers_keep_glibc_malloc_defaults():
    """dask's nannies would set MALLOC_TRIM_THRESHOLD_ (fresh mmaps for every array above 128 kB,
    1.6-2x slower variants); the sweep's LocalCluster leaves it unset and restores this
    process's environment after the nannies wrote into it."""
    from distributed import Client, LocalCluster

    def environ():  # distributed marks the first process that starts a cluster, once (process titles)
        return {k: v for k, v in os.environ.items() if k != "__DASK_PARENT_PID"}

    before = environ()
    cluster = bdask.start_local_cluster(LocalCluster, 1)
    try:
        assert environ() == before
        with Client(cluster) as client:
            (settings,) = client.run(_worker_settings).values()
    finally:
        cluster.close()
    assert settings == (None, "1", False, "1s")


@pytest.mark.slow
@pytest.mark.parametrize("scheduler", [None, "local"])
def test_workers_exit_after_the_sweep(small_plan, serial_records, scheduler):
    """run() returns once every row is in; the workers exit in the background and
    wait_closed() leaves none behind."""
    import multiprocessing

    recs = []
    sw.run(small_plan, sw.Options(step=0.05), workers=2, scheduler=scheduler, on_record=recs.append)
    assert sorted(r["variant"] for r in recs) == sorted(r["variant"] for r in serial_records)
    sw.wait_closed()
    assert multiprocessing.active_children() == []


@pytest.mark.parametrize("n,size,workers,minimum", [(1000, 32, 2, 2), (1000, 32, 2, 10), (7, 1, 2, 2),
                                                    (5, 200, 8, 10), (0, 4, 2, 1), (333, 21, 3, 1)])
def test_guided_chunks_cover_every_variant_once(n, size, workers, minimum):
    items = list(range(n))
    parts = sw.guided_chunks(items, size, workers, minimum)
    assert [i for p in parts for i in p] == items
    assert all(1 <= len(p) <= size for p in parts)
    sizes = [len(p) for p in parts[:-1]]
    assert sizes == sorted(sizes, reverse=True)  # shrinking towards the end
    assert all(len(p) >= min(minimum, size) for p in parts[:-1])


# ----------------------------------------------------------------------------
# Failed variants, damaged journals and baselines, refused runs
# ----------------------------------------------------------------------------

SMALL = ["sweep", PLANAR2, "--vary", "effector.mass=0.8,1.2", "--step", "0.1", "--workers", "1", "--quiet"]


def _refused(r, *needles):
    """A clean refusal: exit 2, one short message naming each needle, no traceback."""
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and not isinstance(r.exception, (ZeroDivisionError, TypeError,
                                                                        KeyError, AttributeError)), r.output
    for n in needles:
        assert str(n) in r.output, (n, r.output)


@pytest.mark.parametrize("vary", [["winch.motor=NOPE"], ["winch.motor=NOPE,NOPE2", "effector.mass=1,2"],
                                  ["winch.motor=NOPE", "effector.mass=1,2", "tension.1=15,20"]])
def test_every_variant_failed_still_draws_the_picture(tmp_path, vary):
    args = [a for v in vary for a in ("--vary", v)]
    r = invoke("sweep", PLANAR2, *args, "--step", "0.5", "--workers", "1", "--out", tmp_path, "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["errors"] == s["variants"] and s["passed"] == 0
    header, rows = read_csv(tmp_path / "sweep.csv")
    assert all("NOPE" in row[header.index("error")] for row in rows)
    assert (tmp_path / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_unknown_motor_option_is_refused_before_any_work(tmp_path):
    r = invoke("sweep", PLANAR2, "--vary", "effector.mass=1", "--motor", "NOPE", "--step", "0.5",
               "--workers", "1", "--out", tmp_path / "o")
    _refused(r, "--motor", "NOPE", "not in the motor catalogue")
    assert not (tmp_path / "o").exists()
    long_name = "M" * 5000
    r = invoke("sweep", PLANAR2, "--vary", "effector.mass=1", "--motor", long_name, "--out", tmp_path / "o")
    _refused(r, "--motor")
    assert len(r.output) < 600 and not (tmp_path / "o").exists()


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    """A finished two-variant sweep's folder (sweep.csv and its journal)."""
    out = tmp_path_factory.mktemp("finished")
    r = invoke(*SMALL, "--no-picture", "--out", out)
    assert r.exit_code == 0, r.output
    return out


@pytest.mark.parametrize("damage", [
    lambda lines: lines + ['{"variant": "x", "values": [1.2], "figures": {}, "error": ""}'],
    lambda lines: lines + ['{"variant": 1.5, "values": [1.2], "figures": {}, "error": ""}'],
    lambda lines: lines + ['{"variant": true, "values": [1.2], "figures": {}, "error": ""}'],
    lambda lines: lines + ['{"variant": 7, "values": [1.2], "figures": {}, "error": ""}'],
    lambda lines: lines[:2] + [lines[2].replace('"values": [1.2]', '"values": [3.5]')] + lines[3:],
    lambda lines: lines[:2] + [lines[2].replace('"values": [1.2]', '"values": 1.2')] + lines[3:],
    lambda lines: [lines[0], json.dumps({**json.loads(lines[1]), "figures": 5})] + lines[2:],
    lambda lines: [lines[0], json.dumps({**json.loads(lines[1]), "figures": {"fraction": [1, 2]}})] + lines[2:],
    lambda lines: [lines[0], json.dumps({**json.loads(lines[1]), "error": 3})] + lines[2:],
    lambda lines: [lines[0], json.dumps({k: v for k, v in json.loads(lines[1]).items() if k != "figures"})]
    + lines[2:],
])
def test_resume_refuses_a_damaged_journal(tmp_path, finished_sweep, damage):
    out = tmp_path / "o"
    shutil.copytree(finished_sweep, out)
    journal = out / "sweep.journal.jsonl"
    lines = damage(journal.read_text().splitlines())
    bad_line = next(k + 1 for k, line in enumerate(lines) if line not in journal.read_text().splitlines())
    journal.write_text("\n".join(lines) + "\n")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    r = invoke(*SMALL, "--no-picture", "--out", out, "--resume")
    _refused(r, "--resume", "sweep.journal.jsonl", f"line {bad_line}")
    assert len(r.output) < 600
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing rewritten


def _baseline(tmp_path, base, edit, name="edited.csv"):
    header, rows = read_csv(base)
    header, rows = edit(header, [list(r) for r in rows])
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows([header] + rows)
    p = tmp_path / name
    p.write_text(buf.getvalue())
    return p


def _set(col, value, row=1):
    def edit(header, rows):
        rows[row][header.index(col)] = value
        return header, rows
    return edit


@pytest.mark.parametrize("edit,needles", [
    (lambda h, rows: (["index"] + h[1:], rows), ["'variant' column"]),
    (lambda h, rows: (h, []), ["no variant rows"]),
    (_set("fraction", "abc"), ["row 2", "variant 1", "fraction", "'abc'"]),
    (_set("fraction", "nan"), ["row 2", "variant 1", "fraction", "'nan'"]),
    (_set("peak_tension", "inf", row=0), ["row 1", "variant 0", "peak_tension", "'inf'"]),
    (_set("poses", "-inf", row=0), ["row 1", "variant 0", "poses", "'-inf'"]),
    (lambda h, rows: (h, [rows[0], list(rows[0])]), ["variant 0", "rows 1 and 2"]),  # and variant 1 missing
    (_set("variant", "x"), ["row 2", "'x'"]),
    (_set("variant", "9"), ["row 2", "variant 9", "another sweep"]),
    (_set("effector.mass", "5"), ["row 2", "variant 1", "effector.mass", "another sweep"]),
    (lambda h, rows: (h, rows[:1]), ["no row for variant 1"]),
    (lambda h, rows: (h, [rows[0], rows[1][:-1]]), ["row 2", "cells"]),
    (lambda h, rows: (h + ["fraction"], [r + [r[h.index("fraction")]] for r in rows]), ["'fraction'", "twice"]),
])
def test_broken_baseline_is_refused_before_any_work(tmp_path, finished_sweep, edit, needles):
    base = _baseline(tmp_path, finished_sweep / "sweep.csv", edit)
    r = invoke(*SMALL, "--out", tmp_path / "o", "--check-against", base)
    _refused(r, "--check-against", base, *needles)
    assert not (tmp_path / "o").exists()


def test_legitimate_baselines_still_pass(tmp_path, finished_sweep):
    """Empty cells where the sweep leaves the figure empty too are no damage."""
    header, rows = read_csv(finished_sweep / "sweep.csv")
    empty = [c for c in header if all(r[header.index(c)] == "" for r in rows)]
    assert "error" in empty and len(empty) > 1  # the sweep itself leaves figures empty
    r = invoke(*SMALL, "--no-picture", "--out", tmp_path / "o", "--check-against", finished_sweep / "sweep.csv",
               "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["regressions"] == [] == json.loads(r.stdout)["improvements"]


def _interrupted(tmp_path, finished_sweep):
    """A folder holding an interrupted sweep: its journal with one of two variants done."""
    out = tmp_path / "o"
    shutil.copytree(finished_sweep, out)
    journal = out / "sweep.journal.jsonl"
    journal.write_text("\n".join(journal.read_text().splitlines()[:2]) + "\n")
    (out / "sweep.csv").unlink()
    return out, journal.read_bytes()


@pytest.mark.parametrize("bad", [
    ["--scheduler", "garbage"], ["--scheduler", "tcp://"], ["--scheduler", "tcp://host:port"],
    ["--scheduler", "nonsense://host:8786"], ["--scheduler", "tcp://:8786"], ["--scheduler", "tcp://host:99999"],
    ["--rank-by", "nonsense"], ["--check-against", "missing.csv"], ["--motor", "NOPE"],
])
def test_refused_run_leaves_the_folder_as_it_was(tmp_path, finished_sweep, bad):
    out, journal = _interrupted(tmp_path, finished_sweep)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    r = invoke(*SMALL, "--no-picture", "--out", out, *bad)
    _refused(r, bad[0])
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # the journal is not truncated
    r = invoke(*SMALL, "--no-picture", "--out", tmp_path / "fresh", *bad)
    _refused(r, bad[0])
    assert not (tmp_path / "fresh").exists()


def test_backend_refusing_to_start_keeps_the_journal(tmp_path, finished_sweep, monkeypatch):
    """A run refused while its backend starts (an unreachable scheduler) has not touched the journal."""
    out, journal = _interrupted(tmp_path, finished_sweep)

    def unreachable(*args, **kwargs):
        raise InputError("--scheduler: cannot connect to tcp://127.0.0.1:1: timed out")

    monkeypatch.setattr(sw, "run", unreachable)
    for resume in ([], ["--resume"]):
        r = invoke(*SMALL, "--no-picture", "--out", out, *resume)
        _refused(r, "cannot connect")
        assert (out / "sweep.journal.jsonl").read_bytes() == journal
    r = invoke(*SMALL, "--no-picture", "--out", tmp_path / "fresh")
    _refused(r, "cannot connect")
    assert not (tmp_path / "fresh").exists()


def test_long_values_are_shortened_in_messages(tmp_path):
    long = "x" * 5000
    for extra, needle in (
            (["--vary", f"effector.mass={long}"], "variant 0 (effector.mass=xxx"),
            (["--vary", f"{long}=1"], "unknown key"),
            (["--vary", f"effector.mass=1,{long},{long}2"], "variant 1 (effector.mass=xxx"),
            (["--vary", f"cables.{long}.outlet.0=1"], "--vary cables.xxx"),
            (["--vary", f"effector.mass.{long}=1"], "--vary effector.mass.xxx"),
            (["--vary", f"effector.mass={'1' * 5000}"], "--vary effector.mass"),
            (["--vary", f"effector.mass=1:2:{'1' * 5000}"], "--vary effector.mass"),
            (["--vary", f"{long}=1", "--vary", f"{long}=2"], "the same key"),
            (["--vary", f"effector.{long}=1", "--vary", "effector.mass=1"], "unknown key"),
            (["--vary", "effector.mass=1", "--rank-by", long], "--rank-by"),
            (["--vary", "effector.mass=1", "--rank-by", f"fraction:{long}"], "--rank-by")):
        r = invoke("sweep", PLANAR2, *extra, "--out", tmp_path / "o", "--quiet")
        _refused(r, needle)
        assert len(r.output) < 600, (extra[-1][:40], len(r.output), r.output[:300])
    assert not (tmp_path / "o").exists()
