"""The kinds of the public API's arguments, checked where a call begins: a list of names, a list
of numbers, a time window, a flag, a table of options, an object of one class.

What the values must be (a known controller, a positive speed) is checked where they are used
(`railride.validation`); here only what kind of thing was given, so that a value of no kind the
call takes is an `InputError` naming the argument before any work, not an AttributeError or a
TypeError from deep inside it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from railride.errors import InputError
from railride.validation import is_number, shown


def sequence(name: str, value, what: str) -> list:
    """The items of a list, tuple, set or other iterable that is not text, bytes or a mapping."""
    if isinstance(value, (str, bytes, bytearray, Mapping)) or not isinstance(value, Iterable):
        raise InputError(f"{name} = {_shown(value)}: {what}")
    return list(value)


def _shown(value) -> str:
    text = shown(value)
    return text if len(text) <= 80 else text[:77] + "..."


def names(name: str, value, what: str = "names") -> list:
    """``value`` as a list: one name (text), or a list of names."""
    if isinstance(value, str):
        return [value]
    items = sequence(name, value, f"allowed a name or a list of {what}")
    bad = [v for v in items if not isinstance(v, str)]
    if bad:
        raise InputError(f"{name} = {_shown(value)}: {_shown(bad[0])} is not a name; allowed a list of {what}")
    return items


def repeated(values) -> tuple | None:
    """``(value,)`` of the first of ``values`` given twice (equal to one before it), else None;
    values that cannot be hashed are left to the checks that own them."""
    seen: set = set()
    for v in values:
        try:
            if v in seen:
                return (v,)
            seen.add(v)
        except TypeError:
            pass
    return None


def numbers(name: str, value, what: str = "numbers") -> list:
    """``value`` as a list of real numbers (their ranges are checked where they are used)."""
    if is_number(value):
        return [value]
    items = sequence(name, value, f"allowed a number or a list of {what}")
    bad = [v for v in items if not is_number(v)]
    if bad:
        raise InputError(f"{name} = {_shown(value)}: {_shown(bad[0])} is not a number; allowed a list of {what}")
    return items


def window(name: str, value):
    """None, or (start, end) in seconds as two numbers (their range is checked against the run)."""
    if value is None:
        return None
    allowed = "allowed (start, end) in seconds, two numbers, or None for the whole run"
    if isinstance(value, (str, bytes, bytearray, Mapping)) or not isinstance(value, Iterable):
        raise InputError(f"{name} = {_shown(value)}: {allowed}")
    items = list(value)
    if len(items) != 2 or not all(is_number(v) for v in items):
        raise InputError(f"{name} = {_shown(value)}: {allowed}")
    return tuple(items)


def flag(name: str, value) -> bool:
    """True or False (NumPy's too), nothing else."""
    if value is True or value is False or type(value).__name__ == "bool_":
        return bool(value)
    raise InputError(f"{name} = {_shown(value)}: allowed True or False")


def options(name: str, value, allowed=None) -> dict:
    """None or a mapping from option names (text; with ``allowed``, among those) to values, as a
    dict."""
    if value is None:
        return {}
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise InputError(f"{name} = {_shown(value)}: allowed a mapping of option names to values, or None")
    unknown = [k for k in value if allowed is not None and k not in allowed]
    if unknown:
        raise InputError(f"{name}: unknown option {unknown[0]!r}; allowed: {', '.join(allowed)}")
    return dict(value)


def instance(name: str, value, cls: type, what: str):
    """None or an object of class ``cls`` (``what``: the class in words, for the message)."""
    if value is None or isinstance(value, cls):
        return value
    raise InputError(f"{name} = {_shown(value)}: allowed {what} or None")
