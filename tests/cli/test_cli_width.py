"""Every table fits an 80-column console: no line passes 80 characters, no cell is cut, and
every number printed on a wide console is printed, whole, at 80 columns too."""

from __future__ import annotations

import io
import json
import re

import pytest
from typer.testing import CliRunner

from railride.cli import app

runner = CliRunner()
#: a decimal number as the tables print it (0.3195, -12.3, 1.2e+07, 0.00228-0.00720 gives two)
NUMBER = re.compile(r"(?<![\w.])-?\d+\.\d+(?:e[+-]?\d+)?")
#: rich's mark of a cut cell
ELLIPSIS = "\N{HORIZONTAL ELLIPSIS}"

COMMANDS = {
    "compare": ("compare", "--duration", 1),
    "compare-all-comfort": ("compare", "--duration", 1, "--controllers", "all", "--comfort"),
    "compare-fault": ("compare", "--duration", 1, "--fault", "1R-off"),
    "compare-accelerometers": ("compare", "--duration", 1, "--sensing", "accelerometers"),
    "league": ("compare", "--scenario", "paper-sine,fra4", "--duration", 1, "--controllers", "all"),
    "simulate-comfort": ("simulate", "--scenario", "fra4", "--duration", 1, "--comfort"),
    "study": (
        *("study", "--controllers", "pid,sas-attitude-ride", "--track-seed", "0,1", "--speed", 40),
        *("--load", "1,1.3", "--fault", "none,2L-on+1R-disconnected@0.5", "--duration", 1),
    ),
    "tune": ("tune", "--controllers", "pid,sas-attitude-ride", "--duration", 0.5, "--values", 3, "--budget", 6),
    "sweep": (
        *("sweep", "--scenario", "fra4", "--duration", 1, "--speed", "20,40"),
        *("--suspension", "passive,sas-attitude-ride", "--damper-scale", "1,2"),
    ),
    "pareto": ("pareto", "--suspension", "pid", "--samples", 4, "--duration", 1),
    "modes": ("modes",),
    "frf": ("frf", "--points", 50),
    "damper": ("damper", "--amplitude", 0.01, "--frequency", 2, "--cycles", 2, "--voltage", "0,1,2.25"),
    "tracking": ("tracking", "--desired", "sawtooth", "--amplitude", 10000, "--frequency", 1),
    "ride-spectrum": ("ride-spectrum", "--controllers", "all", "--points", 100),
}


def printed(args, columns) -> str:
    env = {"COLUMNS": None if columns is None else str(columns)}
    result = runner.invoke(app, [str(a) for a in args], env=env)
    assert result.exit_code == 0, (result.exit_code, result.stdout, result.stderr)
    return result.stdout


def table_numbers(text: str) -> set[str]:
    """The numbers in the tables' rows (not in the notes, which hold wall times)."""
    return {n for line in text.splitlines() if line.startswith("│") for n in NUMBER.findall(line)}


def assert_fits(text: str, width: int) -> None:
    longest = max(text.splitlines(), key=len)
    assert len(longest) <= width, longest
    assert ELLIPSIS not in text, text


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_table_fits_80_columns_with_its_numbers_whole(name):
    args = COMMANDS[name]
    narrow, wide = printed(args, 80), printed(args, 400)
    assert_fits(narrow, 80)
    numbers = table_numbers(wide)
    assert numbers  # the comparison has something to compare
    assert table_numbers(narrow) == numbers


def test_a_pipe_without_columns_gets_80_and_columns_asks_wider():
    args = ("compare", "--duration", 1)
    assert_fits(printed(args, None), 80)
    wider = printed(args, 140)
    assert max(len(line) for line in wider.splitlines()) > 80  # the width is used, not capped
    assert_fits(wider, 140)
    assert "(part 1 of" in printed(args, 80) and "(part 1 of" not in wider  # split only when narrow


def test_the_compare_tables_keep_every_rms_value_and_its_unit_at_80_columns():
    args = ("compare", "--duration", 1, "--controllers", "all")
    doc = json.loads(printed((*args, "--format", "json"), 80))
    text = printed(args, 80)
    flat = " ".join(text.split())
    assert doc["controllers"]
    for row in doc["controllers"]:
        assert row["label"] in flat
        for response, unit in (("acceleration_m_s2", "(m/s^2)"), ("displacement_m", "(m)"), ("pitch_deg", "(deg)")):
            assert f"{row['metrics'][response]['rms']:#.4g}" in text  # four significant digits, whole
            assert unit in text


# -- the fitting itself, on made-up tables -------------------------------------------------------
def console(width: int):
    from rich.console import Console

    return Console(file=io.StringIO(), width=width, record=True, color_system=None)


def wide_table():
    """Long words in the labels and headings, numbers that must not be cut."""
    from railride.cli._width import FitTable

    table = FitTable(title="made up")
    table.add_column("response")
    for name in ("SAS (attitude+ride)", "Skyhook on-off"):
        table.add_column(name, justify="right")
        table.add_column("red. %", justify="right", no_wrap=True)
    table.add_row("acceleration (m/s^2)", *["0.0009854", "-111.8"] * 2)
    return table


@pytest.mark.parametrize("width", [70, 80])
def test_a_table_that_fits_by_wrapping_words_never_cuts_one(width):
    out = console(width)
    table = wide_table()
    out.print(table)
    text = out.export_text()
    assert_fits(text, width)
    assert text.count("0.0009854") == 2 and text.count("-111.8") == 2
    for word in ("acceleration", "(attitude+ride)", "Skyhook", "on-off"):
        assert word in text


def test_a_table_printed_again_fits_the_new_width():
    table = wide_table()
    narrow, wide = console(64), console(200)
    narrow.print(table)
    wide.print(table)
    assert_fits(narrow.export_text(), 64)
    assert "acceleration (m/s^2)" not in narrow.export_text()  # the label wrapped at 64 ...
    assert "acceleration (m/s^2)" in wide.export_text()  # ... and not at 200: the table is as built


def test_a_split_table_repeats_its_reference_in_every_part():
    from railride.cli._width import FitTable, Split

    def build(names):
        table = FitTable(title="RMS")
        table.add_column("response")
        for name in names:
            table.add_column(name, justify="right")
        table.add_row("acceleration (m/s^2)", *[f"{len(n)}.{len(n)}" for n in names])
        return table

    names = [f"suspension-{i}-with-a-long-name" for i in range(6)]
    out = console(80)
    out.print(Split(build, names, repeat=["passive"]))
    text = out.export_text()
    assert_fits(text, 80)
    parts = re.findall(r"\(part (\d) of (\d)\)", text)
    assert len(parts) > 1 and all(total == str(len(parts)) for _, total in parts)
    assert text.count("passive") == len(parts)
    for name in names:
        assert text.count(name) == 1
    wide = console(400)
    wide.print(Split(build, names, repeat=["passive"]))
    assert "(part" not in wide.export_text()
