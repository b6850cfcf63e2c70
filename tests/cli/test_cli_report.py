"""`railride report` and --report on compare, sweep, tune and study: one HTML file, written
after the command's output, with the tables it printed; bad paths are input errors before any
run."""

from __future__ import annotations

import base64
import gzip
import html
import json
import re

import pytest
from clihelp import assert_input_error, ok, run

SHORT = ("--duration", 1, "--controllers", "passive,pid", "--no-bounds")


def _page(path) -> str:
    assert path.is_file()
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    # nothing from the network: no script, style, image or frame with a remote source
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text, flags=re.I)
    return text


def _packs(page: str) -> dict[str, bytes]:
    """The page's packed data by id, unpacked here (base64, then gzip) as a browser would."""
    found = re.findall(r'<script type="application/gzip" id="([^"]+)">([^<]*)</script>', page)
    return {key: gzip.decompress(base64.b64decode(text)) for key, text in found}


def _findings(page: str) -> list[str]:
    """The sentences under the answer's table."""
    found = re.search(r'<ul class="findings">(.*?)</ul>', page, flags=re.S)
    return [html.unescape(item) for item in re.findall(r"<li>(.*?)</li>", found.group(1))] if found else []


def test_report_command(tmp_path):
    out = tmp_path / "r" / "ride.html"
    result = ok("report", *SHORT, "--speed", 40, "--out", out)
    page = _page(out)
    assert f"wrote {out}" in result.stderr
    assert "Ride comparison: RMS of the carbody responses" in result.stdout  # compare's tables, printed
    # and the same tables in the page, as HTML, with the command line that made it
    assert '<pre class="console">' in page and "Peak-to-peak of the carbody responses" in page
    assert "railride report --controllers passive,pid --speed 40.0 --duration 1.0 --no-references --out" in page
    assert page.count('class="plotly-graph-div"') == 5  # the four responses and the spectra
    assert [p.name for p in out.parent.iterdir()] == ["ride.html"]
    # the answer first: the results' table and the trade-offs before the first figure
    assert page.index('<section id="answer">') < page.index('<table class="data">') < page.index("<figure")
    assert page.index('<ul class="findings">') < page.index("<figure") < page.index('<section id="settings">')
    printed = " ".join(result.stdout.split())  # the trade-offs the command printed, unwrapped
    assert _findings(page) and all(line in printed for line in _findings(page))
    assert any(line.startswith(("trade-off: ", "no trade-off: ")) for line in _findings(page))


def test_report_figures_unpack(tmp_path):
    """Each figure's packed data is gzip of what the browser draws: plotly's JavaScript once, a
    figure's JSON with a trace per suspension, an SVG per static figure (or a PNG data URI)."""
    out = tmp_path / "ride.html"
    ok("report", *SHORT, "--out", out)
    page = _page(out)
    packs = _packs(page)
    assert page.count('id="pack-plotly"') == 1 and b"Plotly" in packs["pack-plotly"][:5000]
    assert len(packs["pack-plotly"]) > 3_000_000  # the whole library, not a stub
    for name in ("acceleration", "displacement", "pitch", "roll", "psd"):
        figure = json.loads(packs[f"pack-figure-{name}"])
        assert [t["name"] for t in figure["data"]] == ["Passive", "PID"], name
        assert f'data-pack="pack-figure-{name}"' in page
    for name in ("damper_forces", "damper_hysteresis", "voltages"):
        tag = re.search(rf'<figure id="figure-{name}".*?<img [^>]*>', page, flags=re.S).group(0)
        if "data:image/png;base64," not in tag:
            assert packs[f"pack-figure-{name}"].lstrip().startswith(b"<?xml"), name
            assert b"<svg" in packs[f"pack-figure-{name}"][:2000]


def test_paper_report_fits_an_email(tmp_path):
    """The paper's comparison at its full size (four suspensions, 10 s at dt 1e-4) makes a page of
    at most 3 MB, with the answer on top and nothing fetched from the network."""
    out = tmp_path / "paper.html"
    result = ok("report", "--out", out)
    page = _page(out)
    assert out.stat().st_size <= 3_000_000, out.stat().st_size
    assert page.index('<table class="data">') < page.index("<figure")
    assert "<script src" not in page.replace(" ", "") and 'src="http' not in page
    printed = " ".join(result.stdout.split())
    assert len(_findings(page)) >= 2 and all(line in printed for line in _findings(page))
    assert page.count('class="plotly-graph-div"') == 5 and page.count("<img ") == 3
    # plotly's JavaScript, the five interactive figures, and the static ones packed as SVG
    assert len(_packs(page)) == 1 + 5 + page.count('data-type="image/svg+xml"')


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


def test_design_report_recommends_first(tmp_path):
    """A design's page opens on its recommendation, the words of its JSON document."""
    out = tmp_path / "design.html"
    doc = json.loads(
        ok(
            "design",
            *("--controllers", "pid,skyhook", "--track", "fra4", "--speed", 40, "--load", 1),
            *("--train-seeds", 0, "--test-seeds", 1, "--duration", 2, "--budget", 13, "--values", 3),
            *("--format", "json", "--report", out),
        ).stdout
    )
    page = _page(out)
    found = re.search(r'<p class="recommendation">(.*?)</p>', page, flags=re.S)
    assert found and html.unescape(found.group(1)) == doc["recommendation"]["text"]
    assert doc["recommendation"]["text"].startswith("Recommended: ")
    assert page.index('<section id="answer">') < found.start() < page.index("<figure")


class _Drawn:
    """A result of two matplotlib figures: a smooth line (a few kB of SVG) and 200,000 samples
    of noise (megabytes of SVG, far more than its PNG), the first with a note under it."""

    def report_contents(self):
        import numpy as np
        from matplotlib.figure import Figure

        from railride.model.params import VehicleParams
        from railride.output.report import Contents

        # not through pyplot: its registry stays empty for the other tests
        smooth = Figure()
        smooth.subplots().plot(np.linspace(0, 1, 50) ** 2)
        noisy = Figure()
        ax = noisy.subplots()
        ax.plot(np.random.default_rng(0).normal(size=200_000), lw=0.3)
        return Contents(
            title="two figures",
            settings={},
            params=VehicleParams.preset("paper"),
            figures=[("smooth", "a parabola", smooth, "drawn from 50 points & no more"), ("noisy", "noise", noisy)],
        )


def test_static_figures_svg_or_png():
    """Each static figure goes in as the smaller of its compressed SVG and its PNG; a figure's
    note is printed under it."""
    from railride.output.report import report_html

    page = report_html(_Drawn())
    smooth = re.search(r'<figure id="figure-smooth".*?</figure>', page, flags=re.S).group(0)
    noisy = re.search(r'<figure id="figure-noisy".*?</figure>', page, flags=re.S).group(0)
    assert 'data-type="image/svg+xml"' in smooth and b"<svg" in _packs(page)["pack-figure-smooth"]
    assert 'src="data:image/png;base64,' in noisy and "pack-figure-noisy" not in _packs(page)
    assert smooth.index("<img") < smooth.index('<p class="note">drawn from 50 points &amp; no more</p>')
    assert "pack-plotly" not in _packs(page)  # no interactive figure: no plotly
    assert page.index('<section id="answer">') < page.index("This result has no table.") < page.index("<figure")


def test_sweep_reports_draw_two_axes_and_say_why_three_have_no_figure(tmp_path):
    """--report of a sweep over two axes holds its figure, one line per value of the second axis;
    over three axes, no figure and, where the figures would be, the line the command printed."""
    two = tmp_path / "two.html"
    ok("sweep", "--speed", "20,40", "--wavelength", "30,60", "--duration", 0.2, "--no-comfort", "--report", two)
    page = _page(two)
    figure = re.search(r'<figure id="figure-sweep".*?</figure>', page, flags=re.S)
    assert figure and "one line per wavelength" in figure.group(0)
    three = tmp_path / "three.html"
    args = ("--speed", "20,40", "--wavelength", "30,60", "--amplitude", "0.01,0.02", "--duration", 0.2)
    ok("sweep", *args, "--no-comfort", "--report", three)
    page = _page(three)
    assert "<figure" not in page
    section = re.search(r'<section id="figures">(.*?)</section>', page, flags=re.S)
    assert section and "no figure: 3 axes have several values" in html.unescape(section.group(1))
