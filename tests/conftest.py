"""Shared fixtures: paths and small random designs built through the spec format."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

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
