"""A user's own MR damper as a TOML file with a ``[damper]`` table (docs/dampers.md, "Your own
damper"): the parameters of a Bouc-Wen or Spencer model identified on a rig, read into the same
`railride.secondary.dampers` model that a preset is, so that every command and study runs it.

The table either names a base with ``preset = "railway"`` and lists only the parameters that
differ, or names the ``model`` ("bouc-wen" or "spencer") and lists every parameter. Values are in
SI units, as `railride.secondary.dampers.BoucWen.describe` lists them."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from railride.errors import InputError
from railride._io import atomic_write_text
from railride.secondary import dampers
from railride.validation import parse_toml, shown

#: the models a file may name, by the name their records give
MODELS = dampers.MR_MODELS


def to_toml(model) -> str:
    """TOML text of an MR damper's parameters under ``[damper]``; `from_toml` reads it back
    exactly (floats written with ``repr``, the shortest text that parses to the same double)."""
    if model.model not in MODELS:
        raise InputError(f"damper = {model.model!r}: only the MR models ({', '.join(MODELS)}) have a damper file")
    lines = ["# railride MR damper parameters (SI units)", "[damper]", f'model = "{model.model}"']
    for name, unit, doc in model.describe():
        lines.append(f"{name} = {float(getattr(model, name))!r}  # {unit}: {doc}")
    return "\n".join(lines) + "\n"


def save(model, path: str | Path) -> None:
    """Write ``model``'s damper file at ``path`` (atomically)."""
    atomic_write_text(Path(path), to_toml(model))


def from_toml(text: str, source: str = "<string>"):
    """The MR damper of the ``[damper]`` table of TOML ``text``; ``source`` names it in errors."""
    table = parse_toml(text, source).get("damper")
    if not isinstance(table, dict):
        raise InputError(f"{source}: needs a [damper] table of MR damper parameters")
    table = dict(table)
    base_name, model_name = table.pop("preset", None), table.pop("model", None)
    if base_name is not None and (not isinstance(base_name, str) or base_name not in dampers.PRESETS):
        raise InputError(
            f"{source}: [damper] preset = {shown(base_name)}: unknown MR damper preset; "
            f"allowed: {', '.join(dampers.PRESETS)}"
        )
    if model_name is not None and (not isinstance(model_name, str) or model_name not in MODELS):
        raise InputError(f"{source}: [damper] model = {shown(model_name)}: allowed: {', '.join(MODELS)}")
    base = None if base_name is None else dampers.PRESETS[base_name]
    if base is not None and model_name is not None and model_name != base.model:
        raise InputError(
            f"{source}: [damper] model = {model_name!r} and preset = {base_name!r} (a {base.model} damper): "
            "give one, or the preset's own model"
        )
    if base is None and model_name is None:
        raise InputError(
            f"{source}: [damper] needs model = {' or '.join(repr(m) for m in MODELS)} with every parameter, "
            'or a base to start from, e.g. preset = "railway"'
        )
    cls = type(base) if base is not None else MODELS[str(model_name)]
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(table) - set(names))
    if unknown:
        raise InputError(
            f"{source}: [damper] unknown {cls.model} damper parameter(s) {', '.join(unknown)}; allowed: "
            f"{', '.join(names)}"
        )
    if base is None:
        missing = [n for n in names if n not in table]
        if missing:
            raise InputError(
                f"{source}: [damper] missing {cls.model} damper parameter(s) {', '.join(missing)} (list them all, "
                'or start from a base with preset = "railway")'
            )
    try:
        return base.replace(**table) if base is not None else cls(**table)
    except (ValueError, TypeError) as exc:  # the field's rule: name the file and table too
        raise InputError(f"{source}: [damper] {exc}") from None


def load(path: str | Path, option: str = "damper"):
    """The MR damper of the damper file at ``path``; errors name ``option``, the path and why."""
    path = Path(path)
    if path.is_dir():  # reading it fails with an OS's own words ("Is a directory")
        raise InputError(
            f"{option} = {str(path)!r}: a folder, not a damper file; give a FILE.toml with a [damper] table"
        )
    try:
        text = path.read_text(encoding="utf-8-sig")  # an editor's byte-order mark is no part of the TOML
    except OSError as exc:
        raise InputError(f"{option} = {str(path)!r}: cannot read the damper file: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{option} = {str(path)!r}: not a UTF-8 text TOML file") from None
    return from_toml(text, source=str(path))


def file_model(text, option: str = "damper"):
    """The model of the damper file ``text`` names (a path ending in .toml, or any file that is
    there), else None: text that names no file is the caller's to check (a name it knows)."""
    if isinstance(text, str) and text and (text.endswith(".toml") or Path(text).is_file()):
        if Path(text).exists():
            return load(text, option)
        raise InputError(f"{option} = {text!r}: no such damper file")
    return None


def resolve(text: str, option: str = "damper", *, allowed=None):
    """A damper option's text at the edge: a name of ``allowed`` (default every name
    `railride.secondary.dampers.preset` knows) stays a name; else the path of a damper file gives
    its model; else an InputError naming ``option``, the value and what is allowed."""
    allowed = dampers.NAMES if allowed is None else allowed
    if text in allowed:
        return text
    model = file_model(text, option)
    if model is not None:
        return model
    why = ": unknown damper model, and no such file" if text not in dampers.NAMES else ""
    raise InputError(
        f"{option} = {text!r}{why}; allowed: {', '.join(allowed)}, or the path of a FILE.toml with a [damper] table"
    )
