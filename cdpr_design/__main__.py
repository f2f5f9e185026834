"""``python -m cdpr_design`` and the ``cdpr-design`` console script."""

import sys


def main() -> None:
    # start the picture worker before importing the command line (typer, rich,
    # numpy): its matplotlib import then overlaps all of the parent's start-up
    from cdpr_design.cli import env
    from cdpr_design.plots import worker as _picture_worker

    if _picture_worker.wanted(sys.argv[1:]):
        _picture_worker.prestart(enabled=env.picture_worker_enabled())
    from cdpr_design.cli.app import main as cli_main

    cli_main()


if __name__ == "__main__":
    main()
