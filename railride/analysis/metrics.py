"""Ride metrics (docs/model.md, Metrics): RMS and peak-to-peak of the four carbody responses.

RMS is taken about zero, not about the mean, as in the paper's Table 1: every channel is a
perturbation from static equilibrium, so the mean belongs to the response.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import xarray as xr

from railride.errors import InputError

#: response name -> (channel, factor to the reported unit)
RESPONSES = {
    "acceleration_m_s2": ("carbody_acceleration", 1.0),
    "displacement_m": ("carbody_bounce", 1.0),
    "pitch_deg": ("carbody_pitch", 180.0 / math.pi),
    "roll_deg": ("carbody_roll", 180.0 / math.pi),
}
STATISTICS = ("rms", "ptp")
#: the attributes of the metrics and their coordinates (CF conventions; a label has the units "").
#: The responses differ in unit: each response's name ends in its own
METRICS_ATTRS = {
    "long_name": "carbody ride metrics: RMS about zero and peak-to-peak",
    "units": "per response, as its name ends: m/s^2, m, deg, deg",
}
COORD_ATTRS = {
    "response": {"long_name": "carbody response (the name ends in its unit)", "units": ""},
    "statistic": {"long_name": "statistic (rms: RMS about zero; ptp: peak-to-peak)", "units": ""},
    "sample": {"long_name": "sample of the batch", "units": ""},
}


def parse_window(text: str) -> tuple[float, float]:
    """ "START:END" in seconds; either side may be empty (start of run, end of run), and both
    must be finite."""
    parts = text.split(":")
    if len(parts) != 2:
        raise InputError(f"window = {text!r}: expected START:END in seconds, e.g. 2:10")
    try:
        start = float(parts[0]) if parts[0].strip() else 0.0
        end = float(parts[1]) if parts[1].strip() else math.inf
    except ValueError:
        raise InputError(f"window = {text!r}: START and END must be numbers of seconds") from None
    typed = [float(p) for p in parts if p.strip()]
    if not all(math.isfinite(v) for v in typed):
        # an empty END is the end of the run; a typed inf or nan is a slip, not a window
        raise InputError(
            f"window = {text!r}: START and END must be finite numbers of seconds "
            "(leave END empty for the end of the run)"
        )
    return start, end


def check_window(window, t_end: float, t_start: float = 0.0) -> tuple[float, float]:
    """Check ``window`` = (start, end) s against a run from t_start to t_end; an infinite end
    means the end of the run. Returns the window with the end resolved."""
    start, end = window
    if math.isinf(end) and end > 0:
        end = t_end
    if not (math.isfinite(start) and math.isfinite(end) and t_start <= start < end <= t_end + 1e-9):
        raise InputError(
            f"window = {start:g}:{end:g} s: must satisfy {t_start:g} <= START < END <= {t_end:g} (inside the run)"
        )
    return float(start), float(end)


def select_window(ds: xr.Dataset, window) -> xr.Dataset:
    """The part of a run inside ``window`` = (start, end) seconds, checked against the run."""
    if window is None:
        return ds
    start, end = check_window(window, float(ds.time[-1]), float(ds.time[0]))
    part = ds.sel(time=slice(start - 1e-12, end + 1e-12))
    if part.sizes["time"] < 2:
        raise InputError(f"window = {start:g}:{end:g} s holds fewer than two output samples")
    return part


def ride_metrics(ds: xr.Dataset, window=None, diverged=None) -> xr.DataArray:
    """RMS and peak-to-peak per response, dims (response, statistic) plus ``sample`` in a batch.

    Responses: carbody CG vertical acceleration (m/s^2), bounce displacement (m), pitch (deg)
    and roll (deg). ``window`` = (start, end) in seconds restricts the time range. ``diverged``:
    per sample, whether the run diverged (its metrics are NaN; see `metrics_from_arrays`).
    """
    part = select_window(ds, window)
    lead = ["sample"] if "sample" in part.dims else []
    acceleration, bounce, pitch, roll = (
        part[channel].transpose(*lead, "time").values for channel, _ in RESPONSES.values()
    )
    return metrics_from_arrays(
        acceleration, bounce, pitch, roll, sample=part["sample"].values if lead else None, diverged=diverged
    )


def metrics_from_arrays(acceleration, bounce, pitch, roll, sample=None, diverged=None) -> xr.DataArray:
    """`ride_metrics` of channels given as arrays (..., time) in SI units (pitch, roll in rad),
    already cut to the window: the one implementation behind both the Dataset path and the
    fast path of `RideResult.metrics` that skips building the Dataset.

    A metric that is not finite raises RuntimeError, except for the samples marked in
    ``diverged`` (bool per sample: runs that diverged, whose metrics are NaN by design)."""
    values = []
    for x, (_, factor) in zip((acceleration, bounce, pitch, roll), RESPONSES.values()):
        x = np.asarray(x) * factor
        # NumPy, not xarray reductions: several times faster, and NaN propagates
        values.append(np.stack([np.sqrt(np.mean(x**2, axis=-1)), np.ptp(x, axis=-1)], axis=-1))
    data = np.stack(values, axis=-2)  # (..., response, statistic)
    lead = [] if data.ndim == 2 else ["sample"]
    coords: dict[str, Any] = {
        "response": ("response", list(RESPONSES), COORD_ATTRS["response"]),
        "statistic": ("statistic", list(STATISTICS), COORD_ATTRS["statistic"]),
    }
    if lead:
        coords["sample"] = ("sample", np.arange(data.shape[0]) if sample is None else sample, COORD_ATTRS["sample"])
    out = xr.DataArray(
        data, dims=lead + ["response", "statistic"], coords=coords, name="ride_metrics", attrs=dict(METRICS_ATTRS)
    )
    finite = np.isfinite(data)
    if diverged is not None:
        mask = np.atleast_1d(np.asarray(diverged, dtype=bool))
        finite |= mask[:, None, None] if data.ndim == 3 else bool(mask.any())
    if not np.all(finite):
        raise RuntimeError("a ride metric is not finite: the run did not produce finite responses")
    return out


def reduction(metrics: xr.DataArray, baseline: xr.DataArray) -> xr.DataArray:
    """Reduction in % against a baseline run: (baseline - metrics) / baseline * 100."""
    if np.any(baseline.values == 0):
        raise InputError("a baseline metric is zero: the reduction in % is undefined")
    out = (baseline - metrics) / baseline * 100.0
    out.name = "reduction_percent"
    out.attrs = {"long_name": "reduction against the baseline, (baseline - value) / baseline", "units": "%"}
    return out


def still_passive(scenario: dict) -> str:
    """Why ratios or reductions against passive are undefined: its carbody did not move (a flat
    or vanishing rail, a vehicle all but standing still), naming the scenario's settings
    (``Scenario.describe()``)."""
    given = [
        f"{name} = {scenario[key]:g} {unit}"
        for name, key, unit in (
            ("amplitude", "amplitude_m", "m"),
            ("height", "height_m", "m"),
            ("speed", "speed_m_s", "m/s"),
        )
        if key in scenario
    ]
    return (
        f"the passive run's carbody did not move ({', '.join(given) or scenario.get('name', 'this scenario')}): "
        "an RMS response of 0, against which no ratio or reduction is defined; give a rail input and a speed "
        "that move the vehicle"
    )


def to_dict(metrics: xr.DataArray) -> dict:
    """{response: {rms, ptp}} for one run (the JSON schema of docs/cli.md)."""
    if "sample" in metrics.dims:
        raise InputError("to_dict takes the metrics of one run; select a sample first")
    return {r: {s: float(metrics.sel(response=r, statistic=s)) for s in STATISTICS} for r in metrics.response.values}
