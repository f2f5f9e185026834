"""``python -m cdpr_design`` and the ``cdpr-design`` console script."""

import gc
import importlib
import signal
import sys


def main() -> None:
    # a command allocates most of its objects once, at start-up (typer, pydantic, numba), and
    # keeps them: collecting the youngest generation every 200,000 allocations instead of every
    # 700 walks those objects far fewer times (figures: docs/performance.md).  Cycles made later are still collected
    gc.set_threshold(200_000, 20, 20)
    # past a file-size limit (``ulimit -f``) a write fails with EFBIG, which the command reports (exit 2
    # naming the file), instead of SIGXFSZ ending the process: Python ignores it at start-up, said here
    # for an interpreter embedded without its signal set-up
    if hasattr(signal, "SIGXFSZ"):
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    # start the picture worker before importing the command line (typer, rich, pydantic):
    # its matplotlib import then overlaps the rest of the parent's start-up.  numpy first:
    # the worker is a copy of this process where it can be (plots.worker.can_fork), which
    # then has numpy, Python and its site already (less CPU than a new interpreter)
    from cdpr_design.cli import env

    env.settle_blas_threads()  # before anything imports numpy
    env.use_kernel_cache()  # before anything imports numba
    from cdpr_design.plots import worker as _picture_worker

    if _picture_worker.wanted(sys.argv[1:]):
        importlib.import_module("numpy")
        _picture_worker.prestart(enabled=env.picture_worker_enabled())
    from cdpr_design.cli.app import main as cli_main

    cli_main()


if __name__ == "__main__":
    main()
