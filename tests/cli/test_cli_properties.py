"""A property of the whole command line: whatever number a user types into a numeric option, and
whatever a parameters or gains file holds, the command either succeeds with finite numbers in
its output, or exits 2 with one paragraph on stderr that names an option or a field and prints
the numbers it computes to at most four significant digits. Never status 1 (an internal fault),
never an exception.

Each command runs on a tiny case (0.2 s at dt = 1 ms, a few frequencies or cycles) so that one
example takes a fraction of a second; the examples are derandomized, so CI sees the same ones
on every run."""

from __future__ import annotations

import json
import math
import re
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from clihelp import run

PROPERTY = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)

#: the files vary more (a table, an entry, a value): more examples, each as fast
FILES = settings(PROPERTY, max_examples=100)

# -- what a user types --------------------------------------------------------------------------
#: numbers at the edges as typed on a command line: zero and signs, the smallest and largest
#: doubles and past them, inf and nan as people spell them, whole numbers past a double's
#: precision, int64 and any float, and text that is no number
EDGES = (
    "0",
    "-0",
    "-1",
    "1e-300",
    "-1e-300",
    "1e300",
    "-1e300",
    "1e400",
    "inf",
    "-inf",
    "+Infinity",
    "nan",
    "NaN",
    "9" * 400,
    "-" + "9" * 400,
    "18446744073709551616",
    "9007199254740993",
    "",
    " ",
    "abc",
    "1e",
    "0x10",
)


def _text(value: float) -> str:
    return f"{value:.6g}"


def number(lo: float, hi: float) -> st.SearchStrategy[str]:
    """An ordinary value in [lo, hi] (as a user would type it) or an edge value."""
    ordinary = st.floats(lo, hi, allow_nan=False).map(_text)
    return st.one_of(ordinary, st.sampled_from(EDGES))


def whole(lo: int, hi: int) -> st.SearchStrategy[str]:
    return st.one_of(st.integers(lo, hi).map(str), st.sampled_from(EDGES), st.sampled_from(("2.5", "1e3")))


def listed(item: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
    """A comma list or a START:STOP:COUNT range of a multi-valued option."""
    count = st.one_of(st.integers(1, 3).map(str), st.sampled_from(("0", "-1", "1e12", "2.5", "nan", "")))
    return st.one_of(
        item,
        st.lists(item, min_size=1, max_size=3).map(",".join),
        st.tuples(item, item, count).map(":".join),
    )


def window() -> st.SearchStrategy[str]:
    side = st.one_of(st.just(""), number(0.0, 0.3))
    return st.tuples(side, side).map(":".join) | st.sampled_from(("0:inf", "nan:1", "1", ":", "0:", "0.1:0.05"))


def four(lo: float, hi: float) -> st.SearchStrategy[str]:
    """Four numbers Z,ANGLE,VEL,RATE (sensor noise, weights), sometimes three or five."""
    return st.lists(number(lo, hi), min_size=3, max_size=5).map(",".join)


def size() -> st.SearchStrategy[str]:
    return st.sampled_from(("64M", "4G", "1K", "0", "-1G", "1e300G", "nanG", "infG", "", "9" * 400))


# -- the commands, each on a tiny case ----------------------------------------------------------
SHORT = {"--duration": "0.2", "--dt": "1e-3"}
STORED = {**SHORT, "--output-rate": "100"}
SCENE = {
    "--speed": number(1.0, 150.0),
    "--duration": number(0.05, 0.3),
    "--dt": number(2e-4, 5e-3),
    "--window": window(),
}
SINE = {
    "--amplitude": number(-0.1, 0.1),
    "--wavelength": number(1.0, 200.0),
    "--rail-phase": number(-360.0, 360.0),
}
RANDOM = {
    "--track-seed": whole(0, 10),
    "--min-wavelength": number(0.5, 10.0),
    "--max-wavelength": number(10.0, 300.0),
}

#: name -> (the fixed options, the numeric options drawn and their values); every command
#: prints JSON (--format json), whose numbers are checked
CASES: dict[str, tuple[dict[str, str], dict[str, st.SearchStrategy[str]]]] = {
    "simulate": (
        STORED,
        {**SCENE, **SINE, "--output-rate": number(10.0, 1000.0), "--load": number(0.5, 2.0), "--max-memory": size()},
    ),
    "simulate-bump": ({**STORED, "--scenario": "bump"}, {**SCENE, **SINE}),
    "simulate-random": ({**STORED, "--scenario": "fra4", "--min-wavelength": "2"}, {**SCENE, **RANDOM}),
    "simulate-mr": (
        {**STORED, "--suspension": "mr"},
        {"--voltage": number(0.0, 3.0), "--damper-scale": number(0.1, 10.0), "--dt": number(2e-4, 2e-3)},
    ),
    "compare": (
        {**STORED, "--control-rate": "100", "--controllers": "pid", "--no-bounds": ""},
        {
            **SCENE,
            "--speed": listed(number(1.0, 150.0)),
            "--control-rate": number(1.0, 1000.0),
            "--damper-scale": number(0.1, 10.0),
            "--delay": whole(1, 8),
            "--load": number(0.5, 2.0),
            "--sensor-noise": four(0.0, 1e-3),
            "--fault": number(0.0, 0.3).map(lambda t: f"1R-off@{t}"),
        },
    ),
    "compare-noise": (
        {
            **STORED,
            "--control-rate": "100",
            "--controllers": "sas-attitude",
            "--no-bounds": "",
            "--sensor-noise": "0,0,0,0",
        },
        {"--seed": whole(0, 10), "--sensor-noise": four(0.0, 1e-3)},
    ),
    "frf": (
        {"--points": "16"},
        {
            "--speed": number(1.0, 150.0),
            "--fmin": number(0.01, 1.0),
            "--fmax": number(1.0, 50.0),
            "--points": whole(2, 64),
        },
    ),
    "damper": (
        {"--cycles": "2", "--frequency": "2", "--amplitude": "0.01", "--voltage": "0,1"},
        {
            "--amplitude": number(1e-3, 0.05),
            "--frequency": number(0.5, 10.0),
            "--voltage": listed(number(0.0, 3.0)),
            "--cycles": whole(2, 4),
        },
    ),
    "tracking": (
        {"--cycles": "2"},
        {
            "--amplitude": number(100.0, 20000.0),
            "--frequency": number(0.5, 5.0),
            "--B": number(0.0, 2.0),
            "--G": number(0.0, 0.01),
            "--stroke": number(1e-3, 0.05),
            "--cycles": whole(2, 4),
        },
    ),
    "ride-spectrum": (
        {"--points": "32", "--controllers": "passive,pid"},
        {
            "--speed": number(1.0, 150.0),
            "--min-wavelength": number(0.5, 10.0),
            "--max-wavelength": number(10.0, 300.0),
            "--points": whole(2, 64),
            "--control-rate": number(10.0, 1000.0),
            "--delay": whole(0, 4),
            "--load": number(0.5, 2.0),
        },
    ),
    "sweep": (
        {**SHORT, "--speed": "40,50"},
        {
            **SCENE,
            "--speed": listed(number(1.0, 150.0)),
            "--wavelength": listed(number(1.0, 200.0)),
            "--amplitude": listed(number(-0.1, 0.1)),
            "--rail-phase": listed(number(-360.0, 360.0)),
            "--workers": whole(1, 2),
        },
    ),
    "sweep-random": (
        {**SHORT, "--scenario": "fra4", "--track-seed": "0,1"},
        {
            "--track-seed": listed(whole(0, 10)),
            "--min-wavelength": number(0.5, 10.0),
            "--speed": listed(number(1.0, 150.0)),
        },
    ),
    "sweep-mr": (
        {**SHORT, "--suspension": "mr", "--voltage": "0,1"},
        {"--voltage": listed(number(0.0, 3.0)), "--damper-scale": listed(number(0.1, 10.0))},
    ),
    "sweep-pid": (
        {**SHORT, "--suspension": "pid", "--noise": "1e-4,0,0,0", "--seed": "0,1"},
        {
            "--noise": four(0.0, 1e-3),
            "--seed": listed(whole(0, 10)),
            "--gain": listed(number(0.0, 1e7)).map(lambda v: f"pid.kp={v}"),
        },
    ),
    "study": (
        {**SHORT, "--scenario": "fra4", "--track-seed": "0,1", "--controllers": "passive,pid"},
        {
            **SCENE,
            "--track-seed": listed(whole(0, 10)),
            "--speed": listed(number(1.0, 150.0)),
            "--load": listed(number(0.5, 2.0)),
            "--stiffness": listed(number(0.5, 2.0)),
            "--delay": listed(whole(1, 4)),
        },
    ),
    "tune": (
        {**SHORT, "--controllers": "pid", "--values": "3", "--budget": "8"},
        {
            "--values": whole(1, 4),
            "--budget": whole(1, 12),
            "--span": number(1.01, 100.0),
            "--speed": number(1.0, 150.0),
            "--load": listed(number(0.5, 2.0)),
            "--damper-scale": number(0.1, 10.0),
            "--penalty": number(0.0, 10.0),
        },
    ),
    "tune-objective": (
        {
            **SHORT,
            "--controllers": "pid",
            "--values": "3",
            "--budget": "8",
            "--objective": "constrained",
            "--bound": "1",
        },
        {"--bound": number(0.1, 10.0)},
    ),
    "tune-weights": (
        {
            **SHORT,
            "--controllers": "pid",
            "--values": "3",
            "--budget": "8",
            "--objective": "weighted",
            "--weights": "1,1,1,1",
        },
        {"--weights": four(0.0, 10.0)},
    ),
    "pareto": (
        {**SHORT, "--samples": "4"},
        {"--samples": whole(1, 8), "--seed": whole(0, 10), "--speed": number(1.0, 150.0)},
    ),
}


def command_line(name: str, drawn: dict[str, str]) -> list[str]:
    base, _ = CASES[name]
    args = [name if name == "ride-spectrum" else name.split("-")[0]]  # compare-noise: compare
    for flag, value in {**base, **drawn}.items():
        args += [flag] if flag.startswith("--no-") else [flag, value]
    return [*args, "--format", "json"]


# -- the property -------------------------------------------------------------------------------
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")


#: a field named as the library names it: ``duration = 0.2``, ``'m_c' = ...``, ``dt <= ...``,
#: ``error: dt: ...``
FIELD = re.compile(r"(?:'[A-Za-z_][\w.]*'|\b[A-Za-z_]\w*) [<>]?= |^error: [A-Za-z_][\w.]*: ")

#: messages known to print a computed number with more digits than four, left to the work on
#: the formatting of numbers in messages (they still pass every other check); remove an entry
#: once its message is fixed, and the property checks its digits again
LONG_NUMBERS_ELSEWHERE: tuple[str, ...] = ()


def significant_digits(text: str) -> int:
    mantissa = re.split("[eE]", text.lstrip("+-"))[0].replace(".", "")
    return len(mantissa.strip("0")) or 1


def _as_float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def computed_numbers(message: str, given: list[str], paths=()) -> list[str]:
    """The numbers of ``message`` that are not the user's own (anything of the same value in
    ``given``, the command line and the file's values), without those in the ``paths`` named."""
    for path in paths:
        message = message.replace(str(path), "PATH")
    own = [_as_float(m) for text in given for m in NUMBER.findall(text)]
    # an echo may round the user's value (1.84467e+19 for 18446744073709551616)
    return [m for m in NUMBER.findall(message) if not any(math.isclose(_as_float(m), v, rel_tol=1e-5) for v in own)]


def check(result, args: list[str], names=(), given=(), paths=()) -> None:
    """Success with finite numbers on stdout, or status 2 with one paragraph on stderr naming an
    option of ``args`` or one of ``names``; numbers it computes have at most four significant
    digits (whole numbers, counts and limits, are exact)."""
    where = f"railride {' '.join(repr(a) if not a or ' ' in a else a for a in args)}"
    if result.exit_code == 0:
        doc = json.loads(result.stdout)
        bad = [path for path, v in _numbers(doc) if not math.isfinite(v)]
        assert not bad, f"{where}: non-finite numbers in the output at {bad[:5]}"
        return
    assert result.exit_code == 2, f"{where}: exit {result.exit_code}\n{result.stderr}"
    message = result.stderr.strip()
    assert message and "\n\n" not in message, f"{where}: more than one paragraph:\n{result.stderr}"
    assert "Traceback" not in result.stderr, f"{where}:\n{result.stderr}"
    named = [a for a in args if a.startswith("--")] + list(names)
    assert any(n in message for n in named) or FIELD.search(message), f"{where}: names no option or field:\n{message}"
    long = [
        m
        for m in computed_numbers(message, [*args, *given], paths)
        if ("." in m or "e" in m.lower()) and significant_digits(m) > 4
    ]
    if long and any(re.search(known, message) for known in LONG_NUMBERS_ELSEWHERE):
        return  # checked above for all but its digits: see LONG_NUMBERS_ELSEWHERE
    assert not long, f"{where}: computed numbers {long} with more than four significant digits:\n{message}"


def _numbers(doc, path="$"):
    if isinstance(doc, bool) or doc is None or isinstance(doc, str):
        return
    if isinstance(doc, (int, float)):
        yield path, float(doc) if not isinstance(doc, int) or abs(doc) < 2**1000 else math.inf
    elif isinstance(doc, dict):
        for key, value in doc.items():
            yield from _numbers(value, f"{path}.{key}")
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield from _numbers(value, f"{path}[{i}]")


@st.composite
def drawn_options(draw, name: str) -> dict[str, str]:
    """One or two of the command's numeric options, each with a value."""
    options = CASES[name][1]
    flags = draw(st.lists(st.sampled_from(sorted(options)), min_size=1, max_size=2, unique=True))
    return {flag: draw(options[flag]) for flag in flags}


@pytest.mark.parametrize("name", sorted(CASES))
@PROPERTY
@given(data=st.data())
def test_numeric_options(name, data):
    drawn = data.draw(drawn_options(name), label="options")
    args = command_line(name, drawn)
    check(run(*args), args)


# -- what the property found, kept as examples of their own -------------------------------------
FOUND = [
    # the parser's usage errors were a usage text, a hint, a blank line and "Error: ..."
    ["frf", "--points", "1e-300", "--format", "json"],
    ["compare", "--control-rate", "", "--format", "json"],
    # 2 cycles at 1.5 Hz were 1.333 s, not a whole number of 0.1 ms steps: an error
    ["tracking", "--cycles", "2", "--frequency", "1.5", "--format", "json"],
    # a cycle of 1e304 steps: the search for a stride that divides it never ended
    ["damper", "--amplitude", "0.01", "--voltage", "1", "--frequency", "1e-300", "--format", "json"],
    # an open window's end (inf) went into the JSON record: "not JSON compliant"
    ["study", *sum(map(list, SHORT.items()), []), "--scenario", "fra4", "--track-seed", "0,1", "--window", "0:"]
    + ["--controllers", "passive,pid", "--format", "json"],
    # the step of a range of 400-digit seeds overflowed a float in the message
    ["sweep", *sum(map(list, SHORT.items()), []), "--scenario", "fra4", "--track-seed", f"0:{'9' * 400}:3"]
    + ["--format", "json"],
]


@pytest.mark.parametrize("args", FOUND, ids=[" ".join(a[:3]) for a in FOUND])
def test_found_by_the_property(args):
    check(run(*args), args)


def test_a_usage_error_is_one_line_naming_the_option_and_the_value():
    result = run("frf", "--points", "1e3")
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr.startswith("error: --points = '1e3': ") and result.stderr.count("\n") == 1, result.stderr
    result = run("frf", "--pionts", "100")
    assert result.exit_code == 2 and result.stderr.count("\n") == 1
    assert "--pionts" in result.stderr and "railride frf --help" in result.stderr, result.stderr


def test_the_open_end_of_a_study_window_is_the_run_s_end():
    args = [*FOUND[4]]
    doc = json.loads(run(*args).stdout)
    assert doc["settings"]["window_s"] == [0.0, 0.2]


# -- the files: parameters (--params) and gains (--gains) -------------------------------------------
#: values at the edges as a TOML file holds them: the numbers above, an integer past any float
#: and one past the digits Python converts, and every other TOML type where a number belongs
TOML_EDGES = (
    "0",
    "-0.0",
    "-1.0",
    "1e-300",
    "1e300",
    "1.7976931348623157e308",
    "inf",
    "-inf",
    "nan",
    "9" * 400,
    "-" + "9" * 400,
    "9" * 5000,
    "1" * 25,
    "0x7fffffffffffffff",
    '""',
    '"1.0"',
    "true",
    "[]",
    "[1.0, 2.0]",
    "{}",
    "1979-05-27",
    "07:32:00",
)
#: what can be wrong with a whole file besides one value
BROKEN = ("", "[vehicle", "x = = 1", "[other]\na = 1", "a = 1\na = 2")


def entries(text: str) -> list[tuple[int, str, str, float]]:
    """(line, [table], key, value) of every numeric entry of a TOML text as `to_toml` writes it."""
    found, table = [], ""
    for i, line in enumerate(text.splitlines()):
        if line.startswith("["):
            table = line.strip("[] ")
        elif " = " in line:
            key, _, rest = line.partition(" = ")
            value = rest.split("#")[0].strip()
            if value not in ("true", "false"):  # the numbers: a switch (rigid_carbody) is not one
                found.append((i, table, key, float(value)))
    return found


@st.composite
def toml_file(draw, text: str) -> tuple[str, list[str], list[str]]:
    """(the file's text, the tables and keys changed, the values written): one or two entries
    of ``text`` changed (scaled, or an edge value), or one taken out, or one unknown added, or a
    broken file."""
    lines = text.splitlines()
    kind = draw(st.sampled_from(("value", "value", "value", "drop", "unknown", "broken")))
    if kind == "broken":
        return draw(st.sampled_from(BROKEN)), [], []
    found = entries(text)
    picked = draw(st.lists(st.sampled_from(found), min_size=1, max_size=2, unique=True))
    names = [n for _, table, key, _ in picked for n in (table, key)]
    if kind == "drop":
        del lines[picked[0][0]]
        return "\n".join(lines), names, []
    if kind == "unknown":
        lines.insert(picked[0][0], "unknown_entry = 1.0")
        return "\n".join(lines), [*names, "unknown_entry"], []
    written = []
    for i, _, key, value in picked:
        scaled = st.floats(0.01, 100.0).map(lambda f, v=value: repr(v * f) if v else repr(f))
        new = draw(st.one_of(scaled, st.sampled_from(TOML_EDGES)))
        lines[i] = f"{key} = {new}"
        written.append(new)
    return "\n".join(lines), names, written


def _params_text() -> str:
    from railride.model.params import VehicleParams

    return VehicleParams.preset("paper").to_toml()


def _gains_text() -> str:
    from railride.secondary.control import GainSet

    return GainSet.default().to_toml(provenance=False)  # the gains' entries, every one a number


#: the commands that read each file, on their tiny cases
PARAMS_COMMANDS = (
    ["modes"],
    ["frf", "--points", "16"],
    ["simulate", *sum(map(list, STORED.items()), [])],
    ["ride-spectrum", "--points", "32", "--controllers", "passive"],
)
GAINS_COMMANDS = (
    ["compare", *sum(map(list, STORED.items()), []), "--control-rate", "100", "--controllers", "all", "--no-bounds"],
    ["ride-spectrum", "--points", "32", "--controllers", "all"],
    ["sweep", *sum(map(list, SHORT.items()), []), "--suspension", "sas-attitude-ride"],
)


def _run_with_file(option: str, command: list[str], text: str, names: list[str], written: list[str]) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "file.toml"
        path.write_text(text, encoding="utf-8")
        args = [*command, option, str(path), "--format", "json"]
        check(run(*args), args, names=[*names, str(path)], given=written, paths=[path, folder])


@FILES
@given(data=st.data())
def test_parameters_files(data):
    command = data.draw(st.sampled_from(PARAMS_COMMANDS), label="command")
    text, names, written = data.draw(toml_file(_params_text()), label="file")
    _run_with_file("--params", command, text, names, written)


@FILES
@given(data=st.data())
def test_gains_files(data):
    command = data.draw(st.sampled_from(GAINS_COMMANDS), label="command")
    text, names, written = data.draw(toml_file(_gains_text()), label="file")
    _run_with_file("--gains", command, text, names, written)
