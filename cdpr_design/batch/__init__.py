"""Batch parameter sweeps over copies of a design (``cdpr-design sweep``).

=============  ==============================================================
module         what
=============  ==============================================================
``variants``   --vary KEY=VALUES, dotted key paths, the grid of variants (Plan)
``local``      one variant's evaluation, in this process or a process pool
``dask``       the same on Dask (a LocalCluster or a running scheduler)
``sweep``      :func:`run`: every variant of a plan, rows to a callback
``table``      ``sweep.csv`` rows, the best variants, regression checks
``results``    a finished sweep as a table (the Python API's result)
=============  ==============================================================

Nothing here touches files: the command line journals the rows and writes
the tables (:mod:`cdpr_design.jobs.sweep`).
"""

from cdpr_design.batch.dask import check_scheduler
from cdpr_design.batch.local import (JOURNAL_VERSION, Options, RunStats, chunk_size, chunks, default_workers,
                                     guided_chunks, record, wait_closed)
from cdpr_design.batch.sweep import run
from cdpr_design.batch.table import (HEADLINE, HIGHER_IS_BETTER, KNOWN_FIGURES, LOWER_IS_BETTER, NUMERIC_FIGURES,
                                     Difference, best, check_baseline, compare, parse_rank, table)
from cdpr_design.batch.variants import (HARD_MAX_VARIANTS, MAX_VARIANTS, Axis, Plan, make_plan, parse_path,
                                        parse_values, parse_vary, resolve, vary_from_spec, with_value)

__all__ = ["HARD_MAX_VARIANTS", "MAX_VARIANTS", "HEADLINE", "HIGHER_IS_BETTER", "JOURNAL_VERSION", "KNOWN_FIGURES",
           "LOWER_IS_BETTER", "NUMERIC_FIGURES", "Axis", "Difference", "Options", "Plan", "RunStats", "best",
           "check_baseline", "check_scheduler", "chunk_size", "chunks", "compare",
           "default_workers", "guided_chunks", "make_plan", "parse_path", "parse_rank", "parse_values",
           "parse_vary", "record", "resolve", "run", "table", "vary_from_spec", "wait_closed", "with_value"]
