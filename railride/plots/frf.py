"""The carbody frequency responses of `railride.model.vehicle.Vehicle.frequency_response`, as
tabulated by `railride.analysis.spectra.frf_frame`: magnitude and phase, with the modes of
`Vehicle.modes()` marked."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from railride.analysis.spectra import FRF_PATTERNS, FRF_RESPONSES, frf_excited
from railride.plots._style import PAGE_WIDTH, given_axes, new_figure, set_title, styled

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


def _phase_line(frequency, phase):
    """The phase [deg] with a gap where it wraps from -180 to 180 (no vertical line there)."""
    f = np.asarray(frequency, dtype=float)
    y = np.asarray(phase, dtype=float)
    wraps = np.flatnonzero(np.abs(np.diff(y)) > 180.0) + 1
    return np.insert(f, wraps, np.nan), np.insert(y, wraps, np.nan)


def _mark_modes(a, groups, labels_at) -> None:
    """Dotted lines at the modes' frequencies; their numbers above the panel when given."""
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


@styled
def plot_frf(frame: pd.DataFrame, modes: pd.DataFrame | None = None, ax=None, *, title: str | None = None):
    """The carbody frequency responses (`railride.analysis.spectra.frf_frame`) against frequency, per
    response (bounce m/m, pitch and roll deg/m, acceleration (m/s^2)/m) a magnitude panel on
    log-log axes and below it a phase panel [deg, against the left rail at the leading
    wheelset, -180 to 180; a line breaks where the phase wraps], one line per rail pattern.
    ``modes`` (`railride.model.modes.modes_frame`) are marked as dotted vertical lines at their
    undamped natural frequencies, numbered at the top of each magnitude panel (modes within 1 %
    of each other share a line) and listed below the plot. A response a pattern does not excite
    is not drawn; the panel says so. ``ax``: eight Axes to draw in, per response its magnitude
    then its phase (the legend goes into the first, no title), or None for a new figure titled
    ``title``. Returns the `Figure`."""
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 8.4))
        grid = fig.subplots(4, 2, sharex=True, height_ratios=(2.0, 1.0, 2.0, 1.0))
        # per response (bounce, pitch top; roll, acceleration below): magnitude, then phase
        axes = [grid[r + k, c] for r in (0, 2) for c in (0, 1) for k in (0, 1)]
    else:
        axes = given_axes(
            ax,
            2 * len(FRF_RESPONSES),
            "per response (bounce, pitch, roll, acceleration) its magnitude, then its phase",
        )
        fig = axes[0].figure
    patterns = list(dict.fromkeys(frame["pattern"]))
    f_all = frame["frequency_hz"].values
    lo, hi = float(f_all.min()), float(f_all.max())
    groups, labels_at = _mode_groups(modes, lo, hi)
    for k, (name, _, _, ylabel, column) in enumerate(FRF_RESPONSES):
        a, b = axes[2 * k], axes[2 * k + 1]
        top = float(frame[column].max())
        silent = []
        for pattern in patterns:
            part = frame[frame["pattern"] == pattern]
            y = part[column].values
            if not frf_excited(y, top):
                silent.append(pattern)
                continue
            style = FRF_STYLES.get(pattern, {})
            f = part["frequency_hz"].values
            a.loglog(f, np.where(y > 0, y, np.nan), linewidth=1.2, label=pattern, **style)
            b.plot(*_phase_line(f, part[f"{name}_phase_deg"].values), linewidth=1.0, **style)
        everywhere = all(p in silent for p in patterns)
        for p in (a, b):
            p.set_xscale("log")
            p.set_xlim(lo, hi)
            p.grid(True, which="minor", linewidth=0.3, alpha=0.35)
            _mark_modes(p, groups, labels_at if p is a else [])
        if everywhere:
            a.set_yscale("linear")
        b.set_ylim(-195.0, 195.0)
        b.set_yticks([-180, -90, 0, 90, 180])
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
                b.set_yticks([])
        a.set_ylabel(ylabel)
        b.set_ylabel("phase (deg)")
        a.set_title(f"carbody {name}", pad=12)
    for b in axes[5::2] if ax is None else axes[1::2]:
        b.set_xlabel("frequency (Hz)")
    handles, labels = _legend_entries(axes, modes, groups)
    if ax is not None:
        if handles:
            axes[0].legend(handles, labels, fontsize="x-small")
        return fig
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize="small", handlelength=2.2, frameon=False)
    set_title(fig, title or "Carbody frequency responses per metre of rail amplitude")
    return fig
