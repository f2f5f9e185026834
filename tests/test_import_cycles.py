"""No import cycles between the package's modules.

``lint-imports`` keeps the layers in order, but modules of one layer may still import each
other in a circle; then neither can be read, tested or moved without the other.  This builds
the import graph of ``cdpr_design`` with grimp (import-linter's graph builder), which counts
every import statement, those inside functions (lazy imports) included, and fails listing
every strongly connected component of more than one module.

The cycles in :data:`ALLOWED` are known and owned by work under way; each is named exactly, a
cycle outside them fails, and an allowance whose modules no longer form a cycle fails too (so
the list can only shrink: delete the entry once its cycle is gone).
"""

from __future__ import annotations

from pathlib import Path

import grimp
import pytest

import cdpr_design

#: Cycles still to remove, each with its owner; a cycle must lie within one of these sets.
ALLOWED: dict = {}


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components of more than one node of ``graph`` (node -> the nodes
    it imports): two modules share one when each reaches the other."""
    reach = {}
    for start in graph:
        seen, todo = {start}, [start]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        reach[start] = seen
    found = {frozenset(b for b in reach[a] if a in reach.get(b, ())) for a in graph}
    return sorted((c for c in found if len(c) > 1), key=sorted)


def package_graph(package: str = "cdpr_design") -> dict[str, set[str]]:
    """The import graph of ``package`` (found on ``sys.path``, as Python would import it)."""
    g = grimp.build_graph(package, cache_dir=None)
    return {m: set(g.find_modules_directly_imported_by(m)) for m in g.modules}


@pytest.fixture(scope="module")
def found():
    return cycles(package_graph())


def test_the_cycle_finder_finds_cycles():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e", "d"}, "f": {"g"}, "g": {"f"}}
    assert cycles(graph) == [frozenset("abc"), frozenset("fg")]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_a_cycle_through_a_lazy_import_counts(tmp_path, monkeypatch):
    pkg = tmp_path / "cyclepkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from cyclepkg import b\n")
    (pkg / "b.py").write_text("def f():\n    from cyclepkg.a import g\n    return g\n")
    (pkg / "c.py").write_text("import cyclepkg.b\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert cycles(package_graph("cyclepkg")) == [frozenset({"cyclepkg.a", "cyclepkg.b"})]


def test_the_graph_is_the_package_the_tests_import():
    graph = package_graph()
    assert len(graph) > 60 and all(m.startswith("cdpr_design") for m in graph)
    # grimp finds the package on sys.path as the import above did: this worktree's copy
    assert Path(cdpr_design.__file__).resolve().parents[1] == Path(__file__).resolve().parents[1]


def test_no_module_cycles(found):
    outside = [sorted(c) for c in found if not any(c <= allowed for allowed in ALLOWED)]
    assert not outside, f"import cycles between modules: {outside}"


def test_the_allowances_are_still_needed(found):
    stale = [sorted(a) for a in ALLOWED if not any(c <= a for c in found)]
    assert not stale, f"these modules no longer form a cycle: remove them from ALLOWED: {stale}"
