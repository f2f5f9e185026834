"""Shared fixtures: paths and small designs built through the spec format (helpers.py builds them)."""

from __future__ import annotations

import os
import signal

import pytest

from cdpr_design.cli import env as _cli_env

# numba's cache as the command line chooses it (a folder per version of the kernels' sources), before
# anything imports numba: the tests' kernels and the commands they start share it
_cli_env.use_kernel_cache()

from .helpers import DESIGNS, PLANAR2, ROOT, planar2_raw, random_planar_data, write_spec  # noqa: F401


def _sigint_handled() -> None:
    """A test session started with SIGINT ignored (``nohup``, a shell's background job) would pass
    that on to every command the tests start, and the tests of Ctrl-C would see no interrupt (exit
    0, not 130). Handle SIGINT as usual here: a child then starts with the default disposition, as
    from a terminal."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        try:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        except ValueError:  # not the main thread: nothing can be changed from here
            pass


_sigint_handled()


@pytest.fixture
def planar2_data() -> dict:
    """designs/planar2.yaml as plain data (a fresh copy per test)."""
    return planar2_raw()


@pytest.fixture(scope="module")
def planar2():
    """designs/planar2.yaml loaded (one per test module)."""
    from cdpr_design.model import spec

    return spec.load(PLANAR2)


@pytest.fixture(scope="module")
def catalogue():
    """The shipped motor catalogue."""
    from cdpr_design.model import spec

    return spec.load_catalogue()


def pytest_addoption(parser):
    parser.addoption("--fuzz-scale", type=float, default=1.0,
                     help="Run the fuzz tests (test_fuzz.py) with this many times their examples, fresh random "
                          "seeds when > 1 (CI: 1, a fixed set).")


def pytest_configure(config):
    # read by test_fuzz.py when it is imported (its hypothesis settings are made then)
    os.environ["CDPR_FUZZ_SCALE"] = str(config.getoption("--fuzz-scale"))

