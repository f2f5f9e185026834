"""``certify`` on workers (batch/certify.py) and resumed from its journal: the paving is the same
box for box, in the same order, whatever runs it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cdpr_design as cd
from cdpr_design.batch import certify as batch_certify
from cdpr_design.batch import wait_closed
from cdpr_design.api import certify

ROOT = Path(__file__).resolve().parents[1]
PLANAR2 = "designs/planar2.yaml"


def _cli(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT), CDPR_DESIGN_PICTURE_WORKER="0")
    return subprocess.run([sys.executable, "-m", "cdpr_design", *args], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=600)


def _same_paving(a, b):
    assert a.status.size == b.status.size
    np.testing.assert_array_equal(a.lower, b.lower)
    np.testing.assert_array_equal(a.upper, b.upper)
    np.testing.assert_array_equal(a.status, b.status)
    assert (a.classified, a.truncated) == (b.classified, b.truncated)


def _summary(folder: Path) -> dict:
    s = json.loads((folder / "summary.json").read_text())
    s.pop("timings"), s.pop("elapsed_s")
    return s


@pytest.fixture(scope="module")
def planar2():
    return cd.load(str(ROOT / PLANAR2))


@pytest.mark.slow
def test_process_pool_gives_the_serial_paving(planar2):
    """Two spawned workers, each level cut into several blocks (resolution 3 mm: levels of
    thousands of boxes): the same boxes in the same order as in this process."""
    serial = certify(planar2, resolution=0.003)
    assert serial.status.size > 4 * batch_certify.MIN_BLOCK and set(np.unique(serial.status)) == {-1, 0, 1}
    pooled = certify(planar2, resolution=0.003, classifier=batch_certify.classifier(workers=2))
    wait_closed()
    _same_paving(serial, pooled)
    # the limits stop the parallel paving where they stop the serial one
    _same_paving(certify(planar2, resolution=0.003, max_boxes=3000),
                 certify(planar2, resolution=0.003, max_boxes=3000, classifier=batch_certify.classifier(workers=2)))
    wait_closed()


@pytest.mark.slow
def test_dask_local_cluster_gives_the_serial_paving(planar2):
    pytest.importorskip("distributed")
    serial = certify(planar2, kind="wrench-feasible", resolution=0.005, min_margin=1.0)
    dask = certify(planar2, kind="wrench-feasible", resolution=0.005, min_margin=1.0,
                   classifier=batch_certify.classifier(workers=2, scheduler="local"))
    wait_closed()
    _same_paving(serial, dask)


def test_bad_workers_and_scheduler_are_refused_with_exit_2(tmp_path):
    r = _cli("certify", PLANAR2, "--workers", "0", "--out", str(tmp_path))
    assert r.returncode == 2 and "--workers" in r.stderr and "Traceback" not in r.stderr
    r = _cli("certify", PLANAR2, "--scheduler", "tcp://host:99999", "--out", str(tmp_path))
    assert r.returncode == 2 and "--scheduler" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "boxes.csv").exists()


@pytest.mark.slow
def test_command_with_workers_writes_the_same_files(tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    for folder, w in ((one, "1"), (two, "2")):
        r = _cli("certify", PLANAR2, "--resolution", "0.005", "--workers", w, "--out", str(folder), "--quiet")
        assert r.returncode == 0, r.stderr
    assert (one / "boxes.csv").read_bytes() == (two / "boxes.csv").read_bytes()
    assert _summary(one) == _summary(two)


@pytest.mark.slow
def test_stopped_then_resumed_run_equals_a_straight_run(tmp_path):
    """A run stopped by --max-boxes (deterministically, after some levels were journalled), its
    journal's last line torn as by a kill, then resumed on two workers: the straight run's files."""
    straight, part = tmp_path / "straight", tmp_path / "part"
    r = _cli("certify", PLANAR2, "--resolution", "0.005", "--out", str(straight), "--quiet")
    assert r.returncode == 0, r.stderr
    r = _cli("certify", PLANAR2, "--resolution", "0.005", "--max-boxes", "1500", "--out", str(part), "--json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["truncated"] == "max_boxes"
    journal = part / "certify.journal.jsonl"
    levels = journal.read_text().splitlines()[1:]
    assert len(levels) >= 3
    with journal.open("a") as fh:
        fh.write('{"level": %d, "boxes": 12, "sta' % len(levels))  # torn by a kill: dropped on resume
    r = _cli("certify", PLANAR2, "--resolution", "0.005", "--out", str(part), "--resume", "--workers", "2")
    assert r.returncode == 0, r.stderr
    assert f"resuming: {len(levels)} level(s)" in r.stderr
    assert (straight / "boxes.csv").read_bytes() == (part / "boxes.csv").read_bytes()
    assert _summary(straight) == _summary(part)


@pytest.mark.slow
def test_resume_refuses_another_pavings_journal(tmp_path):
    r = _cli("certify", PLANAR2, "--resolution", "0.02", "--out", str(tmp_path), "--quiet")
    assert r.returncode == 0, r.stderr
    r = _cli("certify", PLANAR2, "--resolution", "0.01", "--out", str(tmp_path), "--resume")
    assert r.returncode == 2 and "another paving" in r.stderr and "Traceback" not in r.stderr
    journal = tmp_path / "certify.journal.jsonl"
    lines = journal.read_text().splitlines()
    lines[2] = lines[2].replace('"boxes": 2', '"boxes": 3')
    journal.write_text("\n".join(lines) + "\n")
    r = _cli("certify", PLANAR2, "--resolution", "0.02", "--out", str(tmp_path), "--resume")
    assert r.returncode == 2 and "line 3 is damaged" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_interrupted_run_on_workers_resumes_to_the_straight_run(tmp_path):
    """Ctrl-C (SIGINT to the process group, workers included) once the first level is journalled:
    exit 130, the journal kept and no boxes written; --resume then gives the straight run's files."""
    import signal
    import time

    straight, part = tmp_path / "straight", tmp_path / "part"
    args = ("certify", PLANAR2, "--resolution", "0.001", "--quiet")
    r = _cli(*args, "--out", str(straight))
    assert r.returncode == 0, r.stderr
    env = dict(os.environ, PYTHONPATH=str(ROOT), CDPR_DESIGN_PICTURE_WORKER="0")
    proc = subprocess.Popen([sys.executable, "-m", "cdpr_design", *args, "--workers", "2", "--out", str(part)],
                            cwd=ROOT, env=env, stderr=subprocess.PIPE, text=True, start_new_session=True)
    journal = part / "certify.journal.jsonl"
    try:
        deadline = time.monotonic() + 300
        while not (journal.exists() and len(journal.read_text().splitlines()) >= 2):
            assert proc.poll() is None, "the run finished before the first level was journalled"
            assert time.monotonic() < deadline
            time.sleep(0.005)
        assert proc.poll() is None, "the run finished before it could be interrupted"
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130 and "interrupted" in err and "Traceback" not in err, err
    assert not (part / "boxes.csv").exists()
    levels = len(journal.read_text().splitlines()) - 1
    r = _cli(*args, "--out", str(part), "--resume")
    assert r.returncode == 0, r.stderr
    assert (straight / "boxes.csv").read_bytes() == (part / "boxes.csv").read_bytes()
    assert _summary(straight) == _summary(part)
    assert levels >= 1
