"""--figure-format and --dpi: every command that writes figures into its --out folder writes them
in the formats asked, PNG at the resolution asked, and refuses bad values in one line."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest
import typer.main
from clihelp import assert_input_error, is_png, ok, run

from railride.cli import app

#: the commands that write figures into their --out folder
FIGURE_COMMANDS = ("compare", "simulate", "frf", "damper", "tracking", "tune", "study", "sweep", "pareto")


def _png_width(path) -> int:
    data = path.read_bytes()
    assert data[12:16] == b"IHDR"
    return int.from_bytes(data[16:20], "big")


def test_every_figure_command_takes_the_options():
    commands = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    for name in FIGURE_COMMANDS:
        options = {opt for param in commands[name].params for opt in param.opts}
        assert {"--out", "--figure-format", "--dpi"} <= options, name


def test_simulate_writes_each_format_and_the_png_follows_dpi(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    ok("simulate", "--duration", 0.3, "--out", a, "--figure-format", "png,pdf,svg", "--dpi", 50)
    ok("simulate", "--duration", 0.3, "--out", b, "--dpi", 100)
    assert is_png(a / "body_responses.png")
    assert (a / "body_responses.pdf").read_bytes().startswith(b"%PDF")
    assert ET.parse(a / "body_responses.svg").getroot().tag == "{http://www.w3.org/2000/svg}svg"
    assert _png_width(b / "body_responses.png") == 2 * _png_width(a / "body_responses.png")
    assert not (b / "body_responses.pdf").exists()


def test_frf_and_the_rig_write_the_formats_asked(tmp_path):
    ok("frf", "--points", 30, "--out", tmp_path / "frf", "--figure-format", "pdf")
    assert sorted(p.name for p in (tmp_path / "frf").iterdir()) == ["frf.csv", "frf.json", "frf.pdf", "modes.csv"]
    args = ("--amplitude", 0.01, "--frequency", 2, "--voltage", "0,1", "--cycles", 2)
    ok("damper", *args, "--out", tmp_path / "loops", "--figure-format", "svg,png")
    assert (tmp_path / "loops" / "loops.svg").is_file() and is_png(tmp_path / "loops" / "loops.png")
    ok("tracking", "--cycles", 2, "--out", tmp_path / "track", "--figure-format", "pdf", "--dpi", 300)
    assert (tmp_path / "track" / "tracking.pdf").read_bytes().startswith(b"%PDF")


def test_compare_writes_every_figure_in_every_format(tmp_path):
    out = tmp_path / "cmp"
    ok("compare", "--controllers", "pid", "--no-bounds", "--duration", 0.5, "--out", out, "--figure-format", "svg")
    svgs = sorted(p.stem for p in out.glob("*.svg"))
    assert svgs == sorted(
        ["acceleration", "displacement", "pitch", "roll", "damper_forces", "damper_hysteresis", "voltages", "psd"]
    )
    assert not list(out.glob("*.png"))


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--dpi", 0), ("--dpi = 0", ">= 10 and <= 1200")),
        (("--dpi", -5), ("--dpi = -5",)),
        (("--dpi", "abc"), ("--dpi = 'abc'",)),
        (("--dpi", 5000), ("--dpi = 5000", "<= 1200")),
        (("--dpi", "inf"), ("--dpi = inf",)),
        (("--figure-format", "tiff"), ("--figure-format = 'tiff'", "png, pdf, svg")),
        (("--figure-format", "png,jpg"), ("'jpg' is not a figure format",)),
    ],
)
def test_bad_values_exit_2_naming_the_option(tmp_path, args, fragments):
    out = tmp_path / "out"
    assert_input_error(run("simulate", "--duration", 0.3, "--out", out, *args), *fragments)
    assert not out.exists()


def test_the_options_need_an_output_folder():
    assert_input_error(run("frf", "--points", 30, "--dpi", 300), "--dpi: applies with --out only")
    assert_input_error(run("simulate", "--figure-format", "pdf"), "--figure-format: applies with --out only")


def test_a_bad_dpi_is_refused_before_a_long_run(tmp_path):
    # the check comes first: no run table, no runs
    out = tmp_path / "sw"
    assert_input_error(run("sweep", "--speed", "20,30", "--out", out, "--dpi", 0), "--dpi = 0")
    assert not out.exists()


def test_a_league_table_writes_its_figures_in_the_formats_asked(tmp_path):
    out = tmp_path / "lg"
    ok("compare", "--speed", "30,40", "--duration", 0.5, "--controllers", "pid", "--out", out, "--figure-format", "svg")
    names = {p.name for p in out.iterdir()}
    assert {"league.svg", "league_comfort.svg"} <= names and "league.png" not in names
