"""How large a run may be: the one home of the memory limit (`max_memory`, raised with
`set_max_memory` or the command line's ``--max-memory``), of the size checks the runs make
before they allocate (`check`), and of the work limit of one run (`max_work`, raised with
`set_max_work` or ``--max-steps`` on the command line; `check_work`).

Every run that allocates in proportion to an input (the time histories of `railride.simulate`,
the rail input tables, the exact stepper's maps, the damper rig's tables, the points of a
frequency response, the candidate values of a tuning sweep, the values of a range on the
command line) estimates its bytes first. Above the limit it raises a ValueError that says how
much the run would need and how to shrink it, instead of a MemoryError (or a swapping machine)
half way through. The default limit is half the memory of the machine (or of its container's
cgroup, when that is smaller): a run may take a large share, and the other half is left to
the operating system, the plots and the other processes.

Memory is not time: the stepper stores every output interval's last step only, so a run at a
tiny dt fits in memory and still takes days. The work of a run (samples x steps, its
sample-steps; the sub-steps of stiff dampers are not known before the run, so they are not
counted) is checked against `max_work` before it starts, and the error says how long the run
would take at the stepper's measured rate (`STEP_RATE`).
"""

from __future__ import annotations

import contextlib
import math
import os
import re

from railride.errors import InputError

#: the share of the machine's memory a run may take by default
DEFAULT_SHARE = 0.5
#: the limit assumed when the machine's memory cannot be read
FALLBACK_BYTES = 4 * 2**30
#: the largest number of steps of one run: time is k dt in float64, exact for whole k up to 2**53
MAX_STEPS = 2**53
#: what one value of a range on the command line holds before its runs: the number in a list and
#: a set, and the case (a row of the grid) it becomes, about 1 kB
VALUE_BYTES = 1024

#: the order of the stepper's rate, sample-steps a second on one core of a recent machine: the
#: closed loop with MR dampers runs 0.21-0.23 us a step, batches of 8 or more about 7 M
#: sample-steps a second a core (docs/performance.md); the sub-stepped dampers are slower
STEP_RATE = 4e6
#: the default most sample-steps of one run: about 40 minutes at `STEP_RATE` on one core, a hundred
#: times the paper's 10 s run at dt = 1e-4 s for a batch of a thousand samples
DEFAULT_MAX_WORK = 10**10

_UNITS = {"": 1, "B": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
#: the limits set for this process; None: the default (a share of the machine, `DEFAULT_MAX_WORK`)
_set: dict[str, int | None] = {"memory": None, "work": None}


def _setter(kind: str, parse):
    """The pair (set the limit, the same within a ``with`` block) of one kind of limit."""

    def set_limit(value) -> int | None:
        previous = _set[kind]
        _set[kind] = None if value is None else parse(value)
        return previous

    @contextlib.contextmanager
    def limited(value):
        previous = set_limit(value)
        try:
            yield
        finally:
            _set[kind] = previous

    return set_limit, limited


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
    limit = _set["memory"]
    return default_max_memory() if limit is None else limit


def parse_size(text, name: str = "max_memory") -> int:
    """A size as bytes: a whole number of bytes, or a number with a unit K, M, G or T (powers
    of 1024, an optional trailing B or iB: "4G", "512MiB", "1.5 GB"). ValueError naming
    ``name`` otherwise."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([KMGT]?)(?:i?B)?\s*", str(text), re.I)
        if match is None:
            raise InputError(
                f"{name} = {text!r}: expected a size such as 4G, 512M or 1.5T (powers of 1024), or a number of bytes"
            )
        value, unit = float(match.group(1)), match.group(2).upper()
    size = value * _UNITS[unit]
    if not math.isfinite(size) or size < 2**20:
        raise InputError(f"{name} = {text!r}: must be at least 1M (a megabyte) and finite")
    return int(size)


_set_memory, _memory_limit = _setter("memory", parse_size)


def set_max_memory(size) -> int | None:
    """Set the limit (bytes, or a size text as `parse_size` reads it; None: back to the
    default) for this process; returns the previous setting (None: the default). The workers of
    a Dask cluster keep their own."""
    return _set_memory(size)


def memory_limit(size):
    """`set_max_memory` within a ``with`` block only."""
    return _memory_limit(size)


#: the largest track file read [bytes]: 256 MiB holds about 5 million rows (s, z_L, z_R), a line
#: of 1,000 km at 0.2 m spacing (docs/cli.md, --scenario)
MAX_TRACK_FILE_BYTES = 256 * 2**20


def check_file(path, what: str, most: int) -> None:
    """ValueError unless ``path`` is a regular file of at most ``most`` bytes: a device such as
    /dev/zero, or a pipe, would be read without end. OSError where it cannot be read."""
    import stat

    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        raise InputError(f"{what} {path}: not a regular file")
    if info.st_size > most:
        raise InputError(f"{what} {path}: {shown_bytes(info.st_size)}, more than the {shown_bytes(most)} allowed")


def shown_bytes(n: float) -> str:
    """Bytes to three significant digits in binary units: 1.5 GiB, 312 MiB."""
    if not n < 2.0**1000:  # an integer beyond any float (a 400-digit count), or inf
        return "more than 1e300 B"
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
    where = "half this machine" if _set["memory"] is None else "set with --max-memory or railride.limits.set_max_memory"
    raise InputError(
        f"{what} would need {shown_bytes(need)} of memory, more than the limit of "
        f"{shown_bytes(limit)} ({where}): {shrink}, or raise the limit (--max-memory SIZE, "
        "railride.limits.set_max_memory)"
    )


def check_steps(name: str, steps: float, shrink: str) -> None:
    """ValueError when a run would take more than `MAX_STEPS` steps (``name``: what counts)."""
    if not steps <= MAX_STEPS:
        raise InputError(f"{name}: {steps:.4g} steps, more than the {MAX_STEPS:.4g} a run can count exactly: {shrink}")


# -- the work of a run ---------------------------------------------------------------------------
def max_work() -> int:
    """The most sample-steps (samples x steps) one run may take."""
    limit = _set["work"]
    return DEFAULT_MAX_WORK if limit is None else limit


def parse_count(text, name: str = "max_steps") -> int:
    """A number of sample-steps: a whole number, or a number such as 1e11; at least 1e6 (the
    smallest run worth a limit). ValueError naming ``name`` otherwise."""
    value = math.nan
    if not isinstance(text, bool):
        with contextlib.suppress(ValueError, OverflowError):  # a 400-digit number is no limit either
            value = float(text) if isinstance(text, (int, float)) else float(str(text).strip())
    if not math.isfinite(value) or value < 1e6:
        raise InputError(f"{name} = {text!r}: must be a finite number of sample-steps >= 1e6, such as 1e11")
    return int(value)


_set_work, _work_limit = _setter("work", parse_count)


def set_max_work(count) -> int | None:
    """Set the most sample-steps of one run (a number, or a text as `parse_count` reads it;
    None: back to `DEFAULT_MAX_WORK`) for this process; returns the previous setting (None: the
    default). The workers of a Dask cluster keep their own."""
    return _set_work(count)


def work_limit(count):
    """`set_max_work` within a ``with`` block only."""
    return _work_limit(count)


def shown_duration(seconds: float) -> str:
    """A duration to two or three significant digits in the largest unit that keeps it >= 1:
    45 s, 12 min, 3.2 h, 41 days, 3.2e+03 years."""
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            value = seconds / size
            return f"{value:.2g} {unit}" if value < 1e4 else f"{value:.2e} {unit}"
    return f"{seconds:.2g} s"


def check_work(samples: int, steps: float, what: str, shrink: str) -> None:
    """ValueError when ``samples`` x ``steps`` exceed `max_work`: ``what`` (e.g. "1 run of 10 s
    at dt 1e-09 s") would take so long at `STEP_RATE`; ``shrink`` says how to need less."""
    work, limit = float(samples) * float(steps), max_work()
    if work <= limit:
        return
    where = "set with --max-steps or set_max_work" if _set["work"] is not None else "the default, about 40 minutes"
    raise InputError(
        f"{what}: {samples} x {steps:.4g} steps = {work:.3g} sample-steps, about "
        f"{shown_duration(work / STEP_RATE)} at {STEP_RATE / 1e6:.0f} M sample-steps a second (the stepper's "
        f"rate on one core), more than the limit of {limit:.3g} ({where}): {shrink}, or raise the limit "
        "(--max-steps N, railride.limits.set_max_work)"
    )
