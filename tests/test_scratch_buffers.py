"""No output depends on what an ``np.empty`` buffer held (issue 40, finding 1).

The kernels (``cdpr_design/kernels``) and the CSV writer (``io/csvfast.py``) allocate
their scratch and output buffers with ``np.empty``.  A path that returns or reads
such a buffer before writing it prints whatever memory held (a sagging pose with a
zero-length cable printed a structure matrix of 1e+243 ...).  This test runs the
kernels as Python (``NUMBA_DISABLE_JIT=1``, in a child process) with ``np.empty`` and
``np.empty_like`` in those modules filling every new buffer with a poison, twice with
two different poisons, over sweeps and poses that take every path (ideal, elastic and
sagging cables; static, wrench-feasible and wrench-closure; m = n and m > n; zero-length
cables; swivel pulleys and interference; a hanging effector; the CSV writer): every
output must be the same bit for bit.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from .helpers import ROOT

CHILD = textwrap.dedent(r'''
    import importlib, pickle, pkgutil, sys, types
    import numpy

    POISON = {"A": (float("nan"), -7, 0xAB), "B": (1.2345e300, 99, 0x55)}[sys.argv[1]]

    def poisoned(shape, dtype=float, order="C", **kw):
        a = numpy.empty(shape, dtype=dtype, order=order)
        kind = a.dtype.kind
        a.fill(POISON[0] if kind == "f" else POISON[2] if a.dtype == numpy.uint8 else POISON[1])
        return a

    def poisoned_like(p, dtype=None, **kw):
        return poisoned(numpy.shape(p), dtype if dtype is not None else numpy.asarray(p).dtype)

    class NP(types.ModuleType):
        def __getattr__(self, name):
            return getattr(numpy, name)

    fake = NP("numpy")
    fake.empty, fake.empty_like = poisoned, poisoned_like
    import cdpr_design.kernels as K
    import cdpr_design.io.csvfast as CF
    mods = [CF] + [importlib.import_module(f"cdpr_design.kernels.{m.name}") for m in pkgutil.iter_modules(K.__path__)]
    for mod in mods:
        if getattr(mod, "np", None) is numpy:
            mod.np = fake

    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.model.spec import with_cable_model
    from cdpr_design import api
    from cdpr_design.io.csvfast import numba_rows

    out = {}

    def sweep(tag, design, step=None, **analysis):
        chunks = []
        ws.run(design, ws.Analysis(**analysis), step=step, on_chunk=chunks.append, keep_maps=False)
        for k, c in enumerate(chunks):
            out[f"{tag}/{k}/feasible"] = numpy.asarray(c.feasible)
            out[f"{tag}/{k}/margin"] = numpy.asarray(c.margin)
            out[f"{tag}/{k}/tensions"] = numpy.asarray(c.tensions)
            out[f"{tag}/{k}/lengths"] = numpy.asarray(c.lengths)
            for name, v in sorted(c.extra.items()):
                out[f"{tag}/{k}/{name}"] = numpy.asarray(v)

    def pose(tag, design, p, **kw):
        r = api.pose(design, p, **kw)
        out[f"{tag}/W"], out[f"{tag}/t"], out[f"{tag}/L"] = r.W, r.tensions, r.lengths
        out[f"{tag}/m"] = numpy.array([r.margin, float(r.feasible)])
        if r.cable_state is not None:
            st = r.cable_state
            out[f"{tag}/cs"] = numpy.concatenate([st.outlet_tensions, st.unstretched_lengths, st.sag])

    D = "designs/"
    planar2 = spec.load(D + "planar2.yaml")
    for kind in ("static", "wrench-feasible", "wrench-closure"):
        sweep(f"planar2/{kind}", planar2, kind=kind, step=0.25)
    for model in ("elastic", "sagging"):
        sweep(f"planar2/{model}", with_cable_model(planar2, model), step=0.25)
    sweep("sagging40", spec.load(D + "sagging40.yaml"), step=5.0)
    sweep("planar4", spec.load(D + "planar4.yaml"), kind="wrench-feasible", step=0.5)
    sweep("ipanema3", spec.load(D + "ipanema3.yaml"), step=1.0, collisions=True)
    sweep("cogiro", spec.load(D + "cogiro.yaml"), step=4.0)
    sweep("crane4", spec.load(D + "crane4.yaml"), step=1.0)
    # five and six cables in the plane (m - n = 3, 4: the Goldfarb-Idnani QP), with a wrench box
    import numpy as np_
    from tests.helpers import random_planar_data
    for m in (5, 6):
        data = random_planar_data(np_.random.default_rng(m), m, "2T")
        data["workspace"]["external_wrench"] = {"lower": [-1.0, -1.0], "upper": [1.0, 1.0]}
        sweep(f"planar{m}", spec.from_dict(data), kind="wrench-feasible")
    # poses on an outlet (zero-length cables) and ordinary ones
    s40 = spec.load(D + "sagging40.yaml")
    for model in ("ideal", "elastic", "sagging"):
        d = with_cable_model(s40, model)
        pose(f"s40/{model}/outlet", d, [0.15, 19.85])
        pose(f"s40/{model}/mid", d, [20.0, 10.0])
        pose(f"s40/{model}/minmax", d, [20.0, 10.0], objective="min-max")
    pose("planar2/outlet", planar2, [0.06, 1.44])
    cog = spec.load(D + "cogiro.yaml")
    pose("cogiro/outlet", cog, list(cog.outlets[0] - cog.attachments[0]) + [0.0, 0.0, 0.0])
    out["csv"] = numpy.frombuffer(numba_rows([numpy.array([1.5, numpy.nan, -2e-300, 3.0]),
                                              numpy.array([1, 2, 3, 4])]), dtype=numpy.uint8)
    pickle.dump(out, sys.stdout.buffer)
''')


def run_poisoned(which: str) -> dict:
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", CHILD, which], capture_output=True, cwd=ROOT, env=env, timeout=3000)
    assert r.returncode == 0, r.stderr.decode()[-3000:]
    return pickle.loads(r.stdout)


@pytest.mark.slow
def test_no_output_depends_on_uninitialised_memory():
    a, b = run_poisoned("A"), run_poisoned("B")
    assert a.keys() == b.keys() and len(a) > 50
    differ = [k for k in a if not np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == "f")]
    assert not differ, {k: (a[k], b[k]) for k in differ[:5]}
