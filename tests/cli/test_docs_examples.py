"""The command lines that README.md and docs/*.md show, checked against the command line itself,
so that a changed message, a renamed option or a removed command fails here and not in a
reader's shell.

* Every documented error, a line ``$ railride ...`` in a code block followed by a line
  ``error: ...``, runs in-process in an empty folder (with the few files a table below makes)
  and must exit with status 2, print nothing on stdout, and print exactly that line on stderr.
* Every other ``railride`` command line in a code block (``$ railride``, ``railride``, the
  ``railride`` part of ``pip install ... && railride ...``, ``python -m railride``) must parse:
  its command exists and the parser takes its options and values (click's ``make_context``,
  nothing run). A value an option's metavar lists the choices of (``--method auto|rk4|exact``)
  must be one of them. A usage synopsis (a line with ``[...]``, and its continuation lines)
  cannot parse; every option it names must be an option of its command.
* Every documented command that is cheap also runs, in-process in an empty folder, and must exit
  with status 0: a value out of range, a refused combination or a file the docs assume fails
  here. The files a command names (``--gains my_gains.toml``, ``file:track.csv``) are made from
  a table below (`FILES`). Cheap is a rule: each documented line's run was timed once on a
  2-core machine and the lines that took at most about 5 s run; no test asserts a time. By that
  rule these stay parse-only (`parse_only`): ``tune``, ``design``, ``study``, ``sweep`` and
  ``pareto`` (minutes); ``--backend gpu`` (it needs a GPU, and under the tests' CUDA simulator
  a run takes far longer); a comparison that draws its figures or page for ``--controllers all``
  (``report``, ``--report``, ``--out``: 11 to 13 s measured here). The ``fmu`` lines that build
  a binary need a C compiler, and are skipped without one, as the FMU tests are.
* A parse-only command runs up to its first vehicle run, where a stand-in stepper stops it: its
  values and their combination passed every check the command makes before it runs. Not the
  lines that need what a test has not: a cluster (``--scheduler``, ``--scheduler-file``) or a
  GPU (``--backend gpu``).
"""

from __future__ import annotations

import csv
import re
import shlex
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import typer.main

import railride
from railride.cli import app
from railride.model.track import spectrum
from railride.run import simulation
from clihelp import run

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
GROUP = typer.main.get_command(app)


@dataclass(frozen=True)
class Line:
    page: str
    number: int
    text: str

    @property
    def where(self) -> str:
        return f"{self.page}:{self.number}"


def _code_lines(path: Path) -> list[Line]:
    """The lines inside the fenced code blocks of a page, a line ending in a backslash joined
    with the next (a shell continuation)."""
    lines, inside, held = [], False, None
    for number, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if raw.lstrip().startswith("```"):
            inside, held = not inside, None
            continue
        if not inside:
            continue
        if held is not None:
            held = Line(held.page, held.number, held.text + " " + raw.strip())
        else:
            held = Line(str(path.relative_to(ROOT)), number, raw)
        if held.text.rstrip().endswith("\\"):
            held = Line(held.page, held.number, held.text.rstrip()[:-1])
            continue
        lines.append(held)
        held = None
    return lines


CODE = [line for page in PAGES for line in _code_lines(page)]

#: the shell's words that end one command and start another
_OPERATORS = {"&&", "||", "|", ";", ">", ">>", "<", "&"}
#: how a line starts a railride command: ``railride``, ``python -m railride``
_STARTS = (["railride"], ["python", "-m", "railride"], ["python3", "-m", "railride"])


def _railride_words(text: str) -> list[list[str]]:
    """The railride commands of a shell line: for each, the words after ``railride``. A command
    counts where it starts the line (after an optional ``$``) or follows ``&&``, ``|``, ``;``
    (so a table row that holds the word railride is no command); a ``#`` comment is dropped."""
    lexer = shlex.shlex(text.strip().removeprefix("$ "), posix=True, punctuation_chars="&|;<>")
    lexer.whitespace_split = True
    lexer.commenters = "#"
    words = list(lexer)
    commands, start = [], 0
    for end in [i for i, w in enumerate(words) if w in _OPERATORS] + [len(words)]:
        segment = words[start:end]
        for head in _STARTS:
            if segment[: len(head)] == head:
                commands.append(segment[len(head) :])
        start = end + 1
    return commands


def _is_command(line: Line) -> bool:
    return (
        re.match(r"\s*(\$ )?(python3? -m )?railride( |$)", line.text) is not None
        or re.search(r"(&&|\||;)\s*(python3? -m )?railride( |$)", line.text) is not None
    )


def _is_synopsis(line: Line) -> bool:
    return _is_command(line) and "[" in line.text


# ---------------------------------------------------------------------------------------------
# the documented errors


def _errors() -> list[tuple[Line, str]]:
    found = []
    for page in PAGES:
        lines = _code_lines(page)
        for line, after in zip(lines, lines[1:]):
            if line.text.startswith("$ railride ") and after.text.startswith("error: "):
                found.append((line, after.text))
    return found


ERRORS = _errors()


def _gains_with_a_bad_entry(folder: Path) -> None:
    """gains.toml: the shipped gains, but for ``kd = 'lots'`` in ``[pid]``."""
    shipped = (Path(railride.__file__).parent / "data" / "gains.toml").read_text(encoding="utf-8")
    bad, n = re.subn(r"(?m)(^\[pid\]\n(?:[^\[\n].*\n|\n)*?)kd = .*$", r"\1kd = 'lots'", shipped)
    assert n == 1, "the shipped gains.toml has no [pid] kd entry to spoil"
    (folder / "gains.toml").write_text(bad, encoding="utf-8")


def _earlier_tune(folder: Path) -> None:
    """paper-tune/runs.csv: the run table an earlier ``tune --out paper-tune`` left."""
    (folder / "paper-tune").mkdir()
    (folder / "paper-tune" / "runs.csv").write_text("study,run\n", encoding="utf-8")


def _no_run(*args, **kwargs):
    raise AssertionError("a documented error example reached a vehicle run: it must fail before any")


#: the files a documented error needs in the folder it runs in, by its command line (after
#: ``$ railride``); the docs show the command and the error, not how the file came to be
SETUP = {
    "compare --gains gains.toml": _gains_with_a_bad_entry,
    "tune --out paper-tune": _earlier_tune,
}


def test_the_docs_hold_the_error_examples():
    """The parser finds the examples (an empty list would pass every test below)."""
    assert len(ERRORS) >= 30, [line.where for line, _ in ERRORS]
    commands = {line.text.removeprefix("$ railride ") for line, _ in ERRORS}
    assert set(SETUP) <= commands, set(SETUP) - commands  # no file made for an example that is gone


@pytest.mark.parametrize(
    ("line", "error"), ERRORS, ids=[f"{line.page}:{line.text.removeprefix('$ railride ')}" for line, _ in ERRORS]
)
def test_a_documented_error_is_the_error_the_command_prints(line, error, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # an example that no longer fails would run its command in full (a tune: minutes); the
    # stepper of the vehicle runs refuses, so that it fails at once (as an internal error)
    monkeypatch.setattr(simulation, "step", _no_run)
    command = line.text.removeprefix("$ railride ")
    if command in SETUP:
        SETUP[command](tmp_path)
    result = run(*shlex.split(command))
    # the note of a first compile comes where the process meets a cold cache (by test order)
    printed = [text for text in result.stderr.splitlines() if not text.startswith("compiling the stepper once")]
    said = f"{line.where}: railride {command}\n{result.stderr}{result.stdout}"
    assert (result.exit_code, printed) == (2, [error]), said
    assert result.stdout == ""


# ---------------------------------------------------------------------------------------------
# every other documented command line parses


def _synopses() -> list[tuple[Line, str, list[str]]]:
    """(line, command, options) of every usage synopsis, its continuation lines (those that
    start with ``[`` under it) included."""
    found = []
    for page in PAGES:
        lines = _code_lines(page)
        for i, line in enumerate(lines):
            if not _is_synopsis(line):
                continue
            text = line.text
            for after in lines[i + 1 :]:
                if not after.text.lstrip().startswith("["):
                    break
                text += " " + after.text
            name = re.match(r"\s*(?:\$ )?(?:python3? -m )?railride ([a-z-]+)", text)
            assert name is not None, line.where
            found.append((line, name.group(1), re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", text)))
    return found


SYNOPSES = _synopses()

#: lines that are neither a command nor a synopsis of one, and the commands they stand for
STANDS_FOR = {
    "railride compare | sweep | tune | study | design | ride-spectrum ... --report FILE.html": [
        [name, "--report", "page.html"] for name in ("compare", "sweep", "tune", "study", "design", "ride-spectrum")
    ],
}


def _commands() -> list[tuple[Line, list[str]]]:
    """(line, words after railride) of every documented command that is not an error example
    nor a synopsis."""
    errors = {(line.page, line.number) for line, _ in ERRORS}
    found = []
    for line in CODE:
        if not _is_command(line) or _is_synopsis(line) or (line.page, line.number) in errors:
            continue
        if line.text.strip() in STANDS_FOR:
            found += [(line, words) for words in STANDS_FOR[line.text.strip()]]
            continue
        found += [(line, words) for words in _railride_words(line.text)]
    return found


COMMANDS = _commands()


def _options(command) -> dict[str, object]:
    return {opt: param for param in command.params for opt in [*param.opts, *param.secondary_opts]}


def _choices(param) -> list[str] | None:
    """The values an option's metavar lists (``auto|rk4|exact``), or None where it names a kind
    of value (``NAME|FILE.toml``, ``M/S[,...]|A:B:COUNT``)."""
    metavar = getattr(param, "metavar", None) or ""
    words = metavar.split("|")
    if len(words) > 1 and all(re.fullmatch(r"[a-z][a-z0-9-]*", w) for w in words):
        return words
    return None


def _parse(words: list[str]):
    """The command's parsed context: its name must be a command, and its options and values
    must satisfy the parser. Nothing runs."""
    group_options = _options(GROUP)
    while words and words[0].startswith("-"):
        assert words[0] in group_options, f"{words[0]}: not an option of railride"
        words = words[1:]
    assert words, "no command"
    command = GROUP.get_command(GROUP.make_context("railride", [], resilient_parsing=True), words[0])
    assert command is not None, f"{words[0]!r}: no such command; the commands are {sorted(GROUP.commands)}"
    context = command.make_context(words[0], list(words[1:]))
    options = _options(command)
    for word, value in zip(words[1:], words[2:]):
        param = options.get(word)
        allowed = _choices(param) if param is not None else None
        if allowed is not None:
            assert value in allowed, f"{word} {value}: not one of {'|'.join(allowed)}"
    return context


def test_the_docs_hold_the_commands():
    assert len(COMMANDS) >= 60, [line.where for line, _ in COMMANDS]
    assert len(SYNOPSES) >= 10, [line.where for line, *_ in SYNOPSES]
    shown = {line.text.strip() for line in CODE}
    assert set(STANDS_FOR) <= shown, set(STANDS_FOR) - shown


@pytest.mark.parametrize(
    ("line", "words"), COMMANDS, ids=[f"{line.where} {' '.join(words)}"[:120] for line, words in COMMANDS]
)
def test_a_documented_command_parses(line, words, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        _parse(words)
    except Exception as exc:  # the parser's usage error or a failed check above, named
        pytest.fail(f"{line.where}: railride {' '.join(words)}\n{type(exc).__name__}: {exc}")


@pytest.mark.parametrize(
    ("line", "name", "options"), SYNOPSES, ids=[f"{line.where} {name}" for line, name, _ in SYNOPSES]
)
def test_a_documented_synopsis_names_options_of_its_command(line, name, options):
    command = GROUP.commands.get(name)
    assert command is not None, f"{line.where}: {name!r}: no such command"
    unknown = sorted(set(options) - set(_options(command)))
    assert not unknown, f"{line.where}: railride {name} has no option {', '.join(unknown)}"


def test_the_checks_fail_where_they_should():
    """What the checks above must refuse: a removed command, an unknown option, a value an
    integer option cannot take, a value outside a metavar's list."""
    for words in (
        ["nosuch"],
        ["frf", "--pionts", "100"],
        ["frf", "--points", "abc"],
        ["simulate", "--method", "rk5"],
    ):
        with pytest.raises(Exception):  # noqa: B017 (the parser's or the check's own)
            _parse(words)
    assert _parse(["simulate", "--method", "rk4", "--speed", "40"]).params["speed"] == 40.0
    assert _railride_words("python3 -m pip install . && railride compare --speed 40  # a comment") == [
        ["compare", "--speed", "40"]
    ]
    assert _railride_words("│ acceleration │ railride │ 0.56 │") == []
    # the rule of what runs, and a run that fails is a failure
    assert parse_only(["tune", "--out", "t"]) and parse_only(["compare", "--backend", "gpu"])
    assert parse_only(["compare", "--controllers", "all", "--comfort", "--report", "all.html"])
    assert parse_only(["report", "--controllers", "all"])
    assert parse_only(["compare", "--controllers", "all"]) is None
    assert parse_only(["fmu", "--out", "v.fmu"]) is None
    with pytest.raises(AssertionError, match="exited with status 2"):
        _run_documented(["simulate", "--speed", "-1"])


# ---------------------------------------------------------------------------------------------
# every cheap documented command runs

#: the commands that run for minutes (a tuning, a study, a sweep over speeds or seeds)
LONG = ("tune", "design", "study", "sweep", "pareto")


def _name(words: list[str]) -> str:
    """The command's name: its first word that is not an option of railride itself."""
    return next((w for w in words if not w.startswith("-")), "")


def _value(words: list[str], option: str) -> str | None:
    return next((value for word, value in zip(words, words[1:]) if word == option), None)


def parse_only(words: list[str]) -> str | None:
    """Why a documented command (the words after railride) only parses, by the module's rule;
    None where it runs."""
    name = _name(words)
    if name in LONG:
        return f"railride {name} runs for minutes"
    if _value(words, "--backend") == "gpu":
        return "--backend gpu needs a GPU (under the tests' CUDA simulator a run takes far longer)"
    draws = name == "report" or "--report" in words or "--out" in words
    if name in ("compare", "report") and _value(words, "--controllers") == "all" and draws:
        return "the figures of every law take over the rule's 5 s"
    return None


def _shipped_gains(path: Path) -> None:
    """The gains file railride ships (railride/data/gains.toml), as the reader's own."""
    shutil.copyfile(Path(railride.__file__).parent / "data" / "gains.toml", path)


def _measured_track(path: Path) -> None:
    """A measured profile (s, z_L, z_R): the rails of railride's FRA class 4 track, seed 0, every
    0.25 m from s = 0 to 1000 m (the default run, 55.56 m/s for 10 s, covers 556 m)."""
    s = np.arange(0.0, 1000.0 + 0.125, 0.25)
    z_left, z_right, *_ = railride.scenario("fra4", seed=0).track.evaluate(s)
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(["s [m]", "z_L [m]", "z_R [m]"])
        writer.writerows(zip(s, z_left, z_right))


def _own_damper(path: Path) -> None:
    """A damper file: the railway damper with a stronger field-dependent yield force."""
    path.write_text('[damper]\npreset = "railway"\nalpha_b = 5.0e6\n', encoding="utf-8")


def _own_spectrum(path: Path) -> None:
    """A spectrum table: FRA class 4 at 60 log-spaced wavenumbers over wavelengths 0.5-200 m."""
    W = np.geomspace(2 * np.pi / 200, 2 * np.pi / 0.5, 60)
    rows = zip(W, spectrum("fra4", W), spectrum("fra4", W, "cross-level"))
    path.write_text(
        "wavenumber_rad_per_m,vertical,cross_level\n"
        + "".join(f"{float(w)!r},{float(v)!r},{float(x)!r}\n" for w, v, x in rows),
        encoding="utf-8",
    )


#: the files a documented command names and the docs assume the reader has, by their name on
#: the command line (``file:NAME`` for a measured profile, ``psd:NAME`` for a spectrum), and how
#: the test makes them
FILES = {
    "my_gains.toml": _shipped_gains,
    "track.csv": _measured_track,
    "my_damper.toml": _own_damper,
    "my_line.csv": _own_spectrum,
}

RUNS = [(line, words) for line, words in COMMANDS if parse_only(words) is None]


def _files(words: list[str]) -> list[str]:
    return [name for word in words if (name := word.removeprefix("file:").removeprefix("psd:")) in FILES]


def _run_documented(words: list[str]) -> None:
    """Run the command in the current folder, after making the files it names; fail unless it
    exits with status 0."""
    for name in _files(words):
        FILES[name](Path(name))
    result = run(*words)
    assert result.exit_code == 0, (
        f"railride {' '.join(words)} exited with status {result.exit_code}\n{result.stderr}{result.stdout}"
    )


def test_the_docs_hold_commands_that_run():
    """The rule leaves a run for each cheap command the docs show, and every file the table
    makes is named by a command that runs (no file for a line that is gone)."""
    names = {_name(words) for _, words in RUNS}
    cheap = {"simulate", "compare", "report", "frf", "modes", "vehicles", "damper", "tracking", "ride-spectrum", "fmu"}
    assert cheap <= names, cheap - names
    assert len(RUNS) >= 40, [line.where for line, _ in RUNS]
    named = {name for _, words in RUNS + CHECKED for name in _files(words)}
    assert named == set(FILES), set(FILES) ^ named


@pytest.mark.parametrize(("line", "words"), RUNS, ids=[f"{line.where} {' '.join(words)}"[:120] for line, words in RUNS])
def test_a_documented_command_runs(line, words, tmp_path, monkeypatch):
    if _name(words) == "fmu" and "--sources-only" not in words and shutil.which("cc") is None:
        pytest.skip("no C compiler to build the FMU")
    monkeypatch.chdir(tmp_path)
    try:
        _run_documented(words)
    except AssertionError as exc:
        pytest.fail(f"{line.where}: {exc}")


class _FirstRun(Exception):
    """The stand-in stepper's signal: the command got to its first vehicle run."""


def _needs_what_a_test_has_not(words: list[str]) -> bool:
    """A Dask cluster (its address or its scheduler file) or a GPU."""
    return "--scheduler" in words or "--scheduler-file" in words or _value(words, "--backend") == "gpu"


CHECKED = [(line, words) for line, words in COMMANDS if parse_only(words) and not _needs_what_a_test_has_not(words)]


def test_the_long_commands_are_checked_up_to_their_first_run():
    names = {_name(words) for _, words in CHECKED}
    assert set(LONG) <= names, set(LONG) - names


def _up_to_the_first_run(words: list[str], monkeypatch) -> None:
    """Run the command in the current folder, after making the files it names, with a stepper
    that stops it at its first vehicle run; fail unless it got there."""
    reached = []

    def first_run(*args, **kwargs):
        reached.append(True)
        raise _FirstRun

    monkeypatch.setattr(simulation, "step", first_run)
    for name in _files(words):
        FILES[name](Path(name))
    result = run(*words)
    assert reached, f"railride {' '.join(words)} stopped before its first run, with status {result.exit_code}\n" + (
        result.stderr + result.stdout
    )


def test_a_long_command_refused_before_its_first_run_fails_the_check(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(AssertionError, match="stopped before its first run, with status 2"):
        _up_to_the_first_run(["tune", "--budget", "0", "--out", "t"], monkeypatch)


@pytest.mark.parametrize(
    ("line", "words"), CHECKED, ids=[f"{line.where} {' '.join(words)}"[:120] for line, words in CHECKED]
)
def test_a_long_documented_command_gets_to_its_first_run(line, words, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        _up_to_the_first_run(words, monkeypatch)
    except AssertionError as exc:
        pytest.fail(f"{line.where}: {exc}")
