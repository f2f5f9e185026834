"""Reading input files safely: regular files only, of bounded size.

A FIFO, a terminal or a device (``/dev/zero``) given as a spec or a log
would block or never end; a file far larger than any spec or log would
exhaust memory.  :func:`read_text` opens without blocking, checks what it
opened (not what the name pointed to a moment before), and reads at most
``max_bytes``.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from cdpr_design.errors import InputError

#: Largest CSV log or pose file read (``compare``, ``csv`` trajectories) [bytes]:
#: a 1 ms log of a 16-cable robot runs about 250 B a row, so 512 MiB is
#: two million rows, more than half an hour of samples.
MAX_LOG_BYTES = 512 << 20


def read_text(path: str | Path, max_bytes: int, encoding: str = "utf-8") -> str:
    """The text of the regular file ``path``, at most ``max_bytes`` long.

    Raises
    ------
    InputError
        Missing, a folder, not a regular file, larger than ``max_bytes``,
        unreadable or not text in ``encoding``; the message names the path
        and says which (the caller adds the option or key it came from).
    """
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError(f"cannot read {p}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{p} is a folder, expected a file") from None
    except OSError as exc:
        raise InputError(f"cannot read {p}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise InputError(f"{p} is a folder, expected a file")
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"{p} is not a regular file (a pipe, socket or device), expected a file")
        if st.st_size > max_bytes:
            raise InputError(f"{p} is {st.st_size:,} bytes, more than the {max_bytes:,} read")
        with os.fdopen(fd, "rb", closefd=True) as fh:
            fd = -1
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise InputError(f"cannot read {p}: {exc.strerror or exc}") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > max_bytes:  # it grew while we read
        raise InputError(f"{p} is more than the {max_bytes:,} bytes read")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise InputError(f"cannot read {p}: not {encoding} text ({exc.reason} at byte {exc.start})") from None
