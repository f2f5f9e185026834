"""The benchmarks of ``scripts/bench.py``, one module each, on one harness (:mod:`benchmarks.harness`)."""
