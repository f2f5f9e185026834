"""Shared test helpers: paths, spec data builders, the command line, small references.

Plain functions (fixtures live in conftest.py and build on these).
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]

#: A test of a file the JIT-off CI run repeats (.ci/run) that calls no numba kernel (checked by
#: profiling which functions of cdpr_design.kernels and io.csvfast each test calls): the same
#: numpy code twice, so that run leaves it out (``-m "not no_kernels"``).
NO_KERNELS = pytest.mark.no_kernels
DESIGNS = ROOT / "designs"
PLANAR2 = DESIGNS / "planar2.yaml"


# ----------------------------------------------------------------------------
# Files and the command line
# ----------------------------------------------------------------------------


def planar2_raw() -> dict:
    """A fresh copy of designs/planar2.yaml as plain data."""
    return yaml.safe_load(PLANAR2.read_text())


def write_spec(tmp_path: Path, data: dict, name: str = "spec.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


def light_spec(tmp_path: Path) -> Path:
    """planar2 without its motor and speed requirements: quick optimize trials."""
    raw = planar2_raw()
    raw["winch"].pop("motor")
    for k in ("max_speed", "max_acceleration"):
        raw["requirements"].pop(k)
    return write_spec(tmp_path, raw, "light.yaml")


def invoke(*args, **kwargs):
    """Run the command line in-process (typer's CliRunner); arguments are str()-ed."""
    from typer.testing import CliRunner

    from cdpr_design.cli.app import app

    return CliRunner().invoke(app, [str(a) for a in args], **kwargs)


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    """Header and rows (strings) of a CSV file."""
    rows = list(csv.reader(io.StringIO(path.read_text())))
    return rows[0], rows[1:]


def csv_header(path: Path) -> list[str]:
    with open(path) as fh:
        return next(csv.reader(fh))


def subprocess_env(**extra) -> dict:
    """This process's environment with the repository first on PYTHONPATH (for ``python -m cdpr_design``)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.update(extra)
    return env


# ----------------------------------------------------------------------------
# Spec data builders
# ----------------------------------------------------------------------------


def random_planar_data(rng: np.random.Generator, m: int = 2, motion: str = "2T") -> dict:
    """A random planar robot: outlets on the upper part of a frame, small attachments."""
    w, h = rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0)
    cables = []
    for i in range(m):
        cables.append({
            "name": f"k{i}",
            # outlets spread left to right over the upper part of the frame
            "outlet": [float(rng.uniform(i * w / m, (i + 1) * w / m)), float(rng.uniform(0.6 * h, h))],
            "attachment": [float(rng.uniform(-0.1, 0.1)), float(rng.uniform(-0.1, 0.1))],
            "tension": [float(rng.uniform(0, 2)), float(rng.uniform(15, 60))],
        })
    return {
        "name": "random", "motion": motion,
        "frame": {"lower": [0.0, 0.0], "upper": [w, h]},
        "effector": {"mass": float(rng.uniform(0.2, 3.0)), "size": [0.1, 0.1]},
        "cables": cables,
        "workspace": {"grid": {"step": float(min(w, h) / 24)}},
    }


def random_spatial_data(rng: np.random.Generator, m: int, motion: str, jitter: float = 0.0) -> dict:
    """A random spatial robot (``motion`` 3T or 3R3T): outlets near the corners of a box frame, the
    first four (every one for 3T) near its top and the others near its bottom; attachments at
    the corners of a 0.2 m square, each of their horizontal coordinates moved by up to ``jitter``
    [m]; no external wrench."""
    w = rng.uniform(1.5, 3.0, 3)
    corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
    cables = []
    for i in range(m):
        cx, cy = corners[i % 4]
        top = i < 4 or motion == "3T"
        outlet = [float(cx * w[0] + rng.uniform(-0.1, 0.1)), float(cy * w[1] + rng.uniform(-0.1, 0.1)),
                  float(w[2] * (rng.uniform(0.8, 1.0) if top else rng.uniform(0.0, 0.2)))]
        shift = rng.uniform(-jitter, jitter, 2) if jitter else (0.0, 0.0)
        cables.append({
            "name": f"k{i}", "outlet": outlet,
            "attachment": [float((cx - 0.5) * 0.2 + shift[0]), float((cy - 0.5) * 0.2 + shift[1]),
                           float(0.05 if top else -0.05)],
            "tension": [float(rng.uniform(0, 2)), float(rng.uniform(40, 200))],
        })
    return {"name": "random3d", "motion": motion,
            "frame": {"lower": [0.0, 0.0, 0.0], "upper": [float(v) for v in w]},
            "effector": {"mass": float(rng.uniform(0.2, 3.0)), "size": [0.2, 0.2, 0.1]},
            "cables": cables, "workspace": {"grid": {"step": float(min(w) / 5)}}}


def point_mass(outlets, mass=1.0, tension=(0.0, 100.0), motion="2T", gravity=None, attachments=None,
               size=None, inertia=None):
    """A robot of the given outlets on a 10 m frame around the origin; the effector is a point
    (size 0) at the cables' meeting point unless size / attachments say otherwise."""
    from cdpr_design.model import spec

    d = len(outlets[0])
    data = {
        "name": "pm", "motion": motion,
        "frame": {"lower": [-5.0] * d, "upper": [5.0] * d},
        "effector": {"mass": mass, "size": list(size) if size is not None else [0.0] * d},
        "tension": list(tension),
        "cables": [{"name": f"c{i}", "outlet": list(a),
                    "attachment": list(attachments[i]) if attachments else [0.0] * d}
                   for i, a in enumerate(outlets)],
    }
    if gravity is not None:
        data["gravity"] = list(gravity)
    if inertia is not None:
        data["effector"]["inertia"] = inertia
    return spec.from_dict(data)


def static_tensions(design, pose):
    """t = W^-1 w_req (m = n): the statics at rest, plain numpy."""
    from cdpr_design.statics import kinematics as kin

    return np.linalg.solve(kin.structure_matrix(design, pose), kin.required_wrench(design, pose))


def add_pulleys(cables: list, radius, axes) -> list:
    """Put a swivel pulley of ``radius`` on every cable (axis ``axes[i]``); radius None: none."""
    if radius is not None:
        for c, k in zip(cables, axes):
            c["pulley"] = {"radius": radius, "axis": list(k)}
    return cables


# IPAnema 3 (docs/sources.md: cdpyr sample ipanema_3): outlet, attachment
IPANEMA3 = [
    ((-8.544, 5.463, 3.202), (-0.07, 0.648, -0.26)),
    ((8.184, 5.692, 3.236), (0.06, 0.648, -0.262)),
    ((8.224, -5.492, 3.25), (0.06, -0.651, -0.262)),
    ((-8.491, -5.322, 3.221), (-0.07, -0.651, -0.26)),
    ((-8.192, 5.648, -0.589), (-0.085, 0.748, 0.261)),
    ((7.208, 6.463, -0.548), (0.095, 0.749, 0.26)),
    ((7.869, -5.557, -0.527), (0.095, -0.745, 0.26)),
    ((-8.27, -5.545, -0.582), (-0.085, -0.746, 0.261)),
]


def ipanema3_data(name: str, radius=None, **keys) -> dict:
    """IPAnema 3's geometry, mass and tensions; with ``radius`` swivel pulleys (upper cables come
    up their posts, +z; lower cables come down, -z).  ``keys``: further top-level keys."""
    cables = [{"name": f"c{i + 1}", "outlet": list(a), "attachment": list(b)} for i, (a, b) in enumerate(IPANEMA3)]
    add_pulleys(cables, radius, [[0.0, 0.0, 1.0 if i < 4 else -1.0] for i in range(len(cables))])
    data = {
        "name": name, "motion": "3R3T", "gravity": [0, 0, -9.81],
        "frame": {"lower": [-8.544, -5.557, -0.589], "upper": [8.224, 6.463, 3.25]},
        "effector": {"mass": 30.0, "size": [0.19, 1.5, 0.53], "inertia": [5.226154, 0.637352, 4.723802]},
        "tension": [100.0, 3000.0],
    }
    if "cable" in keys:
        data["cable"] = keys.pop("cable")
    data["cables"] = cables
    data.update(keys)
    return data


def planar4_cables() -> list:
    """Four cables from the corners of a 2 m frame to the corners of a 0.2 x 0.1 m platform."""
    return [{"name": "c1", "outlet": [0, 2], "attachment": [-0.1, 0.05]},
            {"name": "c2", "outlet": [2, 2], "attachment": [0.1, 0.05]},
            {"name": "c3", "outlet": [2, 0], "attachment": [0.1, -0.05]},
            {"name": "c4", "outlet": [0, 0], "attachment": [-0.1, -0.05]}]


def planar4_orient(name: str, **wsx):
    """A 1R2T robot with four cables of 4 mm on the frame's corners, grid 0.1 at orientation 0.05;
    ``wsx``: further workspace keys (orientation_set, orientation_range)."""
    from cdpr_design.model import spec

    return spec.from_dict({
        "name": name, "motion": "1R2T", "gravity": [0, -9.81],
        "frame": {"lower": [0, 0], "upper": [2, 2]}, "effector": {"mass": 1.0, "size": [0.2, 0.1]},
        "tension": [1, 60], "cable": {"diameter": 0.004},
        "cables": planar4_cables(),
        "workspace": {"grid": {"step": 0.1}, "orientation": [0.05], **wsx},
    })


def collect_chunks(run, *args, **kwargs):
    """Call a sweep (``run(*args, on_chunk=..., **kwargs)``); its result and the chunks it streamed."""
    chunks = []
    res = run(*args, on_chunk=chunks.append, **kwargs)
    assert chunks, "the sweep streamed no chunk"
    return res, chunks


def resolved(design, command: str = "workspace", **options):
    """``design`` resolved for ``command`` (:func:`cdpr_design.statics.robot.resolve`): what the
    library's functions below the jobs take."""
    from cdpr_design.statics.robot import Analysis, resolve

    return resolve(design, Analysis(command=command, **options))
