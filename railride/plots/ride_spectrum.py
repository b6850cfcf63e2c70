"""The frequency-domain ride of `railride.frequency.ride_spectrum.RideSpectrum`: acceleration PSDs at the
carbody floor points, one line per suspension, with their RMS and Wb-weighted RMS in the
legend."""

from __future__ import annotations

from railride.plots._style import (
    PAGE_WIDTH,
    given_axes,
    new_figure,
    set_title,
    styled,
    suspension_label,
    suspension_style,
)


@styled
def plot_ride_spectrum(result, path=None, *, ax=None):
    """One log-log panel per floor point (centre, front, rear) of the acceleration PSD
    ((m/s^2)^2/Hz) against frequency (Hz); the legend gives each suspension's RMS and
    Wb-weighted RMS there. ``ax``: three Axes, or None for a new figure. Returns the figure."""
    from railride.analysis.comfort import FLOOR

    if ax is None:
        fig = new_figure((PAGE_WIDTH, 3.4))
        axes = list(fig.subplots(1, len(FLOOR), sharey=True))
        set_title(fig, result.title())
    else:
        axes = given_axes(ax, len(FLOOR), "the floor points " + ", ".join(FLOOR))
        fig = axes[0].figure
    f = result.psd["frequency"].values
    top = max(float(result.psd[f"floor_acceleration_{p}"].max()) for p in FLOOR)
    for a, point in zip(axes, FLOOR):
        name = f"floor_acceleration_{point}"
        for s in result.suspensions:
            rms = float(result.rms.sel(suspension=s, response=name))
            wb = float(result.weighted.sel(suspension=s, position=point, weighting="Wb"))
            label = f"{suspension_label(s)}: {rms:.3g}, {wb:.3g} m/s²"
            a.loglog(f, result.psd[name].sel(suspension=s).values, label=label, **suspension_style(s))
        a.set_title(f"floor, {point}")
        a.set_xlabel("frequency (Hz)")
        # the wheelbase filter's notches reach zero: six decades below the peak show the ride
        a.set_ylim(top * 1e-6, top * 3)
        # below the panel: the PSDs fill the axes
        a.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), fontsize="x-small", title="RMS, Wb-weighted RMS")
    axes[0].set_ylabel("PSD ((m/s²)²/Hz)")
    return fig
