"""A sweep (a `railride.studies.sweep.SweepResult`): the RMS of the carbody responses and the ride
comfort against its swept axis, with one line per value of a second swept axis where there is
one. An ordered axis (speed, a gain, a voltage, a damper scale) is drawn as lines; a categorical
one (track and noise seeds) as markers at evenly spaced, labelled positions, never joined."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride.analysis.labels import describe_dampers, describe_scenario, grid_axis_label
from railride.plots._style import (
    PAGE_WIDTH,
    given_axes,
    new_figure,
    set_title,
    styled,
    suspension_label,
    suspension_style,
)

#: (RMS column, axis label) of the four panels of `plot_sweep`
RMS_PANELS = (
    ("acceleration_m_s2_rms", "acceleration RMS (m/s$^2$)"),
    ("displacement_m_rms", "displacement RMS (m)"),
    ("pitch_deg_rms", "pitch RMS (deg)"),
    ("roll_deg_rms", "roll RMS (deg)"),
)
#: (column, axis label) of the two panels of `plot_sweep_comfort`
COMFORT_PANELS = (
    ("centre_N_MV_z", "N$_{MV,z}$, carbody centre (EN 12299, vertical part)"),
    ("centre_aw_Wk", "a$_w$ Wk, carbody centre (m/s$^2$)"),
)


#: the grid columns whose values name things rather than measure them: a seed picks one
#: realisation, and seed 3 lies no nearer seed 4 than seed 40; drawn as markers at categorical
#: positions, never joined by a line (`is_categorical`)
CATEGORICAL_AXES = ("track_seed", "seed")
#: the most axes with several values one figure draws: the first along x, the second as one line
#: per value
MAX_PLOT_AXES = 2


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def swept_axes(result) -> list[str]:
    """The grid columns of the sweep ``result`` besides ``suspension`` with more than one value
    (`SweepGrid.grid_values`), in the grid's order."""
    grid = result.grid.grid_values()
    return [c for c, values in grid.items() if c != "suspension" and len(values) > 1]


def is_categorical(result, axis: str) -> bool:
    """Whether the grid column ``axis`` of ``result`` is a category (a seed, `CATEGORICAL_AXES`,
    or an axis whose values are not all numbers): markers at evenly spaced positions labelled by
    the value, no line between them. An ordered axis (speed, load, a gain, a voltage) is a line."""
    values = result.grid.grid_values().get(axis, [])
    return axis in CATEGORICAL_AXES or not all(_is_number(v) for v in values)


def sweep_plot_axes(result) -> tuple[str, str | None] | None:
    """(x, lines) of `plot_sweep` for the sweep ``result``: with one swept axis (`swept_axes`),
    (that axis, None); with two, the ordered one along x and one line per value of the other
    (both ordered, or both categories: the one with more values along x, the first in the grid's
    order on a tie). None with none or more than `MAX_PLOT_AXES` (`sweep_figure_note` says why)."""
    several = swept_axes(result)
    if len(several) == 1:
        return several[0], None
    if len(several) != MAX_PLOT_AXES:
        return None
    grid = result.grid.grid_values()
    x = min(several, key=lambda c: (is_categorical(result, c), -len(grid[c]), several.index(c)))
    return x, next(c for c in several if c != x)


def sweep_plot_axis(result) -> str | None:
    """The grid column `plot_sweep` draws along x (`sweep_plot_axes`), or None where it draws
    no figure (`sweep_figure_note`)."""
    axes = sweep_plot_axes(result)
    return None if axes is None else axes[0]


def sweep_figure_note(result) -> str | None:
    """One line saying why the sweep ``result`` has no figure (sweep.png), or None when it has
    one (`sweep_plot_axes`)."""
    several = swept_axes(result)
    if not several:
        return (
            "no figure: no single numeric axis has several values to plot against "
            "(every axis besides the suspension has one value); the table holds every run"
        )
    if len(several) > MAX_PLOT_AXES:
        return (
            f"no figure: {len(several)} axes have several values ({', '.join(several)}); a figure "
            f"draws at most {MAX_PLOT_AXES} (one along x, one line per value of the other): give the "
            "others one value, or plot from sweep.json or runs.csv"
        )
    return None


def has_comfort(result) -> bool:
    """Whether the sweep ``result`` has runs and their rows hold the comfort indices (`run_sweep`
    with comfort, `railride sweep --comfort`)."""
    return len(result.grid.cases) > 0 and all(c in result.metric_columns() for c, _ in COMFORT_PANELS)


def _log_axis(axis: str, xs: list) -> bool:
    """A logarithmic x axis for values spanning 100:1, or 4:1 for a factor (damper_scale, whose
    grids are geometric)."""
    ratio = 4 if axis == "damper_scale" else 100
    return bool(xs) and min(xs) > 0 and max(xs) / min(xs) >= ratio


def _value_text(axis: str, value) -> str:
    """A value of the grid column ``axis`` as a legend names it: "speed 20 m/s", "track seed 3"."""
    label = grid_axis_label(axis)
    name, unit = (label[:-1].rsplit(" (", 1) + [""])[:2] if label.endswith(")") else (label, "")
    shown = f"{value:g}" if _is_number(value) else str(value)
    return f"{name} {shown}" + (f" {unit}" if unit and unit != "-" else "")


#: the markers that tell the suspensions apart where colour tells the values of a second axis
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "<", ">")


@dataclass(frozen=True)
class _Layout:
    """How a sweep's values are drawn: ``x`` the column along x, ``series`` the column drawn as
    one line per value (None: one axis), ``categories`` the values of a categorical x in order
    (None: an ordered x, a line), ``values`` the series column's values in order."""

    x: str
    series: str | None
    categories: list | None
    values: list
    series_categorical: bool = False


def _key(value):
    """A value as a dictionary key: numbers by their float value (a seed read back as 3.0 is 3)."""
    return float(value) if _is_number(value) else str(value)


def _layout(result, axis: str | None, series: str | None) -> _Layout:
    """The `_Layout` of `plot_sweep`: ``axis`` and ``series`` as given, or `sweep_plot_axes`."""
    grid = result.grid.grid_values()
    several = swept_axes(result)
    if axis is None:
        axes = sweep_plot_axes(result)
        if axes is None:
            raise InputError(f"the sweep has no figure: {sweep_figure_note(result)}")
        axis, auto = axes
        series = auto if series is None else series
    elif series is None and len(several) == MAX_PLOT_AXES and axis in several:
        series = next(c for c in several if c != axis)
    for name, value in (("axis", axis), ("series", series)):
        if value is not None and (value == "suspension" or value not in grid):
            allowed = ", ".join(c for c in grid if c != "suspension") or "none (the sweep has no axis)"
            raise InputError(f"{name} = {value!r}: not an axis of the sweep; allowed {allowed}")
    if series == axis:
        raise InputError(f"series = {series!r}: the same axis as axis; give another axis, or None")
    categories = list(grid[axis]) if is_categorical(result, axis) else None
    if series is None:
        return _Layout(axis, None, categories, [None])
    return _Layout(axis, series, categories, list(grid[series]), is_categorical(result, series))


def _series_colour(layout: _Layout, k: int):
    """The colour of the ``k``-th value of the series axis: a sequence for an ordered axis
    (light to dark with the value), distinct colours for categories."""
    from matplotlib import colormaps

    n = len(layout.values)
    if layout.series_categorical:
        return colormaps["tab10"](k % 10)
    return colormaps["viridis"](0.85 * k / max(1, n - 1))


def _sweep_lines(ax, frame, layout: _Layout, column, suspensions):
    """``column`` against ``layout.x`` from the rows ``frame`` (`SweepResult.to_pandas`): per
    suspension one line, or with a series axis one per value it takes (a horizontal line where
    the x axis does not act on the suspension); on a categorical x, markers at the categories'
    positions, side by side, with no line between them."""
    x, series = layout.x, layout.series
    position = {_key(v): i for i, v in enumerate(layout.categories or [])}
    groups: list[tuple] = []  # (suspension index, suspension, series index, series value, rows)
    for s, name in enumerate(suspensions):
        mine = frame[frame["suspension"] == name]
        if series is None or mine[series].isna().all():
            groups.append((s, name, None, None, mine))
            continue
        for k, value in enumerate(layout.values):
            part = mine[[pd.notna(v) and _key(v) == _key(value) for v in mine[series]]]
            if len(part):
                groups.append((s, name, k, value, part))
    dodge = min(0.6 / max(1, len(groups)), 0.15) if layout.categories is not None else 0.0
    for g, (s, name, k, value, rows) in enumerate(groups):
        style = dict(suspension_style(name))
        label = suspension_label(name)
        if k is not None and series is not None:
            style.update(color=_series_colour(layout, k))
            label = f"{label}, {_value_text(series, value)}"
        marker = _MARKERS[s % len(_MARKERS)] if series is not None else "o"
        # a run that diverged has no metrics (empty): it leaves a gap, not a point
        on = [(x_, float(y)) for x_, y in zip(rows[x], rows[column]) if pd.notna(x_) and pd.notna(y)]
        off = [float(y) for x_, y in zip(rows[x], rows[column]) if pd.isna(x_) and pd.notna(y)]
        if on and layout.categories is not None:
            shift = (g - (len(groups) - 1) / 2) * dodge
            at = [position[_key(v)] + shift for v, _ in on]
            style["linestyle"] = "None"  # categories: no line joins them
            ax.plot(at, [y for _, y in on], marker=marker, markersize=4.5, label=label, **style)
        elif on:
            xs, ys = zip(*sorted((float(v), y) for v, y in on))
            ax.plot(xs, ys, marker=marker, markersize=3.5, label=label, **style)
        elif off:
            ax.axhline(float(np.mean(off)), linewidth=1.0, alpha=0.8, label=f"{label} (not swept)", **style)


def _x_axis(a, layout: _Layout, log_x: bool, label: bool) -> None:
    """The x axis of a panel: categories at 0, 1, ... labelled by their value (at most about 12
    labels), or a line's axis, logarithmic with ``log_x``; its label where ``label``."""
    if layout.categories is not None:
        n = len(layout.categories)
        step = max(1, -(-n // 12))
        ticks = list(range(0, n, step))
        a.set_xticks(ticks, [_value_text(layout.x, layout.categories[i]).rsplit(" ", 1)[-1] for i in ticks])
        a.set_xlim(-0.6, n - 0.4)
        a.grid(False, axis="x")
    elif log_x:
        a.set_xscale("log")
    if label:
        a.set_xlabel(grid_axis_label(layout.x))


def _x_values(frame, layout: _Layout) -> list:
    return [float(v) for v in frame[layout.x] if pd.notna(v)] if layout.categories is None else []


def _panels(result, panels, ax, figsize, shape):
    """The rows (`SweepResult.to_pandas`), the suspensions, the figure and the Axes of the
    panels ``panels``."""
    frame = result.to_pandas()
    suspensions = list(dict.fromkeys(frame["suspension"]))
    if ax is None:
        fig = new_figure(figsize)
        axes = list(np.ravel(fig.subplots(*shape, sharex=True)))
    else:
        axes = given_axes(ax, len(panels), "one per panel: " + ", ".join(c for c, _ in panels))
        fig = axes[0].figure
    return frame, suspensions, fig, axes


def _title(fig, axes, text: str, context: str) -> None:
    """The legend below the panels and the title ``text`` with its wrapped ``context``."""
    handles, names = axes[0].get_legend_handles_labels()
    # as many columns as the longest entry lets fit across the page (8 pt text: about 0.055 in a
    # character, 0.55 in for the line sample and the gap)
    fit = int((fig.get_figwidth() - 0.2) / (0.55 + 0.055 * max((len(n) for n in names), default=1)))
    fig.legend(handles, names, loc="outside lower center", ncols=max(1, min(4, len(names), fit)), frameon=False)
    set_title(fig, text + (f"\n{context}" if context else ""))


def _against(layout: _Layout) -> str:
    """What a title says the panels are drawn against."""
    text = grid_axis_label(layout.x)
    if layout.series is not None:
        name = grid_axis_label(layout.series).split(" (")[0]
        text += f", one line per {name}"
    return text


@styled
def plot_sweep(result, ax=None, *, axis: str | None = None, series: str | None = None):
    """The RMS of the four carbody responses against the swept axis of a sweep (the
    `railride.studies.sweep.SweepResult` ``result``): four panels, one line per suspension in the paper's
    style. A suspension the axis does not act on (passive against --voltage, say) ran once: a
    thin horizontal line at its value. ``axis`` (the x axis) and ``series`` (one line per value
    of this second axis, coloured by value; the suspensions then told apart by line style and
    marker) default to `sweep_plot_axes`. A categorical axis (`is_categorical`: track or noise
    seeds) is drawn as markers at evenly spaced positions labelled by the value, no line joining
    them. ``ax``: four Axes to draw in (legend in the first, no title), or None for a new figure.
    Returns the `Figure`; InputError where the sweep has no figure (`sweep_figure_note`)."""
    layout = _layout(result, axis, series)
    frame, suspensions, fig, axes = _panels(result, RMS_PANELS, ax, (PAGE_WIDTH, 5.4), (2, 2))
    log_x = _log_axis(layout.x, _x_values(frame, layout))
    for k, (a, (column, ylabel)) in enumerate(zip(axes, RMS_PANELS)):
        _sweep_lines(a, frame, layout, column, suspensions)
        a.set_ylabel(ylabel)
        a.set_ylim(bottom=0)
        _x_axis(a, layout, log_x, label=k >= 2)
    if ax is not None:
        axes[0].legend(fontsize="small")
        return fig
    settings = result.settings
    context = describe_scenario(settings.get("scenario") or {})
    duration = (settings.get("scenario") or {}).get("duration_s")
    extra = [
        p
        for p in (
            f"{duration:g} s" if _is_number(duration) else "",
            describe_dampers(settings) if settings.get("damper") else "",
        )
        if p
    ]
    if extra:
        context = ", ".join([context, *extra]) if context else ", ".join(extra)
    _title(fig, axes, f"RMS of the carbody responses against {_against(layout)}", context)
    return fig


@styled
def plot_sweep_comfort(result, ax=None, *, axis: str | None = None, series: str | None = None):
    """The ride comfort of a sweep with comfort columns (`railride.studies.sweep.SweepResult` of
    `run_sweep` with comfort, ``railride sweep --comfort``) against
    its swept axis: N_MV,z and a_w (Wk) at the carbody centre, two panels, drawn as in
    `plot_sweep` (``axis``, ``series``); the N_MV,z panel marks the EN 12299 class bounds. ``ax``:
    two Axes to draw in (legend in the first, no title), or None for a new figure. Returns the
    `Figure`."""
    from railride.analysis.comfort import COMFORT_SCALE

    layout = _layout(result, axis, series)
    if not has_comfort(result):
        raise InputError("the sweep's rows hold no comfort indices (run_sweep with comfort, railride sweep --comfort)")
    frame, suspensions, fig, axes = _panels(result, COMFORT_PANELS, ax, (PAGE_WIDTH, 3.2), (1, 2))
    log_x = _log_axis(layout.x, _x_values(frame, layout))
    for a, (column, ylabel) in zip(axes, COMFORT_PANELS):
        _sweep_lines(a, frame, layout, column, suspensions)
        a.set_ylabel(ylabel, fontsize="small")
        a.set_ylim(bottom=0)
        _x_axis(a, layout, log_x, label=True)
    top = axes[0].get_ylim()[1]
    for bound, label in COMFORT_SCALE:
        if math.isfinite(bound) and bound < top:
            axes[0].axhline(bound, color="0.5", linewidth=0.6, linestyle=":")
            axes[0].annotate(
                f"{label} below",
                (0.99, bound),
                xycoords=("axes fraction", "data"),
                fontsize="x-small",
                color="0.4",
                va="top",
                ha="right",
            )
    if ax is not None:
        axes[0].legend(fontsize="small")
        return fig
    context = describe_scenario(result.grid.scenario_record())
    _title(fig, axes, f"Ride comfort against {_against(layout)}", context)
    return fig
