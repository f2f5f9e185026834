"""The command line's progress display (cli/common.progress_bar): bars for big work, and a moving
bar with the stage's description once a stage has been silent for a while (a cold numba compile)."""

from __future__ import annotations

import io
import time

import pytest
from rich.console import Console

from cdpr_design.cli import common


@pytest.fixture
def terminal(monkeypatch):
    buf = io.StringIO()
    monkeypatch.setattr(common, "err", Console(file=buf, force_terminal=True, width=100))
    monkeypatch.setattr(common, "SILENT_S", 0.05)
    return buf


def test_a_silent_stage_shows_its_description_after_a_while(terminal):
    with common.progress_bar("loading the kernels", quiet=False, min_total=500_000) as cb:
        assert cb is not None
        time.sleep(0.4)
    assert "loading the kernels" in terminal.getvalue()


def test_a_quick_stage_shows_nothing(terminal, monkeypatch):
    monkeypatch.setattr(common, "SILENT_S", 5.0)
    with common.progress_bar("workspace planar2", quiet=False, min_total=500_000) as cb:
        cb(10, 100)  # under min_total: no bar
    assert "workspace planar2" not in terminal.getvalue()


def test_big_work_gets_a_bar_with_counts(terminal, monkeypatch):
    monkeypatch.setattr(common, "SILENT_S", 5.0)
    with common.progress_bar("workspace big", quiet=False, min_total=10) as cb:
        cb(50, 100)
        time.sleep(0.3)
    out = terminal.getvalue()
    assert "workspace big" in out and "50/100" in out


def test_quiet_and_not_a_terminal_show_nothing(monkeypatch):
    buf = io.StringIO()
    monkeypatch.setattr(common, "SILENT_S", 0.01)
    monkeypatch.setattr(common, "err", Console(file=buf, force_terminal=True))
    with common.progress_bar("x", quiet=True) as cb:
        time.sleep(0.1)
    assert cb is None and buf.getvalue() == ""
    monkeypatch.setattr(common, "err", Console(file=buf, force_terminal=False))
    with common.progress_bar("x", quiet=False) as cb:
        time.sleep(0.1)
    assert cb is None and buf.getvalue() == ""
