"""The sensitivity curves of a tuning study (`railride.studies.tuning`, ``TuneResult.curves``): one
panel per gain, at most `PAGE_PANELS` panels a page (sensitivity.png, sensitivity_2.png, ...)."""

from __future__ import annotations

import math

import numpy as np

from railride.errors import InputError
from railride.analysis.labels import gain_unit
from railride.plots._style import PAGE_WIDTH, fit_text, given_axes, grid_shape, new_figure, set_title, styled


#: the most panels on one page of the sensitivity figure: four rows of three, each panel wide
#: enough for its gain's name, unit and ticks (47 panels on one page ran their ticks together)
PAGE_PANELS = 12
#: panels a row of a page
PAGE_COLUMNS = 3
#: the file stem of page k of the sensitivity figure: sensitivity, sensitivity_2, ...
SENSITIVITY_STEM = "sensitivity"


def _label_width(text: str, size_pt: float) -> float:
    """About how wide the tick label ``text`` is [in] at ``size_pt``: a digit is about 0.6 of
    the size; a decade "$10^{k}$" about three digits."""
    if text.startswith("$10^"):
        chars = 2 + 0.7 * len(text[5:-2])
    else:
        chars = len(text)
    return (0.6 * chars + 0.8) * size_pt / 72.0


def _log_ticks(ax, candidates: list, xlim: tuple, size_pt: float) -> None:
    """Label the ticks ``candidates`` ((value, label), left to right, the first kept always) of
    the log x axis of ``ax`` spanning ``xlim``, leaving out each one whose label would reach
    the last one kept, from the panel's width (`_label_width`)."""
    spec = ax.get_subplotspec()
    columns = spec.get_gridspec().ncols if spec is not None else 1
    width = max(0.5, ax.figure.get_figwidth() / columns - 0.6)  # less the y tick labels and label
    lo, hi = math.log10(xlim[0]), math.log10(xlim[1])

    def place(v: float) -> float:  # inches from the left edge
        return (math.log10(v) - lo) / (hi - lo) * width

    kept: list = []
    for value, label in candidates:
        x, half = place(value), _label_width(label, size_pt) / 2
        if not 0 <= x <= width:
            continue
        if kept and x - half < kept[-1][2] + 0.05:  # runs into the last label kept
            continue
        kept.append((value, label, x + half))
    ax.set_xticks([v for v, _, _ in kept], [label for _, label, _ in kept])


def _decades(left: float, right: float) -> list:
    """(value, label) of the decades within [left, right]; where fewer than two fit, the values
    1, 2 and 5 times a power of ten within it."""
    lo, hi = math.ceil(math.log10(left)), math.floor(math.log10(right))
    if hi > lo:
        return [(10.0**k, f"$10^{{{k}}}$") for k in range(lo, hi + 1)]
    steps = [m * 10.0**k for k in range(lo - 1, hi + 1) for m in (1, 2, 5)]
    return [(v, f"{v:g}") for v in steps if left <= v <= right]


def _zero_axis(ax, zero_x: float, edge: float, xlim: tuple, size_pt: float) -> None:
    """A log x axis whose left edge (below ``edge``) stands for the value 0, plotted at
    ``zero_x``: shaded, with a tick "0"; decade ticks above ``edge``."""
    from matplotlib.ticker import FixedLocator

    right = xlim[1]
    ax.axvspan(xlim[0], edge, color="0.9", zorder=0, linewidth=0)
    _log_ticks(ax, [(zero_x, "0"), *_decades(edge, right)], xlim, size_pt)
    hi = math.floor(math.log10(right))
    minor = [
        j * 10.0**k
        for k in range(math.floor(math.log10(edge)), hi + 1)
        for j in range(2, 10)
        if edge < j * 10.0**k < right
    ]
    ax.xaxis.set_minor_locator(FixedLocator(minor))


def _panel_title(ax, name: str, unit: str | None, final: float) -> dict:
    """A panel's title, the gain's name and unit over its chosen value, fitted to its column's
    width (a long gain name with its unit ran into the next panel's): the unit goes to a line
    of its own when both do not fit on one."""
    from matplotlib.font_manager import FontProperties

    spec = ax.get_subplotspec()
    columns = spec.get_gridspec().ncols if spec is not None else 1
    # a column less a margin: a title centred on its axes may not reach the page's edge
    width = ax.figure.get_figwidth() / columns - 0.45
    size = FontProperties(size="small").get_size_in_points()
    head = f"{name} ({unit})" if unit else name
    if unit and "\n" in fit_text(head, width, size):
        head = f"{name}\n({unit})"
    return {"label": fit_text(f"{head}\nchosen {final:.3g}", width, size), "fontsize": "small"}


def _draw_parameter(ax, mine: list, colour) -> bool:
    """The curves ``mine`` of one parameter into ``ax``; True if a curve holds the value 0."""
    values = [np.asarray(c.values, dtype=float) for c in mine]
    chosen = [float(c.chosen) for c in mine]
    positive = np.concatenate([v[v > 0] for v in values] + [np.array([x for x in chosen if x > 0])])
    has_zero = any((v == 0).any() for v in values) or any(x == 0 for x in chosen)
    lo, hi = (positive.min(), positive.max()) if positive.size else (1.0, 1.0)
    zero_x, edge = lo / 5.0, lo / 2.2

    def x(v):
        v = np.asarray(v, dtype=float)
        return np.where(v > 0, v, zero_x)

    for c, vals in zip(mine, values):
        order = np.argsort(vals)
        vals, obj = vals[order], np.asarray(c.objective, dtype=float)[order]
        col, pos = colour(int(c.sweep_pass)), vals > 0
        ax.plot(vals[pos], obj[pos], "-o", color=col, markersize=2.5)
        if (~pos).any():
            ax.plot(x(vals[~pos]), obj[~pos], "s", color=col, markerfacecolor="none", markersize=4.5)
            if pos.any():
                ax.plot([zero_x, vals[pos][0]], [obj[~pos][0], obj[pos][0]], ":", color=col, linewidth=1.0)
        k = np.flatnonzero(vals == float(c.chosen))
        if k.size:
            ax.plot(
                x(c.chosen),
                obj[k[0]],
                "*",
                color=col,
                markersize=10,
                markeredgecolor="k",
                markeredgewidth=0.5,
                zorder=5,
            )
    from matplotlib.font_manager import FontProperties
    from matplotlib.ticker import MaxNLocator, NullFormatter

    final = chosen[-1]
    ax.axvline(float(x(final)), color="tab:red", linestyle="--", linewidth=0.9, zorder=1)
    ax.set_xscale("log")
    xlim = ((zero_x if has_zero else lo) / 1.8, hi * 1.8)
    ax.set_xlim(*xlim)
    ax.tick_params(labelsize="small")
    size = FontProperties(size="small").get_size_in_points()
    if has_zero:
        _zero_axis(ax, zero_x, edge, xlim, size)
    else:
        _log_ticks(ax, _decades(*xlim), xlim, size)
    ax.xaxis.set_minor_formatter(NullFormatter())  # log minor ticks unlabelled: they ran together
    ax.yaxis.set_major_locator(MaxNLocator(nbins=4))
    parameter = mine[0].parameter
    unit = gain_unit(parameter)
    ax.set_title(**_panel_title(ax, parameter, unit, final))
    ax.set_ylabel("tracking error" if parameter.startswith("inner.") else "objective", fontsize="small")
    return has_zero


def sensitivity_pages(curves, per_page: int = PAGE_PANELS) -> list[list[str]]:
    """The parameters of each page of the sensitivity figure, in the order tuned: at most
    ``per_page`` panels a page, a law's panels on one page where they fit (a law that does not
    fit what is left of a page starts the next; one with more than ``per_page`` gains fills
    pages of its own)."""
    laws: dict[str, list[str]] = {}
    seen: set = set()
    for c in curves:
        if c.parameter not in seen:
            seen.add(c.parameter)
            laws.setdefault(str(c.controller), []).append(c.parameter)
    pages: list[list[str]] = []
    page: list[str] = []
    for parameters in laws.values():
        if page and len(page) + len(parameters) > per_page:
            pages.append(page)
            page = []
        for parameter in parameters:
            if len(page) == per_page:
                pages.append(page)
                page = []
            page.append(parameter)
    if page:
        pages.append(page)
    return pages


def sensitivity_stem(page: int) -> str:
    """The file stem of page ``page`` (1, 2, ...) of the sensitivity figure: "sensitivity" for
    the first (the name it always had), "sensitivity_2", "sensitivity_3", ... after it."""
    return SENSITIVITY_STEM if page == 1 else f"{SENSITIVITY_STEM}_{page}"


@styled
def plot_sensitivity(curves, ax=None, *, title: str | None = None, page: int = 1):
    """The sensitivity curves of a tuning study (``TuneResult.curves``, a sequence of
    `railride.studies.tune_result.Curve`): one panel per parameter (in the order tuned), the objective
    against the parameter's value on a log axis, one line per pass (coloured by pass). The
    value 0 (the gain switched off) cannot sit on a log axis: it is plotted at the shaded left
    edge, on a tick labelled 0, as an open square joined by a dotted line. The value kept after
    each pass is a star; a dashed red line marks the final choice, which the panel's title
    gives. The inner-loop panels (B, G) show the normalised force-tracking error. Tick labels
    that would run into their neighbour are left out.

    ``page``: a new figure holds one page of `sensitivity_pages` (at most `PAGE_PANELS`
    panels, `PAGE_COLUMNS` a row; its title says which page of how many, and the laws on it);
    `plot_sensitivity_pages` draws them all. ``ax``: one Axes per parameter, every page's, to
    draw in (the legend goes into the first, ``title`` and ``page`` are left out), or None for
    a new figure. Returns the figure.
    """
    from matplotlib import colormaps
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    curves = list(curves)
    if not curves:
        raise InputError("no sensitivity curves to plot")
    if ax is None:
        pages = sensitivity_pages(curves)
        if isinstance(page, bool) or not isinstance(page, (int, np.integer)) or not 1 <= page <= len(pages):
            raise InputError(
                f"page = {page!r}: the sensitivity figure has {len(pages)} page(s); allowed 1 to {len(pages)}"
            )
        parameters = pages[page - 1]
        nrows, ncols = grid_shape(len(parameters), PAGE_COLUMNS)
        fig = new_figure((PAGE_WIDTH, 2.1 * nrows + 1.2))
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    else:
        parameters = list(dict.fromkeys(c.parameter for c in curves))
        axes = given_axes(ax, len(parameters), f"one per parameter: {', '.join(parameters)}")
        fig = axes[0].figure
    max_pass = max(int(c.sweep_pass) for c in curves)
    cmap = colormaps["viridis"]

    def colour(sweep_pass):
        return cmap(0.85 * (sweep_pass - 1) / max(1, max_pass - 1))

    any_zero = False
    for a, parameter in zip(axes, parameters):
        any_zero = _draw_parameter(a, [c for c in curves if c.parameter == parameter], colour) or any_zero
    for a in axes[len(parameters) :]:
        a.set_visible(False)
    # the passes drawn on this page (their colours as on every page)
    drawn = sorted({int(c.sweep_pass) for c in curves if c.parameter in set(parameters)})
    handles: list = [Line2D([], [], color=colour(k), marker="o", markersize=3, label=f"pass {k}") for k in drawn]
    handles.append(
        Line2D(
            [],
            [],
            color="0.3",
            marker="*",
            linestyle="none",
            markersize=9,
            markeredgecolor="k",
            markeredgewidth=0.5,
            label="kept in that pass",
        )
    )
    handles.append(Line2D([], [], color="tab:red", linestyle="--", label="final value"))
    if any_zero:
        handles.append(Patch(color="0.9", label="value 0 (gain off)"))
    if ax is not None:
        axes[0].legend(handles=handles, loc="best", fontsize="x-small")
        return fig
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4), frameon=False)
    text = title or "Sensitivity of the tuning objective, one parameter at a time"
    if len(pages) > 1:
        laws = dict.fromkeys(str(c.controller) for c in curves if c.parameter in set(parameters))
        text += f"\npage {page} of {len(pages)}: {', '.join(laws)}"
    set_title(fig, text)
    return fig


def plot_sensitivity_pages(curves, *, title: str | None = None) -> list:
    """Every page of the sensitivity figure (`plot_sensitivity` of each page of
    `sensitivity_pages`), in order; the first is written as sensitivity.png, the next as
    sensitivity_2.png, ... (`sensitivity_stem`)."""
    curves = list(curves)
    if not curves:
        raise InputError("no sensitivity curves to plot")
    return [plot_sensitivity(curves, title=title, page=k) for k in range(1, len(sensitivity_pages(curves)) + 1)]
