"""One self-contained HTML file of a result, to open in any browser and send to colleagues.

`write_report(result, path)` writes, for a result with a report (`REPORTED`: `Comparison`,
`DesignResult`, `SweepResult`, `TuneResult`, `StudyResult`, `LeagueTable`, `RideResult`,
`RideSpectrum`, `FrfResult`), a page that gives the answer first: the result's own table
(``to_pandas()``), the trade-offs in words and the recommendation where the result has them;
then every figure its ``save()`` writes, every page of a figure in pages (time histories, spectra
and frequency responses as interactive plotly figures, `railride.plots.interactive`; the others
as the package's matplotlib figures; where a result has none, the line that says why), the
tables the command line printed (HTML fragments given by the caller, ``console_html``), the
run's settings and provenance (railride version, scenario, the command line) and the vehicle's
modal table.

Nothing is fetched when the page opens, and the page fits an e-mail: plotly's JavaScript and
each figure's data are inlined once, gzip-compressed and base64-encoded, and unpacked by the
browser (``DecompressionStream``, `LOADER`); a static figure is a compressed SVG, or a PNG data
URI where that is smaller. See docs/report.md.

A new result type is one function returning its `Contents`, which the result's ``report_contents()``
method calls: the report is chosen by what a result has, never by its class's name.
"""

from __future__ import annotations

import base64
import datetime as _dt
import functools
import gzip
import html
import io
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from railride.errors import InputError
from railride._version import __version__, versions
from railride._io import atomic_write_text

#: rows of a result table shown in the report; a longer table shows its first rows and says so
MAX_TABLE_ROWS = 500
#: gzip level of what the page packs (plotly's JavaScript, the figures' data, the SVG figures)
GZIP_LEVEL = 9
#: file names a report may take
SUFFIXES = (".html", ".htm")


@dataclass
class Contents:
    """What a result contributes to its report. ``figures``: (name, caption, figure) or (name,
    caption, figure, note) with a plotly or matplotlib figure, one per figure file its ``save()``
    writes (``name``.png), in that order; the note, if any, is printed under the figure (a
    caveat the figure's reader needs); ``tables``: (caption, DataFrame), the first of them the
    answer at the top of the page; ``findings``: sentences under it (a comparison's trade-offs);
    ``recommendation``: what the result recommends, in words, above it ("" if nothing);
    ``settings``: nested values shown flat; ``scenario``: the scenario's record
    (`Scenario.describe()`), if one; ``params``: the `VehicleParams` of the modal table (None:
    the vehicles differ, no single table); ``figure_note``: where the result has no figure,
    one line saying why, printed where the figures would be (a sweep over three axes)."""

    title: str
    settings: dict
    params: Any
    scenario: dict | None = None
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    findings: list = field(default_factory=list)
    recommendation: str = ""
    figure_note: str = ""


#: the result types with a report (each has a ``report_contents()`` method that calls one of the
#: functions below), named in the error for a result without one
REPORTED = (
    "Comparison",
    "DesignResult",
    "FrfResult",
    "LeagueTable",
    "RideResult",
    "RideSpectrum",
    "StudyResult",
    "SweepResult",
    "TuneResult",
)


def contents(result) -> Contents:
    """The `Contents` of ``result``: its ``report_contents()`` (InputError for a result without one)."""
    make = getattr(result, "report_contents", None)
    if not callable(make):
        raise InputError(f"result: a {type(result).__name__} has no report; allowed: {', '.join(REPORTED)}")
    return make()


# -- the result types ---------------------------------------------------------------------------
def _vehicle(settings: dict):
    """The vehicle of a result's settings, for its modal table: ``vehicle_params`` (the vehicle
    run), else the vehicle record's values at its load (the first of several), else paper."""
    from railride.model.params import VehicleParams

    record = settings.get("vehicle_params")
    if record:
        return VehicleParams(**record)
    named = settings.get("vehicle")
    if isinstance(named, dict) and "values" in named:
        load = named.get("load", 1.0)
        load = load[0] if isinstance(load, list) else load
        base = VehicleParams(**named["values"])
        return base if load == 1.0 else base.loaded(load)
    return VehicleParams.preset("paper")


def comparison_contents(result) -> Contents:
    """The report of a `railride.studies.comparison.Comparison`."""
    from railride.analysis.spectra import PSD_SEGMENT_S, comparison_psd
    from railride.analysis.labels import CARBODY_RESPONSES, psd_title
    from railride.plots import comparison as plots
    from railride.output.trade_offs import paper_ranking_text, trade_off_lines
    from railride.plots.interactive import comparison_psd_figure, comparison_response_figure

    doc = result.to_dict()
    settings = doc["settings"]
    ds = result.combined()
    window = settings.get("window_s")
    figures = [(r, f"carbody {r} against time", comparison_response_figure(ds, r)) for r in CARBODY_RESPONSES]
    psd = comparison_psd_figure(comparison_psd(ds, window), title=psd_title(ds, window, PSD_SEGMENT_S))
    figures.append(("psd", "acceleration spectra", psd))
    figures += [
        (name, words, draw(result))
        for name, words, draw in (
            ("damper_forces", "damper forces", plots.plot_comparison_damper_forces),
            ("damper_hysteresis", "damper force against deflection rate", plots.plot_comparison_hysteresis),
            ("voltages", "command voltages", plots.plot_comparison_voltages),
        )
    ]
    return Contents(
        title="Ride comparison" + (" beside the paper's Table 1" if doc["paper_case"] else ""),
        settings={**settings, "paper_case": doc["paper_case"], "gains": doc["gains"], "tuning": doc["tuning"]},
        params=_vehicle(settings),
        scenario=settings.get("scenario"),
        figures=figures,
        tables=[
            (
                "RMS and peak-to-peak per response (rows) and suspension (columns), reduction % against passive",
                _wide(result.to_pandas()),
            )
        ],
        findings=[
            *([doc["tuning"]["track"]["note"]] if doc.get("tuning", {}).get("track") else []),
            *trade_off_lines(doc),
            *([paper_ranking_text(doc["paper_ranking"])] if doc.get("paper_ranking") else []),
        ],
    )


def _wide(frame: pd.DataFrame) -> pd.DataFrame:
    """A comparison's table (one row per suspension, response and statistic) as one row per
    response and statistic, a column per suspension and, where it has one, its reduction in %
    (one decimal, as the command line prints it)."""
    index = frame.set_index(["controller", "response", "statistic"])
    rows = list(dict.fromkeys(zip(frame["response"], frame["statistic"])))
    out = pd.DataFrame(rows, columns=["response", "statistic"])
    for name in dict.fromkeys(frame["controller"]):
        keys = [(name, r, s) for r, s in zip(out["response"], out["statistic"])]
        part = index.reindex(keys)
        out[name] = part["value"].to_numpy()
        if part["reduction_percent"].notna().any():
            out[f"{name} red. %"] = part["reduction_percent"].round(1).to_numpy()
    return out


def sweep_contents(result) -> Contents:
    """The report of a `railride.studies.sweep.SweepResult`: its figures where one or two axes
    have several values (the first along x, one line per value of the second), else the line
    ``figure_note`` that says why there is none."""
    from railride.analysis.labels import grid_axis_label
    from railride.plots.sweep import has_comfort, sweep_plot_axes

    settings = result.settings
    axes = sweep_plot_axes(result)  # None: no figure, and figure_note says why
    figures = []
    if axes is not None:
        x, series = axes
        against = grid_axis_label(x)
        if series is not None:
            against += f", one line per {grid_axis_label(series).split(' (')[0]}"
        figures.append(("sweep", f"RMS against {against}", result.plot(axis=x, series=series)))
        if has_comfort(result):
            figures.append(("comfort", f"comfort against {against}", result.plot(comfort=True, axis=x, series=series)))
    return Contents(
        title="Sweep",
        settings={**settings, "date": result.date, "runs": int(result.runs)},
        params=_vehicle(settings),
        scenario=settings.get("scenario"),
        figures=figures,
        tables=[("one row per run", result.to_pandas())],
        figure_note=result.figure_note or "",
    )


def tune_contents(result) -> Contents:
    """The report of a `railride.studies.tune_result.TuneResult`: every page of its sensitivity
    figure (``plot_pages``: sensitivity.png, sensitivity_2.png, ...)."""
    from railride.plots.tuning import sensitivity_stem

    doc = result.to_dict()
    keys = ("controllers", "scenario", "settings", "objective", "date", "runs", "gains")
    pages = result.plot_pages() if result.curves else []
    figures = [
        (
            sensitivity_stem(k),
            "sensitivity curves" + (f", page {k} of {len(pages)}" if len(pages) > 1 else ""),
            page,
        )
        for k, page in enumerate(pages, start=1)
    ]
    return Contents(
        title="Tuning: every law by the sensitivity study",
        settings={k: doc[k] for k in keys},
        params=_vehicle(doc["settings"]),
        scenario=doc["scenario"],
        figures=figures,
        tables=[("the sensitivity curves, one row per value tried", result.to_pandas())],
    )


def study_contents(result) -> Contents:
    """The report of a `railride.studies.study.StudyResult`."""
    return Contents(
        title="Statistics over tracks, speeds, loads and faults",
        settings={**result.settings, "runs": int(len(result.cases))},
        params=_vehicle(result.settings),
        figures=[("study", "reductions against passive with their 5-95 % bands", result.plot())],
        tables=[("one row per controller, condition and metric", result.to_pandas())],
    )


def design_contents(result) -> Contents:
    """The report of a `railride.studies.design_result.DesignResult`."""
    from railride.plots.design import plot_design_costs

    return Contents(
        title="Which controller: a robust design judged on held-out track",
        settings={**result.settings, "recommended": result.recommended},
        params=_vehicle(result.settings),
        figures=[
            ("design", "RMS ratios to passive against speed, held out, with their 5-95 % bands", result.plot()),
            ("design_costs", "each law's score against the RMS damper force it asks for", plot_design_costs(result)),
        ],
        tables=[("one row per law, speed, load and metric (held out)", result.to_pandas())],
        recommendation=result.recommendation,
    )


def league_contents(result) -> Contents:
    """The report of a `railride.studies.league.LeagueTable`."""
    from railride.plots.league import plot_league_comfort

    settings = result.to_dict().get("settings") or {}
    return Contents(
        title="League table over scenarios, speeds and seeds",
        settings=settings,
        params=_vehicle(settings),
        figures=[
            ("league", "RMS reductions per case", result.plot()),
            ("league_comfort", "N_MV against speed", plot_league_comfort(result)),
        ],
        tables=[("one row per case and controller", result.to_pandas())],
    )


def ride_contents(result) -> Contents:
    """The report of a `railride.run.ride.RideResult`."""
    from railride.analysis.labels import json_records
    from railride.plots.interactive import ride_figure
    from railride.plots.ride import ride_title, sample_labels

    ds = result.dataset
    params = result.params
    if isinstance(params, list):  # a batch: one modal table if they share the vehicle
        params = params[0] if all(p == params[0] for p in params) else None
    elif params is None and (records := json_records(ds, "vehicle_params")):
        params = _vehicle({"vehicle_params": records[0]})
    if result.is_batch:
        records = json_records(ds, "scenario")
        settings: dict = {"samples": int(ds.sizes["sample"]), "dt_s": ds.attrs.get("dt_s")}
        scenario = records[0] if records and all(r == records[0] for r in records) else None
        labels = sample_labels(ds)
    else:
        doc = result.to_dict()
        settings = {k: v for k, v in doc.items() if k not in ("schema", "railride_version", "metrics")}
        scenario, labels = doc["scenario"], None
    metrics = result.metrics().to_dataframe(name="value").reset_index()
    return Contents(
        title="Ride of the vehicle",
        settings=settings,
        params=params,
        scenario=scenario,
        figures=[("body_responses", "carbody responses", ride_figure(ds, labels=labels, title=ride_title(ds)))],
        tables=[("RMS and peak-to-peak of the carbody responses", metrics)],
    )


def frf_contents(result) -> Contents:
    """The report of a `railride.frequency.frf.FrfResult`."""
    from railride.plots.interactive import frf_figure

    doc = result.to_dict()
    figure = frf_figure(result.to_pandas(), result.modes.to_pandas(), title=result.title())
    return Contents(
        title="Frequency responses of the passive vehicle",
        settings={
            **{k: v for k, v in doc.items() if k.startswith("vehicle") and k != "vehicle_params"},
            **doc["settings"],
        },
        params=result.params,
        figures=[("frf", "carbody frequency responses", figure)],
        tables=[("magnitudes and phases per rail pattern and frequency", result.to_pandas())],
    )


def ride_spectrum_contents(result) -> Contents:
    """The report of a `railride.frequency.ride_spectrum.RideSpectrum`."""
    from railride.plots.interactive import ride_spectrum_figure

    return Contents(
        title="Ride in the frequency domain",
        settings=result.to_dict()["settings"],
        params=result.params,
        figures=[("ride_spectrum", "floor acceleration PSDs per suspension", ride_spectrum_figure(result))],
        tables=[("RMS and weighted RMS per suspension and response", result.to_pandas())],
    )


# -- the page -----------------------------------------------------------------------------------
def check_report_path(path, field: str = "path") -> Path:
    """``path`` as a Path if a report can be written there: a file name ending in .html or .htm,
    not a folder, whose parent is not a file. ValueError naming ``field`` otherwise."""
    path = Path(path)
    if path.is_dir():
        raise InputError(
            f"{field} = {str(path)!r}: a folder; give the name of the HTML file to write, e.g. report.html"
        )
    if path.suffix.lower() not in SUFFIXES:
        raise InputError(f"{field} = {str(path)!r}: must end in .html or .htm (one HTML file), e.g. report.html")
    from railride import validation

    validation.creatable(path, f"{field} = {str(path)!r}")
    return path


def write_report(result, path, *, console_html=(), title: str | None = None, command: str | None = None) -> Path:
    """Write the report of ``result`` to ``path`` (`report_html`), atomically. Returns the path."""
    path = check_report_path(path)
    atomic_write_text(path, report_html(result, console_html=console_html, title=title, command=command))
    return path


def report_html(result, *, console_html=(), title: str | None = None, command: str | None = None) -> str:
    """The report of ``result`` as one HTML document. ``console_html``: HTML fragments (or whole
    documents, whose body is taken) of the tables a command printed, e.g. rich's
    ``Console.export_html(inline_styles=True)``, inlined as given; ``title`` replaces the
    result's; ``command``: the command line that made the result.

    The answer comes first (the result's table, its findings and recommendation), then the
    figures, what the command printed, the settings and provenance, the vehicle; the packed
    data and their loader close the page."""
    from railride.model.modes import modes

    part = contents(result)
    heading = title or part.title
    packs: dict[str, bytes | None] = {}
    sections = [("answer", "Results", _answer_html(part))]
    if part.figures:
        sections.append(("figures", "Figures", "\n".join(_figure_html(packs, *f) for f in part.figures)))
    elif part.figure_note:
        sections.append(("figures", "Figures", f'<p class="note">{html.escape(part.figure_note)}</p>'))
    if part.tables[1:]:
        sections.append(("tables", "More tables", "\n".join(_caption_table(c, t) for c, t in part.tables[1:])))
    if console_html:
        sections.append(("console", "What the command printed", "\n".join(_fragment(f) for f in console_html)))
    sections.append(("settings", "Settings and provenance", _settings_html(part, command)))
    if part.params is not None:
        table = modes(part.params).to_pandas()
        sections.append(("vehicle", "Vehicle: modes and parameters", _table_html(table) + _params_html(part.params)))
    else:
        sections.append(("vehicle", "Vehicle", "<p>The runs' vehicles differ: no single modal table.</p>"))
    nav = " | ".join(f'<a href="#{key}">{html.escape(name)}</a>' for key, name, _ in sections)
    body = "\n".join(
        f'<section id="{key}"><h2>{html.escape(name)}</h2>\n{text}</section>' for key, name, text in sections
    )
    when = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="railride {__version__}">
<title>railride: {html.escape(heading)}</title>
<style>{STYLE}</style>
</head><body>
<header><h1>{html.escape(heading)}</h1>
<p class="meta">railride {__version__}, written {when}</p>
<nav>{nav}</nav></header>
{body}
{_packed_html(packs)}
</body></html>
"""


def _answer_html(part: Contents) -> str:
    """The top of the page: the recommendation, the result's own table, the findings."""
    lines = []
    if part.recommendation:
        lines.append(f'<p class="recommendation">{html.escape(part.recommendation)}</p>')
    if part.tables:
        lines.append(_caption_table(*part.tables[0]))
    if part.findings:
        items = "".join(f"<li>{html.escape(line)}</li>" for line in part.findings)
        lines.append(f'<ul class="findings">{items}</ul>')
    return "\n".join(lines) or "<p>This result has no table.</p>"


STYLE = """
body { font-family: system-ui, sans-serif; margin: 0 auto; max-width: 1200px; padding: 0 1.5em 3em;
  color: #222; line-height: 1.4; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
.meta { color: #666; margin: 0; } nav { margin: 0.6em 0; } nav a { color: #1f5fa8; }
table.data { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0 1em; }
table.data th, table.data td { border-bottom: 1px solid #e2e2e2; padding: 2px 8px; }
table.data th { background: #f4f4f4; } .num { text-align: right; } .text { text-align: left; }
table.data tbody tr:hover { background: #f7fafc; }
.scroll { overflow-x: auto; } .note { color: #555; font-size: 0.9em; }
pre.console { font-family: "DejaVu Sans Mono", Menlo, Consolas, monospace; font-size: 0.8em; line-height: 1.25;
  background: #fcfcfc; border: 1px solid #e6e6e6; padding: 0.6em; overflow-x: auto; }
figure { margin: 1.2em 0; } figcaption { color: #444; font-size: 0.9em; margin-bottom: 0.3em; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
.recommendation { background: #f3f8ef; border-left: 4px solid #5a9a3c; padding: 0.5em 0.8em; }
ul.findings { padding-left: 1.2em; } ul.findings li { margin: 0.2em 0; }
"""

#: what a figure says until it is drawn (and stays saying where the page's script does not run)
WAITING = "Unpacking the figure... (it needs JavaScript: Chrome or Edge 80, Firefox 113, Safari 16.4 or later)"

#: the page's one script: unpacks each <script type="application/gzip"> (base64 of gzip) with
#: the browser's DecompressionStream, runs plotly's JavaScript, draws each plotly figure
#: (Plotly.newPlot with __CONFIG__) and shows each packed SVG from a blob: URL; nothing is
#: fetched. When done, <html data-figures="drawn"> (or "failed", with the reason in the figure
#: and the console), which the browser test waits for.
LOADER = """
(function () {
  "use strict";
  var config = __CONFIG__;
  var root = document.documentElement;
  var plots = Array.prototype.slice.call(document.querySelectorAll("div[data-pack]"));
  var images = Array.prototype.slice.call(document.querySelectorAll("img[data-pack]"));
  function say(node, text) {
    var p = document.createElement("p");
    p.className = "note";
    p.textContent = text;
    if (node.tagName === "IMG") { node.parentNode.replaceChild(p, node); return; }
    node.textContent = "";
    node.appendChild(p);
  }
  function unpack(id) {
    var text = atob(document.getElementById(id).textContent.replace(/\\s+/g, ""));
    var bytes = new Uint8Array(text.length);
    for (var i = 0; i < text.length; i++) { bytes[i] = text.charCodeAt(i); }
    return new Response(new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip")));
  }
  if (typeof DecompressionStream === "undefined") {
    plots.concat(images).forEach(function (node) {
      say(node, "This browser cannot unpack the figures (it lacks DecompressionStream): " +
        "open the page in Chrome or Edge 80, Firefox 113, Safari 16.4 or later.");
    });
    root.dataset.figures = "failed";
    return;
  }
  var plotly = !plots.length ? Promise.resolve() : unpack("pack-plotly").text().then(function (code) {
    window.PlotlyConfig = { MathJaxConfig: "local" };
    var script = document.createElement("script");
    script.text = code;
    document.head.appendChild(script);
  });
  function failed(node) {
    return function (error) {
      say(node, "This figure could not be drawn: " + error);
      throw error;
    };
  }
  var jobs = plots.map(function (div) {
    return Promise.all([plotly, unpack(div.dataset.pack).json()]).then(function (done) {
      div.textContent = "";
      return Plotly.newPlot(div, done[1].data, done[1].layout, config);
    }).catch(failed(div));
  }).concat(images.map(function (img) {
    return unpack(img.dataset.pack).blob().then(function (blob) {
      return new Promise(function (resolve, reject) {
        img.onload = resolve;
        img.onerror = function () { reject(new Error("the image did not decode")); };
        img.src = URL.createObjectURL(new Blob([blob], { type: img.dataset.type }));
      });
    }).catch(failed(img));
  }));
  Promise.all(jobs).then(function () { root.dataset.figures = "drawn"; }, function (error) {
    root.dataset.figures = "failed";
    console.error("railride report: " + error);
  });
})();
"""


def _settings_html(part: Contents, command: str | None) -> str:
    from railride.analysis.labels import describe_scenario

    lines = []
    if command:
        lines.append(f"<p>Command: <code>{html.escape(command)}</code></p>")
    if part.scenario:
        lines.append(f"<p>Scenario: {html.escape(describe_scenario(part.scenario))}</p>")
    from railride.model.params import vehicle_text

    # the software that made it, as every result's document records it
    rows = [(f"{name} version" if name != "python" else "Python version", v or "-") for name, v in versions().items()]
    for k, v in part.settings.items():
        if k == "vehicle" and isinstance(v, dict) and "name" in v:  # its values: the parameters' table
            rows.append(("vehicle", vehicle_text(v).removeprefix("vehicle: ")))
        elif k != "vehicle_params":
            rows += _flat(k, v)
    frame = pd.DataFrame(rows, columns=["setting", "value"])
    return "\n".join(lines) + _table_html(frame)


def _flat(prefix: str, value) -> list[tuple[str, str]]:
    """Nested settings as (dotted key, text) rows; lists of records as JSON text."""
    if isinstance(value, dict) and value:
        return [row for k, v in value.items() for row in _flat(f"{prefix}.{k}" if prefix else str(k), v)]
    if isinstance(value, (list, tuple)) and not any(isinstance(v, (dict, list)) for v in value):
        text = ", ".join("-" if v is None else str(v) for v in value)
    elif isinstance(value, (dict, list, tuple)):
        text = json.dumps(value) if value else "-"
    else:
        text = "-" if value is None else str(value)
    return [(prefix, text)]


def _params_html(params) -> str:
    values = params.to_dict()
    rows = [(name, values[name], unit, meaning) for name, unit, meaning, _ in params.describe()]
    table = _table_html(pd.DataFrame(rows, columns=["parameter", "value", "unit", "meaning"]))
    return f"<details><summary>Vehicle parameters ({len(rows)})</summary>{table}</details>"


def _table_html(frame: pd.DataFrame) -> str:
    """A DataFrame as an HTML table: numbers right-aligned with six significant digits, text
    left-aligned, every cell escaped."""
    numeric = [frame[c].dtype.kind in "iuf" for c in frame.columns]

    def cell(value, number: bool, tag: str = "td") -> str:
        if value is None or (number and pd.isna(value)):
            text = ""
        elif number and isinstance(value, float):
            text = f"{value:.6g}"
        else:
            text = str(value)
        return f'<{tag} class="{"num" if number else "text"}">{html.escape(text)}</{tag}>'

    head = "".join(cell(c, n, "th") for c, n in zip(frame.columns, numeric))
    rows = "\n".join(
        "<tr>" + "".join(cell(v, n) for v, n in zip(row, numeric)) + "</tr>"
        for row in frame.itertuples(index=False, name=None)
    )
    return (
        f'<div class="scroll"><table class="data"><thead><tr>{head}</tr></thead><tbody>\n{rows}</tbody></table></div>'
    )


def _caption_table(caption: str, frame: pd.DataFrame) -> str:
    n = len(frame)
    note = (
        f"{n} rows" if n <= MAX_TABLE_ROWS else f"the first {MAX_TABLE_ROWS} of {n} rows (all: to_pandas(), or --out)"
    )
    table = _table_html(frame.head(MAX_TABLE_ROWS))
    summary = f'{html.escape(caption)} <span class="note">({note})</span>'
    opened = " open" if n <= 40 else ""
    return f"<details{opened}><summary>{summary}</summary>{table}</details>"


def _fragment(text: str) -> str:
    """A console fragment: the body of a whole document, else the text as it is."""
    found = re.search(r"<body[^>]*>(.*)</body>", text, flags=re.S | re.I)
    return found.group(1) if found else text


def _figure_html(packs: dict, name: str, caption: str, figure, note: str | None = None) -> str:
    """A figure: a plotly figure as an empty plot whose data go into ``packs`` (drawn by
    `LOADER`), a matplotlib one as an image (`_image`); the caption above, the note below."""
    key = f"figure-{name}"
    if hasattr(figure, "to_plotly_json"):  # plotly
        import plotly.io

        packs[key] = _gzip(plotly.io.to_json(figure, validate=False, pretty=False).encode("utf-8"))
        packs.setdefault("plotly", None)  # plotly's JavaScript, once, and only with a plotly figure
        height = figure.layout.height or 450
        inner = (
            f'<div id="plot-{html.escape(name)}" class="plotly-graph-div" data-pack="pack-{html.escape(key)}" '
            f'style="height:{int(height)}px; width:100%;"><p class="note">{WAITING}</p></div>'
        )
        kind = "interactive"
    else:  # matplotlib
        inner = _image(packs, key, figure, caption)
        kind = "static"
    caption = f"{caption} ({name}.png in the output folder)"
    after = f'<p class="note">{html.escape(note)}</p>' if note else ""
    return (
        f'<figure id="{html.escape(key)}" class="{kind}"><figcaption>{html.escape(caption)}</figcaption>'
        f"{inner}{after}</figure>"
    )


def _image(packs: dict, key: str, figure, alt: str) -> str:
    """A matplotlib figure as an <img>, whichever is smaller: its SVG (sharp at any zoom),
    gzip-compressed into ``packs`` and shown by `LOADER` from a blob: URL (an <img> keeps each
    SVG's ids to itself), or its PNG as a data URI. A long noisy history in SVG keeps every
    vertex matplotlib cannot simplify away, and comes out larger than its PNG."""
    from railride.plots._style import PNG_DPI

    buffer = io.BytesIO()
    figure.savefig(buffer, format="svg", metadata={"Date": None})
    svg = _gzip(buffer.getvalue())
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=PNG_DPI)
    png = buffer.getvalue()
    if len(svg) <= len(png):
        packs[key] = svg
        return f'<img alt="{html.escape(alt)}" data-pack="pack-{html.escape(key)}" data-type="image/svg+xml">'
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def _gzip(data: bytes) -> bytes:
    return gzip.compress(data, GZIP_LEVEL, mtime=0)


@functools.lru_cache(maxsize=1)
def _plotly_pack() -> bytes:
    """plotly's JavaScript (4.8 MB), gzip-compressed: once per process."""
    import plotly.offline

    return _gzip(plotly.offline.get_plotlyjs().encode("utf-8"))


def _packed_html(packs: dict) -> str:
    """The packed data of the figures (``packs``: id -> gzip bytes; "plotly": None for plotly's
    JavaScript, once), each a base64 text in a <script> the browser does not run, and `LOADER`,
    which unpacks them."""
    if not packs:
        return ""
    from railride.plots.interactive import CONFIG

    scripts = [
        f'<script type="application/gzip" id="pack-{html.escape(key)}">'
        f"{base64.b64encode(_plotly_pack() if data is None else data).decode('ascii')}</script>"
        for key, data in packs.items()
    ]
    loader = LOADER.replace("__CONFIG__", json.dumps(CONFIG))
    return "\n".join(scripts) + f"\n<script>{loader}</script>"
