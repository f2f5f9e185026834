"""The jit options of every kernel, set once, and where numba caches them.

``cache=True`` so users pay the compile time once per machine (numba's on-disk
cache), ``nogil`` so sweeps run their blocks of poses on threads
(:mod:`cdpr_design.kernels.parallel`; no kernel uses ``parallel=True``), ``error_model='numpy'`` so a
division by zero gives inf/NaN as in numpy instead of raising.

Cache validity.  numba keys a function's cached machine code on its own
source file only (modification time and size), but that code has every
kernel it calls compiled into it.  After an edit -- or a ``git pull`` in an
editable install -- that changes ``hsm.py`` and not ``sweep.py``, numba would
load ``sweep.py``'s stale sweep: old numbers, or a crash where a shared data
layout changed (seen: a scratch tuple grown by one array segfaulted).  So the
kernels' cache entries are stamped with a digest of the *contents* of every
module of this package instead (:func:`source_digest`): any change to any
kernel recompiles them all, and a copy with the same sources reuses the cache.
numba offers no public hook for this; :func:`_register_locators` puts
subclasses of its cache locators first in its list (the classes and the list
have the same roles in numba 0.59 to 0.68; ``tests/test_jit_cache.py`` fails if
that stops working).
"""

from __future__ import annotations

import functools
import hashlib
import os

import numba as nb
from numba.extending import register_jitable

_HERE = os.path.dirname(os.path.abspath(__file__))


@functools.lru_cache(maxsize=None)
def source_digest(folder: str = _HERE) -> str:
    """SHA-256 (hex) of the names and contents of the ``.py`` files in ``folder`` (this package)."""
    h = hashlib.sha256()
    for name in sorted(os.listdir(folder)):
        if name.endswith(".py"):
            h.update(name.encode() + b"\0")
            with open(os.path.join(folder, name), "rb") as fh:
                h.update(fh.read())
            h.update(b"\0")
    return h.hexdigest()


class _PackageStamp:
    """Cache-locator mixin: kernels of this package only, stamped with :func:`source_digest`."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if os.path.dirname(os.path.abspath(py_file)) != _HERE:
            return None  # not a kernel of this package: numba's own locators take it
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return ("cdpr-design kernels", source_digest())


def _register_locators() -> None:
    """Put the stamped locators before numba's own (NUMBA_CACHE_DIR, in-tree, user-wide, in that order)."""
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")
    ours = []
    for name in ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator"):
        base = getattr(caching, name, None) or getattr(caching, "_" + name)
        ours.append(type("Kernel" + name, (_PackageStamp, base), {"__module__": __name__}))
    impl._locator_classes = ours + [c for c in impl._locator_classes if not issubclass(c, _PackageStamp)]


_register_locators()


JIT = dict(cache=True, nogil=True, error_model="numpy")
njit = nb.njit(**JIT)
#: Reassociation (vectorised reductions) without giving up NaN/inf semantics.
FAST = {"reassoc", "contract", "arcp"}
njit_fast = nb.njit(fastmath=FAST, **JIT)
#: Small helpers of the hot loops, inlined into their callers (no call, no reference counting per call).
njit_inline = nb.njit(fastmath=FAST, inline="always", **JIT)
#: A function with a single caller, inlined into it in numba's IR with the caller's own options:
#: a separately compiled function is optimised by LLVM again, with everything it calls, in the
#: module of every function that calls it, so each level of a chain of calls costs its whole
#: depth again (the sagging cables' fixed point).
njit_folded = nb.njit(inline="always", **JIT)
#: The loops over poses: compiled without numba's reference counting (``_nrt=False``).
#: numba counts references to every array a function binds or passes on -- an atomic
#: increment and decrement per array per pose, the scratch tuple alone holding 31 -- and
#: the kernels' block loops spent more than half their time on it (docs/performance.md).
#: Such a loop gets its arrays from a block function
#: that allocates them and outlives the loop.  Neither the loop nor anything it calls may
#: allocate: numba compiles the calls with the same option, and refuses an allocation there
#: when it compiles (so the kernels that solve a polynomial's roots with fresh arrays, the
#: hanging tilt, keep reference counting; the sagging cables' loops and fixed point do without it,
#: the Newton step's arrays in the block's scratch: a faster sweep and a shorter compile without
#: the counter code around its many calls).  A
#: callee that does not set the option itself takes its first caller's, for good (numba's
#: cache keeps it): an allocating callee fails where it is first reached from such a loop,
#: and a counting one reached first from elsewhere would slow the loop down.  So every
#: kernel that allocates nothing is declared without counting
#: (``njit_noref``, ``njit_fast_noref``), and only the ones that allocate use ``njit``.
#: ``tests/test_jit_cache.py`` compiles each loop first, and after the per-pose kernel, in
#: a new process with an empty cache, and fails if numba stops honouring the option.
NOREF = dict(JIT, _nrt=False)
njit_noref = nb.njit(**NOREF)
njit_fast_noref = nb.njit(fastmath=FAST, **NOREF)


def jitable(func):
    """``func`` itself, a plain Python function, and compiled into the kernels that call it.

    For the functions that only allocate a kernel's arrays (:func:`~cdpr_design.kernels.hsm.make_scratch`):
    called from Python, numpy allocates them and nothing is compiled -- a compiled function
    returning a tuple of 31 arrays costs more to compile on a machine's first run than the
    allocation costs in a whole sweep (``numba.extending.register_jitable``).
    """
    return register_jitable(func)


def pointer(dispatcher, sig):
    """A C function pointer to ``dispatcher`` compiled for ``sig`` (a numba signature with its return
    type): the dispatcher's own compiled function, compiled or loaded from numba's cache for
    ``sig``'s argument types, through the C wrapper numba makes of every compiled function
    (numba's ``CompileResultWAP``, its wrapper-address protocol: typed as a first-class function
    ``FunctionType(sig)``).  Nothing is compiled twice: callers that call ``dispatcher`` directly
    link the same compiled function.  For :mod:`cdpr_design.kernels.pointers`."""
    from numba.core.types.function_type import CompileResultWAP

    dispatcher.compile(sig.args)
    cres = dispatcher.overloads[tuple(sig.args)]
    if cres.signature != sig:
        raise TypeError(f"{dispatcher.py_func.__name__} compiles to {cres.signature}, not the pointer's {sig}")
    return CompileResultWAP(cres)


#: the pointers :func:`pointer_for` made in this process, by (dispatcher, argument types)
_pointers: dict = {}


def pointer_for(dispatcher, args):
    """:func:`pointer` to ``dispatcher`` compiled for the numba types of the values ``args`` (what
    a kernel will pass it), made once per process and types.  Under ``NUMBA_DISABLE_JIT``,
    ``dispatcher`` itself (a Python function)."""
    if nb.config.DISABLE_JIT:
        return dispatcher
    types = tuple(nb.typeof(a) for a in args)
    key = (dispatcher, types)
    made = _pointers.get(key)
    if made is None:
        dispatcher.compile(types)
        made = _pointers[key] = pointer(dispatcher, dispatcher.overloads[types].signature)
    return made
