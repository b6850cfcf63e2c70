"""What an output folder held before a command wrote into it: files the command did not write,
and which command's results they are (read from the ``schema`` of their JSON files), so that two
commands sharing one ``--out`` say so instead of mixing their results in silence."""

from __future__ import annotations

import json
from pathlib import Path

#: the command that writes each JSON schema's results (the part before "/" of "schema")
SCHEMA_COMMANDS = {
    "railride.comparison": "railride compare",
    "railride.league": "railride compare (a league table)",
    "railride.damper": "railride damper",
    "railride.tracking": "railride tracking",
    "railride.design": "railride design",
    "railride.frf": "railride frf",
    "railride.linear": "railride ride-spectrum",
    "railride.ride-spectrum": "railride ride-spectrum",
    "railride.modes": "railride modes",
    "railride.optimise": "railride tune",
    "railride.sensitivity": "railride tune",
    "railride.tune": "railride tune",
    "railride.pareto": "railride pareto",
    "railride.simulation": "railride simulate",
    "railride.study": "railride study",
    "railride.sweep": "railride sweep",
    "railride.vehicles": "railride vehicles",
}
#: files a command keeps in its folder beside what it writes at the end: the run table that
#: ``--resume`` continues is written run by run, not by the final write
KEPT = frozenset({"runs.csv"})


def entries(folder: Path) -> set[str]:
    """The visible entries of ``folder`` (none if it is not a folder yet)."""
    try:
        return {p.name for p in folder.iterdir() if not p.name.startswith(".")}
    except OSError:
        return set()


def _command(path: Path) -> str | None:
    """The command that wrote the JSON file ``path``, from its ``schema``; None if unknown."""
    try:
        if path.suffix != ".json" or path.stat().st_size > 50_000_000:
            return None
        schema = json.loads(path.read_text(encoding="utf-8")).get("schema")
    except (OSError, ValueError, AttributeError):
        return None
    if not isinstance(schema, str):
        return None
    return SCHEMA_COMMANDS.get(schema.split("/")[0], schema)


def others_note(folder: Path, before: set[str], written) -> str | None:
    """One line when ``folder`` holds entries, from before this write, that it did not write:
    how many, their names (the first few), and whose results they are. None if there are none."""
    top = set()
    for p in written:
        p = Path(p)
        try:
            top.add(p.relative_to(folder).parts[0])
        except ValueError:
            top.add(p.name)
    others = sorted(before - top - KEPT)
    if not others:
        return None
    mine = {c for name in top if (c := _command(folder / name))}
    theirs = sorted({c for name in others if (c := _command(folder / name))})
    if theirs and set(theirs) <= mine:
        whose = f"from an earlier run of {', '.join(theirs)} with other options"
    elif theirs:
        whose = f"the results of {', '.join(t for t in theirs if t not in mine) or ', '.join(theirs)}"
    else:
        whose = "not railride results this command knows"
    shown = ", ".join(others[:6]) + (f" and {len(others) - 6} more" if len(others) > 6 else "")
    return (
        f"note: --out {folder} also holds {len(others)} file(s) this command did not write ({whose}): "
        f"{shown}; left as they were. Give each command a folder of its own to keep results apart."
    )
