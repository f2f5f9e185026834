"""The limits of the spec format, and why each is what it is.

A spec is checked against these before anything is built from it:

- the file (:data:`MAX_SPEC_BYTES`, regular files only: see
  :func:`cdpr_design.io.inputs.read_text`);
- the parsed YAML document (:func:`check_yaml`): nesting depth
  (:data:`MAX_YAML_DEPTH`) and node count with every alias expanded
  (:data:`MAX_YAML_NODES`), counted on the parser's event stream before a
  single Python object is built, so a small file that expands to billions
  of nodes (an alias bomb) or nests 20,000 lists deep is refused at once;
- every number of the validated spec (:func:`check_numbers`): finite (the
  schema) and within the physical bounds of :data:`BOUNDS` for its key;
- strings: names by :data:`NAME_PATTERN`, every other text at most
  :data:`MAX_TEXT` characters;
- counts: cables (:data:`MAX_CABLES`) and orientation samples per position
  (:data:`MAX_ORIENTATION_SAMPLES`).

The bounds are deliberately wide (ten to a thousand times the largest robot
built) so that no real design meets them; what they exclude is input whose
arithmetic would overflow to inf or NaN (``mass: 1e308``) and sizes that
would exhaust memory.  docs/spec-format.md ("Limits") lists them with these
reasons.
"""

from __future__ import annotations

import math
import re
from typing import Any, Iterator

import yaml

from cdpr_design.errors import quote

Problems = list[tuple[str, str]]

#: Largest spec (or catalogue) file read [bytes].  The shipped specs are 1-4 kB;
#: a polyline of 10,000 waypoints is about 300 kB.  Longer paths belong in a
#: ``csv`` trajectory file.
MAX_SPEC_BYTES = 1 << 20
#: Largest YAML document [nodes, every alias expanded]: ten times a 10,000-waypoint polyline.
MAX_YAML_NODES = 200_000
#: Deepest YAML nesting [levels].  The spec format needs 5 (trajectories.NAME.waypoints[k][j]).
MAX_YAML_DEPTH = 32
#: Most cables of one design.  Hyperplane shifting enumerates the C(m, n - 1)
#: subsets of cables: 201,376 for 32 cables of a spatial robot; published
#: robots have at most 16.
MAX_CABLES = 32
#: Design, cable and trajectory names: letters, digits and ``_ . + -``, not starting
#: with a dot (a design's name is its default output folder: never ``.``, ``..``,
#: a hidden folder or a path), at most :data:`MAX_NAME_LENGTH` characters.
NAME_PATTERN = r"^[A-Za-z0-9_+-][A-Za-z0-9_.+-]*$"
MAX_NAME_LENGTH = 64
#: Longest text value (description, file names, PLC symbols) [characters].
MAX_TEXT = 10_000
#: Most orientations tested per position (``orientation_set`` counts multiplied;
#: ``orientation_range`` levels x count^rotations).
MAX_ORIENTATION_SAMPLES = 10_000
#: Most trials of one ``optimize`` study: every trial is a row of optimize.csv, built in
#: memory at the end (as sweep's variants, ``batch.variants.HARD_MAX_VARIANTS``).
MAX_TRIALS = 1_000_000
#: Most worker processes of one ``optimize`` run (as ``sweep --workers``).
MAX_WORKERS = 1024
#: Sampler seeds are numpy's: 0 to 2**32 - 1.
SEED_LIMIT = 2 ** 32

#: Lengths and coordinates [m]: 10 km, fifteen times the largest cable robot
#: built (FAST's 600 m feed cabin support); squares and moments stay far from overflow.
LENGTH = 1e4
#: Angles [rad]: 100 rad is 16 turns; an orientation is meaningful modulo 2 pi.
ANGLE = 100.0
#: Forces [N] and moments [N m]: 1e9 N, a thousand times the strongest winches.
FORCE = 1e9
#: Any other number: magnitude at most 1e12, so that products of two stay finite.
ANY = 1e12


def lengths_problem(lengths, positive: bool = False) -> str | None:
    """What is wrong with cable ``lengths`` [m] (a sequence) for a forward kinematics; None when each is
    finite and from 0 (above 0 when ``positive``) to :data:`LENGTH`, the bound ``--lengths`` takes too
    (the solvers square lengths and coordinates: 1e300 m overflowed them)."""
    values = [float(v) for v in lengths]
    bad = [v for v in values if not (math.isfinite(v) and (v > 0 if positive else v >= 0) and v <= LENGTH)]
    if not bad:
        return None
    return f"cable lengths must be finite and in {'(0' if positive else '[0'}, {LENGTH:g}] m (got {bad[0]:g})"


def net_id_problem(text) -> str | None:
    """What is wrong with ``text`` as an AMS net id (six numbers 0 to 255 joined by dots, as
    ``5.80.201.232.1.1``); None when nothing is."""
    parts = text.split(".") if isinstance(text, str) else []
    if len(parts) == 6 and all(p.isascii() and p.isdigit() and len(p) <= 3 and int(p) <= 255 for p in parts):
        return None
    return f"expected an AMS net id, six numbers 0 to 255 joined by dots (e.g. 5.80.201.232.1.1), got {quote(text)}"


#: Physical bounds per key (path without indices; ``*`` a trajectory's name):
#: (lowest, highest, what).
BOUNDS: dict[str, tuple[float, float, str]] = {
    "gravity": (-1e3, 1e3, "m/s^2 (100 g)"),
    "frame.lower": (-LENGTH, LENGTH, "m"), "frame.upper": (-LENGTH, LENGTH, "m"),
    "effector.mass": (0.0, 1e6, "kg (1,000 t)"),
    "effector.size": (0.0, LENGTH, "m"), "effector.center_of_mass": (-LENGTH, LENGTH, "m"),
    "effector.inertia": (-ANY, ANY, "kg m^2"),
    "tension": (0.0, FORCE, "N"), "cables.tension": (0.0, FORCE, "N"),
    "cables.outlet": (-LENGTH, LENGTH, "m"), "cables.attachment": (-LENGTH, LENGTH, "m"),
    "cables.pulley.radius": (0.0, LENGTH, "m"), "cables.pulley.axis": (-ANY, ANY, "(a direction)"),
    # a drum of 0.1 mm and a gear ratio of 1/1000: far beyond any winch, yet the sizing's
    # speeds (v / r i) and reflected inertias (J i^2) stay finite
    "winch.drum_radius": (1e-4, LENGTH, "m"), "cables.winch.drum_radius": (1e-4, LENGTH, "m"),
    "winch.gear_ratio": (1e-3, 1e6, "(motor turns per drum turn)"),
    "cables.winch.gear_ratio": (1e-3, 1e6, "(motor turns per drum turn)"),
    "cable.diameter": (0.0, LENGTH, "m"), "cables.diameter": (0.0, LENGTH, "m"),
    "cable.axial_stiffness": (0.0, ANY, "N"), "cables.axial_stiffness": (0.0, ANY, "N"),
    "cable.mass_per_length": (0.0, 1e4, "kg/m"), "cables.mass_per_length": (0.0, 1e4, "kg/m"),
    "workspace.grid.lower": (-LENGTH, LENGTH, "m"), "workspace.grid.upper": (-LENGTH, LENGTH, "m"),
    "workspace.grid.step": (0.0, LENGTH, "m"),
    "workspace.orientation": (-ANGLE, ANGLE, "rad"),
    "workspace.external_wrench.lower": (-FORCE, FORCE, "N or N m"),
    "workspace.external_wrench.upper": (-FORCE, FORCE, "N or N m"),
    "workspace.orientation_set.lower": (-ANGLE, ANGLE, "rad"),
    "workspace.orientation_set.upper": (-ANGLE, ANGLE, "rad"),
    "workspace.orientation_set.count": (1, 1000, "samples"),
    "workspace.orientation_range.max": (0.0, ANGLE, "rad"),
    "workspace.orientation_range.levels": (1, 1000, "levels"),
    "workspace.orientation_range.count": (2, 1000, "samples"),
    "requirements.task_box.lower": (-LENGTH, LENGTH, "m"), "requirements.task_box.upper": (-LENGTH, LENGTH, "m"),
    "requirements.max_speed": (0.0, 1e3, "m/s"), "requirements.max_acceleration": (0.0, 1e6, "m/s^2"),
    "requirements.min_margin": (-FORCE, FORCE, "N"),
    "requirements.safety_factor": (1.0, 100.0, ""),
    "requirements.min_cable_frequency": (0.0, 1e6, "Hz"),
    "requirements.min_stiffness": (0.0, 1e12, "N/m"), "requirements.min_frequency": (0.0, 1e6, "Hz"),
    "requirements.max_frame_load": (0.0, FORCE, "N"),
    "requirements.acceleration.lower": (-1e6, 1e6, "m/s^2 or rad/s^2"),
    "requirements.acceleration.upper": (-1e6, 1e6, "m/s^2 or rad/s^2"),
    "requirements.min_acceleration": (0.0, 1e6, "m/s^2"),
    "trajectories.*.speed": (1e-6, 1e3, "m/s"), "trajectories.*.acceleration": (1e-6, 1e6, "m/s^2"),
    "trajectories.*.jerk": (1e-6, 1e9, "m/s^3"), "trajectories.*.cycle_time": (1e-5, 1.0, "s"),
    "trajectories.*.center": (-LENGTH, LENGTH, "m"), "trajectories.*.start": (-LENGTH, LENGTH, "m"),
    "trajectories.*.side": (0.0, LENGTH, "m"), "trajectories.*.radius": (0.0, LENGTH, "m"),
    "trajectories.*.waypoints": (-LENGTH, LENGTH, "m or rad"),
    "trajectories.*.laps": (1, 1000, "laps"), "trajectories.*.orientation": (-ANGLE, ANGLE, "rad"),
    "plc.cycle_time": (1e-4, 10.0, "s"),
}


# ----------------------------------------------------------------------------
# The YAML document
# ----------------------------------------------------------------------------


#: The parsers :func:`check_yaml` walks with, in turn: libyaml when PyYAML has it built in (the
#: same events, faster), then PyYAML's pure-Python parser, which sets no limits.
_PARSERS = tuple(dict.fromkeys((getattr(yaml, "CSafeLoader", yaml.SafeLoader), yaml.SafeLoader)))


def check_yaml(text: str) -> str | None:
    """What is wrong with the shape of a YAML document, or None when it is within the limits.

    Walks the parser's events (nothing is constructed): the nesting depth must
    stay within :data:`MAX_YAML_DEPTH` and the node count, every alias counted
    as the whole node it repeats, within :data:`MAX_YAML_NODES`; an alias of a
    node still open (a self-containing document) is refused.  Syntax errors
    are left to the loader that follows (None).

    A parser that refuses the text is followed by the next of :data:`_PARSERS`:
    libyaml may refuse a document by limits of its own before it yields the
    events that break ours (newer releases stop at 1,000 levels while scanning
    ahead, before the first event of ``[[[[...``), and the user is then told
    this module's limit, the same on every PyYAML, not the library's words.
    """
    for parser in _PARSERS:
        try:
            return _shape_problem(yaml.parse(text, Loader=parser))
        except yaml.YAMLError:
            continue
    return None  # not YAML at all: the loader that follows says what is wrong


def _shape_problem(events) -> str | None:
    """The first limit a YAML event stream breaks (see :func:`check_yaml`), or None."""
    sizes: dict[str, int] = {}  # anchor -> expanded node count
    stack: list[tuple] = []  # open collections: (anchor, nodes counted before it)
    nodes = 0  # expanded nodes so far
    for ev in events:
        if isinstance(ev, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            if len(stack) >= MAX_YAML_DEPTH:
                return f"the YAML nests deeper than {MAX_YAML_DEPTH} levels (line {_line(ev)})"
            stack.append((ev.anchor, nodes))
            nodes += 1
        elif isinstance(ev, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            anchor, before = stack.pop()
            if anchor is not None:
                sizes[anchor] = nodes - before
        elif isinstance(ev, yaml.ScalarEvent):
            nodes += 1
            if ev.anchor is not None:
                sizes[ev.anchor] = 1
        elif isinstance(ev, yaml.AliasEvent):
            if ev.anchor in sizes:
                nodes += sizes[ev.anchor]
            elif any(a == ev.anchor for a, _ in stack):
                return f"the alias *{ev.anchor} repeats a node that contains it (line {_line(ev)})"
        if nodes > MAX_YAML_NODES:
            return (f"the YAML document expands to more than {MAX_YAML_NODES:,} nodes "
                    f"(aliases counted in full; line {_line(ev)})")
    return None


def _line(ev) -> int:
    return ev.start_mark.line + 1 if ev.start_mark is not None else 0


# ----------------------------------------------------------------------------
# Numbers and strings of a validated spec
# ----------------------------------------------------------------------------


def _bound_key(path: tuple) -> str:
    """``("cables", 3, "outlet", 1)`` -> ``cables.outlet``; a trajectory's name becomes ``*``."""
    keys = [p for p in path if not isinstance(p, int)]
    if len(keys) >= 2 and keys[0] == "trajectories":
        keys[1] = "*"
    return ".".join(str(k) for k in keys)


def _show_path(path: tuple) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (("." if out else "") + str(p))
    return out


def _leaves(data: Any, path: tuple = ()) -> Iterator[tuple[tuple, Any]]:
    """Every (path, scalar) of plain data (dicts and lists), depth first."""
    if isinstance(data, dict):
        for k, v in data.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(data, (list, tuple)):
        for i, v in enumerate(data):
            yield from _leaves(v, path + (i,))
    else:
        yield path, data


def check_numbers(data: dict, skip: tuple[str, ...] = ("sweep",)) -> Problems:
    """Every number and string of validated spec data outside its bounds, as (key path, message).

    Numbers: :data:`BOUNDS` for their key, else magnitude at most :data:`ANY`.
    Strings: at most :data:`MAX_TEXT` characters.  Top-level sections in
    ``skip`` are left alone (a sweep's values are checked in each variant).
    """
    p: Problems = []
    for path, v in _leaves(data):
        if path and path[0] in skip:
            continue
        if isinstance(v, str):
            if len(v) > MAX_TEXT:
                p.append((_show_path(path), f"expected at most {MAX_TEXT:,} characters, got {len(v):,}"))
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            continue
        lo, hi, unit = BOUNDS.get(_bound_key(path), (-ANY, ANY, ""))
        if not (math.isfinite(v) and lo <= v <= hi):
            p.append((_show_path(path), f"expected a value in [{lo:g}, {hi:g}]{' ' + unit if unit else ''} "
                                        f"(the spec format's limits), got {quote(v)}"))
    return p


def check_orientation_samples(workspace: dict | None, rotations: int) -> Problems:
    """Orientations per position of ``workspace.orientation_set`` / ``orientation_range`` (plain
    data, ``rotations`` coordinates) at most :data:`MAX_ORIENTATION_SAMPLES` (counted as floats)."""
    p: Problems = []
    ws = workspace or {}
    oset, orng = ws.get("orientation_set"), ws.get("orientation_range")
    if oset is not None and rotations:
        counts = list(oset.get("count", [5]))
        n = math.prod(float(c) for c in (counts * rotations if len(counts) == 1 else counts))
        if n > MAX_ORIENTATION_SAMPLES:
            p.append(("workspace.orientation_set.count", f"expected at most {MAX_ORIENTATION_SAMPLES:,} "
                                                         f"orientations per position, got {n:,.0f}"))
    if orng is not None and rotations:
        n = float(orng.get("levels", 10)) * float(orng.get("count", 3)) ** rotations
        if n > MAX_ORIENTATION_SAMPLES:
            p.append(("workspace.orientation_range", f"expected at most {MAX_ORIENTATION_SAMPLES:,} orientations "
                                                     f"per position (levels x count^{rotations}), got {n:,.0f}"))
    return p


def check_name(path: str, name: str) -> Problems:
    """A name (design, cable, trajectory) against :data:`NAME_PATTERN` and :data:`MAX_NAME_LENGTH`."""
    if not isinstance(name, str) or not (0 < len(name) <= MAX_NAME_LENGTH and re.match(NAME_PATTERN, name)):
        return [(path, f"expected a name of 1 to {MAX_NAME_LENGTH} letters, digits and _ . + - "
                       f"not starting with a dot, got {quote(name)}")]
    return []
