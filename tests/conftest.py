"""Shared fixtures and factories: paths, the shipped designs, small robots built through the spec format, the CLI."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from cdpr_design.model import spec

ROOT = Path(__file__).resolve().parents[1]
DESIGNS = ROOT / "designs"
PLANAR2 = DESIGNS / "planar2.yaml"


@pytest.fixture
def planar2_data() -> dict:
    return yaml.safe_load(PLANAR2.read_text())


def write_spec(tmp_path: Path, data: dict, name: str = "spec.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


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


def modified(data: dict, **changes) -> dict:
    out = copy.deepcopy(data)
    out.update(changes)
    return out


@pytest.fixture(scope="session")
def planar2():
    """The seed paper's robot, ``designs/planar2.yaml``, loaded once."""
    return spec.load(PLANAR2)


def invoke(*args):
    """Run the command line in-process (typer's CliRunner) with the arguments as text."""
    from typer.testing import CliRunner

    from cdpr_design.cli.app import app

    return CliRunner().invoke(app, [str(a) for a in args])


def point_mass(outlets, mass=1.0, tension=(0.0, 100.0), motion="2T", gravity=None, attachments=None,
               size=None, inertia=None):
    """A design whose cables meet at (or near) one point of the effector, outlets given [m];
    frame +-5 m, effector box ``size`` (default 0.1 m per axis) [m], mass [kg], tension bounds [N]."""
    d = len(outlets[0])
    data = {
        "name": "pm", "motion": motion,
        "frame": {"lower": [-5.0] * d, "upper": [5.0] * d},
        "effector": {"mass": mass, "size": list(size) if size is not None else [0.1] * d},
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


#: The 1R2T robot with four crossed cables (outlets at the corners of a 2 m square) [m].
CROSSED4_CABLES = [{"name": "c1", "outlet": [0, 2], "attachment": [-0.1, 0.05]},
                   {"name": "c2", "outlet": [2, 2], "attachment": [0.1, 0.05]},
                   {"name": "c3", "outlet": [2, 0], "attachment": [0.1, -0.05]},
                   {"name": "c4", "outlet": [0, 0], "attachment": [-0.1, -0.05]}]

#: IPAnema 3 (cdpyr sample, ``designs/ipanema3.yaml``): (outlet, attachment) per cable [m].
IP3 = [((-8.544, 5.463, 3.202), (-0.07, 0.648, -0.26)), ((8.184, 5.692, 3.236), (0.06, 0.648, -0.262)),
       ((8.224, -5.492, 3.25), (0.06, -0.651, -0.262)), ((-8.491, -5.322, 3.221), (-0.07, -0.651, -0.26)),
       ((-8.192, 5.648, -0.589), (-0.085, 0.748, 0.261)), ((7.208, 6.463, -0.548), (0.095, 0.749, 0.26)),
       ((7.869, -5.557, -0.527), (0.095, -0.745, 0.26)), ((-8.27, -5.545, -0.582), (-0.085, -0.746, 0.261))]
#: IPAnema 3's frame, effector and tension bounds (our choice of bounds; see designs/ipanema3.yaml).
IP3_BODY = {
    "name": "ip3", "motion": "3R3T", "gravity": [0, 0, -9.81],
    "frame": {"lower": [-8.544, -5.557, -0.589], "upper": [8.224, 6.463, 3.25]},
    "effector": {"mass": 30.0, "size": [0.19, 1.5, 0.53], "inertia": [5.226154, 0.637352, 4.723802]},
    "tension": [100.0, 3000.0],
}
