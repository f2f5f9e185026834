"""Hypothesis strategies for the fuzz tests (test_fuzz.py, scripts/fuzz.py): random valid specs,
random mutations of them (wrong types, missing keys, extreme numbers, odd strings, nesting),
YAML text mutations, and hostile option values.

Valid specs are small on purpose (a few hundred grid poses, short paths) so
that every command's library entry point runs in well under a second.
"""

from __future__ import annotations

import copy
import math

from hypothesis import strategies as st

#: Numbers a hostile user tries.
EXTREME_NUMBERS = [0, -0.0, 1, -1, 1e-320, 1e-300, 1e-11, 1e9, 1e12, 1e13, 1e308, -1e308, math.inf, -math.inf,
                   math.nan, 10 ** 30, -(10 ** 30), 2 ** 63, 0.1, 3]
#: Strings a hostile user tries.
ODD_STRINGS = ["", ".", "..", "../x", "a/b", "/", "[/x]", "[bold]x", "a,b", "a\nb", "\x00", "\t", " ", "é",
               "x" * 300, "1.0", "true", "nan", "inf", "-", "_", "c1", "NOPE", "~", "!!python/none", "*a", "&a",
               "%s%n", "{}", "[]", "\u202e", "\ud7ff"]

finite = st.floats(allow_nan=False, allow_infinity=False)


def _deep(depth: int):
    v: object = 1.0
    for _ in range(depth):
        v = [v]
    return v


#: Any hostile value: wrong types, extreme numbers, odd strings, nesting.
hostile_values = st.one_of(
    st.booleans(), st.none(), st.sampled_from(EXTREME_NUMBERS), st.floats(), st.integers(),
    st.sampled_from(ODD_STRINGS), st.text(max_size=12),
    st.lists(st.one_of(st.floats(), st.integers(), st.text(max_size=3)), max_size=6),
    st.lists(st.lists(st.floats(), max_size=4), max_size=4),
    st.dictionaries(st.text(max_size=6), st.one_of(st.integers(), st.floats(), st.text(max_size=4)), max_size=3),
    st.integers(min_value=0, max_value=60).map(_deep),
)


def _r(x: float) -> float:
    return float(f"{x:.6g}")


@st.composite
def spec_data(draw) -> dict:
    """A random valid spec (plain data): 2T, 1R2T or 3T, 2 to 4 cables, a small grid, often a
    task box, a square or polyline path and winch keys."""
    motion = draw(st.sampled_from(["2T", "2T", "2T", "1R2T", "3T"]))
    dim = 3 if motion == "3T" else 2
    m = draw(st.integers(min_value=2 if motion == "2T" else 3, max_value=4))
    size = [_r(draw(st.floats(0.5, 4.0))) for _ in range(dim)]
    ext = [_r(draw(st.floats(0.0, 0.3))) for _ in range(dim)]
    cables = []
    for i in range(m):
        outlet = [_r(draw(st.floats(0.0, s))) for s in size]
        if dim == 2:
            outlet[1] = _r(draw(st.floats(0.5 * size[1], size[1])))
        cables.append({"name": f"c{i + 1}", "outlet": outlet,
                       "attachment": [_r(draw(st.floats(-e / 2, e / 2))) for e in ext]})
    tmin = _r(draw(st.floats(0.0, 5.0)))
    data = {
        "name": draw(st.sampled_from(["fz", "fuzz-1", "a.b", "X_2"])),
        "motion": motion,
        "frame": {"lower": [0.0] * dim, "upper": size},
        "effector": {"mass": _r(draw(st.floats(0.0, 30.0))), "size": ext},
        "tension": [tmin, _r(tmin + draw(st.floats(1.0, 500.0)))],
        "cables": cables,
        "workspace": {"grid": {"step": _r(max(size) / (14 if dim == 2 else 6))}},
    }
    if motion == "1R2T":
        data["workspace"]["orientation"] = [_r(draw(st.floats(-0.3, 0.3)))]
    if draw(st.booleans()):
        data["winch"] = {"drum_radius": _r(draw(st.floats(0.005, 0.2))), "gear_ratio": _r(draw(st.floats(1.0, 50.0)))}
    lo = [_r(s * draw(st.floats(0.2, 0.45))) for s in size]
    hi = [_r(s * draw(st.floats(0.55, 0.8))) for s in size]
    if draw(st.booleans()):
        data["requirements"] = {"task_box": {"lower": lo, "upper": hi}, "max_speed": 0.5, "max_acceleration": 2.0}
    centre = [_r((a + b) / 2) for a, b in zip(lo, hi)]
    kind = draw(st.sampled_from(["square", "polyline", None]))
    if kind == "square":
        data["trajectories"] = {"sq": {"type": "square", "center": centre, "side": _r(min(size) / 5),
                                       "speed": _r(draw(st.floats(0.05, 2.0))), "acceleration": 2.0}}
    elif kind == "polyline":
        data["trajectories"] = {"pl": {"type": "polyline", "waypoints": [lo, hi], "speed": 0.5,
                                       "acceleration": _r(draw(st.floats(0.5, 10.0)))}}
    return data


def _paths(data, path=()):
    """Every key path (tuples of keys and indices) into plain data, containers included."""
    yield path
    if isinstance(data, dict):
        for k, v in data.items():
            yield from _paths(v, path + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            yield from _paths(v, path + (i,))


def _get(data, path):
    for p in path:
        data = data[p]
    return data


@st.composite
def mutated_spec_data(draw) -> dict:
    """A valid spec with one to three hostile changes: a value replaced (wrong type, extreme
    number, odd string, nesting), a key deleted, an unknown key added, a value wrapped in lists."""
    data = copy.deepcopy(draw(spec_data()))
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(data) if p]
        path = draw(st.sampled_from(paths))
        parent, key = _get(data, path[:-1]), path[-1]
        action = draw(st.sampled_from(["replace", "replace", "replace", "delete", "add", "wrap"]))
        if action == "replace":
            parent[key] = draw(hostile_values)
        elif action == "delete":
            del parent[key]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(st.sampled_from(ODD_STRINGS + ["extra", "mass", "name"]))] = draw(hostile_values)
        elif action == "wrap":
            parent[key] = [parent[key]] * draw(st.integers(1, 3))
    return data


#: YAML snippets spliced into a spec's text.
YAML_SNIPPETS = ["&a ", "*a", "*b", "[", "]", "{", "}", ": ", "- ", "\t", "!!python/object:os.system ", "!!binary ",
                 "!!float ", "!!str ", "? ", "|\n", "'", '"', "#", "\ufeff", "\x00", "---\n", "...\n", "<<: *a\n",
                 "&a [*a]", "1e308", ".nan", ".inf", "~", "0x1F", "2001-12-14", "yes", "on"]


@st.composite
def mutated_yaml(draw, base_text: str) -> str:
    """The YAML text of a spec cut, spliced or with a line repeated."""
    text = base_text
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(text)))
        action = draw(st.sampled_from(["cut", "splice", "splice", "repeat", "delete"]))
        if action == "cut":
            text = text[:i]
        elif action == "splice":
            text = text[:i] + draw(st.one_of(st.sampled_from(YAML_SNIPPETS), st.text(max_size=8))) + text[i:]
        elif action == "repeat":
            lines = text.splitlines(keepends=True)
            if lines:
                k = draw(st.integers(0, len(lines) - 1))
                lines.insert(k, lines[k])
                text = "".join(lines)
        else:
            j = draw(st.integers(i, min(len(text), i + 20)))
            text = text[:i] + text[j:]
    return text


#: Option values: mostly sensible, often hostile (numbers for steps, cycle times, tolerances).
def option_floats(low: float, high: float):
    return st.one_of(st.none(), st.floats(low, high), st.sampled_from(EXTREME_NUMBERS).map(float))


# ----------------------------------------------------------------------------
# Cable models, the hanging pose (effector.orientation, requirements.max_tilt)
# ----------------------------------------------------------------------------

CABLE_MODELS = ["ideal", "elastic", "sagging"]
#: The keys of the later features, mutated by :func:`mutated_feature_data`.
FEATURE_KEYS = ("cable", "model", "axial_stiffness", "mass_per_length", "orientation", "max_tilt",
                "center_of_mass")


def _cable_props(draw, model: str, always: bool) -> dict:
    """What ``model`` needs (EA [N], mass per length [kg/m]); with ``always`` every property."""
    props: dict = {}
    if model != "ideal" or always:
        props["axial_stiffness"] = _r(draw(st.floats(1e3, 1e7)))
    if model == "sagging" or always:
        props["mass_per_length"] = _r(draw(st.floats(1e-3, 0.5)))
    return props


@st.composite
def feature_spec_data(draw) -> dict:
    """A random valid spec (:func:`spec_data`) that also draws a cable model (design-wide, often with
    the properties of every model, sometimes per cable) and, for the designs it applies to (2T with
    two cables, 3T with three or four: under-constrained), ``effector.orientation: free`` with a
    centre of mass below the attachments and often ``requirements.max_tilt``."""
    data = draw(spec_data())
    model = draw(st.sampled_from(CABLE_MODELS))
    if model != "ideal" or draw(st.booleans()):
        data["cable"] = {"model": model, **_cable_props(draw, model, draw(st.booleans()))}
    for c in data["cables"]:
        if draw(st.integers(0, 4)) == 0:  # a cable of its own model
            own = draw(st.sampled_from(CABLE_MODELS))
            c.update({"model": own, **_cable_props(draw, own, False)})
    m, motion = len(data["cables"]), data["motion"]
    under = (motion == "2T" and m == 2) or (motion == "3T" and m <= 4)
    if under and draw(st.booleans()):
        data["effector"]["orientation"] = "free"
        if not data["effector"]["mass"] >= 1e-12:  # it hangs under its weight (below 1e-12 N it is refused)
            data["effector"]["mass"] = _r(draw(st.floats(1e-3, 30.0)))
        dim = 3 if motion == "3T" else 2
        data["effector"]["center_of_mass"] = [0.0] * (dim - 1) + [-_r(draw(st.floats(0.0, 0.3)))]
        if draw(st.booleans()):
            data.setdefault("requirements", {})["max_tilt"] = _r(draw(st.floats(0.0, 180.0)))
    elif draw(st.integers(0, 5)) == 0:
        data["effector"]["orientation"] = "fixed"
    return data


def _feature_paths(data):
    return [p for p in _paths(data) if p and any(k in FEATURE_KEYS for k in p if isinstance(k, str))]


@st.composite
def mutated_feature_data(draw) -> dict:
    """A :func:`feature_spec_data` spec with one to three hostile changes to the keys of cable models and
    the hanging pose: a model or orientation misspelt or of the wrong type, a property the model needs
    deleted, extreme numbers (EA 0 or 1e308, a negative density, max_tilt 500 or NaN), ``free`` or
    ``max_tilt`` where they do not apply."""
    data = copy.deepcopy(draw(feature_spec_data()))
    for _ in range(draw(st.integers(1, 3))):
        action = draw(st.sampled_from(["replace", "replace", "delete", "model", "free", "tilt"]))
        paths = _feature_paths(data)
        if action == "model":  # a model whose properties may be missing, on the design or one cable
            cables = data.get("cables") if isinstance(data.get("cables"), list) else []
            if not isinstance(data.get("cable", {}), dict):
                continue
            places = [w for w in [data.setdefault("cable", {})] + cables if isinstance(w, dict)]
            where = draw(st.sampled_from(places))
            where["model"] = draw(st.sampled_from(CABLE_MODELS + ["Sagging", "catenary", "", None, 1, True]))
        elif action == "free" and isinstance(data.get("effector"), dict):
            data["effector"]["orientation"] = draw(st.sampled_from(["free", "fixed", "Free", "hanging", True, 0,
                                                                    None, ["free"]]))
        elif action == "tilt" and isinstance(data.get("requirements", {}), dict):
            data.setdefault("requirements", {})["max_tilt"] = draw(st.one_of(
                st.sampled_from([-1, 180.0001, 500, 1e308, math.nan, math.inf, "10", True, None, [10]]),
                st.floats(0, 180)))
        elif action in ("replace", "delete") and paths:
            path = draw(st.sampled_from(paths))
            parent, key = _get(data, path[:-1]), path[-1]
            if action == "replace":
                parent[key] = draw(st.one_of(hostile_values, st.sampled_from(
                    [0, -1.0, 1e-300, 1e308, 1e13, math.nan, "sagging", "free"])))
            else:
                del parent[key]
    return data
