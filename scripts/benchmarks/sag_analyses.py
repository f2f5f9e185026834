"""Interference checks and orientation workspaces with sagging cables, against straight cables.

Two sweeps, each timed in interleaved rounds in this process against its straight-cable
counterpart (the same design with elastic cables: straight, the same checks on chords) and
against the same cable model without the option:

* sagging40 (40 m planar span, 2 heavy cables), the static workspace with ``--collisions``:
  the catenaries' polylines checked at every pose (:mod:`cdpr_design.kernels.sag_clearance`);
* CoGiRo (8 cables, 3R3T), ``--orientations total`` over a set of 3 orientations: every
  orientation solved with its catenaries.

Ratios are CPU seconds (numba's threads included) of the sweep with the option over the sweep
of the same model without it, and of the sagging sweep over the elastic one with the same option.
"""

from __future__ import annotations

from benchmarks import harness as h

OPTIONS = {"sag40_step": 0.5, "cogiro_step": 0.75}
QUICK = {"sag40_step": 1.0, "cogiro_step": 1.5}


def _design(name: str, model: str):
    """designs/<name>.yaml with ``model`` cables; a rotational design with an orientation set of 3
    orientations, the nominal and +-0.1 rad about z."""
    from cdpr_design.model import spec

    d = spec.load(h.ROOT / "designs" / f"{name}.yaml")
    if d.motion.rotational:
        raw = dict(d.raw)
        wsx = dict(raw["workspace"])
        nominal = [float(v) for v in d.default_orientation_full()]
        wsx["orientation_set"] = {"lower": nominal[:2] + [nominal[2] - 0.1], "upper": nominal[:2] + [nominal[2] + 0.1],
                                  "count": [1, 1, 3]}
        raw["workspace"] = wsx
        d = spec.from_dict(raw, source=d.source)
    return spec.with_cable_model(d, model)


def _sweep(design, step, **options):
    from cdpr_design import workspaces as ws
    from cdpr_design.statics.robot import Analysis

    def go():
        return ws.run(design, Analysis(**options), step=step, keep_maps=False, tilt=False)
    return go


def run(b: h.Bench) -> None:
    cases = {
        "sagging40": (b.opt["sag40_step"], {"plain": {}, "collisions": {"collisions": True}}),
        "cogiro": (b.opt["cogiro_step"], {"plain": {}, "orientations total": {"orientations": "total"}}),
    }
    for name, (step, opts) in cases.items():
        variants = {}
        results = {}
        for model in ("elastic", "sagging"):
            d = _design(name, model)
            for label, kw in opts.items():
                fn = _sweep(d, step, **kw)
                cold, res = h.timed(fn)  # numba's cache loaded (or compiled) here
                results[(model, label)] = res
                variants[(model, label)] = fn
                b.say(f"{name} {model} {label}: first call {cold.wall:.2f} s wall, {cold.cpu:.2f} CPU-s; "
                      f"{res.summary()['poses']:,} poses, feasible {res.summary()['feasible']:,}")
        t = h.rounds(variants, b.rounds)
        label = [k for k in opts if k != "plain"][0]
        for model in ("elastic", "sagging"):
            b.row(f"{name} {model}: {label} against plain", h.seconds(h.spread(x.cpu for x in t[(model, label)])),
                  h.spread(c.cpu / p.cpu for c, p in zip(t[(model, label)], t[(model, "plain")])),
                  "CPU time ÷ the same model's plain sweep")
        b.row(f"{name}: sagging {label} against elastic {label}",
              h.seconds(h.spread(x.cpu for x in t[("sagging", label)])),
              h.spread(s.cpu / e.cpu for s, e in zip(t[("sagging", label)], t[("elastic", label)])),
              "CPU time ÷ the straight (elastic) cables' sweep with the same option")

