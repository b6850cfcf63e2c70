"""How large a run may be: the one home of the memory limit (`max_memory`, raised with
`set_max_memory` or the command line's ``--max-memory``) and of the size checks the runs make
before they allocate (`check`).

Every run that allocates in proportion to an input (the time histories of `railride.simulate`,
the rail input tables, the exact stepper's maps, the damper rig's tables, the points of a
frequency response, the candidate values of a tuning sweep, the values of a range on the
command line) estimates its bytes first. Above the limit it raises a ValueError that says how
much the run would need and how to shrink it, instead of a MemoryError (or a swapping machine)
half way through. The default limit is half the memory of the machine (or of its container's
cgroup, when that is smaller): a run may take a large share, and the other half is left to
the operating system, the plots and the other processes.
"""

from __future__ import annotations

import contextlib
import math
import os
import re

#: the share of the machine's memory a run may take by default
DEFAULT_SHARE = 0.5
#: the limit assumed when the machine's memory cannot be read
FALLBACK_BYTES = 4 * 2**30
#: the largest number of steps of one run: time is k dt in float64, exact for whole k up to 2**53
MAX_STEPS = 2**53
#: what one value of a range on the command line holds before its runs: the number in a list and
#: a set, and the case (a row of the grid) it becomes, about 1 kB
VALUE_BYTES = 1024

_UNITS = {"": 1, "B": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
_limit: int | None = None  # None: the default share of the machine


def machine_memory() -> int | None:
    """Bytes of memory of this machine, or of its cgroup (a container) when smaller; None when
    neither can be read."""
    sizes = []
    try:
        sizes.append(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        pass
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path) as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit() and 0 < int(text) < 2**60:  # "max" or a huge number: no limit
            sizes.append(int(text))
    sizes = [s for s in sizes if s > 0]
    return min(sizes) if sizes else None


def default_max_memory() -> int:
    """The default limit [bytes]: `DEFAULT_SHARE` of `machine_memory` (`FALLBACK_BYTES` when
    unknown)."""
    total = machine_memory()
    return FALLBACK_BYTES if total is None else int(DEFAULT_SHARE * total)


def max_memory() -> int:
    """The limit in force [bytes]."""
    return default_max_memory() if _limit is None else _limit


def parse_size(text, name: str = "max_memory") -> int:
    """A size as bytes: a whole number of bytes, or a number with a unit K, M, G or T (powers
    of 1024, an optional trailing B or iB: "4G", "512MiB", "1.5 GB"). ValueError naming
    ``name`` otherwise."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([KMGT]?)(?:i?B)?\s*", str(text), re.I)
        if match is None:
            raise ValueError(
                f"{name} = {text!r}: expected a size such as 4G, 512M or 1.5T (powers of 1024), or a number of bytes"
            )
        value, unit = float(match.group(1)), match.group(2).upper()
    size = value * _UNITS[unit]
    if not math.isfinite(size) or size < 2**20:
        raise ValueError(f"{name} = {text!r}: must be at least 1M (a megabyte) and finite")
    return int(size)


def set_max_memory(size) -> int | None:
    """Set the limit (bytes, or a size text as `parse_size` reads it; None: back to the
    default) for this process; returns the previous setting (None: the default). The workers of
    a Dask cluster keep their own."""
    global _limit
    previous = _limit
    _limit = None if size is None else parse_size(size)
    return previous


@contextlib.contextmanager
def memory_limit(size):
    """`set_max_memory` within a ``with`` block only."""
    previous = set_max_memory(size)
    try:
        yield
    finally:
        global _limit
        _limit = previous


def shown_bytes(n: float) -> str:
    """Bytes to three significant digits in binary units: 1.5 GiB, 312 MiB."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}" if n / size < 1000 else f"{n / size:.4g} {unit}"
    return f"{n:.0f} B"


def check(need: float, what: str, shrink: str) -> None:
    """ValueError when ``need`` bytes exceed the limit: ``what`` (e.g. "the time histories of 3
    runs x 10001 samples") would need so much; ``shrink`` says how to need less."""
    limit = max_memory()
    if need <= limit:
        return
    where = "set with --max-memory or railride.limits.set_max_memory" if _limit is not None else "half this machine"
    raise ValueError(
        f"{what} would need {shown_bytes(need)} of memory, more than the limit of "
        f"{shown_bytes(limit)} ({where}): {shrink}, or raise the limit (--max-memory SIZE, "
        "railride.limits.set_max_memory)"
    )


def check_steps(name: str, steps: float, shrink: str) -> None:
    """ValueError when a run would take more than `MAX_STEPS` steps (``name``: what counts)."""
    if not steps <= MAX_STEPS:
        raise ValueError(f"{name}: {steps:.4g} steps, more than the {MAX_STEPS:.4g} a run can count exactly: {shrink}")
