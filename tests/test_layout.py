"""Rules of the project that a reader of its code and docs relies on: only the command line reads
the environment, nothing points outside the repository, README gives the layers lint-imports checks.

The import order of the layers is checked by ``lint-imports`` (contracts in
pyproject.toml), which ``.ci/run`` runs.  Module and function sizes are not
tests: a module holds one idea whatever its length.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from .conftest import ROOT

PACKAGE = ROOT / "cdpr_design"
MODULES = sorted(PACKAGE.rglob("*.py"))


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
