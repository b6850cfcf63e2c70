"""Checks on input values: the one home of the rules that every parameter, scenario and study
option obeys, so that an error reads the same wherever it is raised.

Every check raises ``ValueError`` naming the field, the value given and what is allowed; the
command line turns that into exit status 2. NumPy scalars (``np.float32(0.1)``,
``np.int64(40)``) count as numbers; ``True``/``False`` and text do not.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import numbers
from dataclasses import field
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any, NamedTuple

from railride.errors import InputError

if TYPE_CHECKING:  # numpy comes with the first check that needs it, not with this module
    import numpy as np

#: the largest seed: NumPy's generators take any whole number >= 0, but a seed must also
#: survive the run table's CSV, whose readers hold whole numbers in 64 bits
SEED_MAX = 2**64 - 1

#: rule name -> (the words of the rule, the test on a finite float)
RULES = {
    "positive": ("a finite number > 0", lambda v: v > 0.0),
    "nonnegative": ("a finite number >= 0", lambda v: v >= 0.0),
    "at_least_one": ("a finite number >= 1", lambda v: v >= 1.0),
    "finite": ("a finite number", lambda v: True),
    # checked by `seed`, never through a float: the test here is not used
    "seed": ("a whole number >= 0 and <= 2**64 - 1", lambda v: False),
}


def is_number(value) -> bool:
    """A real number (Python or NumPy), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def as_float(value) -> float:
    """A number as a float; a whole number too large for one (a 400-digit TOML integer) is
    infinite, so that the finite-number rules refuse it instead of raising OverflowError."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def obeys(value, rule: str) -> bool:
    """Whether ``value`` is a finite number obeying `RULES` ``rule``."""
    if not is_number(value):
        return False
    v = as_float(value)
    return math.isfinite(v) and RULES[rule][1](v)


def shown(value) -> str:
    """``value`` as an error message shows it: NumPy scalars as the plain number they hold
    (float32 at its own precision: 0.1, not 0.10000000149011612), a huge whole number by its
    first four digits and its power of ten, a float with float noise to four significant digits."""
    if isinstance(value, (list, tuple)):
        inner = ", ".join(map(shown, value)) + ("," if isinstance(value, tuple) and len(value) == 1 else "")
        return f"[{inner}]" if isinstance(value, list) else f"({inner})"
    if isinstance(value, (datetime.date, datetime.time)):  # a TOML date or time, as the file wrote it
        return f"{value.isoformat()} (a {type(value).__name__})"
    if not is_number(value):
        return repr(value)
    if isinstance(value, numbers.Integral):
        v = int(value)
        if abs(v) < 10**30:  # seeds (up to 20 digits) shown exactly
            return str(v)
        # math.log10 takes any int; str() would refuse one past 4300 digits
        power = int(math.log10(abs(v)))
        mantissa = abs(v) / 10**power
        if mantissa >= 10.0:
            power, mantissa = power + 1, mantissa / 10.0
        return f"{'-' if v < 0 else ''}{mantissa:.4g}e+{power} (a {power + 1}-digit whole number)"
    text = str(value) if type(value) is not float else repr(value)
    digits = sum(c.isdigit() for c in text.split("e")[0].lstrip("-0."))
    return f"{float(value):.4g}" if digits > 10 else text


def number(name: str, value, rule: str = "positive", unit: str = "", *, allowed: str | None = None) -> float:
    """``value`` as a float if it is a finite real number obeying ``rule`` (see `RULES`);
    else ValueError "name = value: must be <allowed> (unit)". ``allowed`` replaces the rule's
    words where a field needs its own (e.g. "a finite angle in degrees")."""
    if not obeys(value, rule):
        words = RULES[rule][0]
        text = allowed if allowed is not None else words + (f" ({unit})" if unit else "")
        raise InputError(f"{name} = {shown(value)}: must be {text}")
    return float(value)


def integer(name: str, value, minimum: int, maximum: int | None = None, what: str = "") -> int:
    """``value`` as an int if it is a whole number in [minimum, maximum]."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    ok = ok and value >= minimum and (maximum is None or value <= maximum)
    if not ok:
        upper = f" and <= {maximum}" if maximum is not None else ""
        raise InputError(
            f"{name} = {shown(value)}: must be a whole number >= {minimum}{upper}" + (f" ({what})" if what else "")
        )
    return int(value)


#: the largest count (of cycles, values, steps) taken: 2**53, the whole numbers a float holds
#: exactly, as counts are multiplied by floats (a 400-digit count overflows them)
COUNT_MAX = 2**53


def count(name: str, value, minimum: int, what: str = "") -> int:
    """``value`` as an int if it is a whole number from ``minimum`` to `COUNT_MAX`."""
    n = integer(name, value, minimum, what=what)
    if n > COUNT_MAX:
        raise InputError(f"{name} = {shown(n)}: at most 2**53 = {COUNT_MAX} (the counts a float holds exactly)")
    return n


def seed(name: str, value) -> int:
    """``value`` as a Python int if it is a seed: a whole number in [0, `SEED_MAX`], Python or
    NumPy; a whole float (3.0) too, as studies once stored seeds. Never passed through a float,
    which would round seeds past 2**53 (9007199254740993 to ...992)."""
    whole = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if not whole and is_number(value) and math.isfinite(as_float(value)) and float(value).is_integer():
        value, whole = int(value), True
    if not (whole and 0 <= value <= SEED_MAX):
        raise InputError(f"{name} = {shown(value)}: must be {RULES['seed'][0]}")
    return int(value)


def frequencies(name: str, value) -> "np.ndarray":
    """``value`` (one number or an array of them) as a 1-D float array of frequencies [Hz]:
    finite and >= 0; anything else an InputError naming ``name``."""
    import numpy as np

    try:
        f = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        f = None
    if f is None or f.ndim != 1 or not np.all(np.isfinite(f)) or np.any(f < 0):
        raise InputError(f"{name} = {shown(value)}: must be a number or a 1-D array of numbers, finite and >= 0 (Hz)")
    return f


def choice(name: str, value, allowed) -> str:
    """``value`` if it is one of the names ``allowed``."""
    if not isinstance(value, str) or value not in allowed:
        raise InputError(f"{name} = {shown(value)}: allowed {', '.join(map(str, allowed))}")
    return value


def param(unit: str, doc: str, rule: str = "positive", default: Any = dataclasses.MISSING) -> Any:
    """A parameter field of a frozen dataclass: SI unit, meaning and rule (see `RULES`),
    checked by `validate_fields`; with a ``default`` the field is optional. A default of None
    means "absent" (no bump stops): None is then allowed besides the rule."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "rule": rule})


class PlausibilityWarning(UserWarning):
    """A value inside its error range but outside the typical range of a full-size rail vehicle."""


class Range(NamedTuple):
    """The allowed range of a field (an error outside) and, for a vehicle field, its typical
    range (a `PlausibilityWarning` outside; None: no warning). The tables are
    `railride.model.plausible`."""

    low: float  # error below
    high: float  # error above
    why: str
    typical: tuple[float, float] | None = None  # a warning outside (None: no warning)


def validate_fields(obj, what: str, ranges: Mapping[str, Range] | None = None, then=None) -> None:
    """Check every field of a frozen parameter dataclass against the rule in its metadata and
    store it as float (a seed as int); the error names the field, its value, its meaning and
    unit, and the rule. Then the fields named in ``ranges`` against their allowed range (an
    error), ``then()`` (a check across fields, if any), and their typical range (a
    `PlausibilityWarning` for each field outside it)."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        rule = f.metadata["rule"]
        if value is None and f.default is None:  # an optional element left out
            continue
        if rule == "seed":
            try:
                object.__setattr__(obj, f.name, seed(f"{what} {f.name!r}", value))
            except ValueError:
                pass
            else:
                continue
        elif obeys(value, rule):
            object.__setattr__(obj, f.name, float(value))
            continue
        raise InputError(
            f"{what} {f.name!r} = {shown(value)} ({f.metadata['doc']}, {f.metadata['unit']}): must be {RULES[rule][0]}"
        )
    if not ranges:
        return
    fields = {f.name: f for f in dataclasses.fields(obj)}
    for name, r in ranges.items():
        value, meta = getattr(obj, name), fields[name].metadata
        if value is None:
            continue
        if not r.low <= value <= r.high:
            unit = _after_number(meta["unit"])
            raise InputError(
                f"{what} {name!r} = {shown(value)} ({meta['doc']}, {meta['unit']}): must be between {r.low:g} and "
                f"{r.high:g}{unit} ({r.why})"
            )
    if then is not None:
        then()
    for note in atypical(obj, ranges, what):
        warnings.warn(note, PlausibilityWarning, stacklevel=caller_level())


_PACKAGE = str(Path(__file__).resolve().parent)


def caller_level() -> int:
    """The ``stacklevel`` of a warning raised by the function that calls this, such that the
    warning points at the first line outside railride (the user's call), past dataclasses'
    generated ``__init__`` (file ``<string>``) and
    `dataclasses.replace`."""
    frame: FrameType | None = sys._getframe(2)
    level = 2
    while frame is not None and (
        frame.f_code.co_filename.startswith((_PACKAGE, "<")) or frame.f_code.co_filename == dataclasses.__file__
    ):
        frame, level = frame.f_back, level + 1
    return level


def atypical(obj, ranges: Mapping[str, Range], what: str) -> list[str]:
    """One line for each field of ``obj`` outside its typical range in ``ranges``."""
    out = []
    fields = {f.name: f for f in dataclasses.fields(obj)}
    for name, r in ranges.items():
        if r.typical is None:
            continue
        low, high = r.typical
        value, meta = getattr(obj, name), fields[name].metadata
        if value is not None and not low <= value <= high:
            out.append(
                f"{what} {name!r} = {shown(value)}{_after_number(meta['unit'])} ({meta['doc']}) is outside the "
                f"{low:g} to {high:g}{_after_number(meta['unit'])} of full-size rail vehicles; the results are for it "
                "as given"
            )
    return out


def _after_number(unit: str) -> str:
    """A unit as it follows a number: " kg", and nothing for a ratio (unit "1": "0.5 1" reads
    as two numbers)."""
    return "" if unit in ("1", "") else f" {unit}"


def toml_error(exc: ValueError) -> str:
    """What is wrong with a TOML text, from the ValueError of ``tomllib.loads``: its syntax
    error, or an integer longer than Python converts (4300 digits), which it raises as a plain
    ValueError that advises a Python setting."""
    import tomllib

    if isinstance(exc, tomllib.TOMLDecodeError):
        return str(exc)
    return "an integer with more than 4300 digits"


def parse_toml(text: str, source: str) -> dict:
    """The tables of TOML ``text``, else an InputError naming ``source``: its syntax error, or
    nesting deeper than a railride file has (tomllib recurses into nested arrays and tables)."""
    import tomllib

    try:
        return tomllib.loads(text)
    except ValueError as exc:
        raise InputError(f"{source}: not valid TOML: {toml_error(exc)}") from None
    except RecursionError:
        raise InputError(f"{source}: nested too deeply to be a railride file") from None


def rule_words(rule: str) -> str:
    """The words of a rule, for tables of parameters."""
    return RULES[rule][0]


# -- places to write ----------------------------------------------------------------------------
def creatable(path, name: str) -> None:
    """InputError starting with ``name`` unless a file or folder can be made at ``path``: the
    nearest folder that exists at or above its parent must be a folder and take a new entry
    (the missing ones between are made on writing)."""
    parent = Path(path).absolute().parent
    nearest = next(p for p in (parent, *parent.parents) if p.exists() or p == p.parent)
    if not nearest.is_dir():
        raise InputError(f"{name}: {nearest} is a file, not a folder")
    takes_entries(nearest, name)


def takes_entries(folder, name: str) -> None:
    """InputError starting with ``name`` unless a new entry can be made in the existing
    ``folder``. Tried by making a hidden folder there and removing it at once: the permission
    bits do not tell (root passes them, yet nothing can be made in /proc or on a read-only file
    system)."""
    import os
    import tempfile

    try:
        probe = tempfile.mkdtemp(prefix=".railride-probe-", dir=folder)
    except OSError as exc:
        raise InputError(f"{name}: nothing can be written in {folder} ({exc.strerror or exc})") from None
    os.rmdir(probe)
