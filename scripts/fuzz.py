"""The long fuzz run: tests/test_fuzz.py with many times CI's examples and fresh random seeds.

    python scripts/fuzz.py              # 20 x CI's examples (about 45,000), 20-60 min on 2 cores
    python scripts/fuzz.py --scale 5    # a quicker pass
    python scripts/fuzz.py -- -k load   # pytest arguments after --

Hypothesis keeps the failing examples it finds in .hypothesis/ and prints a
patch that adds them to the tests; a spec that fails belongs in
tests/data/fuzz_corpus/ (first line ``# expect: ...``), a failing call of an
entry point in the "found" section of tests/test_fuzz.py.  CI runs the fixed
set of scale 1 (``pytest`` runs it with the other tests).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=20.0, help="times CI's examples (default 20)")
    ap.add_argument("pytest_args", nargs="*", help="further pytest arguments (after --)")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "pytest", "-q", str(ROOT / "tests" / "test_fuzz.py"), "--fuzz-scale", str(a.scale),
           "--hypothesis-show-statistics", *a.pytest_args]
    rc = subprocess.call(cmd, cwd=ROOT)
    print(f"fuzz run at scale {a.scale:g}: exit {rc} after {time.perf_counter() - t0:.0f} s")
    return rc


if __name__ == "__main__":
    sys.exit(main())
