"""Where numba caches the kernels: a folder per version of the kernels' sources.

numba caches a compiled function on disk (``cache=True``) keyed on its own source file only (the
file's modification time and size), but the machine code it caches has every kernel it calls
compiled into it.  After an edit -- or a ``git pull`` in an editable install -- that changes
``hsm.py`` and not ``sweep.py``, numba would load ``sweep.py``'s stale sweep: old numbers, or a
crash where a shared data layout changed.  numba's documented setting for where it caches,
``NUMBA_CACHE_DIR``, read once when numba is imported, is the answer: the command line
(``python -m cdpr_design``, before anything imports numba) points it at a folder named after a
digest of the contents of every kernel module (:func:`folder`), so any change to any kernel
starts an empty folder (everything compiled again) and the same sources reuse theirs.

This module imports no numba: the command line calls it first.
"""

from __future__ import annotations

import functools
import hashlib
import os

_HERE = os.path.dirname(os.path.abspath(__file__))
#: the start of the name of a kernels' cache folder (then the first 16 hex digits of :func:`source_digest`)
PREFIX = "cdpr-design-kernels-"


@functools.lru_cache(maxsize=None)
def source_digest(package: str = _HERE) -> str:
    """SHA-256 (hex) of the names and contents of the ``.py`` files in ``package`` (the kernels)."""
    h = hashlib.sha256()
    for name in sorted(os.listdir(package)):
        if name.endswith(".py"):
            h.update(name.encode() + b"\0")
            with open(os.path.join(package, name), "rb") as fh:
                h.update(fh.read())
            h.update(b"\0")
    return h.hexdigest()


def folder(base: str) -> str:
    """The kernels' cache folder under ``base``: ``base/cdpr-design-kernels-<digest>``; ``base`` itself
    when it is already that folder (a command started by another, which chose it)."""
    name = PREFIX + source_digest()[:16]
    base = os.path.abspath(os.path.expanduser(base))
    return base if os.path.basename(base) == name else os.path.join(base, name)

