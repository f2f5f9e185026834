"""Every file a command will write is checked for a foreign file of its name before any work, and a
refused run leaves the folder as it found it (no record, journal, lock or temporary file).

The names come from the command itself: each command is run once into an empty folder, and every
file it wrote there is then put, as a file of the user's, into a new folder the same command is
run in again.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .helpers import PLANAR2, invoke, light_spec


#: command -> its arguments (the spec first: "light" is :func:`light_spec`)
COMMANDS = {
    "workspace": ["workspace", PLANAR2, "--step", "0.25", "--html"],
    "report": ["report", PLANAR2, "--step", "0.25"],
    "size-motors": ["size-motors", PLANAR2],
    "certify": ["certify", PLANAR2, "--resolution", "0.25"],
    "certify-parquet": ["certify", PLANAR2, "--resolution", "0.25", "--format", "parquet"],
    "sweep": ["sweep", PLANAR2, "--vary", "effector.mass=0.5,1", "--step", "0.25", "--workers", "1"],
    "trajectory": ["trajectory", PLANAR2, "square_fast"],
    # outlets where every trial is feasible (past about 0.35 m the task box is not), and a seed: the
    # first run must succeed to say what it writes (unseeded, both trials fell past 0.35 m in 2 %)
    "optimize": ["optimize", "light", "--vary", "cables.0.outlet.0=-0.5:0.2", "--maximize", "task_min_margin",
                 "--trials", "2", "--workers", "1", "--step", "0.25", "--seed", "0"],
}


def written(tmp_path: Path, command: str) -> list[str]:
    args = [light_spec(tmp_path) if a == "light" else a for a in COMMANDS[command]]
    out = tmp_path / "first"
    r = invoke(*args, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    # (not SQLite's own companions of optimize.db, which the in-process run leaves open)
    return sorted(p.name for p in out.iterdir() if not p.name.startswith(".")
                  and not p.name.endswith(("-shm", "-wal", "-journal")))


@pytest.mark.parametrize("command", [c if c == "certify" else pytest.param(c, marks=pytest.mark.slow)
                                     for c in sorted(COMMANDS)])
def test_every_file_a_command_writes_is_refused_before_any_work(tmp_path, command):
    names = written(tmp_path, command)
    assert names
    args = [light_spec(tmp_path) if a == "light" else a for a in COMMANDS[command]]
    for name in names:
        out = tmp_path / f"foreign-{name}"
        out.mkdir()
        (out / name).write_text("mine\n")
        r = invoke(*args, "--out", out, "--quiet")
        assert r.exit_code == 2 and f"{out / name} exists and was not written by cdpr-design" in r.output, \
            (name, r.output)
        # was (certify, boxes.csv): refused after the paving, its journal, record and locks left behind
        assert sorted(p.name for p in out.iterdir()) == [name], name
        assert (out / name).read_text() == "mine\n"
