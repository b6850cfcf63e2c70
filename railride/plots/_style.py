"""What every railride plot shares: the one house style (font sizes, line widths, grid, figure
widths that fit a journal column or page), the new figure, titles that fit it, the metric window
on a time history, the figure files (`FigureOptions`, `save_figure`) and the name and line style
of each suspension.

The style is applied with ``matplotlib.rc_context`` around the drawing of a figure a plot
function makes itself (`styled`), never by changing matplotlib's global settings; a figure drawn
into the caller's Axes keeps the caller's style."""

from __future__ import annotations

import functools
import inspect
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from railride.errors import InputError
from railride._io import atomic_write
from railride.validation import number, shown

#: resolution of PNG figures unless asked otherwise [dots per inch]
PNG_DPI = 120
#: the highest resolution accepted: 1200 dpi is what print asks of line art
MAX_DPI = 1200
#: the lowest: a figure a few dozen pixels wide, whose text no one can read (below 1 dpi matplotlib
#: draws an image of no pixels at all and cannot write it)
MIN_DPI = 10
#: the file formats a figure can be written in
FIGURE_FORMATS = ("png", "pdf", "svg")
#: figure widths [in]: one column of a two-column journal page (88-90 mm) and the full text
#: width (178-190 mm); a figure printed at its size keeps the font sizes of `STYLE`
COLUMN_WIDTH = 3.5
PAGE_WIDTH = 7.0
#: the house style: 9 pt text and 8 pt tick labels read at print size; grid on, thin and light
STYLE: dict[str, Any] = {
    "font.size": 9.0,
    "axes.titlesize": 9.0,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "legend.title_fontsize": 8.0,
    "figure.titlesize": 9.5,
    "lines.linewidth": 1.0,
    "lines.markersize": 4.0,
    "axes.linewidth": 0.6,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "axes.grid": True,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.6,
    "legend.framealpha": 0.85,
    "legend.edgecolor": "0.8",
    "axes.titlepad": 4.0,
}
#: read when a figure is written: TrueType fonts in PDF (publishers refuse Type 3 fonts); SVG
#: element ids from a fixed salt, so that the same figure gives the same file
SAVE_STYLE: Any = {"pdf.fonttype": 42, "ps.fonttype": 42, "svg.hashsalt": "railride"}
#: the colour of the parts of a time history outside the metric window
OUTSIDE_WINDOW = "0.9"
#: line style and colour per suspension, as in the paper's Figs. 8-11 (passive dash-dot, PID
#: dotted, SAS (attitude) dashed, SAS (attitude+ride) solid); "mr" is a sweep's MR damper at a
#: constant voltage
SUSPENSION_STYLES = {
    "passive": {"linestyle": "-.", "color": "0.25"},
    "pid": {"linestyle": ":", "color": "tab:blue"},
    "sas-attitude": {"linestyle": "--", "color": "tab:orange"},
    "sas-attitude-ride": {"linestyle": "-", "color": "tab:red"},
    "mr": {"linestyle": "-", "color": "tab:green"},
    # the laws beyond the paper
    "skyhook": {"linestyle": "-", "color": "tab:purple"},
    "skyhook-on-off": {"linestyle": "--", "color": "tab:purple"},
    "groundhook": {"linestyle": "-", "color": "tab:brown"},
    "hybrid": {"linestyle": "-", "color": "tab:pink"},
    "clipped-optimal": {"linestyle": "-", "color": "tab:cyan"},
    "passive-on": {"linestyle": ":", "color": "0.45"},
    "passive-off": {"linestyle": ":", "color": "0.65"},
}


# -- the style --------------------------------------------------------------------------------------
def styled(plot):
    """Draw ``plot``'s own figure (``ax`` None) in `STYLE`, inside ``matplotlib.rc_context``;
    into the caller's Axes, as the caller's style has it."""
    signature = inspect.signature(plot)

    @functools.wraps(plot)
    def draw(*args, **kwargs):
        if signature.bind_partial(*args, **kwargs).arguments.get("ax") is not None:
            return plot(*args, **kwargs)
        import matplotlib

        with matplotlib.rc_context(STYLE):
            fig = plot(*args, **kwargs)
            _settle_ticks(fig)
        return fig

    return draw


def _settle_ticks(fig) -> None:
    """Make the first tick of every axis now: matplotlib makes ticks when the figure is drawn
    and copies later ones from the first, so they keep `STYLE` outside its context."""
    for a in fig.get_axes():
        for axis in (a.xaxis, a.yaxis):
            axis.get_major_ticks(1)
            axis.get_minor_ticks(1)


def new_figure(figsize):
    """A constrained-layout Figure of ``figsize`` (inches; `PAGE_WIDTH` or `COLUMN_WIDTH` wide)
    on its own Agg canvas, never registered with pyplot."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def fit_text(text: str, width_in: float, size_pt: float) -> str:
    """``text`` with each line wrapped at spaces to fit ``width_in`` inches at ``size_pt``
    points in the current font, as measured from the glyphs' outlines (a little wider than the
    rendered text, so that a line never overflows)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    font = FontProperties(size=size_pt)
    limit = width_in * 72.0

    def fits(line: str) -> bool:
        return text_to_path.get_text_width_height_descent(line, font, ismath=False)[0] <= limit

    out = []
    for line in text.split("\n"):
        current = ""
        for word in line.split(" "):
            trial = f"{current} {word}" if current else word
            if current and not fits(trial):
                out.append(current)
                current = word
            else:
                current = trial
        out.append(current)
    return "\n".join(out)


def set_title(fig, text: str) -> None:
    """The figure's title ``text``, wrapped to the figure's width."""
    import matplotlib
    from matplotlib.font_manager import FontProperties

    size = FontProperties(size=matplotlib.rcParams["figure.titlesize"]).get_size_in_points()
    fig.suptitle(fit_text(text, fig.get_figwidth() - 0.2, size))


# -- time histories and the metric window -----------------------------------------------------------
def outside_window(time, window) -> bool:
    """Whether ``window`` (start, end) s leaves out part of the run ``time`` (None: it does
    not)."""
    if window is None or len(time) == 0:
        return False
    start, end = float(window[0]), float(window[1])
    return start > float(time[0]) + 1e-9 or end < float(time[-1]) - 1e-9


def window_ylim(time, values, window, pad: float = 0.06):
    """The y-limits (low, high) that frame the ``values`` (arrays over ``time``, any number)
    inside ``window`` (start, end) s with ``pad`` of their range each side; None when the
    window leaves nothing out (autoscale then) or holds no finite value."""
    if not outside_window(time, window):
        return None
    time = np.asarray(time, dtype=float)
    inside = (time >= float(window[0]) - 1e-9) & (time <= float(window[1]) + 1e-9)
    parts = [np.asarray(v, dtype=float)[..., inside] for v in values]
    parts = [p[np.isfinite(p)] for p in parts]
    parts = [p for p in parts if p.size]
    if not parts:
        return None
    lo, hi = min(float(p.min()) for p in parts), max(float(p.max()) for p in parts)
    span = hi - lo if hi > lo else max(abs(hi), 1e-12)
    return lo - pad * span, hi + pad * span


def mark_window(ax, time, window) -> None:
    """Shade the parts of the run ``time`` outside ``window`` (start, end) s, behind the lines."""
    if not outside_window(time, window):
        return
    t0, t1 = float(time[0]), float(time[-1])
    if window[0] > t0:
        ax.axvspan(t0, float(window[0]), color=OUTSIDE_WINDOW, zorder=0, linewidth=0)
    if window[1] < t1:
        ax.axvspan(float(window[1]), t1, color=OUTSIDE_WINDOW, zorder=0, linewidth=0)


def frame_window(axes, time, values, window) -> bool:
    """Mark the metric ``window`` on each Axes of ``axes`` and set their common y-limits from the
    ``values`` inside it (the start-up transient stays drawn, clipped at the axes); True when the
    window left part of the run out."""
    limits = window_ylim(time, values, window)
    for a in axes:
        mark_window(a, time, window)
        if limits is not None:
            a.set_ylim(*limits)
    return outside_window(time, window)


def window_note(window) -> str:
    """The line a figure's title gets when its metric window leaves part of the run out."""
    return f"shaded: outside the metric window {float(window[0]):g}-{float(window[1]):g} s; y-axis fits the window"


# -- figure files -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class FigureOptions:
    """How figures are written: ``figure_formats`` (one or more of `FIGURE_FORMATS`, a sequence
    or one comma-separated text; order kept, repeats dropped) and ``dpi``, the resolution of PNG
    files (a finite number >= `MIN_DPI` and <= `MAX_DPI`; PDF and SVG are vector, drawn at any size)."""

    figure_formats: Any = ("png",)
    dpi: float = PNG_DPI

    def __post_init__(self) -> None:
        given = self.figure_formats
        items = given.split(",") if isinstance(given, str) else given
        try:
            names = [f.strip().lower() if isinstance(f, str) else f for f in items]
        except TypeError:
            names = [given]
        bad = [f for f in names if f not in FIGURE_FORMATS]
        if bad or not names:
            what = f"{shown(bad[0])} is not a figure format" if bad else "no format given"
            raise InputError(
                f"figure_formats = {shown(given)}: {what}; allowed one or more of {', '.join(FIGURE_FORMATS)}"
            )
        object.__setattr__(self, "figure_formats", tuple(dict.fromkeys(names)))
        allowed = f"a finite number >= {MIN_DPI} and <= {MAX_DPI} (dots per inch)"
        dpi = number("dpi", self.dpi, "positive", allowed=allowed)
        if not MIN_DPI <= dpi <= MAX_DPI:
            raise InputError(f"dpi = {shown(self.dpi)}: must be {allowed}")
        object.__setattr__(self, "dpi", dpi)

    def names(self, stem: str) -> list[str]:
        """The file names of figure ``stem``, one per format: "pitch.png", "pitch.pdf"."""
        return [f"{stem}.{fmt}" for fmt in self.figure_formats]


def save_figure(fig, path, format: str | None = None, dpi: float = PNG_DPI) -> None:
    """Write ``fig`` to ``path`` atomically (a reader never sees a half-written file) as
    ``format`` (png, pdf or svg; default: the file's suffix, PNG for another), PNG at ``dpi``."""
    import matplotlib

    path = Path(path)
    if format is None:
        suffix = path.suffix.lower().lstrip(".")
        format = suffix if suffix in FIGURE_FORMATS else "png"
    options = FigureOptions((format,), dpi)
    (fmt,) = options.figure_formats

    def write(tmp: Path) -> None:
        with matplotlib.rc_context(SAVE_STYLE):
            fig.savefig(tmp, format=fmt, dpi=options.dpi, metadata=_metadata(fmt))

    atomic_write(path, write)


def _metadata(fmt: str) -> dict:
    """Who made the file; no creation date, so that the same figure gives the same file."""
    from railride._version import __version__

    creator = f"railride {__version__}"
    if fmt == "png":
        return {"Software": creator}
    if fmt == "pdf":
        return {"Creator": creator, "CreationDate": None}
    return {"Creator": creator, "Date": None}


def save_to(fig, path) -> None:
    """Write ``fig`` to ``path`` (format from its suffix, else PNG) at `PNG_DPI`, atomically;
    nothing when ``path`` is None: the ``path`` argument of the plot functions."""
    if path is not None:
        save_figure(fig, path)


def save_png(fig, path) -> None:
    """Write ``fig`` to ``path`` as PNG at `PNG_DPI`, atomically; nothing when ``path`` is
    None."""
    if path is not None:
        save_figure(fig, path, "png", PNG_DPI)


# -- axes and suspensions ---------------------------------------------------------------------------
def given_axes(ax, count: int, what: str) -> list:
    """The ``count`` Axes of ``ax`` (one Axes or a sequence, any shape) in order; ValueError
    naming what each panel is when the count differs."""
    axes = list(np.ravel(ax))
    if len(axes) != count:
        raise InputError(f"ax: {count} Axes ({what}), got {len(axes)}")
    return axes


def say_not_excited(ax, text: str = "not excited") -> None:
    """Write ``text`` in the middle of ``ax`` in grey and leave its y-axis without ticks: the
    panel of a response that the input does not excite (its trace would be rounding noise,
    autoscaled to the panel's height), which keeps its axes and labels."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, fontsize="medium", color="0.35", ha="center", va="center")
    ax.set_yticks([])


def grid_shape(count: int, max_columns: int = 4) -> tuple[int, int]:
    """(rows, columns) of a grid of ``count`` panels at most ``max_columns`` wide."""
    columns = max(1, min(max_columns, count))
    return math.ceil(count / columns), columns


def suspension_label(name: str) -> str:
    """The display name of a suspension: "Passive", "PID", "SAS (attitude)", ...,
    "MR (constant voltage)"; an unknown name as it is."""
    from railride.secondary.control import LABELS  # here, not above: control pulls in the vehicle model

    if name == "mr":
        return "MR (constant voltage)"
    return LABELS.get(name, name)


def suspension_style(name: str) -> dict:
    """The line style of `SUSPENSION_STYLES` for ``name``; a plain solid line for another."""
    return SUSPENSION_STYLES.get(name, {"linestyle": "-"})
