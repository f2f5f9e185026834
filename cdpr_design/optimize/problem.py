"""A design search problem (keys, objectives, limits, evaluation options) and one trial's evaluation.

A trial is evaluated like a ``sweep`` variant
(:func:`cdpr_design.batch.local.evaluate_variant`: the spec rebuilt with the
trial's values, then :func:`cdpr_design.design.evaluate.evaluate`, the code
behind ``report``), asking only for the figures the objectives and limits
need: the task box is swept, the whole workspace grid only when a figure or
a requirement needs it (:func:`cdpr_design.design.evaluate.parts_needed`).

Outcomes (:class:`Outcome`):

- ``complete``: every objective defined, every limit held;
- ``infeasible``: every objective defined, a limit violated (the reason
  names it); handed to the sampler with its violations;
- ``failed``: the variant could not be evaluated (the spec rejects it, a
  solver raised) or an objective is undefined; the reason says why.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from typing import Sequence

from cdpr_design.batch.local import Job, Options, evaluate_variant
from cdpr_design.errors import InputError, quote
from cdpr_design.optimize import objectives as obj
from cdpr_design.optimize.space import Space, make_space, vary_name


@dataclass(frozen=True)
class Problem:
    """Everything a worker needs to evaluate trials (picklable: sent to worker processes)."""

    name: str
    space: Space
    objectives: tuple[obj.Objective, ...]
    limits: tuple[obj.Limit, ...]
    checks: tuple[str, ...]  # the spec's requirements that are checked
    options: Options  # evaluation options (step, motor, trajectory, catalogue, engine, figures)
    workspace: bool  # trials sweep the whole workspace grid (else only the task box)

    @property
    def directions(self) -> list[str]:
        return [o.direction for o in self.objectives]

    @property
    def figure_columns(self) -> list[str]:
        """The figures a trial records: objectives, limits, the checks' figures (first appearance)."""
        cols: dict[str, None] = {}
        for o in self.objectives:
            cols.setdefault(o.figure, None)
        for lim in self.limits:
            cols.setdefault(lim.figure, None)
        for c in self.checks:
            for f in obj.CHECK_FIGURES[c]:
                cols.setdefault(f, None)
        return list(cols)

    @property
    def constraint_names(self) -> list[str]:
        """The limits as the sampler sees them: the spec's checks, then ``--require`` limits."""
        return list(self.checks) + [lim.text() for lim in self.limits]

    def job(self) -> Job:
        return Job(self.space.plan, self.options)

    def fingerprint(self) -> str:
        """A hash of everything that decides a trial's outcome (a resumed study must be this one's)."""
        from cdpr_design import __version__

        blob = json.dumps({"base": self.space.plan.base, "params": [p.describe() for p in self.space.params],
                           "objectives": [[o.figure, o.maximize] for o in self.objectives],
                           "limits": [lim.text() for lim in self.limits], "checks": list(self.checks),
                           "options": self.options.fingerprint(), "version": __version__},
                          sort_keys=True, default=repr)
        return hashlib.sha256(blob.encode()).hexdigest()[:20]

    def describe(self) -> dict:
        return {"keys": [p.describe() for p in self.space.params],
                "objectives": [{"figure": o.figure, "direction": o.direction} for o in self.objectives],
                "limits": [lim.text() for lim in self.limits], "spec_requirements": list(self.checks),
                "evaluates": "workspace grid and task box" if self.workspace else "task box"}


def make_problem(design, vary: Sequence[str], maximize: Sequence[str] | None, minimize: Sequence[str] | None,
                 require: Sequence[str] | None, options: Options) -> Problem:
    """Check every option against the design (exit 2 naming the option) and build the problem.

    ``options``: the evaluation options (their ``figures`` are set here).
    """
    from dataclasses import replace

    from cdpr_design.design.evaluate import parts_needed

    space = make_space(design, vary)
    catalogue = _catalogue(options)
    _check_motor_option(options.motor, catalogue)
    _check_motor_choices(space, catalogue)
    objectives = obj.make_objectives(design, maximize, minimize)
    limits = tuple(obj.parse_limit(design, t) for t in require or ())
    checks = tuple(obj.spec_checks(design, options.motor))
    figures = obj.figures_needed(objectives, limits)
    options = replace(options, figures=figures)
    workspace = parts_needed(design, figures, options.motor)[0]
    return Problem(design.name, space, tuple(objectives), limits, checks, options, workspace)


def _catalogue(options: Options):
    """The motor catalogue of the evaluations (``options.catalogue``, else the shipped one)."""
    if options.catalogue is not None:
        return options.catalogue
    from cdpr_design.model import spec

    return spec.load_catalogue()


def _check_motor_option(motor: str | None, catalogue) -> None:
    """``--motor`` (every trial's motor) must be in the catalogue, else exit 2, as for ``report``."""
    if motor is not None and catalogue.motor(motor) is None:
        known = ", ".join(m.name for m in catalogue.motors)
        raise InputError(f"--motor: {quote(motor)} is not in the motor catalogue (known: {known}; "
                         "add it with --catalogue FILE)")


def _check_motor_choices(space: Space, catalogue) -> None:
    """A motor choice (``winch.motor``, ``cables.i.winch.motor``) must be in the catalogue, else exit 2."""
    for p in space.params:
        if p.kind == "categorical" and p.path[-1] == "motor":
            bad = [c for c in p.choices if catalogue.motor(str(c)) is None]
            if bad:
                known = ", ".join(m.name for m in catalogue.motors)
                raise InputError(f"{vary_name(p.key)}: the choice {quote(bad[0])} makes the spec invalid (not in the "
                                 f"motor catalogue; known: {known}; add it with --catalogue FILE)")


@dataclass
class Outcome:
    """One trial's result: ``state`` (complete, infeasible, failed), the objective values (None when
    failed), the limits' violations, the recorded figures, the reason (empty when complete)."""

    state: str
    values: list[float] | None
    violations: list[float] = field(default_factory=list)
    figures: dict = field(default_factory=dict)
    reason: str = ""


def judge(problem: Problem, row: dict | None, error: str = "") -> Outcome:
    """The outcome of a trial from its report row (or the error that stopped its evaluation)."""
    if row is None or error:
        return Outcome("failed", None, reason=error or "not evaluated")
    figures = {k: row.get(k) for k in problem.figure_columns}
    values = []
    for o in problem.objectives:
        v = obj.number(row.get(o.figure))
        if v is None:
            return Outcome("failed", None, figures=figures, reason=obj.undefined_reason(o.figure))
        values.append(v)
    violations, failed = [], []
    for c in problem.checks:
        v, text = obj.check_violation(c, row)
        violations.append(v)
        if v > 0:
            failed.append(text)
    for lim in problem.limits:
        v = lim.violation(row.get(lim.figure))
        violations.append(v)
        if v > 0:
            f = obj.number(row.get(lim.figure))
            failed.append(f"{lim.text()} ({lim.figure} = {'undefined' if f is None else f'{f:.4g}'})")
    if failed:
        return Outcome("infeasible", values, violations, figures, "fails " + "; ".join(failed))
    return Outcome("complete", values, violations, figures)


def evaluate(problem: Problem, job: Job, number: int, values: dict) -> Outcome:
    """Build and evaluate the variant of a trial (``values``: key -> value); never raises for a bad
    variant (it is a failed outcome)."""
    rec = evaluate_variant(job, number, [values[k] for k in problem.space.keys])
    return judge(problem, rec["figures"] if not rec["error"] else None, rec["error"])
