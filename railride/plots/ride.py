"""The carbody responses of a ride result (`railride.ride.RideResult`)."""

from __future__ import annotations

import xarray as xr

from ..labels import CARBODY_RESPONSES, describe_scenario, describe_suspension, json_records
from ._style import given_axes, new_figure, save_png


def ride_title(ds: xr.Dataset) -> str:
    """ "carbody responses - <scenario>" with the dampers on a second line, for a result Dataset
    (a batch of several scenarios names them and counts its samples)."""
    records = json_records(ds, "scenario")
    suspension = describe_suspension(ds)
    if not records:
        return f"carbody responses - {suspension}" if suspension else "carbody responses"
    texts = [describe_scenario(r) for r in records]
    if len(set(texts)) == 1:
        title = texts[0]
    else:
        names = sorted({r.get("name", "?") for r in records})
        title = "scenarios " + ", ".join(names)
    if "sample" in ds.dims:
        title = f"{title} ({ds.sizes['sample']} samples)"
    if suspension:
        return f"carbody responses - {title}\n{suspension}" if title else f"carbody responses - {suspension}"
    return f"carbody responses - {title}" if title else "carbody responses"


def plot_body_responses(ds: xr.Dataset, path=None, *, ax=None):
    """Plot carbody CG vertical acceleration (m/s^2), bounce displacement (m), pitch (deg) and
    roll (deg) of a result Dataset (`RideResult.dataset`) against time in four stacked panels
    sharing the time axis.

    A batch gets one line per sample. The title describes the scenario when the dataset records
    one. ``ax``: four Axes to draw in (no title then: the caller owns the figure), or None for
    a new figure. If ``path`` is given the figure is saved there as PNG, atomically. Returns the
    `matplotlib.figure.Figure`.
    """
    missing = [channel for channel, _, _, _ in CARBODY_RESPONSES.values() if channel not in ds.variables]
    if missing:
        raise ValueError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    if ax is None:
        fig = new_figure((9.0, 9.0))
        axes = fig.subplots(len(CARBODY_RESPONSES), 1, sharex=True)
    else:
        axes = given_axes(ax, len(CARBODY_RESPONSES), "one per response: " + ", ".join(CARBODY_RESPONSES))
        fig = axes[0].figure
    time = ds["time"].values
    samples = list(ds["sample"].values) if "sample" in ds.dims else [None]
    names = [r.get("name") for r in json_records(ds, "scenario")]
    legend = {
        s: f"sample {s}" + (f": {names[i]}" if len(names) == len(samples) and names[i] else "")
        for i, s in enumerate(samples)
    }
    for a, (channel, factor, label, _) in zip(axes, CARBODY_RESPONSES.values()):
        da = ds[channel]
        for s in samples:
            y = (da.sel(sample=s) if s is not None and "sample" in da.dims else da).values * factor
            a.plot(time, y, linewidth=0.9, label=None if s is None else legend[s])
        a.set_ylabel(label)
        a.grid(True, linewidth=0.4, alpha=0.6)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(time[0], time[-1])
    if 1 < len(samples) <= 12:
        axes[0].legend(loc="upper right", fontsize="small", ncols=min(4, len(samples)))
    if ax is None:
        fig.suptitle(ride_title(ds), fontsize="medium")
    save_png(fig, path)
    return fig
