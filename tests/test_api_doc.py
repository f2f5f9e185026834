"""docs/api.md's worked example runs as written (doctest) from the repository root."""

from __future__ import annotations

import doctest
import os

from .helpers import ROOT


def test_api_doc_example_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    result = doctest.testfile(os.fspath(ROOT / "docs" / "api.md"), module_relative=False,
                              optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    assert result.attempted >= 15
    assert result.failed == 0
