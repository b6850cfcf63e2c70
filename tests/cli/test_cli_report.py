"""`railride report` and --report on compare, sweep, tune and study: one HTML file, written
after the command's output, with the tables it printed; bad paths are input errors before any
run."""

from __future__ import annotations

import json

import pytest
from clihelp import assert_input_error, ok, run

SHORT = ("--duration", 1, "--controllers", "passive,pid", "--no-bounds")


def _page(path) -> str:
    assert path.is_file()
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    return text


def test_report_command(tmp_path):
    out = tmp_path / "r" / "ride.html"
    result = ok("report", *SHORT, "--speed", 40, "--out", out)
    page = _page(out)
    assert f"wrote {out}" in result.stderr
    assert "Ride comparison: RMS of the carbody responses" in result.stdout  # compare's tables, printed
    # and the same tables in the page, as HTML, with the command line that made it
    assert '<pre class="console">' in page and "Peak-to-peak of the carbody responses" in page
    assert "railride report --controllers passive,pid --speed 40.0 --duration 1.0 --no-bounds --out" in page
    assert page.count('class="plotly-graph-div"') == 5  # the four responses and the spectra
    assert [p.name for p in out.parent.iterdir()] == ["ride.html"]


def test_compare_report_with_json(tmp_path):
    out = tmp_path / "compare.html"
    result = ok("compare", *SHORT, "--format", "json", "--report", out)
    assert json.loads(result.stdout)["schema"] == "railride.comparison/1"
    page = _page(out)
    assert "What each suspension asks of its dampers" in page  # the tables, though none was printed


@pytest.mark.parametrize(
    "args, printed",
    [
        (("sweep", "--duration", 1, "--speed", "20:40:3"), "speed"),
        (("tune", "--controllers", "pid", "--duration", 1, "--values", 4, "--budget", 8), "Tuned gains"),
        (("study", "--controllers", "pid", "--track-seed", "0,1", "--speed", 40, "--duration", 1), "Statistics over"),
    ],
    ids=["sweep", "tune", "study"],
)
def test_report_option(tmp_path, args, printed):
    out = tmp_path / f"{args[0]}.html"
    result = ok(*args, "--report", out)
    page = _page(out)
    assert f"wrote {out}" in result.stderr
    assert printed in page
    assert 'id="figure-' in page and "<img" in page  # the figure its --out folder would hold
    assert "Vehicle: modes and parameters" in page


def test_league_table_report(tmp_path):
    out = tmp_path / "league.html"
    result = ok("compare", "--speed", "30,40", "--duration", 1, "--controllers", "passive,pid", "--report", out)
    page = _page(out)
    assert f"wrote {out}" in result.stderr
    assert "Reduction = (passive - controlled) / passive RMS" in result.stdout  # the table, printed
    assert '<pre class="console">' in page and "Reduction = (passive - controlled)" in page  # and in the page
    assert "railride compare --controllers passive,pid --speed 30,40 --duration 1.0 --report" in page


@pytest.mark.parametrize("command", [("compare", *SHORT), ("sweep", "--duration", 1), ("study", "--duration", 1)])
def test_bad_report_paths(tmp_path, command):
    assert_input_error(run(*command, "--report", tmp_path), "--report", "a folder", "report.html")
    assert_input_error(run(*command, "--report", tmp_path / "r.txt"), "--report", "must end in .html")
    (tmp_path / "file").write_text("x")
    assert_input_error(run(*command, "--report", tmp_path / "file" / "r.html"), "is a file, not a folder")
    assert not list(tmp_path.glob("*.html"))


def test_bad_report_command_paths(tmp_path):
    assert_input_error(run("report", "--out", tmp_path), "--out", "a folder")
    assert_input_error(run("report", "--scenario", "fra4,bump", "--out", tmp_path / "r.html"), "--scenario", "one")
    assert_input_error(run("compare", "--speed", "30,40", "--report", tmp_path), "--report", "a folder")
    assert_input_error(run("report", "--speed", "-1", "--out", tmp_path / "r.html"), "speed = -1.0")
    assert not (tmp_path / "r.html").exists()
