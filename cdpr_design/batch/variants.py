"""What a sweep varies: dotted key paths into the spec, their values, the grid of variants.

A sweep varies keys of the spec, given by dotted paths into the validated
spec data (``effector.mass``, ``frame.upper.0``, ``cables.1.outlet.1``,
``tension.1``, ``winch.drum_radius``; a cable may also be named:
``cables.c2.outlet.0``).  Several keys make a full grid, the last key
varying fastest; variant ``i`` is the i-th point of that grid (0-based).
Every variant is validated up front by :func:`make_plan`.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from dataclasses import dataclass
from typing import Any, Iterable, Iterator, Sequence

from cdpr_design.errors import QUOTE_WIDTH, InputError, SpecError, quote

#: Largest sweep run without ``max_variants`` raised (variants): a day of planar2 variants on one core.
MAX_VARIANTS = 100_000
#: Largest sweep ever (variants): its table (sweep.csv) is built in memory, about 1 kB a variant.
HARD_MAX_VARIANTS = 1_000_000

_INT = re.compile(r"^[+-]?\d+$")


def short(text) -> str:
    """``str(text)`` cut to about :data:`~cdpr_design.errors.QUOTE_WIDTH` characters for a message
    (a key or value as given, without the quotes of :func:`~cdpr_design.errors.quote`)."""
    text = str(text)
    return text if len(text) <= QUOTE_WIDTH else text[: QUOTE_WIDTH - 3] + "..."


def _whole(text: str) -> int:
    """A whole number written in ``text`` (digits); ValueError naming it when Python refuses
    its size (more than 4,300 digits)."""
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"{quote(text.strip())} has too many digits for a whole number") from None


def _scalar(text: str):
    """``"2"`` -> 2, ``"0.5"`` -> 0.5, anything else stays text (a motor name)."""
    t = text.strip()
    if _INT.match(t):
        return _whole(t)
    try:
        v = float(t)
    except ValueError:
        return t
    if not math.isfinite(v):
        raise ValueError(f"expected finite numbers, got {quote(t)}")
    return v


def _tidy(v: float) -> float:
    """A linspace value rounded to 12 significant digits (0.30000000000000004 -> 0.3)."""
    return float(f"{v:.12g}")


def parse_values(text: str) -> tuple:
    """Parse VALUES: ``a,b,c`` (numbers or names) or ``start:stop:count`` (inclusive linspace).

    Raises
    ------
    ValueError
        With a message saying what was expected.
    """
    text = text.strip()
    if not text:
        raise ValueError("expected values: a,b,c or start:stop:count")
    if ":" in text and "," not in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"expected start:stop:count, got {quote(text)}")
        try:
            start, stop = float(parts[0]), float(parts[1])
        except ValueError:
            raise ValueError(f"expected numbers in start:stop:count, got {quote(text)}") from None
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise ValueError(f"expected finite start and stop, got {quote(text)}")
        if not _INT.match(parts[2].strip()) or _whole(parts[2]) < 1:
            raise ValueError(f"expected a whole count >= 1 in start:stop:count, got {quote(parts[2])}")
        n = _whole(parts[2])
        if n > HARD_MAX_VARIANTS:
            raise ValueError(f"expected a count of at most {HARD_MAX_VARIANTS:,} in start:stop:count, "
                             f"got {quote(parts[2].strip())}")
        if n == 1:
            return (_tidy(start),)
        return tuple(_tidy(start + (stop - start) * k / (n - 1)) for k in range(n))
    items = [s for s in text.split(",")]
    if any(not s.strip() for s in items):
        raise ValueError(f"expected comma-separated values without empty entries, got {quote(text)}")
    return tuple(_scalar(s) for s in items)


def parse_vary(option: str) -> tuple[str, tuple]:
    """One ``--vary KEY=VALUES`` option: (key, values).

    Raises
    ------
    InputError
        Bad syntax (exit 2), naming the option.
    """
    key, sep, values = option.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InputError(f"--vary {quote(option)}: expected KEY=VALUES (e.g. effector.mass=0.5,1,2 or "
                         "frame.upper.0=1.2:2.0:5)")
    try:
        return key, parse_values(values)
    except ValueError as exc:
        raise InputError(f"--vary {short(key)}: {exc}") from None


def vary_from_spec(section: dict | None) -> list[tuple[str, tuple]]:
    """The ``sweep.vary`` mapping of a spec: a list of (key, values).

    A value may be a list (each entry one value, lists allowed for vector
    keys), a VALUES string (``"0.5:2:4"``, ``"a,b"``) or a single scalar.
    """
    vary = (section or {}).get("vary") or {}
    out = []
    problems = []
    for key, v in vary.items():
        where = f"sweep.vary.{short(key)}"
        if isinstance(v, str):
            try:
                out.append((str(key), parse_values(v)))
            except ValueError as exc:
                problems.append((where, str(exc)))
        elif isinstance(v, list):
            if not v:
                problems.append((where, "expected at least one value"))
            else:
                out.append((str(key), tuple(v)))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out.append((str(key), (v,)))
        else:
            problems.append((where, f"expected a list of values or 'start:stop:count', got {quote(v)}"))
    if problems:
        raise SpecError(problems)
    return out


def parse_path(key: str) -> tuple:
    """``cables.1.outlet.1`` or ``cables[1].outlet[1]`` -> ("cables", 1, "outlet", 1)."""
    text = re.sub(r"\[(\w+)\]", r".\1", key.strip())
    parts = text.split(".")
    if not text or any(p == "" for p in parts):
        raise ValueError(f"expected a dotted key path such as effector.mass, got {quote(key)}")
    return tuple(_whole(p) if _INT.match(p) else p for p in parts)


def _locate(container, part, trail: str):
    """The index or key ``part`` addresses in ``container`` (lists: an index or a cable name)."""
    if isinstance(container, dict):
        if isinstance(part, int):
            part = str(part)
        return part
    if isinstance(container, list):
        if isinstance(part, int):
            if not -len(container) <= part < len(container):
                raise ValueError(f"{short(trail)}: index {short(part)} is out of range "
                                 f"(the spec has {len(container)} entries)")
            return part % len(container)
        for i, item in enumerate(container):
            if isinstance(item, dict) and item.get("name") == part:
                return i
        raise ValueError(f"{short(trail)}: no entry named {quote(part)}")
    raise ValueError(f"{short(trail)} is a value ({quote(container)}), not a section or a list")


def resolve(base: dict, path: tuple) -> tuple:
    """Check a key path against the base spec data; return it with names turned into indices.

    Missing mapping keys are allowed (an optional key the base spec leaves
    out); the validation of each variant then decides whether the key exists
    in the spec format at all.
    """
    node: Any = base
    out = []
    trail = ""
    for k, part in enumerate(path):
        idx = _locate(node, part, trail or "the spec")
        out.append(idx)
        trail = f"{trail}.{part}" if trail else str(part)
        if isinstance(node, dict) and idx not in node:
            rest = path[k + 1:]
            if any(isinstance(p, int) for p in rest):
                raise ValueError(f"{short(trail)} is not in the spec; vary the whole key rather than its entries")
            out.extend(rest)
            return tuple(out)
        node = node[idx]
    return tuple(out)


def with_value(data, path: tuple, value):
    """A copy of ``data`` with the key at ``path`` set to ``value``.

    Only the containers along the path are copied; the rest is shared with
    ``data`` (never modified).
    """
    if not path:
        return value
    head, rest = path[0], path[1:]
    if isinstance(data, dict):
        new = dict(data)
        new[head] = with_value(data.get(head, {}) if rest else None, rest, value)
        return new
    new = list(data)
    new[head] = with_value(data[head], rest, value)
    return new


def _show(v) -> str:
    if isinstance(v, float):
        return format(v, ".10g")
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_show(x) for x in v) + "]"
    return str(v)


@dataclass(frozen=True)
class Axis:
    """One varied key: the dotted key as given, the resolved path, the values."""

    key: str
    path: tuple
    values: tuple


@dataclass(frozen=True)
class Plan:
    """A sweep: the base spec data and the varied keys (a full grid)."""

    base: dict
    axes: tuple[Axis, ...]
    source: str | None = None

    def __len__(self) -> int:
        return math.prod(len(a.values) for a in self.axes)

    @property
    def keys(self) -> list[str]:
        return [a.key for a in self.axes]

    def values(self, index: int) -> tuple:
        """The varied values of variant ``index`` (the last key varies fastest)."""
        out = []
        for a in reversed(self.axes):
            index, r = divmod(index, len(a.values))
            out.append(a.values[r])
        return tuple(reversed(out))

    def variants(self, skip: Iterable[int] = ()) -> Iterator[tuple[int, tuple]]:
        skip = set(skip)
        for i, vals in enumerate(itertools.product(*(a.values for a in self.axes))):
            if i not in skip:
                yield i, vals

    def data(self, values: Sequence) -> dict:
        """The spec data of the variant with these varied values."""
        d = self.base
        for a, v in zip(self.axes, values):
            d = with_value(d, a.path, v)
        return d

    def describe(self, index: int, values: Sequence | None = None) -> str:
        """``variant 3 (effector.mass=2, frame.upper.0=1.8)``."""
        values = self.values(index) if values is None else values
        return f"variant {index} (" + ", ".join(f"{short(a.key)}={short(_show(v))}"
                                                for a, v in zip(self.axes, values)) + ")"

    def fingerprint(self, options) -> str:
        """A hash of everything that decides the rows (for resuming the right sweep);
        ``options``: the sweep's :class:`~cdpr_design.batch.local.Options`."""
        from cdpr_design import __version__

        blob = json.dumps({"base": self.base, "axes": [[a.key, list(a.values)] for a in self.axes],
                           "options": options.fingerprint(), "version": __version__},
                          sort_keys=True, default=repr)
        return hashlib.sha256(blob.encode()).hexdigest()[:20]


def check_count(lengths: Sequence[int], max_variants: int = MAX_VARIANTS) -> None:
    """Refuse a sweep of more than ``max_variants`` (at most :data:`HARD_MAX_VARIANTS`) variants:
    the product of the keys' value counts, computed before a single variant is built."""
    n = math.prod(lengths)
    limit = min(max_variants, HARD_MAX_VARIANTS)
    if n > limit:
        hint = ("pass --max-variants to raise the limit" if n <= HARD_MAX_VARIANTS
                else f"{HARD_MAX_VARIANTS:,} is the most any sweep runs")
        raise InputError(f"--vary: the sweep would have {n:,} variants ({' x '.join(map(str, lengths))}), "
                         f"more than {limit:,}; {hint}")


def make_plan(design, vary: Sequence[tuple[str, Sequence]], max_problems: int = 10,
              max_variants: int = MAX_VARIANTS) -> Plan:
    """Check a sweep definition against the design and validate every variant up front.

    Parameters
    ----------
    design : Design
        The base design (its ``raw`` spec data is varied).
    vary : list of (key, values)
        From :func:`parse_vary` / :func:`vary_from_spec`.
    max_variants : int
        Most variants allowed (:func:`check_count`; default :data:`MAX_VARIANTS`).

    Raises
    ------
    SpecError
        An unknown key path, a key given twice, or a variant the spec format
        rejects; each message names the variant by index and varied values.
    InputError
        More than ``max_variants`` variants.
    """
    from cdpr_design.model import spec

    base = design.raw
    if not vary:
        raise InputError("nothing to vary: give --vary KEY=VALUES or a sweep.vary section in the spec")
    axes = []
    problems = []
    seen = {}
    for key, values in vary:
        try:
            path = resolve(base, parse_path(key))
        except ValueError as exc:
            problems.append((f"--vary {short(key)}", str(exc)))
            continue
        if path in seen:
            problems.append((f"--vary {short(key)}", f"the same key as {short(seen[path])}"))
            continue
        seen[path] = key
        if not values:
            problems.append((f"--vary {short(key)}", "expected at least one value"))
            continue
        axes.append(Axis(key, path, tuple(values)))
    if problems:
        raise SpecError(problems, design.source)
    check_count([len(a.values) for a in axes], max_variants)
    plan = Plan(base, tuple(axes), design.source)
    bad = 0
    seen_problems: set = set()
    hidden = 0
    for i, vals in plan.variants():
        try:
            spec.validate(plan.data(vals))
        except SpecError as exc:
            bad += 1
            new = [(p, m) for p, m in exc.problems if (p, m) not in seen_problems]
            seen_problems.update(exc.problems)
            if not new:
                hidden += 1  # the same problem as a variant already named (an unknown key)
            elif bad - hidden <= max_problems:
                problems.extend((f"{plan.describe(i, vals)}: {short(p)}" if p else plan.describe(i, vals), m)
                                for p, m in new)
    if bad:
        shown = min(bad - hidden, max_problems)
        if bad > shown:
            problems.append(("", f"{bad} of {len(plan)} variants are rejected by the spec format "
                                 f"({bad - shown} not listed)"))
        raise SpecError(problems, design.source)
    return plan
