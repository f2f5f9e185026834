"""Design search over continuous and categorical keys of a spec (``cdpr-design optimize``), with optuna.

=============  ==============================================================
module         what
=============  ==============================================================
``space``      --vary KEY=LO:HI[:log] / KEY=a,b,c: the searched keys
``objectives`` --maximize / --minimize / --require figures, the spec's checks
``problem``    the search problem and one trial's evaluation and outcome
``study``      the optuna study in SQLite: workers, exactly N trials, resuming
``results``    the trials as tables, the best trial, Pareto front, knee
=============  ==============================================================

Nothing here writes output files (:mod:`cdpr_design.jobs.optimize` does); the
study's SQLite file, which optuna keeps, is the only file touched.  optuna is
imported on first use.
"""

from cdpr_design.optimize.objectives import FIGURES, Limit, Objective, known_figures
from cdpr_design.optimize.problem import Outcome, Problem, judge, make_problem
from cdpr_design.optimize.results import Trial, best, convergence, dominates, importances, knee, pareto, table
from cdpr_design.optimize.space import Param, Space, make_space
from cdpr_design.optimize.study import DB, RunStats, finished, run

__all__ = ["DB", "FIGURES", "Limit", "Objective", "Outcome", "Param", "Problem", "RunStats", "Space", "Trial", "best",
           "convergence", "dominates", "finished", "importances", "judge", "knee", "known_figures", "make_problem",
           "make_space", "pareto", "run", "table"]
