"""No traceback from extreme numbers: every numeric option of every command, found in the
application itself (a new option is covered without a change here), given the doubles' ends
(1e308, -1e308, 1e-308), 0, -1, nan, inf and a 400-digit whole number. Each outcome is either
success with finite numbers in the output, or status 2 with one line ``error: ...`` that names
the option; never status 1 (a bug) nor an exception.

Each command runs on a tiny case (0.2 s at dt = 1 ms, a few frequencies, cycles or runs), and an
option that only acts with another gets that one too (``--voltage`` with ``--suspension mr``), so
that the value itself is what is checked."""

from __future__ import annotations

import functools
import json
import re

import pytest

from clihelp import run

VALUES = ("1e308", "-1e308", "1e-308", "0", "-1", "nan", "inf", "1" + "0" * 399)

#: the words of a metavar that stand for numbers (``N``, ``M/S``, ``X[,X...]``, ``A:B:COUNT``,
#: ``Z,ANGLE,VEL,RATE``): a text option all of whose words are these takes numbers
NUMERIC_WORDS = {
    *("N", "X", "M", "S", "HZ", "DEG", "V", "M/S", "B", "V/N", "VALUES", "SIZE"),
    *("Z", "ANGLE", "VEL", "RATE", "A", "D", "P", "R", "COUNT", "START", "END"),
}

SHORT = ("--duration", "0.2", "--dt", "1e-3")
STORED = (*SHORT, "--output-rate", "100")
RANDOM = ("--scenario", "fra4", "--min-wavelength", "2")

#: each command's tiny case
BASE = {
    "simulate": STORED,
    "compare": (*STORED, "--control-rate", "100", "--controllers", "pid", "--no-bounds"),
    "report": (*STORED, "--control-rate", "100", "--controllers", "pid", "--no-bounds"),
    "modes": (),
    "frf": ("--points", "16"),
    "damper": ("--cycles", "2", "--amplitude", "0.01", "--frequency", "2", "--voltage", "0"),
    "tracking": ("--cycles", "2"),
    "tune": (*SHORT, "--controllers", "pid", "--values", "3", "--budget", "8", "--workers", "1"),
    "pareto": (*SHORT, "--samples", "4", "--workers", "1"),
    "sweep": (*SHORT, "--speed", "40,50", "--workers", "1"),
    "study": (*SHORT, "--track-seed", "0,1", "--controllers", "pid", "--workers", "1"),
    "design": tuple(
        "--controllers pid --track fra4 --speed 40 --load 1 --train-seeds 1 --test-seeds 2 "
        "--duration 0.2 --dt 1e-3 --budget 13 --values 3 --workers 1".split()
    ),
    "ride-spectrum": ("--points", "32", "--controllers", "passive,pid"),
    "state-space": (),
    "fmu": ("--damper", "passive"),
}

#: what an option needs beside it to act at all, per command ("*": every command)
NEEDS = {
    ("*", "--track-seed"): RANDOM,
    ("*", "--min-wavelength"): ("--scenario", "fra4"),
    ("*", "--max-wavelength"): RANDOM,
    ("simulate", "--voltage"): ("--suspension", "mr"),
    ("simulate", "--damper-scale"): ("--suspension", "mr"),
    ("sweep", "--voltage"): ("--suspension", "mr"),
    ("sweep", "--damper-scale"): ("--suspension", "mr"),
    ("sweep", "--noise"): ("--suspension", "pid"),
    ("sweep", "--seed"): ("--suspension", "pid", "--noise", "1e-4,0,0,0"),
    ("compare", "--seed"): ("--sensor-noise", "0,0,0,0"),
    ("*", "--bound"): ("--objective", "constrained"),
    ("*", "--weights"): ("--objective", "weighted"),
}
#: options whose value is only used when writing: they get a folder to write
WRITING = {"--dpi"}
#: the commands whose --out is required, and the file each writes there (never the current folder)
FILE_OUT = {"report": "report.html", "fmu": "model.fmu"}


def _kind(param) -> str:
    """The type's name (int, float, str, ...): the option's annotation (typer from 0.22 on, whose
    own click has no ``param.type``), else click's type."""
    descriptor = getattr(param, "type_descriptor", None)
    if descriptor is not None:
        return getattr(descriptor.annotation, "__name__", "")
    return {"float": "float", "integer": "int", "text": "str"}.get(param.type.name, "")


@functools.lru_cache(maxsize=None)
def _options(name: str) -> set[str]:
    """Every option of command ``name``."""
    import typer

    from railride.cli import app

    return {o for p in typer.main.get_command(app).commands[name].params for o in p.opts}


def numeric_options() -> list[tuple[str, str]]:
    """(command, option) of every option that takes a number: typed int or float, or text whose
    metavar names only numbers."""
    import typer

    from railride.cli import app

    found = []
    for name, command in typer.main.get_command(app).commands.items():
        for param in command.params:
            if getattr(param, "is_flag", False) or not param.opts[0].startswith("--"):
                continue
            kind = _kind(param)
            words = [w for w in re.split(r"[^A-Z/]+", (param.metavar or "").upper()) if w]
            if kind in ("int", "float") or (kind == "str" and words and set(words) <= NUMERIC_WORDS):
                found.append((name, param.opts[0]))
    return found


def command_line(name: str, option: str, value: str, folder) -> list[str]:
    """The words of ``railride NAME``: its tiny case, what ``option`` needs, ``option value``
    (replacing the case's own), a place to write where the option writes, and JSON output."""
    args = [*BASE.get(name, ()), *NEEDS.get((name, option), NEEDS.get(("*", option), ()))]
    given: dict[str, str | None] = {}
    i = 0
    while i < len(args):  # flag -> value (None for a switch), the later one winning
        flag = args[i]
        has_value = i + 1 < len(args) and not args[i + 1].startswith("--")
        given[flag] = args[i + 1] if has_value else None
        i += 2 if has_value else 1
    given = {flag: text for flag, text in given.items() if flag in _options(name)}  # NEEDS are for all
    given[option] = value
    if option in WRITING:
        given["--out"] = str(folder / "out")
    if name in FILE_OUT:
        given["--out"] = str(folder / FILE_OUT[name])
    if "--format" in _options(name):
        given["--format"] = "json"
    words = [name]
    for flag, text in given.items():
        words += [flag] if text is None else [flag, text]
    return words


def _finite_json(text: str):
    def refuse(constant):
        raise AssertionError(f"JSON holds {constant}")

    return json.loads(text, parse_constant=refuse)


def check(result, args: list[str], option: str) -> None:
    """Success with finite output, or one line ``error: ...`` naming ``option``, status 2."""
    shown = " ".join(a if len(a) < 40 else a[:12] + "..." for a in args)
    assert result.exit_code in (0, 2), (shown, result.exit_code, result.stderr[-2000:])
    assert "Traceback" not in result.output, shown
    if result.exit_code == 0:
        if "--format" in args:
            _finite_json(result.stdout)
        return
    # the note of a first compile comes where this process meets a cold cache (by test order)
    lines = [line for line in result.stderr.strip().splitlines() if not line.startswith("compiling the stepper once")]
    assert len(lines) == 1 and lines[0].startswith("error: "), (shown, result.stderr)
    assert result.stdout == "", shown
    assert option in lines[0], (shown, lines[0])


CASES = [(name, option, value) for name, option in numeric_options() for value in VALUES]


@pytest.mark.slow
# NumPy's overflow and invalid-value warnings as errors (status 1 then): on the command line they
# are lines on stderr beside the result or the error, which this property allows neither
@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("name, option, value", CASES, ids=[f"{n} {o} {v[:8]}" for n, o, v in CASES])
def test_an_extreme_number_is_a_result_or_one_error_line(tmp_path, name, option, value):
    args = command_line(name, option, value, tmp_path)
    check(run(*args), args, option)


def test_the_numeric_options_are_found():
    # the property above is only as wide as what this finds: typed numbers, lists and ranges
    found = set(numeric_options())
    expected = {("frf", "--points"), ("simulate", "--duration"), ("sweep", "--speed"), ("study", "--track-seed")}
    assert expected <= found and ("tune", "--weights") in found and ("simulate", "--max-steps") in found
    assert ("simulate", "--scenario") not in found and ("compare", "--fault") not in found
