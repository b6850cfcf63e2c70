"""Atomic file output: a reader never sees a half-written file."""

from __future__ import annotations

import os
import tempfile
import threading
from pathlib import Path
from typing import Callable


def atomic_write(path: Path, write: Callable[[Path], object]) -> None:
    """Call ``write(tmp)`` on a temporary file beside ``path``, then rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, _default_mode())  # mkstemp makes it private; results are not
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _default_mode() -> int:
    """The mode a plain ``open(path, "w")`` would give: 0o666 less the umask."""
    return 0o666 & ~umask()


#: the status file whose ``Umask:`` line (Linux 4.7 and later) shows the process's umask
_STATUS = Path("/proc/self/status")


def _proc_umask() -> int | None:
    """The umask from the ``Umask:`` line of /proc/self/status; None where there is none (not
    Linux, a kernel before 4.7, no /proc mounted)."""
    try:
        with open(_STATUS, encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split(":", 1)[1].strip(), 8)
    except (OSError, ValueError):
        pass
    return None


def _set_and_restore_umask() -> int:
    # os.umask has no read-only form: between the two calls the process's umask is 0 for every
    # thread, so this runs once, at import, under a lock
    with _UMASK_LOCK:
        mask = os.umask(0)
        os.umask(mask)
    return mask


_UMASK_LOCK = threading.Lock()
#: the umask at import, for systems without the /proc line
_IMPORT_UMASK = _set_and_restore_umask() if _proc_umask() is None else None


def umask() -> int:
    """The process's umask, read without changing it: from /proc/self/status where the kernel
    shows it (Linux 4.7 and later), so that a later os.umask is seen; elsewhere the one at
    import, since setting it to read it would, for a moment, let another thread create a file
    with none."""
    mask = _proc_umask()
    if mask is not None:
        return mask
    if _IMPORT_UMASK is not None:
        return _IMPORT_UMASK
    return _set_and_restore_umask()  # /proc was there at import and has gone since


def atomic_write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda p: p.write_text(text, encoding="utf-8"))
