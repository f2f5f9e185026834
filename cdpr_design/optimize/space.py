"""What ``optimize`` searches: ``--vary KEY=LO:HI[:log]`` ranges and ``--vary KEY=a,b,c`` choices.

KEY is a dotted path into the spec, the same as ``sweep --vary``
(:mod:`cdpr_design.batch.variants`: ``cables.0.outlet.0``, ``cables.c2.outlet.1``,
``winch.drum_radius``, ``effector.mass``).  A range ``LO:HI`` is continuous
(``LO:HI:log``: sampled on a log scale, LO > 0); where the spec format makes
the key an integer, the range is of integers.  A choice ``a,b,c`` is
categorical (numbers or names, e.g. catalogue motors); one value with no
colon fixes the key.

Checked up front (exit 2, naming ``--vary KEY``): the key exists in the spec
format and takes a number (ranges), LO < HI, every choice gives a valid
spec with the other keys at their base values.  A variant inside a range
may still be invalid (an outlet outside the frame, min > max): that is a
failed trial, with the spec's reason, not bad input.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Sequence

from cdpr_design.batch.variants import Axis, Plan, parse_path, parse_values, resolve
from cdpr_design.errors import QUOTE_WIDTH, InputError, SpecError, quote


@dataclass(frozen=True)
class Param:
    """One searched key: ``kind`` is ``float``, ``int`` or ``categorical``.

    ``low``/``high`` bound a range (both ends included), ``log`` samples it on a log
    scale; ``choices`` are a categorical key's values.
    """

    key: str
    path: tuple
    kind: str
    low: float | None = None
    high: float | None = None
    log: bool = False
    choices: tuple = ()

    def describe(self) -> dict:
        """Plain data (the study's fingerprint, the ``--json`` summary)."""
        if self.kind == "categorical":
            return {"key": self.key, "kind": self.kind, "choices": list(self.choices)}
        return {"key": self.key, "kind": self.kind, "low": self.low, "high": self.high, "log": self.log}

    def suggest(self, trial) -> Any:
        """This key's value for an optuna trial."""
        if self.kind == "float":
            return trial.suggest_float(self.key, self.low, self.high, log=self.log)
        if self.kind == "int":
            return trial.suggest_int(self.key, int(self.low), int(self.high), log=self.log)
        return trial.suggest_categorical(self.key, list(self.choices))


@dataclass(frozen=True)
class Space:
    """The searched keys and the base spec data they vary (a :class:`~cdpr_design.batch.variants.Plan`
    with one axis per key, whose ``data(values)`` builds a variant)."""

    params: tuple[Param, ...]
    plan: Plan

    @property
    def keys(self) -> list[str]:
        return [p.key for p in self.params]

    def data(self, values: dict) -> dict:
        """The spec data with the searched keys at ``values`` (key -> value)."""
        return self.plan.data([values[p.key] for p in self.params])


def vary_name(key: str) -> str:
    """``--vary KEY`` for a message, KEY cut to about :data:`~cdpr_design.errors.QUOTE_WIDTH` characters."""
    return "--vary " + (key if len(key) <= QUOTE_WIDTH else key[: QUOTE_WIDTH - 3] + "...")


def _split_option(option: str) -> tuple[str, str]:
    key, sep, text = option.partition("=")
    key = key.strip()
    if not sep or not key or not text.strip():
        raise InputError(f"--vary {quote(option)}: expected KEY=LO:HI, KEY=LO:HI:log or KEY=a,b,c "
                         "(e.g. cables.0.outlet.0=-0.5:0.5)")
    return key, text.strip()


def _number(text: str, where: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{where}: expected a number, got {quote(text)}") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: expected a finite number, got {quote(text)}")
    return v


def parse_range(key: str, text: str, integer: bool) -> Param:
    """``LO:HI`` or ``LO:HI:log`` of ``--vary KEY`` (``integer``: the spec format's type)."""
    where = vary_name(key)
    parts = [t.strip() for t in text.split(":")]
    if len(parts) not in (2, 3) or (len(parts) == 3 and parts[2] != "log"):
        raise InputError(f"{where}: expected LO:HI or LO:HI:log, got {quote(text)}")
    lo, hi = _number(parts[0], where), _number(parts[1], where)
    log = len(parts) == 3
    if not lo < hi:
        raise InputError(f"{where}: expected LO < HI, got {quote(text)}")
    if log and lo <= 0:
        raise InputError(f"{where}: a log range needs LO > 0, got {quote(text)}")
    if integer:
        if lo != int(lo) or hi != int(hi):
            raise InputError(f"{where}: {key} is an integer in the spec format; expected whole LO and HI, "
                             f"got {quote(text)}")
        return Param(key, (), "int", int(lo), int(hi), log)
    return Param(key, (), "float", lo, hi, log)


def parse_choices(key: str, text: str) -> Param:
    """``a,b,c`` (or one value) of ``--vary KEY``: numbers or names."""
    try:
        values = parse_values(text)
    except ValueError as exc:
        raise InputError(f"{vary_name(key)}: {exc}") from None
    if len(set(map(repr, values))) != len(values):
        raise InputError(f"{vary_name(key)}: a choice is given twice in {quote(text)}")
    return Param(key, (), "categorical", choices=tuple(values))


# ----------------------------------------------------------------------------
# The spec format's type of a key (from its JSON schema)
# ----------------------------------------------------------------------------


def _deref(schema: dict, node: dict) -> dict:
    while isinstance(node, dict) and "$ref" in node:
        node = schema["$defs"][node["$ref"].rsplit("/", 1)[-1]]
    return node


def _variants(schema: dict, node: dict) -> list[dict]:
    """The alternatives of a node (``anyOf`` / ``oneOf``), each dereferenced."""
    node = _deref(schema, node)
    alts = node.get("anyOf") or node.get("oneOf")
    if alts:
        return [v for a in alts for v in _variants(schema, a)]
    return [node]


def _child(schema: dict, node: dict, part) -> list[dict]:
    out = []
    for v in _variants(schema, node):
        if isinstance(part, int):
            if v.get("type") == "array":
                prefix = v.get("prefixItems") or []
                if part < len(prefix):
                    out.append(prefix[part])
                elif "items" in v:
                    out.append(v["items"])
        elif v.get("type", "object") == "object" or "properties" in v:
            props = v.get("properties") or {}
            if part in props:
                out.append(props[part])
                continue
            out += [sub for pattern, sub in (v.get("patternProperties") or {}).items()
                    if re.search(pattern, str(part))]  # named entries (trajectories.NAME)
            if isinstance(v.get("additionalProperties"), dict):
                out.append(v["additionalProperties"])
    return out


def key_types(path: tuple) -> set[str] | None:
    """The JSON-schema types the spec format accepts at ``path`` (a resolved key path);
    None when the key is not in the spec format.  An untyped node (free-form data) gives {"any"}."""
    from cdpr_design.model import spec

    schema = spec.json_schema()
    nodes = [schema]
    for part in path:
        nodes = [c for n in nodes for c in _child(schema, n, part)]
        if not nodes:
            return None
    types: set[str] = set()
    for n in nodes:
        for v in _variants(schema, n):
            types.add(v.get("type", "any"))
    return types


def _resolve(base: dict, key: str) -> tuple:
    try:
        return resolve(base, parse_path(key))
    except ValueError as exc:
        raise InputError(f"{vary_name(key)}: {exc}") from None


def _loc(path: tuple) -> str:
    """A resolved key path as the spec's messages name it: ``cables[0].outlet``."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else ("." if out else "") + str(part)
    return out


def _check_scalar_list(design, param: Param) -> None:
    """A range on a list key (``winch.drum_radius`` takes a number or a list): the spec format must
    take a number there (checked at the range's midpoint), else exit 2."""
    from cdpr_design.batch.variants import with_value
    from cdpr_design.model import spec

    mid = (param.low + param.high) / 2
    try:
        spec.validate(with_value(design.raw, param.path, mid), design.source)
    except SpecError as exc:
        here = [m for p, m in exc.problems if p == _loc(param.path)]
        if here:
            raise InputError(f"{vary_name(param.key)}: a range needs a numeric key; at {mid:g} the spec "
                             f"says: {here[0]}") from None


def _check_choices(design, param: Param) -> None:
    """Every choice gives a valid spec (the other keys at their base values), else exit 2."""
    from cdpr_design.batch.variants import with_value
    from cdpr_design.model import spec

    for c in param.choices:
        try:
            spec.validate(with_value(design.raw, param.path, c), design.source)
        except SpecError as exc:
            problems = "; ".join(f"{p}: {m}" if p else m for p, m in exc.problems)
            raise InputError(f"{vary_name(param.key)}: the choice {quote(c)} makes the spec invalid "
                             f"({problems})") from None


def make_space(design, vary: Sequence[str]) -> Space:
    """The searched keys of ``--vary`` options, checked against the design (see the module notes).

    Raises
    ------
    InputError
        Naming ``--vary KEY``: bad syntax, an unknown key, a key given twice,
        a range on a key that is not a number, LO >= HI, a log range from
        LO <= 0, a choice that makes the spec invalid.
    """
    if not vary:
        raise InputError("--vary: give at least one KEY=LO:HI or KEY=a,b,c to search")
    params = []
    seen: dict[tuple, str] = {}
    for option in vary:
        key, text = _split_option(option)
        path = _resolve(design.raw, key)
        if path in seen:
            raise InputError(f"{vary_name(key)}: the same key as {vary_name(seen[path])}")
        seen[path] = key
        types = key_types(path)
        if types is None:
            raise InputError(f"{vary_name(key)}: not a key of the spec format (see docs/spec-format.md)")
        if ":" in text and "," not in text:
            numeric = types & {"number", "integer", "any"}
            if not numeric and "array" not in types:
                raise InputError(f"{vary_name(key)}: a range needs a numeric key; the key is not a number "
                                 f"({'/'.join(sorted(types))})")
            p = parse_range(key, text, integer=numeric == {"integer"})
        else:
            p = parse_choices(key, text)
        p = Param(p.key, path, p.kind, p.low, p.high, p.log, p.choices)
        if p.kind == "categorical":
            _check_choices(design, p)
        elif not numeric:
            _check_scalar_list(design, p)
        params.append(p)
    plan = Plan(design.raw, tuple(Axis(p.key, p.path, ()) for p in params), design.source)
    return Space(tuple(params), plan)
