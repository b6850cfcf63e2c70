"""TOML text of a record: a gains file's [provenance] table (`provenance_toml`), written so
that `tomllib` reads back the same dict."""

from __future__ import annotations

import datetime
import json
import math
import numbers
import re

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def provenance_toml(provenance: dict, name: str = "provenance") -> str:
    """``provenance`` as the TOML table [``name``] (text ending in a blank line): numbers,
    strings, booleans, dates, lists, flat records of up to 12 plain values as inline tables,
    other tables as [``name``.KEY] sub-tables ([provenance.studies.pid]). None has no TOML form
    and is left out. `tomllib` reads it back as the same dict."""
    lines: list[str] = []

    def table(head: str, values: dict) -> None:
        subs = [(k, v) for k, v in values.items() if isinstance(v, dict) and not _inline(v)]
        plain = [(k, v) for k, v in values.items() if not (isinstance(v, dict) and not _inline(v))]
        if plain or not subs:  # a table of sub-tables only needs no header of its own
            lines.append(f"[{head}]")
            for k, v in plain:
                text = _value(v)
                if text is not None:
                    lines.append(f"{_key(k)} = {text}")
            lines.append("")
        for k, v in subs:
            table(f"{head}.{_key(k)}", v)

    table(_key(name), provenance)
    return "\n".join(lines) + "\n"


def _key(key) -> str:
    key = str(key)
    return key if _BARE.match(key) else _string(key)


def _inline(values: dict) -> bool:
    """A flat record of a few plain values: written as an inline table."""
    return len(values) <= 12 and not any(isinstance(v, (dict, list, tuple)) for v in values.values())


def _string(text: str) -> str:
    # JSON's escapes are TOML's; TOML also wants DEL escaped
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(value) -> str | None:
    """A value as TOML spells it; None for None (TOML has no null)."""
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        x = float(value)
        if math.isnan(x):
            return "nan"
        return repr(x) if math.isfinite(x) else ("inf" if x > 0 else "-inf")
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, (datetime.datetime, datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(t for t in map(_value, value) if t is not None) + "]"
    if isinstance(value, dict):
        items = [(_key(k), _value(v)) for k, v in value.items()]
        return "{" + ", ".join(f"{k} = {t}" for k, t in items if t is not None) + "}"
    return _string(str(value))
