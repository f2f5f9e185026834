"""A finished study as tables: the trials, the best trial, the Pareto front and its knee, importances.

Best trial
----------
Only *complete* trials (every objective defined, every limit held) are
candidates.  One objective: the best value, the earliest trial on a tie.
Several objectives: the Pareto front is the set of complete trials that no
other complete trial dominates (another trial is at least as good in every
objective and better in one); ``best.yaml`` is its *knee*, the compromise
point: each objective is scaled to [0, 1] over the front (0 its best value
on the front, 1 its worst) and the trial nearest the ideal point (0, ..., 0)
in the Euclidean sense is chosen (compromise programming, Zeleny 1973;
earliest trial on a tie).  The rule needs no weights and is invariant to
the objectives' units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from cdpr_design.optimize.problem import Problem

STATES = ("complete", "infeasible", "failed")


@dataclass
class Trial:
    """One finished trial as plain data."""

    number: int
    state: str
    params: dict
    values: list[float] | None
    figures: dict = field(default_factory=dict)
    reason: str = ""
    seconds: float | None = None

    def as_dict(self, problem: Problem) -> dict:
        out = {"trial": self.number, "state": self.state, "params": dict(self.params)}
        if self.values is not None:
            out["objectives"] = {o.figure: v for o, v in zip(problem.objectives, self.values)}
        out["figures"] = dict(self.figures)
        if self.reason:
            out["reason"] = self.reason
        return out


def trials(study_trials: Sequence) -> list[Trial]:
    """Finished optuna trials (:func:`cdpr_design.optimize.study.finished`) as :class:`Trial`, by number."""
    out = []
    for t in study_trials:
        res = t.user_attrs.get("result") or {}
        state = res.get("state", "failed")
        values = list(t.values) if t.values is not None and state != "failed" else None
        out.append(Trial(t.number, state, dict(t.params), values, dict(res.get("figures") or {}),
                         res.get("reason", "" if res else "no result recorded"), res.get("seconds")))
    return sorted(out, key=lambda r: r.number)


def table(problem: Problem, rows: Sequence[Trial]) -> tuple[list[str], list[list]]:
    """``optimize.csv``: trial, state, the searched keys, the recorded figures, reason, seconds."""
    keys, figs = problem.space.keys, problem.figure_columns
    header = ["trial", "state"] + keys + figs + ["reason", "seconds"]
    out = [[r.number, r.state] + [r.params.get(k) for k in keys] + [r.figures.get(f) for f in figs]
           + [r.reason, r.seconds] for r in rows]
    return header, out


def _scores(problem: Problem, r: Trial) -> list[float]:
    """Objective values oriented for minimisation."""
    return [-v if o.maximize else v for o, v in zip(problem.objectives, r.values)]


def dominates(a: Sequence[float], b: Sequence[float]) -> bool:
    """``a`` dominates ``b`` (minimisation): no worse anywhere, better somewhere."""
    return all(x <= y for x, y in zip(a, b)) and any(x < y for x, y in zip(a, b))


def pareto(problem: Problem, rows: Sequence[Trial]) -> list[Trial]:
    """The complete trials no other complete trial dominates, by trial number."""
    done = [r for r in rows if r.state == "complete"]
    scores = [_scores(problem, r) for r in done]
    return [r for r, s in zip(done, scores) if not any(dominates(o, s) for o in scores)]


def knee(problem: Problem, front: Sequence[Trial]) -> Trial | None:
    """The front's compromise point (module notes); None for an empty front."""
    if not front:
        return None
    scores = [_scores(problem, r) for r in front]
    lo = [min(c) for c in zip(*scores)]
    hi = [max(c) for c in zip(*scores)]

    def dist(s):
        return math.sqrt(sum(((x - a) / (b - a) if b > a else 0.0) ** 2 for x, a, b in zip(s, lo, hi)))

    return min(zip(front, scores), key=lambda rs: (dist(rs[1]), rs[0].number))[0]


def best(problem: Problem, rows: Sequence[Trial]) -> Trial | None:
    """The best complete trial (one objective) or the Pareto front's knee (several); None if no
    trial is complete."""
    if len(problem.objectives) > 1:
        return knee(problem, pareto(problem, rows))
    done = [r for r in rows if r.state == "complete"]
    if not done:
        return None
    return min(done, key=lambda r: (_scores(problem, r)[0], r.number))


def convergence(problem: Problem, rows: Sequence[Trial]) -> list[float | None]:
    """Best complete value so far after each trial (one objective; None before the first)."""
    o = problem.objectives[0]
    out, cur = [], None
    for r in rows:
        if r.state == "complete":
            v = r.values[0]
            cur = v if cur is None else (max(cur, v) if o.maximize else min(cur, v))
        out.append(cur)
    return out


#: Complete trials below which parameter importances are not computed.
MIN_IMPORTANCE_TRIALS = 10


def importances(study, problem: Problem) -> dict[str, dict[str, float]]:
    """Each objective's parameter importances (PED-ANOVA, Watanabe et al. 2023: how much each key's
    distribution differs between the top 10 % trials and all, over trials with every objective
    defined); empty with one key or fewer than :data:`MIN_IMPORTANCE_TRIALS` such trials."""
    import warnings

    import optuna

    if len(problem.space.params) < 2:
        return {}
    done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    if len(done) < MIN_IMPORTANCE_TRIALS:
        return {}
    out = {}
    for k, o in enumerate(problem.objectives):
        sign = -1.0 if o.maximize else 1.0  # PED-ANOVA takes lower as better
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # optuna's reminder that lower is better: we orient the target
                imp = optuna.importance.get_param_importances(
                    study, evaluator=optuna.importance.PedAnovaImportanceEvaluator(), params=problem.space.keys,
                    target=lambda t, k=k, sign=sign: sign * t.values[k])
        except (ValueError, RuntimeError):  # too few distinct values to compare
            continue
        out[o.figure] = {key: float(v) for key, v in imp.items()}
    return out
