"""Checks on input values: the one home of the rules that every parameter, scenario and study
option obeys, so that an error reads the same wherever it is raised.

Every check raises ``ValueError`` naming the field, the value given and what is allowed; the
command line turns that into exit status 2. NumPy scalars (``np.float32(0.1)``,
``np.int64(40)``) count as numbers; ``True``/``False`` and text do not.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import field
from typing import Any

#: rule name -> (the words of the rule, the test on a finite float)
RULES = {
    "positive": ("a finite number > 0", lambda v: v > 0.0),
    "nonnegative": ("a finite number >= 0", lambda v: v >= 0.0),
    "finite": ("a finite number", lambda v: True),
}


def is_number(value) -> bool:
    """A real number (Python or NumPy), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def shown(value) -> str:
    """``value`` as an error message shows it: NumPy scalars as the plain number they hold."""
    if is_number(value) and type(value) not in (int, float):
        value = value.item()
    return repr(value)


def number(name: str, value, rule: str = "positive", unit: str = "", *, allowed: str | None = None) -> float:
    """``value`` as a float if it is a finite real number obeying ``rule`` (see `RULES`);
    else ValueError "name = value: must be <allowed> (unit)". ``allowed`` replaces the rule's
    words where a field needs its own (e.g. "a finite angle in degrees")."""
    words, test = RULES[rule]
    ok = is_number(value) and math.isfinite(float(value)) and test(float(value))
    if not ok:
        text = allowed if allowed is not None else words + (f" ({unit})" if unit else "")
        raise ValueError(f"{name} = {shown(value)}: must be {text}")
    return float(value)


def integer(name: str, value, minimum: int, maximum: int | None = None, what: str = "") -> int:
    """``value`` as an int if it is a whole number in [minimum, maximum]."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    ok = ok and value >= minimum and (maximum is None or value <= maximum)
    if not ok:
        upper = f" and <= {maximum}" if maximum is not None else ""
        raise ValueError(
            f"{name} = {shown(value)}: must be a whole number >= {minimum}{upper}" + (f" ({what})" if what else "")
        )
    return int(value)


def choice(name: str, value, allowed) -> str:
    """``value`` if it is one of the names ``allowed``."""
    if not isinstance(value, str) or value not in allowed:
        raise ValueError(f"{name} = {shown(value)}: allowed {', '.join(map(str, allowed))}")
    return value


def param(unit: str, doc: str, rule: str = "positive") -> Any:
    """A parameter field of a frozen dataclass: SI unit, meaning and rule (see `RULES`),
    checked by `validate_fields`."""
    return field(metadata={"unit": unit, "doc": doc, "rule": rule})


def validate_fields(obj, what: str) -> None:
    """Check every field of a frozen parameter dataclass against the rule in its metadata and
    store it as float; the error names the field, its value, its meaning and unit, and the rule."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        words, test = RULES[f.metadata["rule"]]
        if not (is_number(value) and math.isfinite(float(value)) and test(float(value))):
            raise ValueError(
                f"{what} {f.name!r} = {shown(value)} ({f.metadata['doc']}, {f.metadata['unit']}): must be {words}"
            )
        object.__setattr__(obj, f.name, float(value))


def rule_words(rule: str) -> str:
    """The words of a rule, for tables of parameters."""
    return RULES[rule][0]
