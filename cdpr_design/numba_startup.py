"""numba's start-up in this package's processes: two shortcuts.

Every command that sweeps starts numba afresh, and numba's start-up is a fixed
cost under every one of them (IPAnema 3's ``workspace``: about a fifth of the
command before these).  Most of it is set-up that loading code compiled on an
earlier run does not need:

1. :func:`install_lazy_loading`.  Before every load from its on-disk cache,
   numba calls ``target_context.refresh()``: it imports every implementation
   module it has (random generators, typed containers, polynomials, datetime,
   jitclass ...) and registers their lowerings and typing templates, 0.15-0.2 s
   -- for code that is machine code already.  For the functions of this package
   the load skips it and only initialises numba's runtime (the allocator the
   allocating kernels link against).
2. :func:`load_blas_check`.  numba's compiler set-up imports
   ``scipy.linalg.cython_blas`` only to learn that BLAS is there, and importing
   it by name runs the whole of ``scipy.linalg`` first: 0.2-0.3 s for a module
   nothing here calls.  Before a function of this package is compiled (a cache
   miss), the check is answered with that one extension module instead.

Neither changes what runs: numba refreshes its context itself before any
compilation (``CompilerBase``) and when a lowering is first looked up
(``BaseContext.get_function``), so a cache miss, or numba code of another
library in the same process, gets numba's full set-up as without this.  The
lazy load is installed only on the numba versions it was read against and
tested with (:data:`TESTED_NUMBA`); any other version loads as numba does,
and so does anything laid out otherwise.  Tests: ``tests/test_numba_startup.py`` (what a fresh
process imports, cached and compiled, and a user's compile after a lazy load)
and ``tests/test_jit_cache.py`` (the same numbers loaded as compiled).

This module is below every layer that compiles; :mod:`cdpr_design.kernels` and
:mod:`cdpr_design.io.csvfast` call :func:`install_lazy_loading` as they are imported,
before any of their functions is first called.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os
import sys

#: The package whose functions load lazily (their module's name starts with it).
PACKAGE = __name__.rpartition(".")[0] + "."
#: numba releases whose ``Cache.load_overload`` the lazy load replaces (read and tested: 0.68.1).
TESTED_NUMBA = ((0, 68),)

_BLAS_MODULE = "scipy.linalg.cython_blas"


def load_blas_check() -> bool:
    """Import numba's array functions with their BLAS check answered cheaply; True if it was.

    ``numba.np.arraymath`` checks at import -- when numba first sets up its
    compiler in a process -- that ``scipy.linalg.cython_blas`` imports.  Here that
    extension module is loaded from its file (4 ms) and stands in ``sys.modules``
    while ``numba.np.arraymath`` is imported, then is taken out again, so the
    process has no half-imported ``scipy.linalg``: code that uses BLAS or LAPACK
    later (``np.linalg`` in a kernel, ``scipy.linalg``) imports it in full as
    without this, and gets the same module object (Cython keeps one per process).
    Anything unexpected (no scipy, another layout): returns False and numba
    imports ``scipy.linalg`` itself, as without this."""
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        return False
    try:
        scipy = importlib.util.find_spec("scipy")  # locates the package without importing it
        folder = os.path.join(scipy.submodule_search_locations[0], "linalg")
        path = next(p for p in (os.path.join(folder, "cython_blas" + suffix)
                                for suffix in importlib.machinery.EXTENSION_SUFFIXES) if os.path.exists(p))
        spec = importlib.util.spec_from_file_location(_BLAS_MODULE, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    except Exception:  # noqa: BLE001 -- any failure leaves numba's own import to run
        return False
    sys.modules[_BLAS_MODULE] = module
    try:
        importlib.import_module("numba.np.arraymath")  # its check finds the module
    finally:
        # Out again, unless scipy.linalg got imported meanwhile (by another thread: this runs
        # at a compile, on whichever thread compiles): then the entry is scipy's own, the
        # same module object (Cython keeps one per process), and stays.
        if sys.modules.get(_BLAS_MODULE) is module and "scipy.linalg" not in sys.modules:
            del sys.modules[_BLAS_MODULE]
    return True


def ours(cache, target_context=None) -> bool:
    """True if numba ``cache`` is the on-disk cache of a CPU function (``@njit``) of this
    package (and ``target_context``, if given, numba's CPU context): the loads made lazy."""
    from numba.core import caching
    from numba.core.cpu import CPUContext

    return (isinstance(cache, caching.FunctionCache)
            and (target_context is None or isinstance(target_context, CPUContext))
            and getattr(getattr(cache, "_py_func", None), "__module__", "").startswith(PACKAGE))


def _numba_tested() -> bool:
    import numba

    try:
        version = tuple(int(part) for part in numba.__version__.split(".")[:2])
    except ValueError:  # a development build: not one of the tested releases
        return False
    return version in TESTED_NUMBA


def install_lazy_loading() -> bool:
    """Make numba load this package's cached functions without its compiler set-up (see the
    module's description); True if installed (now or before), False where numba is not one of
    :data:`TESTED_NUMBA` or is laid out otherwise (numba then loads them its own way)."""
    from numba.core import caching

    cache = getattr(caching, "Cache", None)
    numba_load = getattr(cache, "load_overload", None)
    if getattr(numba_load, "_lazy_for", None) == PACKAGE:
        return True
    if numba_load is None or not _numba_tested() or not hasattr(cache, "_load_overload") \
            or not hasattr(cache, "_guard_against_spurious_io_errors"):
        return False
    from numba.core.runtime import rtsys

    def load_overload(self, sig, target_context):
        if not ours(self, target_context):
            return numba_load(self, sig, target_context)
        rtsys.initialize(target_context)
        cres = None
        with self._guard_against_spurious_io_errors():  # None if it swallows an error, as numba's own
            cres = self._load_overload(sig, target_context)
        if cres is None:  # not cached: numba compiles it next, and its set-up checks for BLAS
            load_blas_check()
        return cres

    load_overload._lazy_for = PACKAGE
    load_overload.__wrapped__ = numba_load
    load_overload.__doc__ = numba_load.__doc__
    cache.load_overload = load_overload
    return True

