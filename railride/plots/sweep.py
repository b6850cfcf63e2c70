"""A sweep (a `railride.studies.sweep.SweepResult`): the RMS of the carbody responses and the ride
comfort against its one swept numeric axis."""

from __future__ import annotations

import math

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


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def sweep_plot_axis(result) -> str | None:
    """The grid column `plot_sweep` draws against: the one axis of the sweep ``result``
    (`SweepGrid.grid_values`) besides ``suspension`` with more than one value, if there is
    exactly one and its values are numbers; else None."""
    grid = result.grid.grid_values()
    several = [c for c, values in grid.items() if c != "suspension" and len(values) > 1]
    if len(several) != 1 or not all(_is_number(v) for v in grid[several[0]]):
        return None
    return several[0]


def has_comfort(result) -> bool:
    """Whether the sweep ``result`` has runs and their rows hold the comfort indices (`run_sweep`
    with comfort, `railride sweep --comfort`)."""
    return len(result.grid.cases) > 0 and all(c in result.metric_columns() for c, _ in COMFORT_PANELS)


def _log_axis(axis: str, xs: list) -> bool:
    """A logarithmic x axis for values spanning 100:1, or 4:1 for a factor (damper_scale, whose
    grids are geometric)."""
    ratio = 4 if axis == "damper_scale" else 100
    return bool(xs) and min(xs) > 0 and max(xs) / min(xs) >= ratio


def _sweep_lines(ax, frame, axis, column, suspensions):
    """One line per suspension of ``column`` against ``axis`` (a horizontal line for a
    suspension the axis does not act on), from the rows ``frame`` (`SweepResult.to_pandas`)."""
    for name in suspensions:
        mine = frame[frame["suspension"] == name]
        style = suspension_style(name)
        label = suspension_label(name)
        # a run that diverged has no metrics (empty): it leaves a gap, not a point
        on = sorted((float(x), float(y)) for x, y in zip(mine[axis], mine[column]) if pd.notna(x) and pd.notna(y))
        off = [float(y) for x, y in zip(mine[axis], mine[column]) if pd.isna(x) and pd.notna(y)]
        if on:
            x, y = zip(*on)
            ax.plot(x, y, marker="o", markersize=3.5, label=label, **style)
        elif off:
            ax.axhline(float(np.mean(off)), linewidth=1.0, alpha=0.8, label=f"{label} (not swept)", **style)


def _swept_axis(result, axis: str | None) -> str:
    axis = axis or sweep_plot_axis(result)
    if axis is None:
        raise InputError("the sweep has no single numeric axis with several values to plot against")
    return axis


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
    fig.legend(handles, names, loc="outside lower center", ncols=min(4, max(1, len(names))), frameon=False)
    set_title(fig, text + (f"\n{context}" if context else ""))


@styled
def plot_sweep(result, ax=None, *, axis: str | None = None):
    """The RMS of the four carbody responses against the swept axis of a sweep (the
    `railride.studies.sweep.SweepResult` ``result``): four panels, one line per suspension in the paper's
    style. A suspension the axis does not act on (passive against --voltage, say) ran once: a
    thin horizontal line at its value. ``axis`` defaults to `sweep_plot_axis`. ``ax``: four
    Axes to draw in (legend in the first, no title), or None for a new figure. Returns the
    `Figure`."""
    axis = _swept_axis(result, axis)
    frame, suspensions, fig, axes = _panels(result, RMS_PANELS, ax, (PAGE_WIDTH, 5.4), (2, 2))
    xs = [float(x) for x in frame[axis] if pd.notna(x)]
    log_x = _log_axis(axis, xs)
    for a, (column, ylabel) in zip(axes, RMS_PANELS):
        _sweep_lines(a, frame, axis, column, suspensions)
        a.set_ylabel(ylabel)
        a.set_ylim(bottom=0)
        if log_x:
            a.set_xscale("log")
    for a in axes[2:]:
        a.set_xlabel(grid_axis_label(axis))
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
    _title(fig, axes, f"RMS of the carbody responses against {grid_axis_label(axis)}", context)
    return fig


@styled
def plot_sweep_comfort(result, ax=None, *, axis: str | None = None):
    """The ride comfort of a sweep with comfort columns (`railride.studies.sweep.SweepResult` of
    `run_sweep` with comfort, ``railride sweep --comfort``) against
    its swept axis: N_MV,z and a_w (Wk) at the carbody centre, two panels, one line per
    suspension as in `plot_sweep`; the N_MV,z panel marks the EN 12299 class bounds. ``ax``:
    two Axes to draw in (legend in the first, no title), or None for a new figure. Returns the
    `Figure`."""
    from railride.analysis.comfort import COMFORT_SCALE

    axis = _swept_axis(result, axis)
    if not has_comfort(result):
        raise InputError("the sweep's rows hold no comfort indices (run_sweep with comfort, railride sweep --comfort)")
    frame, suspensions, fig, axes = _panels(result, COMFORT_PANELS, ax, (PAGE_WIDTH, 3.2), (1, 2))
    xs = [float(x) for x in frame[axis] if pd.notna(x)]
    log_x = _log_axis(axis, xs)
    for a, (column, ylabel) in zip(axes, COMFORT_PANELS):
        _sweep_lines(a, frame, axis, column, suspensions)
        a.set_ylabel(ylabel, fontsize="small")
        a.set_ylim(bottom=0)
        a.set_xlabel(grid_axis_label(axis))
        if log_x:
            a.set_xscale("log")
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
    _title(fig, axes, f"Ride comfort against {grid_axis_label(axis)}", context)
    return fig
