"""The HTML report (railride.output.report) and its interactive figures (railride.plots.interactive):
what the page holds, read back with the standard library's HTML parser, and the envelope that
thins long histories."""

from __future__ import annotations

import base64
import gzip
import re
from html.parser import HTMLParser

import numpy as np
import pytest

import railride as rr
from railride.output import report
from railride.plots.interactive import comparison_response_figure, envelope


class Page(HTMLParser):
    """The tables (rows of cell texts), the attributes of every tag, the figures' ids and kinds,
    and the text of a page."""

    def __init__(self, text: str):
        super().__init__()
        self.tables: list[list[list[str]]] = []
        self.tags: list[tuple[str, dict]] = []
        self.figures: dict[str, str] = {}
        self._cell: list[str] | None = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.tags.append((tag, attrs))
        if tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "figure":
            self.figures[attrs["id"]] = attrs["class"]

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def table_with(self, *heads) -> list[list[str]]:
        return next(t for t in self.tables if t and tuple(t[0][: len(heads)]) == heads)


def unpacked(text: str) -> dict[str, bytes]:
    """The page's packed data by id (base64 of gzip), unpacked as the browser does."""
    found = re.findall(r'<script type="application/gzip" id="([^"]+)">([^<]*)</script>', text)
    return {key: gzip.decompress(base64.b64decode(data)) for key, data in found}


def image_kinds(text: str) -> list[str]:
    """The type of each <img>: a packed SVG's, or its data URI's."""
    page = Page(text)
    return [
        a.get("data-type") or re.match(r"data:(image/[a-z+]+);", a["src"]).group(1) for t, a in page.tags if t == "img"
    ]


@pytest.fixture(scope="module")
def comparison():
    # short and small: the report's content, not the physics, is under test
    return rr.compare(rr.scenario("paper-sine", duration=2.0, speed=40.0), controllers=["passive", "pid"], bounds=False)


@pytest.fixture(scope="module")
def page_text(comparison):
    fragment = "<html><head><style>x</style></head><body><pre>what the console printed</pre></body></html>"
    return report.report_html(comparison, console_html=[fragment], command="railride compare --speed 40")


@pytest.fixture(scope="module")
def page(page_text):
    return Page(page_text)


def test_nothing_is_fetched(page, page_text):
    """No script, stylesheet, image or frame comes from the network; plotly's JavaScript is
    inlined once (packed)."""
    assert page.tags  # the loop below checks something
    for tag, attrs in page.tags:
        for name in ("src", "href"):
            value = attrs.get(name) or ""
            assert not re.match(r"\s*(https?:)?//", value, re.I), (tag, name, value[:80])
        if tag == "link":
            raise AssertionError(f"a <link> in a self-contained page: {attrs}")
    scripts = [a for t, a in page.tags if t == "script"]
    assert scripts and all("src" not in a for a in scripts)
    assert [key for key, data in unpacked(page_text).items() if b"* plotly.js v" in data[:5000]] == ["pack-plotly"]


def test_settings_and_provenance(page, page_text):
    settings = dict(row for row in page.table_with("setting", "value")[1:])
    assert settings["railride version"] == rr.__version__
    import numpy
    import platform

    assert settings["numpy version"] == numpy.__version__ and settings["Python version"] == platform.python_version()
    assert float(settings["scenario.speed_m_s"]) == 40.0
    assert float(settings["scenario.duration_s"]) == 2.0
    assert settings["scenario.name"] == "paper-sine"
    assert settings["damper"] == "railway"
    assert "railride compare --speed 40" in page_text


def test_modal_table_and_parameters(page):
    """The modal table, read back, is the vehicle's: nine modes, carbody modes first, and the
    parameters table holds the paper's carbody mass."""
    rows = page.table_with("mode", "label", "frequency_hz")
    expected = rr.frf.modes("paper").to_pandas()
    assert len(rows) - 1 == len(expected) == 9
    for row, (_, mode) in zip(rows[1:], expected.iterrows()):
        assert int(row[0]) == mode["mode"] and row[1] == mode["label"]
        assert float(row[2]) == pytest.approx(mode["frequency_hz"], rel=1e-5)
    params = {r[0]: r[1:] for r in page.table_with("parameter", "value", "unit")[1:]}
    assert float(params["m_c"][0]) == rr.VehicleParams.preset("paper").m_c
    assert params["m_c"][1] == "kg"


def test_one_figure_per_saved_figure(page, page_text):
    """One interactive figure per time history and the spectra, the damper figures as images."""
    interactive = {f"figure-{n}" for n in ("acceleration", "displacement", "pitch", "roll", "psd")}
    static = {f"figure-{n}" for n in ("damper_forces", "damper_hysteresis", "voltages")}
    assert {k for k, v in page.figures.items() if v == "interactive"} == interactive
    assert {k for k, v in page.figures.items() if v == "static"} == static
    assert page_text.count('class="plotly-graph-div"') == len(interactive)
    images = [a for t, a in page.tags if t == "img"]
    assert len(images) == len(static)
    packs = unpacked(page_text)
    for image in images:  # a packed SVG, or a PNG data URI
        if "data-pack" in image:
            assert image["data-type"] == "image/svg+xml" and b"<svg" in packs[image["data-pack"]][:2000]
        else:
            assert image["src"].startswith("data:image/png;base64,")


def test_console_fragment_and_result_table(page, page_text, comparison):
    assert "<pre>what the console printed</pre>" in page_text
    assert "<style>x</style>" not in page_text  # the body of a whole document, not its head
    # the answer's table: a row per response and statistic, a column per suspension and reduction
    rows = page.table_with("response", "statistic", "passive", "pid", "pid red. %")
    metrics = comparison.metrics
    assert len(rows) - 1 == metrics.sizes["response"] * metrics.sizes["statistic"] == 8
    for response, statistic, passive, pid, reduction in rows[1:]:
        value = metrics.sel(response=response, statistic=statistic)
        assert float(passive) == pytest.approx(float(value.sel(controller="passive")), rel=1e-5)
        assert float(pid) == pytest.approx(float(value.sel(controller="pid")), rel=1e-5)
        expected = 100 * (1 - value.sel(controller="pid") / value.sel(controller="passive"))
        assert float(reduction) == pytest.approx(float(expected), abs=0.051)


def test_long_histories_are_thinned_and_say_so(comparison):
    html = report.report_html(comparison)
    assert "envelope" not in html  # 2 s at 1000 Hz: 2001 samples, drawn as they are
    longer = rr.compare(rr.scenario("paper-sine", duration=6.0), controllers=["passive"], bounds=False)
    figure = unpacked(report.report_html(longer))["pack-figure-acceleration"].decode()
    assert "max envelope of its 6001 samples in at most 3000 points" in figure
    figure = comparison_response_figure(longer.combined(), "acceleration")
    assert len(figure.data[0].x) <= 3000 < longer.combined().sizes["time"]


def test_envelope_keeps_every_peak():
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 10.0, 100_001)
    y = np.sin(2 * np.pi * 1.3 * t) + 0.1 * rng.standard_normal(t.size)
    y[54_321] = 7.0  # a spike between samples of any regular decimation
    x2, y2 = envelope(t, y, 3000)
    assert y2.size <= 3000
    assert np.all(np.diff(x2) > 0)
    assert y2.max() == 7.0 and y2.min() == y.min()
    assert x2[0] == t[0] and x2[-1] == t[-1]
    index = np.searchsorted(t, x2)  # every point kept is a sample, at its own time
    assert np.array_equal(y[index], y2)
    # the band: in each tenth of the run, the envelope reaches the trace's extremes
    for part in np.array_split(np.arange(t.size), 10):
        inside = (x2 >= t[part[0]]) & (x2 <= t[part[-1]])
        assert y2[inside].max() == y[part].max() and y2[inside].min() == y[part].min()


def test_envelope_short_traces_and_gaps():
    x, y = np.arange(10.0), np.arange(10.0)
    assert envelope(x, y, 10)[1] is y
    y = np.sin(np.arange(10_000.0))
    y[2000:4000] = np.nan  # a run that went wrong: the gap stays a gap
    _, y2 = envelope(np.arange(10_000.0), y, 400)
    assert np.isnan(y2).any() and np.nanmax(y2) == np.nanmax(y)
    with pytest.raises(ValueError, match="max_points = 2"):
        envelope(x, y, 2)


def test_frf_and_ride_results(tmp_path):
    frf = report.report_html(rr.frequency_responses(points=60))
    page = Page(frf)
    assert page.figures == {"figure-frf": "interactive"}
    assert page.table_with("mode", "label")
    ride = rr.simulate(rr.scenario("bump", speed=20.0, duration=1.0))
    path = report.write_report(ride, tmp_path / "sub" / "ride.html", title="A bump")
    page = Page(path.read_text(encoding="utf-8"))
    assert page.figures == {"figure-body_responses": "interactive"}
    assert "<h1>A bump</h1>" in path.read_text(encoding="utf-8")
    assert [p.name for p in path.parent.iterdir()] == ["ride.html"]  # no temporary file left


def test_long_tables_are_cut(monkeypatch, comparison):
    monkeypatch.setattr(report, "MAX_TABLE_ROWS", 5)
    page = Page(report.report_html(comparison))
    rows = page.table_with("response", "statistic", "passive")
    assert len(rows) - 1 == 5
    assert "the first 5 of 8 rows" in report.report_html(comparison)


def test_unknown_results_and_paths(tmp_path):
    with pytest.raises(ValueError, match="result: a dict has no report; allowed: .*Comparison"):
        report.report_html({})
    with pytest.raises(ValueError, match="path = .*a folder"):
        report.check_report_path(tmp_path)
    with pytest.raises(ValueError, match=r"--report = .*must end in \.html"):
        report.check_report_path(tmp_path / "report.pdf", "--report")
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="is a file, not a folder"):
        report.check_report_path(tmp_path / "file" / "report.html")
    assert report.check_report_path(tmp_path / "new" / "r.HTML") == tmp_path / "new" / "r.HTML"


def test_static_figures_svg_when_smaller(monkeypatch, comparison):
    """A static figure is its packed SVG (sharp at any zoom) unless that is larger than its PNG."""
    assert image_kinds(report.report_html(comparison)) == ["image/svg+xml"] * 3
    pack = report._gzip

    def bulky(data: bytes) -> bytes:  # an SVG that packs to 3 MB, far more than any PNG
        return pack(data) + bytes(3_000_000) if data.lstrip().startswith(b"<?xml") else pack(data)

    monkeypatch.setattr(report, "_gzip", bulky)
    assert image_kinds(report.report_html(comparison)) == ["image/png"] * 3


# -- figures in pages, a sweep's two axes, a sweep without a figure -----------------------------------
def _fake_sweep(g):
    """A sweep's result without its runs: made-up metrics (run i has 0.1 + 0.01 i everywhere)."""
    import pandas as pd

    from railride.studies.sweep import COMFORT_COLUMNS, SweepResult, metric_columns

    rows = [dict.fromkeys(metric_columns() + list(COMFORT_COLUMNS), 0.1 + 0.01 * i) for i in range(len(g.cases))]
    return SweepResult(g, pd.DataFrame(rows), comfort=True)


def _figure(text: str, name: str) -> str:
    found = re.search(rf'<figure id="figure-{name}".*?</figure>', text, flags=re.S)
    assert found, name
    return found.group(0)


def test_a_sweep_over_two_axes_shows_its_figures_one_line_per_value():
    """Speed along x, one line per voltage: the RMS and the comfort figures, each captioned so."""
    g = rr.sweep.grid(["passive", "mr"], speed=[20.0, 40.0, 60.0], voltage=[0.0, 1.0], duration=1.0)
    text = report.report_html(_fake_sweep(g))
    assert set(Page(text).figures) == {"figure-sweep", "figure-comfort"}
    for name in ("sweep", "comfort"):
        caption = re.search(r"<figcaption>(.*?)</figcaption>", _figure(text, name)).group(1)
        assert "speed" in caption and "one line per command voltage" in caption, caption
    assert "no figure:" not in text


def test_a_sweep_without_a_figure_says_why_where_the_figures_would_be():
    """Three swept axes: no figure, and the Figures section holds the one line that says why."""
    g = rr.sweep.grid(["mr"], speed=[20.0, 40.0], wavelength=[30.0, 60.0], voltage=[0.0, 1.0], duration=1.0)
    text = report.report_html(_fake_sweep(g))
    assert not Page(text).figures
    section = re.search(r'<section id="figures">(.*?)</section>', text, flags=re.S)
    assert section, "no Figures section"
    note = re.search(r'<p class="note">(.*?)</p>', section.group(1)).group(1)
    assert note.startswith("no figure: 3 axes have several values") and "speed_m_s" in note
    assert text.index('<section id="answer">') < section.start() < text.index('<section id="settings">')


@pytest.mark.filterwarnings("ignore:the inner loop is not tuned")
def test_every_page_of_the_sensitivity_figure_is_in_the_tune_report():
    """25 gains of one law make three pages (12, 12 and 1 panels): three figures, named as the
    files the tuning writes (sensitivity.png, sensitivity_2.png, sensitivity_3.png)."""
    import dataclasses

    from railride.studies.tune_result import Curve

    tuned = rr.tune(
        ["pid"], scenario_options={"duration": 0.2}, n_values=3, budget=5, before_after=False, progress=False
    )
    rng = np.random.default_rng(0)
    curves = [Curve("pid", 1, f"pid.k{k}", np.geomspace(0.1, 10.0, 5), 1 + rng.random(5), 1.0) for k in range(25)]
    text = report.report_html(dataclasses.replace(tuned, curves=curves))
    figures = re.findall(r'<figure id="figure-(sensitivity[^"]*)"', text)
    assert figures == ["sensitivity", "sensitivity_2", "sensitivity_3"]
    for k, name in enumerate(figures, start=1):
        caption = re.search(r"<figcaption>(.*?)</figcaption>", _figure(text, name)).group(1)
        assert f"page {k} of 3" in caption and f"({name}.png in the output folder)" in caption
