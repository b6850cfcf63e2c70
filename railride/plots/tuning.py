"""The sensitivity curves of a tuning study (`railride.studies.tuning`, ``TuneResult.curves``)."""

from __future__ import annotations

import math

import numpy as np

from railride.errors import InputError
from railride.analysis.labels import gain_unit
from railride.plots._style import PAGE_WIDTH, fit_text, given_axes, grid_shape, new_figure, set_title, styled


def _zero_axis(ax, zero_x: float, edge: float, right: float) -> None:
    """A log x axis whose left edge (below ``edge``) stands for the value 0, plotted at
    ``zero_x``: shaded, with a tick "0"; decade ticks above ``edge``."""
    from matplotlib.ticker import FixedLocator, NullFormatter

    ax.axvspan(ax.get_xlim()[0], edge, color="0.9", zorder=0, linewidth=0)
    lo, hi = math.ceil(math.log10(edge)), math.floor(math.log10(right))
    decades = [10.0**k for k in range(lo, hi + 1)]
    labels = [f"$10^{{{k}}}$" for k in range(lo, hi + 1)]
    if not decades:  # a range within one decade: label its ends
        decades = [edge * 2.0, right / 1.6]
        labels = [f"{v:.3g}" for v in decades]
    ax.set_xticks([zero_x, *decades], ["0", *labels])
    minor = [
        j * 10.0**k
        for k in range(math.floor(math.log10(edge)), hi + 1)
        for j in range(2, 10)
        if edge < j * 10.0**k < right
    ]
    ax.xaxis.set_minor_locator(FixedLocator(minor))
    ax.xaxis.set_minor_formatter(NullFormatter())


def _panel_title(ax, name: str, unit: str | None, final: float) -> dict:
    """A panel's title, the gain's name and unit over its chosen value, fitted to its column's
    width (a long gain name with its unit ran into the next panel's): the unit goes to a line
    of its own when both do not fit on one."""
    from matplotlib.font_manager import FontProperties

    spec = ax.get_subplotspec()
    columns = spec.get_gridspec().ncols if spec is not None else 1
    width = ax.figure.get_figwidth() / columns - 0.3
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
    final = chosen[-1]
    ax.axvline(float(x(final)), color="tab:red", linestyle="--", linewidth=0.9, zorder=1)
    ax.set_xscale("log")
    ax.set_xlim((zero_x if has_zero else lo) / 1.8, hi * 1.8)
    if has_zero:
        _zero_axis(ax, zero_x, edge, hi * 1.8)
    parameter = mine[0].parameter
    unit = gain_unit(parameter)
    ax.set_title(**_panel_title(ax, parameter, unit, final))
    ax.set_ylabel("tracking error" if parameter.startswith("inner.") else "objective", fontsize="small")
    ax.tick_params(labelsize="small")
    return has_zero


@styled
def plot_sensitivity(curves, ax=None, *, title: str | None = None):
    """The sensitivity curves of a tuning study (``TuneResult.curves``, a sequence of
    `railride.studies.tune_result.Curve`): one panel per parameter (in the order tuned), the objective
    against the parameter's value on a log axis, one line per pass (coloured by pass). The
    value 0 (the gain switched off) cannot sit on a log axis: it is plotted at the shaded left
    edge, on a tick labelled 0, as an open square joined by a dotted line. The value kept after
    each pass is a star; a dashed red line marks the final choice, which the panel's title
    gives. The inner-loop panels (B, G) show the normalised force-tracking error.

    ``ax``: one Axes per parameter to draw in (the legend goes into the first, and ``title``
    is left out), or None for a new figure, four panels a row. Returns the figure.
    """
    from matplotlib import colormaps
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    curves = list(curves)
    if not curves:
        raise InputError("no sensitivity curves to plot")
    parameters = list(dict.fromkeys(c.parameter for c in curves))
    if ax is None:
        nrows, ncols = grid_shape(len(parameters))
        fig = new_figure((PAGE_WIDTH, 1.9 * nrows + 1.0))
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    else:
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
    handles: list = [
        Line2D([], [], color=colour(k), marker="o", markersize=3, label=f"pass {k}") for k in range(1, max_pass + 1)
    ]
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
    set_title(fig, title or "Sensitivity of the tuning objective, one parameter at a time")
    return fig
