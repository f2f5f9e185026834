"""Before an output folder is written: can it be, and what did a killed run leave in it.

:func:`check_folder` is the pre-flight check of ``--out``: the folder exists
and is writable, or it can be created (its nearest existing ancestor is a
writable folder, not a file).  Nothing is created by the check, so a command
that then refuses its input leaves no trace.

Temporary files carry a marker of their own (``cdpr-design-tmp``) and the id
of the process writing them (:func:`temp_prefix`); :func:`remove_stale`
deletes those whose process is gone, which is what a run killed by SIGKILL
(or a power cut) leaves behind.  Nothing without the marker is touched (a
hidden file of the user's whose name happens to hold a number is not a
leftover), nor the temporary files of a run still going in the same folder.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from cdpr_design.errors import InputError

#: What only cdpr-design's temporary files carry in their names.
TEMP_MARKER = "cdpr-design-tmp"
#: ``.<name>.cdpr-design-tmp.<pid>.<random>.tmp``: the temporary files of :class:`cdpr_design.io.atomic.AtomicFile`.
_TEMP = re.compile(rf"^\..+\.{re.escape(TEMP_MARKER)}\.(\d+)\.[A-Za-z0-9_]+\.tmp$")


def temp_prefix(name: str) -> str:
    """The prefix of this process's temporary files for output ``name``."""
    return f".{name}.{TEMP_MARKER}.{os.getpid()}."


#: Characters a temporary name adds to the longest name it stands for: ``.`` + name +
#: ``.cdpr-design-tmp.<pid>.<8 random>_old.tmp`` (the backup of a replaced file, io.files), with room for pids.
_TEMP_EXTRA = 1 + len(TEMP_MARKER) + 2 + 10 + 1 + 8 + len("_old.tmp")


def _limit(folder: Path, name: str, default: int) -> int:
    """``os.pathconf`` of the nearest existing ancestor of ``folder`` (``default`` where unknown)."""
    for anc in [folder, *folder.parents]:
        try:
            if anc.exists():
                return os.pathconf(anc, name)
        except (OSError, ValueError):
            break
    return default


def check_name(path: str | Path, longest: str = "") -> None:
    """Refuse (an :class:`InputError` naming ``--out``) an output ``path`` whose temporary name
    (:func:`temp_prefix`; ``longest``: a longer name written beside it) does not fit the file
    system's limits: a name of at most ``NAME_MAX`` bytes, a path of less than ``PATH_MAX``."""
    p = Path(path)
    name = max(p.name, longest, key=len)
    tmp = len(os.fsencode(name)) + _TEMP_EXTRA
    whole = len(os.fsencode(str(p.parent))) + 1 + tmp
    name_max = _limit(p.parent, "PC_NAME_MAX", 255)
    path_max = _limit(p.parent, "PC_PATH_MAX", 4096)
    if tmp > name_max or whole >= path_max:
        raise InputError(f"--out: {p} is too long for its temporary file ({whole} bytes; a path must stay "
                         f"under {path_max} bytes and a name within {name_max}): choose a shorter --out")


def check_folder(path: str | Path, option: str = "--out") -> None:
    """Raise an :class:`InputError` naming ``option`` unless ``path`` is (or can be made) a writable folder.

    ``os.access`` is asked, so a read-only file system refuses even root.
    """
    p = Path(path)
    try:
        if p.exists():
            if not p.is_dir():
                raise InputError(f"{option}: {p} exists and is not a folder")
            if not os.access(p, os.W_OK | os.X_OK):
                raise InputError(f"{option}: {p} is not writable")
            return
        for anc in p.absolute().parents:
            if anc.exists():
                break
        else:  # pragma: no cover - the root always exists
            raise InputError(f"{option}: cannot create {p}")
        if not anc.is_dir():
            raise InputError(f"{option}: cannot create {p}: {anc} is a file, not a folder")
        if not os.access(anc, os.W_OK | os.X_OK):
            raise InputError(f"{option}: cannot create {p}: {anc} is not writable")
    except OSError as exc:
        raise InputError(f"{option}: cannot use {p}: {exc.strerror or exc}") from None


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True  # another user's process (or not a pid we can ask about): keep its files
    return True


def remove_stale(folder: str | Path) -> list[Path]:
    """Delete cdpr-design's temporary files in ``folder`` (the marked names of :func:`temp_prefix`)
    whose writing process no longer runs; the paths removed."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for e in entries:
        m = _TEMP.match(e.name)
        if m is None or not e.is_file(follow_symlinks=False) or _alive(int(m.group(1))):
            continue
        try:
            os.unlink(e.path)
            removed.append(Path(e.path))
        except OSError:
            pass
    return removed
