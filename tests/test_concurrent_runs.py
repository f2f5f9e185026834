"""Commands sharing an ``--out`` take turns: two runs started together, or a moment apart, both finish
and leave one run's whole set of files.

Each pair is started many times with small offsets between the two (so that one run's commit lands
in every phase of the other: its start, its checks, its work, its own commit), each pair in a folder
of its own under the test's ``tmp_path``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .helpers import PLANAR2, subprocess_env

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX file locks")

MANIFEST = ".cdpr-design-outputs"
#: seconds between the two starts of each pair
OFFSETS = (0.0, 0.0, 0.1, 0.3, 0.6, 1.0)


def start(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "cdpr_design", *map(str, args), "--quiet"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=subprocess_env())


def pair(args: list, out: Path, offset: float) -> list[tuple[int, str]]:
    a = start(*args, "--out", out)
    time.sleep(offset)
    b = start(*args, "--out", out)
    return [(p.wait(timeout=300), p.stderr.read()) for p in (a, b)]


def no_leftovers(out: Path) -> None:
    assert not [p.name for p in out.iterdir() if p.name.endswith(".tmp")
                or p.name in (".cdpr-design-commit", ".cdpr-design-rollback")]


@pytest.mark.slow
def test_two_workspace_runs_on_one_folder_both_finish(tmp_path):
    outputs = {"workspace.csv", "workspace.png", "tension_map.png", "tilt_map.png", "summary.json"}  # and more
    for k, offset in enumerate(OFFSETS):
        out = tmp_path / f"o{k}"
        for rc, err in pair(["workspace", PLANAR2, "--step", "0.02"], out, offset):
            # was: "workspace.png exists and was not written by cdpr-design", 4 of 4 by hand
            assert rc == 0 and "error" not in err, (offset, err)
        written = {p.name for p in out.iterdir() if not p.name.startswith(".")}
        assert outputs <= written and set((out / MANIFEST).read_text().split()) == written
        rows = (out / "workspace.csv").read_text().count("\n") - 1
        assert json.loads((out / "summary.json").read_text())["poses"] == rows
        no_leftovers(out)


@pytest.mark.slow
def test_two_certify_runs_on_one_folder_both_finish(tmp_path):
    outputs = {"boxes.csv", "certify.png", "summary.json", "certify.journal.jsonl"}
    for k, offset in enumerate(OFFSETS):
        out = tmp_path / f"o{k}"
        for rc, err in pair(["certify", PLANAR2, "--resolution", "0.1"], out, offset):
            # was: "certify.journal.jsonl exists and was not written by cdpr-design" (or certify.png)
            assert rc == 0 and "error" not in err, (offset, err)
        assert set((out / MANIFEST).read_text().split()) == outputs
        s = json.loads((out / "summary.json").read_text())
        rows = (out / "boxes.csv").read_text().count("\n") - 1
        assert sum(s["counts"].values()) == rows
        no_leftovers(out)
