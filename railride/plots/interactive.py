"""Interactive figures for the HTML report (`railride.output.report`): time histories, acceleration
spectra and frequency responses as plotly figures, which the reader zooms, pans and toggles
trace by trace (a click on a legend entry) in any browser, offline.

They draw the same data as the matplotlib figures of this package, with the same names and
colours per suspension. Traces are SVG (``go.Scatter``, not WebGL) so that every browser, a
headless one included, renders them. Long time histories are drawn as a min/max envelope
(`envelope`) of at most `MAX_POINTS` points per trace, which keeps every peak and keeps the
page small and fast; the figure says so. Values are stored as 32-bit floats, ample for a
drawing.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from railride.errors import InputError
from railride.analysis.spectra import FRF_RESPONSES, frf_excited
from railride.analysis.labels import CARBODY_RESPONSES, comparison_title, controller_names
from railride.plots._style import suspension_label, suspension_style

#: the most points one time-history trace keeps (`envelope`): min/max pairs at two a pixel or more
#: on a page up to 1500 px wide, and a 60 s comparison's page under 3 MB
MAX_POINTS = 3000
#: matplotlib line style -> plotly dash
DASHES = {"-": "solid", "--": "dash", ":": "dot", "-.": "dashdot"}
#: colour and dash per rail pattern of the frequency responses (as `railride.plots.frf`)
PATTERN_STYLES = {"in-phase": ("#1f77b4", "solid"), "anti-phase": ("#d62728", "dash")}
#: the plotly configuration of every figure: no logo link, sized by its container, the camera
#: button saves an SVG (drawn in the browser: no request leaves the page)
CONFIG = {"displaylogo": False, "responsive": True, "toImageButtonOptions": {"format": "svg"}}


def envelope(x, y, max_points: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` reduced to at most ``max_points`` samples for drawing: the samples split into
    equal buckets, and of each bucket its smallest and largest value kept, in time order, with
    the first and last sample. Every kept point is a sample of the input, the extremes of the
    whole trace among them, so the drawn band has the trace's peaks. NaN (a diverged run) is
    kept where a bucket holds nothing else. Shorter traces come back as they are."""
    x, y = np.asarray(x), np.asarray(y)
    n = y.size
    if max_points < 4:
        raise InputError(f"max_points = {max_points}: must be a whole number >= 4")
    if n <= max_points:
        return x, y
    buckets = (max_points - 2) // 2
    size = math.ceil(n / buckets)
    padded = np.full(buckets * size, np.nan)
    padded[:n] = y
    rows = padded.reshape(buckets, size)
    nan = np.isnan(rows)
    start = np.arange(buckets) * size
    low = start + np.where(nan, np.inf, rows).argmin(axis=1)
    high = start + np.where(nan, -np.inf, rows).argmax(axis=1)
    keep = np.unique(np.concatenate([[0, n - 1], low, high]))
    keep = keep[keep < n]
    return x[keep], y[keep]


def _plain(label: str) -> str:
    """A matplotlib axis label in plain text: "(m/s$^2$)" -> "(m/s²)"."""
    return label.replace("$^2$", "²").replace("$", "")


def _line(name: str) -> dict:
    style = suspension_style(name)
    colour = style.get("color")
    if colour is not None:
        from matplotlib.colors import to_hex

        colour = to_hex(colour)
    return {"color": colour, "dash": DASHES.get(style.get("linestyle", "-"), "solid"), "width": 1.4}


def _new(rows: int = 1, shared_x: bool = True, titles=None):
    from plotly.subplots import make_subplots

    return make_subplots(
        rows=rows, cols=1, shared_xaxes=shared_x, vertical_spacing=0.06 if rows > 1 else 0.0, subplot_titles=titles
    )


def _finish(fig, title: str, height: int, note: str = ""):
    text = title.replace("\n", "<br>") + (f"<br><sup>{note}</sup>" if note else "")
    fig.update_layout(
        template="plotly_white",
        title={"text": text, "x": 0.0, "xanchor": "left", "font": {"size": 14}},
        height=height,
        margin={"l": 70, "r": 20, "t": 90 if note else 70, "b": 95},
        # below the plot, clear of the title's lines
        legend={"orientation": "h", "yref": "container", "y": 0.0, "yanchor": "bottom", "x": 0.0},
        hovermode="x unified",
    )
    return fig


def _envelope_note(n: int, max_points: int) -> str:
    if n <= max_points:
        return ""
    return (
        f"each trace drawn as a min/max envelope of its {n} samples in at most {max_points} points "
        "(every peak kept; the full-rate data: the result's Dataset, or --out)"
    )


def comparison_response_figure(ds: xr.Dataset, response: str, *, max_points: int = MAX_POINTS):
    """One carbody response (acceleration, displacement, pitch or roll) of a comparison against
    time, one trace per suspension, from its combined Dataset (`Comparison.combined()`).
    Returns the plotly Figure."""
    import plotly.graph_objects as go

    if response not in CARBODY_RESPONSES:
        raise InputError(f"response = {response!r}: allowed {', '.join(CARBODY_RESPONSES)}")
    channel, factor, ylabel, what = CARBODY_RESPONSES[response]
    if channel not in ds.variables:
        raise InputError(f"the dataset lacks the channel {channel}")
    fig = _new()
    time = ds["time"].values
    for i, name in enumerate(controller_names(ds)):
        x, y = envelope(time, ds[channel].isel(controller=i).values * factor, max_points)
        fig.add_trace(
            go.Scatter(
                x=x.astype(np.float32),
                y=y.astype(np.float32),
                mode="lines",
                name=suspension_label(name),
                line=_line(name),
            )
        )
    fig.update_xaxes(title_text="time (s)", range=[float(time[0]), float(time[-1])])
    fig.update_yaxes(title_text=_plain(ylabel))
    context = comparison_title(ds)
    return _finish(fig, what + (f"\n{context}" if context else ""), 430, _envelope_note(time.size, max_points))


def comparison_psd_figure(psd: pd.DataFrame, *, title: str | None = None):
    """The acceleration spectra of `railride.analysis.spectra.comparison_psd` on log-log axes, one trace
    per suspension (the 0 Hz bin left out: a log axis cannot show it). Returns the Figure."""
    import plotly.graph_objects as go

    fig = _new()
    f = psd["frequency_hz"].values
    keep = f > 0
    top = 0.0
    for name in [c for c in psd.columns if c != "frequency_hz"]:
        y = psd[name].values[keep]
        if (y > 0).any():
            top = max(top, float(np.nanmax(y)))
        fig.add_trace(
            go.Scatter(
                x=f[keep].astype(np.float32),
                y=np.where(y > 0, y, np.nan).astype(np.float32),
                mode="lines",
                name=suspension_label(name),
                line=_line(name),
            )
        )
    fig.update_xaxes(type="log", title_text="frequency (Hz)")
    fig.update_yaxes(type="log", title_text="PSD of acceleration ((m/s²)²/Hz)", exponentformat="power")
    if top > 0:  # twelve decades below the highest peak, as the PNG: a sine's numerical floor is not news
        fig.update_yaxes(range=[math.log10(top) - 12, math.log10(top) + 0.5])
    return _finish(fig, title or "PSD of the carbody CG vertical acceleration", 460)


def ride_figure(ds: xr.Dataset, *, labels=None, title: str = "carbody responses", max_points: int = MAX_POINTS):
    """The four carbody responses of a ride result (`RideResult.dataset`) against time, one
    panel each on a shared time axis (zooming one zooms all); a batch gets one trace per sample,
    named by ``labels`` (default "sample k"), toggled in every panel at once. Returns the
    Figure."""
    import plotly.graph_objects as go

    missing = [c for c, _, _, _ in CARBODY_RESPONSES.values() if c not in ds.variables]
    if missing:
        raise InputError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    fig = _new(len(CARBODY_RESPONSES))
    time = ds["time"].values
    samples = list(ds["sample"].values) if "sample" in ds.dims else [None]
    names = list(labels) if labels is not None else [f"sample {s}" if s is not None else "" for s in samples]
    palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf"]
    for row, (channel, factor, ylabel, _) in enumerate(CARBODY_RESPONSES.values(), start=1):
        da = ds[channel]
        for k, s in enumerate(samples):
            values = (da.sel(sample=s) if s is not None and "sample" in da.dims else da).values * factor
            x, y = envelope(time, values, max_points)
            fig.add_trace(
                go.Scatter(
                    x=x.astype(np.float32),
                    y=y.astype(np.float32),
                    mode="lines",
                    name=names[k] or "carbody",
                    legendgroup=str(k),
                    showlegend=row == 1 and len(samples) > 1,
                    line={"color": palette[k % len(palette)], "width": 1.3},
                ),
                row=row,
                col=1,
            )
        fig.update_yaxes(title_text=_plain(ylabel), row=row, col=1)
    fig.update_xaxes(range=[float(time[0]), float(time[-1])])
    fig.update_xaxes(title_text="time (s)", row=len(CARBODY_RESPONSES), col=1)
    return _finish(fig, title, 820, _envelope_note(time.size, max_points))


def frf_figure(frame: pd.DataFrame, modes: pd.DataFrame | None = None, *, title: str | None = None):
    """The magnitudes of the carbody frequency responses (`railride.analysis.spectra.frf_frame`) on
    log-log axes, one panel per response on a shared frequency axis, one trace per rail pattern
    (toggled in every panel at once); a response a pattern does not excite is left out. The
    undamped natural frequencies of ``modes`` (`railride.model.modes.modes_frame`) are dotted
    vertical lines, numbered in the top panel. Returns the Figure."""
    import plotly.graph_objects as go

    titles = [f"carbody {name}" for name, *_ in FRF_RESPONSES]
    fig = _new(len(FRF_RESPONSES), titles=titles)
    patterns = list(dict.fromkeys(frame["pattern"]))
    f_all = frame["frequency_hz"].values
    lo, hi = float(f_all.min()), float(f_all.max())
    for row, (_, _, _, ylabel, column) in enumerate(FRF_RESPONSES, start=1):
        top = float(frame[column].max())
        for pattern in patterns:
            part = frame[frame["pattern"] == pattern]
            y = part[column].values
            if not frf_excited(y, top):
                continue
            colour, dash = PATTERN_STYLES.get(pattern, ("#444444", "solid"))
            fig.add_trace(
                go.Scatter(
                    x=part["frequency_hz"].values.astype(np.float32),
                    y=np.where(y > 0, y, np.nan).astype(np.float32),
                    mode="lines",
                    name=f"{pattern} rails",
                    legendgroup=pattern,
                    showlegend=pattern not in {t.legendgroup for t in fig.data},
                    line={"color": colour, "dash": dash, "width": 1.5},
                ),
                row=row,
                col=1,
            )
        fig.update_yaxes(type="log", title_text=_plain(ylabel), exponentformat="power", row=row, col=1)
    fig.update_xaxes(type="log", range=[math.log10(lo), math.log10(hi)])
    fig.update_xaxes(title_text="frequency (Hz)", row=len(FRF_RESPONSES), col=1)
    if modes is not None:
        shown = modes[(modes["frequency_hz"] >= lo) & (modes["frequency_hz"] <= hi)].sort_values("frequency_hz")
        for f in shown["frequency_hz"]:
            fig.add_vline(x=float(f), line={"color": "#777777", "dash": "dot", "width": 1}, row="all", col=1)
        for group in _clusters(shown):
            freqs = [float(m["frequency_hz"]) for m in group]
            fig.add_annotation(
                x=math.log10(math.sqrt(freqs[0] * freqs[-1])),  # annotations on a log axis take log10
                y=1.0,
                xref="x",
                yref="y domain",
                text=",".join(str(int(m["mode"])) for m in group),
                hovertext="<br>".join(
                    f"mode {int(m['mode'])}: {m['label']}, {float(m['frequency_hz']):.3g} Hz" for m in group
                ),
                showarrow=False,
                yanchor="bottom",
                font={"size": 9, "color": "#555555"},
            )
    note = "dotted: undamped natural frequencies (mode numbers at the top; hover for the mode)"
    return _finish(fig, title or "Carbody frequency responses per metre of rail amplitude", 960, note)


def _clusters(modes: pd.DataFrame) -> list[list]:
    """The rows of ``modes`` (sorted by frequency) in clusters of frequencies within 10 % of the
    previous one, which would overlap as labels on a log axis."""
    groups: list[list] = []
    for _, m in modes.iterrows():
        f = float(m["frequency_hz"])
        if groups and f <= float(groups[-1][-1]["frequency_hz"]) * 1.10:
            groups[-1].append(m)
        else:
            groups.append([m])
    return groups


def ride_spectrum_figure(result):
    """The floor acceleration PSDs of a `railride.frequency.ride_spectrum.RideSpectrum`: a log-log panel per
    floor point, a trace per suspension (legend groups toggle a suspension in every panel).
    Returns the Figure."""
    import plotly.graph_objects as go

    from railride.analysis.comfort import FLOOR

    fig = _new(rows=len(FLOOR), titles=[f"floor, {p}" for p in FLOOR])
    f = result.psd["frequency"].values
    top = max(float(result.psd[f"floor_acceleration_{p}"].max()) for p in FLOOR)
    for row, point in enumerate(FLOOR, start=1):
        for name in result.suspensions:
            y = result.psd[f"floor_acceleration_{point}"].sel(suspension=name).values
            fig.add_trace(
                go.Scatter(
                    x=f.astype(np.float32),
                    y=np.where(y > 0, y, np.nan).astype(np.float32),
                    mode="lines",
                    name=suspension_label(name),
                    legendgroup=name,
                    showlegend=row == 1,
                    line=_line(name),
                ),
                row=row,
                col=1,
            )
        fig.update_yaxes(type="log", title_text="(m/s²)²/Hz", exponentformat="power", row=row, col=1)
        if top > 0:  # six decades below the peak: the wheelbase filter's notches reach zero
            fig.update_yaxes(range=[math.log10(top) - 6, math.log10(top) + 0.5], row=row, col=1)
    fig.update_xaxes(type="log")
    fig.update_xaxes(title_text="frequency (Hz)", row=len(FLOOR), col=1)
    return _finish(fig, result.title(), 820)
