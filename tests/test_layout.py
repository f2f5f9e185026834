"""The package's shape: module and function sizes, where the environment is read, no references outside it.

The import order of the layers is checked by ``lint-imports`` (contracts in
pyproject.toml), which ``.ci/run`` runs.
"""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

import pytest

from .conftest import ROOT

PACKAGE = ROOT / "cdpr_design"
MODULES = sorted(PACKAGE.rglob("*.py"))
MAX_MODULE_LINES = 700
MAX_FUNCTION_LINES = 100


def _functions(path):
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            jit = any("jit" in ast.unparse(d) for d in node.decorator_list)
            yield node, node.end_lineno - node.lineno + 1, jit


def test_the_package_has_its_layers():
    assert len(MODULES) > 60
    for layer in ("cli", "jobs", "plots", "batch", "plc", "motion", "design", "workspaces", "statics", "model",
                  "kernels", "io"):
        assert (PACKAGE / layer / "__init__.py").is_file(), layer


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_and_function_sizes(path):
    lines = len(path.read_text().splitlines())
    assert lines <= MAX_MODULE_LINES, f"{path.name}: {lines} lines"
    long = [(f.name, n) for f, n, jit in _functions(path) if n > MAX_FUNCTION_LINES and not jit]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


def test_only_the_command_line_reads_the_environment():
    readers = []
    for path in MODULES:
        rel = path.relative_to(PACKAGE)
        if rel.parts[0] == "cli":
            continue
        text = path.read_text()
        if re.search(r"os\.environ|os\.getenv|getenv\(", text):
            readers.append(str(rel))
    # dask's nanny writes its pre-spawn variables into this process; batch/dask.py puts them back
    assert readers == ["batch/dask.py"], readers


def test_nothing_in_the_product_points_outside_the_repository():
    pattern = re.compile(r"\.\./shared|shared/(design|reference|seed)|reference/robots\.md")
    hits = []
    for path in [*MODULES, *(ROOT / "designs").glob("*.yaml"), *(PACKAGE / "data").glob("*"), ROOT / "README.md",
                 *(ROOT / "docs").glob("*.md"), *(ROOT / "tests").glob("*.py"), *(ROOT / "scripts").glob("*.py"),
                 ROOT / ".ci" / "run", ROOT / "pyproject.toml"]:
        if path == Path(__file__):  # the pattern itself
            continue
        if pattern.search(path.read_text()):
            hits.append(str(path.relative_to(ROOT)))
    assert not hits, hits


def test_the_readme_gives_the_layers_of_the_import_contract():
    """README's Development section lists the layers in the order lint-imports checks."""
    contract = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"][0]
    assert contract["type"] == "layers"
    want = [" | ".join(name.removeprefix("cdpr_design.") for name in layer.split(" | "))
            for layer in contract["layers"]]
    text = " ".join((ROOT / "README.md").read_text().split())
    chain = re.search(r"\(((?:`[a-z_]+`(?: \| `[a-z_]+`)* → )+`[a-z_]+`(?: \| `[a-z_]+`)*)\); the order", text)
    assert chain, "the layer chain in README.md"
    assert [part.replace("`", "") for part in chain.group(1).split(" → ")] == want
