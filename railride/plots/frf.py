"""The carbody frequency responses of `railride.vehicle.Vehicle.frequency_response`, as
tabulated by `railride.analysis.frf_frame`, with the modes of `Vehicle.modes()` marked."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..analysis import FRF_PATTERNS, FRF_RESPONSES, frf_excited
from ._style import given_axes, new_figure

#: line style per rail pattern
FRF_STYLES = {
    "in-phase": {"color": "tab:blue", "linestyle": "-"},
    "anti-phase": {"color": "tab:red", "linestyle": "--"},
}


def _mode_numbers(numbers) -> str:
    """[4, 5, 6, 7] -> "4-7", [8, 9] -> "8,9", [1] -> "1"."""
    numbers = sorted(numbers)
    if len(numbers) > 2 and numbers == list(range(numbers[0], numbers[-1] + 1)):
        return f"{numbers[0]}-{numbers[-1]}"
    return ",".join(str(n) for n in numbers)


def _mode_groups(modes: pd.DataFrame | None, lo: float, hi: float):
    """The modes inside [lo, hi] as (frequency, [mode numbers]) lines, modes within 1 % of each
    other sharing a line; and the labels of those lines, one per cluster of lines closer than
    10 % (they would overlap on the log axis), at the clusters' geometric centres."""
    groups: list[tuple[float, list[int]]] = []
    if modes is not None:
        for _, m in modes.sort_values("frequency_hz").iterrows():
            f = float(m["frequency_hz"])
            if not lo <= f <= hi:
                continue
            if groups and f <= groups[-1][0] * 1.01:
                groups[-1][1].append(int(m["mode"]))
            else:
                groups.append((f, [int(m["mode"])]))
    labels_at: list[tuple] = []  # (first frequency, [mode numbers], last frequency)
    for f, numbers in groups:
        if labels_at and f <= labels_at[-1][2] * 1.10:
            labels_at[-1] = (labels_at[-1][0], labels_at[-1][1] + numbers, f)
        else:
            labels_at.append((f, list(numbers), f))
    return groups, [(math.sqrt(first * last), numbers) for first, numbers, last in labels_at]


def _legend_entries(axes, modes, groups) -> tuple[list, list]:
    """The legend's handles and labels: the rail patterns, then the modes drawn, as text
    entries."""
    from matplotlib.lines import Line2D

    handles, labels = [], []
    for a in axes:
        for h, lab in zip(*a.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    labels = [f"{lab} rails" if lab in FRF_PATTERNS else lab for lab in labels]
    if groups:
        handles.append(Line2D([], [], color="0.45", linestyle=":", linewidth=0.9))
        labels.append("undamped natural frequencies:")
        shown = {n for _, numbers in groups for n in numbers}
        for _, m in modes.iterrows():
            if int(m["mode"]) in shown:
                handles.append(Line2D([], [], linestyle="none"))
                labels.append(f"{int(m['mode'])}: {m['label']}, {float(m['frequency_hz']):.3g} Hz")
    return handles, labels


def plot_frf(frame: pd.DataFrame, modes: pd.DataFrame | None = None, ax=None, *, title: str | None = None):
    """Magnitudes of the carbody frequency responses (`railride.analysis.frf_frame`) against
    frequency on log-log axes: one panel per response (bounce m/m, pitch and roll deg/m,
    acceleration (m/s^2)/m), one line per rail pattern. ``modes`` (`railride.tables.modes_frame`)
    are marked as dotted vertical lines at their undamped natural frequencies, numbered at the
    top of each panel (modes within 1 % of each other share a line) and listed below the plot.
    A response a pattern does not excite is not drawn; the panel says so. ``ax``: four Axes to
    draw in (the legend goes into the first, no title), or None for a new figure titled ``title``.
    Returns the `Figure`."""
    if ax is None:
        fig = new_figure((11.0, 8.2))
        axes = list(fig.subplots(2, 2, sharex=True).ravel())
    else:
        axes = given_axes(ax, len(FRF_RESPONSES), "one per response: bounce, pitch, roll, acceleration")
        fig = axes[0].figure
    patterns = list(dict.fromkeys(frame["pattern"]))
    f_all = frame["frequency_hz"].values
    lo, hi = float(f_all.min()), float(f_all.max())
    groups, labels_at = _mode_groups(modes, lo, hi)
    for a, (name, _, _, ylabel, column) in zip(axes, FRF_RESPONSES):
        top = float(frame[column].max())
        silent = []
        for pattern in patterns:
            part = frame[frame["pattern"] == pattern]
            y = part[column].values
            if not frf_excited(y, top):
                silent.append(pattern)
                continue
            a.loglog(
                part["frequency_hz"].values,
                np.where(y > 0, y, np.nan),
                linewidth=1.3,
                label=pattern,
                **FRF_STYLES.get(pattern, {}),
            )
        a.set_xscale("log")
        a.set_xlim(lo, hi)
        everywhere = all(p in silent for p in patterns)
        if everywhere:
            a.set_yscale("linear")
        for f, _ in groups:
            a.axvline(f, color="0.45", linestyle=":", linewidth=0.9, zorder=0)
        for f, numbers in labels_at:
            a.annotate(
                _mode_numbers(numbers),
                (f, 1.0),
                xycoords=("data", "axes fraction"),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                va="bottom",
                fontsize="x-small",
                color="0.3",
            )
        if silent:
            a.text(
                0.5 if everywhere else 0.02,
                0.5 if everywhere else 0.03,
                f"not excited by {' or '.join(silent)} rails",
                transform=a.transAxes,
                fontsize="medium" if everywhere else "small",
                color="0.35",
                ha="center" if everywhere else "left",
            )
            if everywhere:
                a.set_yticks([])
        a.set_ylabel(ylabel)
        a.set_title(f"carbody {name}", fontsize="medium", pad=12)
        a.grid(True, which="major", linewidth=0.5, alpha=0.7)
        a.grid(True, which="minor", linewidth=0.3, alpha=0.35)
    for a in axes[2:]:
        a.set_xlabel("frequency (Hz)")
    handles, labels = _legend_entries(axes, modes, groups)
    if ax is not None:
        if handles:
            axes[0].legend(handles, labels, fontsize="x-small")
        return fig
    fig.legend(
        handles,
        labels,
        loc="outside lower center",
        ncols=min(4, len(labels)),
        fontsize="small",
        frameon=False,
        handlelength=2.2,
    )
    fig.suptitle(title or "Carbody frequency responses per metre of rail amplitude", fontsize="medium")
    return fig
