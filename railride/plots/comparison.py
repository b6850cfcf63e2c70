"""A controller comparison (`railride.studies.comparison.Comparison`): the carbody responses, the
damper forces and the command voltages against time, one line or row per suspension in the
paper's style (its Figs. 8-11), and the acceleration spectra of `railride.analysis.spectra.comparison_psd`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride.analysis.labels import CARBODY_RESPONSES, comparison_title, controller_names, coordinate_label
from railride.plots._style import (
    PAGE_WIDTH,
    frame_window,
    given_axes,
    grid_shape,
    new_figure,
    set_title,
    styled,
    suspension_label,
    suspension_style,
    window_note,
)


def _combined(comparison):
    """The combined Dataset of a `Comparison` (dims controller, time, ...)."""
    if not callable(getattr(comparison, "combined", None)):  # read by what it has: plots import no result
        raise InputError(
            f"comparison: expected a railride.studies.comparison.Comparison, got {type(comparison).__name__}"
        )
    return comparison.combined()


@styled
def plot_comparison_response(comparison, response: str, ax=None):
    """One carbody response of a `railride.studies.comparison.Comparison` against time, one line per
    suspension in the paper's style (Figs. 8-11: passive dash-dot, PID dotted, SAS (attitude)
    dashed, SAS (attitude+ride) solid).

    ``response`` is ``acceleration`` (m/s^2), ``displacement`` (bounce, m), ``pitch`` or
    ``roll`` (both in degrees). The whole run is drawn; when the comparison's metric window
    leaves part of it out, that part is shaded and the y-axis fits the values inside the window
    (a start-up transient runs off the axes). Drawn into ``ax`` when given (no title then: the
    caller owns the figure), else into a new figure; returns the `Figure`.
    """
    if response not in CARBODY_RESPONSES:
        raise InputError(f"response = {response!r}: allowed {', '.join(CARBODY_RESPONSES)}")
    ds = _combined(comparison)
    channel, factor, ylabel, what = CARBODY_RESPONSES[response]
    if channel not in ds.variables:
        raise InputError(f"the dataset lacks the channel {channel}")
    own = ax is None
    fig = new_figure((PAGE_WIDTH, 3.4)) if own else ax.figure
    if own:
        ax = fig.subplots()
    time = ds["time"].values
    ys = []
    for i, name in enumerate(controller_names(ds)):
        y = ds[channel].isel(controller=i).values * factor
        ax.plot(time, y, label=suspension_label(name), **suspension_style(name))
        ys.append(y)
    clipped = frame_window([ax], time, ys, comparison.window)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.set_xlim(time[0], time[-1])
    # above the axes, not over the lines
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncols=min(4, ds.sizes["controller"]), frameon=False)
    if own:
        title = comparison_title(ds)
        note = window_note(comparison.window) if clipped else ""
        set_title(fig, "\n".join(t for t in (what, title, note) if t))
    return fig


def _corner_grid(ds, rows: list[str], ax):
    """The (rows x corners) Axes: ``ax`` reshaped, or a new figure's grid sharing both axes."""
    corners = [coordinate_label(c) for c in ds["corner"].values]
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 1.0 + 1.3 * len(rows)))
        axes = np.atleast_2d(fig.subplots(len(rows), len(corners), sharex=True, sharey=True, squeeze=False))
    else:
        flat = given_axes(
            ax, len(rows) * len(corners), f"{len(rows)} suspension(s) x {len(corners)} corners, row by row"
        )
        axes = np.array(flat, dtype=object).reshape(len(rows), len(corners))
        fig = flat[0].figure
    for j, corner in enumerate(corners):
        axes[0, j].set_title(f"corner {corner}")
        axes[-1, j].set_xlabel("time (s)")
    return fig, axes, corners


@styled
def plot_comparison_damper_forces(comparison, ax=None):
    """The secondary damper force on the carbody (kN, up +) at each corner of a
    `railride.studies.comparison.Comparison` against time: one row per suspension (passive: the viscous
    dampers), one column per corner (1R, 1L, 2R, 2L), all panels on the same scale, solid lines
    in each suspension's colour; the common y-axis fits the forces inside the metric window,
    the part of the run outside it shaded. ``ax``: the suspensions x 4 corners Axes, row by row
    (no title then), or None for a new figure. Returns the `Figure`."""
    ds = _combined(comparison)
    if "secondary_damper_force" not in ds.variables:
        raise InputError("the dataset lacks the channel secondary_damper_force")
    names = controller_names(ds)
    fig, axes, corners = _corner_grid(ds, names, ax)
    time = ds["time"].values
    force = ds["secondary_damper_force"].transpose("controller", "time", "corner").values / 1e3
    for i, name in enumerate(names):
        for j in range(len(corners)):
            a = axes[i, j]
            a.plot(time, force[i, :, j], linewidth=0.7, color=suspension_style(name).get("color"))
            a.axhline(0.0, color="0.6", linewidth=0.5)
        axes[i, 0].set_ylabel(f"{suspension_label(name)}\nforce (kN)")
    axes[0, 0].set_xlim(time[0], time[-1])
    clipped = frame_window(
        list(axes.ravel()),
        time,
        [force[i, :, j] for i in range(len(names)) for j in range(len(corners))],
        comparison.window,
    )
    if ax is None:
        title = comparison_title(ds)
        note = window_note(comparison.window) if clipped else ""
        set_title(fig, "\n".join(t for t in ("secondary damper force on the carbody (kN, up +)", title, note) if t))
    return fig


@styled
def plot_comparison_voltages(comparison, ax=None):
    """The command voltage v (V) of each MR damper of a `railride.studies.comparison.Comparison`
    against time: one row per controlled suspension, one column per corner. A comparison
    without a controlled suspension (or with ideal devices) gets one panel saying so. ``ax``:
    those Axes, row by row (no title then), or None for a new figure. Returns the `Figure`."""
    ds = _combined(comparison)
    names = [n for n in controller_names(ds) if n != "passive"]
    if not names or "damper_command_voltage" not in ds.variables:
        if ax is None:
            fig = new_figure((PAGE_WIDTH, 2.0))
            a = fig.subplots()
        else:
            a = given_axes(ax, 1, "no command voltages to draw: one panel saying so")[0]
            fig = a.figure
        why = "passive suspension only" if not names else "ideal actuators"
        a.text(0.5, 0.5, f"{why}: no command voltages", ha="center", va="center", transform=a.transAxes)
        a.set_axis_off()
        if ax is None:
            title = comparison_title(ds)
            set_title(fig, "MR damper command voltage" + (f"\n{title}" if title else ""))
        return fig
    fig, axes, corners = _corner_grid(ds, names, ax)
    time = ds["time"].values
    volts = ds["damper_command_voltage"].transpose("controller", "time", "corner")
    all_names = controller_names(ds)
    top = np.nanmax(volts.values) if np.isfinite(volts.values).any() else 1.0
    for i, name in enumerate(names):
        v = volts.isel(controller=all_names.index(name)).values
        for j in range(len(corners)):
            a = axes[i, j]
            a.plot(time, v[:, j], linewidth=0.6, color=suspension_style(name).get("color"))
        axes[i, 0].set_ylabel(f"{suspension_label(name)}\nvoltage (V)")
    # shaded outside the window; the y-axis keeps the damper's range, which no voltage leaves
    clipped = frame_window(list(axes.ravel()), time, [], comparison.window)
    axes[0, 0].set_xlim(time[0], time[-1])
    axes[0, 0].set_ylim(-0.05 * max(top, 1e-9), 1.08 * max(top, 1e-9))
    if ax is None:
        title = comparison_title(ds)
        note = window_note(comparison.window).split(";")[0] if clipped else ""
        set_title(fig, "\n".join(t for t in ("MR damper command voltage v (V)", title, note) if t))
    return fig


@styled
def plot_comparison_psd(psd: pd.DataFrame, ax=None, *, title: str | None = None):
    """The acceleration spectra of `railride.analysis.spectra.comparison_psd` (its DataFrame) on log-log
    axes, one line per suspension in the paper's style; the 0 Hz bin is left out. Drawn into
    ``ax`` when given (no title then), else into a new figure titled ``title`` (default: what
    was plotted and how the spectra were taken, with their bin width, from the DataFrame's
    ``attrs``, `railride.analysis.psd_plan.psd_plan`); returns the `Figure`."""
    own = ax is None
    fig = new_figure((PAGE_WIDTH, 3.8)) if own else ax.figure
    if own:
        ax = fig.subplots()
    f = psd["frequency_hz"].values
    keep = f > 0
    top = 0.0
    for name in [c for c in psd.columns if c != "frequency_hz"]:
        y = psd[name].values[keep]
        y = np.where(y > 0, y, np.nan)  # a log axis cannot show 0
        if np.isfinite(y).any():
            top = max(top, float(np.nanmax(y)))
        ax.loglog(f[keep], y, label=suspension_label(name), **suspension_style(name))
    if top > 0:  # twelve decades below the highest peak: a pure sine's numerical floor is not news
        ax.set_ylim(bottom=max(ax.get_ylim()[0], top * 1e-12))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD of acceleration ((m/s$^2$)$^2$/Hz)")
    if keep.any():
        ax.set_xlim(f[keep][0], f[keep][-1])
    ax.grid(True, which="minor", linewidth=0.3, alpha=0.4)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncols=min(4, max(1, len(psd.columns) - 1)), frameon=False)
    if own:
        method = psd.attrs.get("text")
        default = "PSD of the carbody CG vertical acceleration" + (f"\n{method}" if method else "")
        set_title(fig, title or default)
    return fig


@styled
def plot_comparison_hysteresis(comparison, ax=None, *, corner: str = "1R"):
    """What each law asks of the device: the secondary damper force on the carbody (kN, up +)
    against the deflection rate across it (m/s) at one ``corner`` of a `Comparison`, over its
    metric window (the whole run without one), one panel per suspension on common axes. A
    passive viscous damper lies on a line through the origin with negative slope; a force in
    the first or third quadrant (f x' > 0) is one no damper can give. ``ax``: one Axes per
    suspension, or None (a grid at most four panels wide). Returns the figure."""
    ds = _combined(comparison)
    window = comparison.window
    if window is not None:
        ds = ds.sel(time=slice(window[0], window[1]))
    if corner not in [str(c) for c in ds["corner"].values]:
        raise InputError(f"corner = {corner!r}: allowed {', '.join(str(c) for c in ds['corner'].values)}")
    names = controller_names(ds)
    if ax is None:
        rows, columns = grid_shape(len(names))
        fig = new_figure((PAGE_WIDTH, 0.6 + 1.9 * rows))
        axes = fig.subplots(rows, columns, sharex=True, sharey=True, squeeze=False).ravel()
        for a in axes[len(names) :]:
            a.set_visible(False)
    else:
        axes = given_axes(ax, len(names), "one per suspension")
        fig = axes[0].figure
        columns = len(names)
    for a, name in zip(axes, names):
        part = ds.sel(controller=name, corner=corner)
        a.plot(
            part["secondary_deflection_velocity"].values,
            part["secondary_damper_force"].values / 1e3,
            linewidth=0.5,
            color=suspension_style(name).get("color"),
        )
        a.axhline(0.0, color="0.6", linewidth=0.5)
        a.axvline(0.0, color="0.6", linewidth=0.5)
        a.set_title(suspension_label(name))
    for k, a in enumerate(axes[: len(names)]):
        if k + columns >= len(names):  # the lowest panel of each column
            a.set_xlabel("deflection rate (m/s)")
        if k % columns == 0:
            a.set_ylabel(f"force at {corner} (kN)")
    if ax is None:
        set_title(fig, "damper force against deflection rate: what each law asks of the damper")
    return fig
