"""The command line on tmp_path: files, columns, JSON keys, exit codes (cli.md)."""

from __future__ import annotations

import ast
import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from .helpers import PLANAR2, invoke

SUMMARY_KEYS = {"name", "kind", "poses", "feasible", "fraction", "measure", "min_margin",
                "max_margin", "max_tension", "elapsed_s"}


@pytest.fixture(scope="module")
def ws_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ws")
    res = invoke("workspace", PLANAR2, "--out", out, "--json", "--step", "0.02")
    return out, res


def test_workspace_files_and_json(ws_run):
    out, res = ws_run
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)  # stdout is one JSON object and nothing else
    assert SUMMARY_KEYS <= set(data)
    assert data["name"] == "planar2" and data["kind"] == "static"
    assert data["poses"] == 76 * 76
    for f in ("workspace.csv", "workspace.png", "tension_map.png", "summary.json"):
        assert (out / f).stat().st_size > 0, f
    assert json.loads((out / "summary.json").read_text())["feasible"] == data["feasible"]
    assert (out / "workspace.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.glob("*.tmp")), "no temporary files are left behind"


def test_workspace_csv_columns(ws_run):
    out, _ = ws_run
    with open(out / "workspace.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    assert header[:8] == ["x", "y", "feasible", "margin", "tension_c1", "tension_c2",
                          "length_c1", "length_c2"]
    assert len(body) == 76 * 76
    summary = json.loads((out / "summary.json").read_text())
    assert sum(r[2] == "1" for r in body) == summary["feasible"]
    for r in body:
        assert r[2] in ("0", "1")
        if r[2] == "0":
            assert r[4] == "" and r[5] == ""  # tensions empty where infeasible
        else:
            t = [float(r[4]), float(r[5])]
            assert 0.0 <= min(t) and max(t) <= 20.0 and float(r[3]) >= 0
    # rows agree with `pose` at the same point
    row = next(r for r in body if r[0] == "0.74" and r[1] == "0.8")
    res = invoke("pose", PLANAR2, "--at", "0.74,0.8", "--json")
    p = json.loads(res.stdout)
    assert float(row[4]) == pytest.approx(p["tensions"]["c1"], rel=1e-9)
    assert float(row[6]) == pytest.approx(p["lengths"]["c1"], rel=1e-9)
    assert float(row[3]) == pytest.approx(p["margin"], rel=1e-9)


def test_pose_json_keys():
    res = invoke("pose", PLANAR2, "--at", "0.75,0.75", "--json")
    assert res.exit_code == 0, res.output
    p = json.loads(res.stdout)
    assert set(p) >= {"pose", "lengths", "tensions", "feasible", "margin", "structure_matrix", "collisions"}
    assert p["feasible"] is True
    assert p["tensions"]["c1"] == pytest.approx(p["tensions"]["c2"])
    assert np.array(p["structure_matrix"]).shape == (2, 2)
    # an infeasible pose: tensions null, margin negative
    res = invoke("pose", PLANAR2, "--at", "0.75,1.45", "--json")
    q = json.loads(res.stdout)
    assert q["feasible"] is False and q["tensions"] == {"c1": None, "c2": None} and q["margin"] < 0


@pytest.mark.parametrize("args,message", [
    (["pose", str(PLANAR2), "--at", "0.75"], "--at: expected 2 numbers (x,y) for motion 2T, got 1"),
    (["pose", str(PLANAR2), "--at", "a,b"], "--at: expected comma-separated numbers"),
    (["pose", str(PLANAR2), "--at", "0.75,,0.75"], "--at: expected comma-separated numbers, got an empty field"),
    (["fk", str(PLANAR2), "--lengths", "1,1,"], "--lengths: expected comma-separated numbers, got an empty field"),
    (["pose", str(PLANAR2), "--at", "nan,1"], "--at: expected finite numbers"),
    (["fk", str(PLANAR2), "--lengths", "1,2,3"], "--lengths: expected 2 cable lengths"),
    (["fk", str(PLANAR2), "--lengths", "-1,2"], "--lengths: cable lengths must be non-negative"),
    (["workspace", str(PLANAR2), "--kind", "dynamic"], "dynamic"),
])
def test_bad_options_exit_2(args, message, tmp_path):
    res = invoke(*args, *(["--out", tmp_path] if args[0] == "workspace" else []))
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert "Traceback" not in res.output


def test_fk_round_trip():
    res = invoke("pose", PLANAR2, "--at", "0.4,0.9", "--json")
    L = json.loads(res.stdout)["lengths"]
    res = invoke("fk", PLANAR2, "--lengths", f"{L['c1']!r},{L['c2']!r}", "--json")
    assert res.exit_code == 0
    f = json.loads(res.stdout)
    assert set(f) >= {"pose", "residual"}
    np.testing.assert_allclose(f["pose"], [0.4, 0.9], atol=1e-12)
    assert f["residual"] < 1e-12


def test_foreign_files_are_not_overwritten(tmp_path):
    (tmp_path / "workspace.csv").write_text("my own data\n")
    res = invoke("workspace", PLANAR2, "--out", tmp_path, "--step", "0.1")
    assert res.exit_code == 2
    assert "--overwrite" in res.output
    assert (tmp_path / "workspace.csv").read_text() == "my own data\n"
    res = invoke("workspace", PLANAR2, "--out", tmp_path, "--step", "0.1", "--overwrite")
    assert res.exit_code == 0
    assert (tmp_path / "workspace.csv").read_text().startswith("x,y,feasible")
    # files cdpr-design wrote itself are simply regenerated on the next run
    res = invoke("workspace", PLANAR2, "--out", tmp_path, "--step", "0.05")
    assert res.exit_code == 0


def test_table_output(tmp_path):
    res = invoke("workspace", PLANAR2, "--out", tmp_path, "--step", "0.05")
    assert res.exit_code == 0
    assert "planar2" in res.stdout and "fraction" in res.stdout


def test_python_dash_m(tmp_path):
    res = subprocess.run([sys.executable, "-m", "cdpr_design", "pose", str(PLANAR2), "--at", "0.75,0.75",
                          "--json"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["feasible"] is True
    res = subprocess.run([sys.executable, "-m", "cdpr_design", "pose", str(tmp_path / "missing.yaml"),
                          "--at", "1,1"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "Traceback" not in res.stderr and "no such file" in res.stderr


def test_lazy_api_never_shadows_a_module():
    """``from . import evaluate`` must find the module, not a lazily bound function; and no API
    name may be a sub-package's (importing ``cdpr_design.workspaces`` would rebind it)."""
    from pathlib import Path

    import cdpr_design

    root = Path(cdpr_design.__file__).parent
    modules = {p.stem for p in root.glob("*.py")} | {p.parent.name for p in root.glob("*/__init__.py")}
    assert {"workspaces", "statics", "model"} <= modules and cdpr_design._LAZY  # neither side is empty
    assert not set(cdpr_design._LAZY) & modules
    for name in cdpr_design._LAZY:
        assert getattr(cdpr_design, name) is not None


def test_every_command_is_registered_by_the_module_cli_app_names():
    """``cli.app.COMMANDS`` (which module to import for a command line) is what the modules
    register, in the help's order; a command line naming one command gets that command alone,
    still under the program's group (``cdpr-design workspace ...``), the others everything."""
    import typer.main

    from cdpr_design.cli import app as cli_app

    every = typer.main.get_command(cli_app.make_app())
    assert list(every.commands) == list(cli_app.COMMANDS)
    for name, module in cli_app.COMMANDS.items():
        assert every.commands[name].callback.__module__.startswith(f"cdpr_design.cli.{module}"), name
        one = typer.main.get_command(cli_app.make_app([name, "--help"]))
        assert set(one.commands) == {n for n, m in cli_app.COMMANDS.items() if m == module}
    for argv in ([], ["--help"], ["worksp", "x.yaml"]):
        assert list(typer.main.get_command(cli_app.make_app(argv)).commands) == list(cli_app.COMMANDS)


def test_every_command_answers_help_and_the_program_lists_them(tmp_path):
    """``cdpr-design --help`` lists every command; ``cdpr-design <command> --help`` of a command
    line naming one command shows that command's usage (what each command costs to start is
    reported by scripts/bench.py startup, in CPU time)."""
    res = subprocess.run([sys.executable, "-m", "cdpr_design", "--help"], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert all(f"  {name} " in res.stdout for name in ("workspace", "size-motors", "optimize", "compare"))
    one = subprocess.run([sys.executable, "-m", "cdpr_design", "pose", "--help"], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert "Usage: python -m cdpr_design pose" in one.stdout and "--at" in one.stdout
    out = subprocess.run([sys.executable, "-m", "cdpr_design", "schema"], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert json.loads(out.stdout)


def test_blas_threads_settled_unless_the_user_chose(monkeypatch):
    """A command's OpenBLAS threads sleep at once when idle (``OPENBLAS_THREAD_TIMEOUT``, set
    before numpy loads), unless the user set the variable."""
    from cdpr_design.cli import env

    environ = {}
    env.settle_blas_threads(environ)
    assert environ == {"OPENBLAS_THREAD_TIMEOUT": env.BLAS_THREAD_TIMEOUT}
    environ = {"OPENBLAS_THREAD_TIMEOUT": "20"}
    env.settle_blas_threads(environ)
    assert environ == {"OPENBLAS_THREAD_TIMEOUT": "20"}
    # the entry point sets it before anything imports numpy (OpenBLAS reads it when it loads)
    code = ("import os, sys; from cdpr_design.__main__ import main; sys.argv = ['cdpr-design', 'schema'];\n"
            "seen = []\n"
            "class Spy:\n"
            "    def find_spec(self, name, *a):\n"
            "        if name == 'numpy' and not seen: seen.append(os.environ.get('OPENBLAS_THREAD_TIMEOUT'))\n"
            "sys.meta_path.insert(0, Spy())\n"
            "try: main()\n"
            "except SystemExit: pass\n"
            "print(seen)")
    for given, expected in ((None, env.BLAS_THREAD_TIMEOUT), ("12", "12")):
        monkeypatch.delenv("OPENBLAS_THREAD_TIMEOUT", raising=False)
        if given is not None:
            monkeypatch.setenv("OPENBLAS_THREAD_TIMEOUT", given)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        assert ast.literal_eval(out.stdout.strip().splitlines()[-1]) == [expected]


@pytest.mark.slow
def test_a_command_printing_only_json_never_imports_rich(tmp_path):
    """rich draws what a person reads (tables, messages, progress bars): with ``--json`` nothing
    is drawn and rich is not imported (40 ms of a command's start-up); without it, the table."""
    code = ("import sys; from cdpr_design.__main__ import main; sys.argv = ['cdpr-design'] + sys.argv[1:]\n"
            "try: main()\n"
            "except SystemExit: pass\n"
            "sys.stderr.write(repr(sorted(m for m in sys.modules if m.split('.')[0] == 'rich')))")
    args = ["workspace", str(PLANAR2), "--step", "0.05", "--out", str(tmp_path / "out")]
    res = subprocess.run([sys.executable, "-c", code, *args, "--json"], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert json.loads(res.stdout)["poses"] > 0
    assert ast.literal_eval(res.stderr.strip().splitlines()[-1]) == []
    res = subprocess.run([sys.executable, "-c", code, *args, "--overwrite"], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert "rich.table" in ast.literal_eval(res.stderr.strip().splitlines()[-1])
    assert "feasible" in res.stdout
