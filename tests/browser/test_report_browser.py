"""The HTML report in a real browser: headless Chromium, driven by playwright, opens reports of
the paper's comparison, of a sweep and of the frequency responses, offline. The page unpacks its
gzip-compressed plotly and figures itself (DecompressionStream); every figure must then be
drawn, no error logged, no request leave the file, and the figures must answer the mouse. A
browser without DecompressionStream must say so in each figure and still show the answer.

Needs Debian's ``chromium`` (.ci/run installs it) and the ``playwright`` package (the test
extra); never ``playwright install``: the browser is the system's. Skips, saying which, when
either is missing.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from clihelp import ok

sync_api = pytest.importorskip(
    "playwright.sync_api", reason="the browser test needs the playwright package (pip install '.[test]')"
)
CHROMIUM = next(
    (Path(p) for p in ("/usr/bin/chromium", shutil.which("chromium"), shutil.which("chromium-browser")) if p),
    None,
)
if CHROMIUM is None or not CHROMIUM.exists():
    pytest.skip(
        "the browser test needs Chromium at /usr/bin/chromium (apt-get install chromium)", allow_module_level=True
    )
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]

#: what each page measures: its plotly figures (with their drawn traces and sizes), its images,
#: its outermost SVGs and whether plotly drew every figure
MEASURE = """() => {
  const box = e => { const r = e.getBoundingClientRect(); return [r.width, r.height]; };
  return {
    plots: [...document.querySelectorAll('.plotly-graph-div')].map(div => ({
      id: div.id,
      traces: (div.data || []).length,
      svg: div.querySelector('svg.main-svg') ? box(div.querySelector('svg.main-svg')) : [0, 0],
      lines: [...div.querySelectorAll('.scatterlayer path.js-line')]
        .filter(p => (p.getAttribute('d') || '').length > 20).length,
    })),
    images: [...document.querySelectorAll('img')].map(i => ({
      alt: i.alt, complete: i.complete, width: i.naturalWidth, height: i.naturalHeight })),
    svgs: [...document.querySelectorAll('svg.main-svg')].map(box),
  };
}"""


@pytest.fixture(scope="module")
def reports(tmp_path_factory) -> dict:
    """The reports to open, by name: (path, plotly figures, images) expected."""
    import railride as rr
    from railride.output.report import write_report

    folder = tmp_path_factory.mktemp("reports")
    ok("report", "--out", folder / "compare.html")  # the paper's comparison, as a user makes it
    ok("sweep", "--duration", 1, "--speed", "20:40:3", "--report", folder / "sweep.html")
    write_report(rr.frequency_responses(), folder / "frf.html")
    ok("ride-spectrum", "--points", 300, "--report", folder / "ride_spectrum.html")
    return {
        "compare": (folder / "compare.html", 5, 3),
        "sweep": (folder / "sweep.html", 0, 2),
        "frf": (folder / "frf.html", 1, 0),
        "ride_spectrum": (folder / "ride_spectrum.html", 1, 0),
    }


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
        yield chromium
        chromium.close()


def _open(browser, path: Path, before: str | None = None):
    """A page on ``path`` with every http(s) request aborted and recorded, and the console's
    errors and the page's exceptions collected, once its script has unpacked and drawn every
    figure (or given up: <html data-figures="failed">). ``before``: a script run first."""
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    if before:
        page.add_init_script(before)
    problems: list[str] = []
    remote: list[str] = []
    page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(f"page error: {e}"))

    def route(r):
        if r.request.url.lower().startswith(("http:", "https:", "ws:", "wss:")):
            remote.append(r.request.url)
            r.abort()
        else:
            r.continue_()

    page.route("**/*", route)
    page.goto(path.as_uri(), wait_until="load")
    page.wait_for_function("() => document.documentElement.dataset.figures", timeout=60_000)
    return page, problems, remote


@pytest.mark.parametrize("name", ["compare", "sweep", "frf", "ride_spectrum"])
def test_report_renders_offline(browser, reports, name, tmp_path):
    path, n_plots, n_images = reports[name]
    page, problems, remote = _open(browser, path)
    state = page.evaluate("() => document.documentElement.dataset.figures")
    found = page.evaluate(MEASURE)
    shot = tmp_path / f"{name}.png"
    page.screenshot(path=str(shot), full_page=True)
    page.close()

    assert problems == []
    assert remote == []  # no script, font, image or beacon from the network
    assert state == "drawn"
    assert len(found["plots"]) == n_plots
    for plot in found["plots"]:
        assert plot["svg"][0] > 300 and plot["svg"][1] > 200, plot
        assert plot["traces"] > 0 and plot["lines"] >= plot["traces"], plot  # every trace drawn
    assert len(found["images"]) == n_images
    for image in found["images"]:
        assert image["complete"] and image["width"] > 0 and image["height"] > 0, image
    assert len(found["svgs"]) >= n_plots and all(w > 0 and h > 0 for w, h in found["svgs"])
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 50_000


def test_figures_answer_the_mouse(browser, reports):
    """A click on a legend entry hides that suspension; a drag across the plot zooms in."""
    page, problems, _ = _open(browser, reports["compare"][0])
    plot = page.locator("#plot-acceleration")
    plot.scroll_into_view_if_needed()
    plot.locator(".legendtoggle").first.click()  # what plotly listens on, over the entry's text
    page.wait_for_function("() => document.getElementById('plot-acceleration').data[0].visible === 'legendonly'")

    before = page.evaluate("() => document.getElementById('plot-acceleration')._fullLayout.xaxis.range.slice()")
    area = plot.locator(".nsewdrag").first.bounding_box()
    y = area["y"] + area["height"] / 2
    page.mouse.move(area["x"] + area["width"] * 0.3, y)
    page.mouse.down()
    page.mouse.move(area["x"] + area["width"] * 0.5, y, steps=8)
    page.mouse.up()
    page.wait_for_function(
        "w => { const r = document.getElementById('plot-acceleration')._fullLayout.xaxis.range;"
        " return r[1] - r[0] < w / 2; }",
        arg=before[1] - before[0],
    )
    page.close()
    assert problems == []


def test_page_without_decompression(browser, reports):
    """In a browser without DecompressionStream the figures say what the reader needs, nothing
    is thrown, and the answer on top is there all the same."""
    page, problems, remote = _open(browser, reports["compare"][0], "delete window.DecompressionStream;")
    state = page.evaluate("() => document.documentElement.dataset.figures")
    plots = page.evaluate("() => [...document.querySelectorAll('.plotly-graph-div')].map(d => d.innerText)")
    rows = page.evaluate("() => document.querySelectorAll('#answer table.data tbody tr').length")
    drawn = page.evaluate("() => document.querySelectorAll('svg.main-svg').length")
    page.close()
    assert problems == [] and remote == []
    assert state == "failed" and drawn == 0
    assert len(plots) == 5 and all("lacks DecompressionStream" in text for text in plots), plots
    assert rows == 8  # four responses by RMS and peak-to-peak
