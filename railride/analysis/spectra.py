"""Analysis of railride's results beyond the RMS metrics: pure functions from Datasets and
DataFrames to data, drawn by `railride.plots` and written by `railride.output.files`.

* `comparison_psd`: the spectra of the carbody acceleration of a controller comparison: on a
  periodic track (the paper's sine) one Hann-windowed segment of whole periods of the input, on
  any other track Welch's method (`psd_plan`).
* `frf_frame` and `frf_peaks`: the carbody frequency responses of
  `railride.model.vehicle.Vehicle.frequency_response` as magnitudes and phases, and their peaks.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from railride.errors import InputError
from railride.analysis.labels import controller_names
from railride.analysis.psd_plan import PSD_SEGMENT_S, psd_plan

#: the rail patterns of `frf_frame`, in order
FRF_PATTERNS = ("in-phase", "anti-phase")
#: per carbody response: (name, channel of the frequency response, magnitude columns with their
#: factor from the channel's unit, axis label of the plot (its unit), magnitude column plotted)
FRF_RESPONSES = (
    ("bounce", "carbody_bounce", (("bounce_m_per_m", 1.0),), "bounce (m/m)", "bounce_m_per_m"),
    (
        "pitch",
        "carbody_pitch",
        (("pitch_rad_per_m", 1.0), ("pitch_deg_per_m", 180.0 / math.pi)),
        "pitch (deg/m)",
        "pitch_deg_per_m",
    ),
    (
        "roll",
        "carbody_roll",
        (("roll_rad_per_m", 1.0), ("roll_deg_per_m", 180.0 / math.pi)),
        "roll (deg/m)",
        "roll_deg_per_m",
    ),
    (
        "acceleration",
        "carbody_acceleration",
        (("acceleration_m_s2_per_m", 1.0),),
        "acceleration ((m/s$^2$)/m)",
        "acceleration_m_s2_per_m",
    ),
)
#: the magnitude columns of `frf_frame`, in order
FRF_MAGNITUDES = tuple(c for *_, columns, _, _ in FRF_RESPONSES for c, _ in columns)
#: a response whose largest magnitude is below this fraction of the largest over the patterns
#: is "not excited" by that pattern (e.g. roll by in-phase rails: exactly 0 on a symmetric car)
FRF_NOT_EXCITED = 1e-9


def comparison_psd(ds: xr.Dataset, window=None, segment: float = PSD_SEGMENT_S) -> pd.DataFrame:
    """The PSD of the carbody CG vertical acceleration of each suspension of a comparison, from
    its combined Dataset (`Comparison.combined()`), over the time ``window`` (start, end) [s]
    (None: the whole run), as `psd_plan` chooses: on a periodic track (the paper's sine) one
    Hann-windowed segment of whole periods of the input (``scipy.signal.periodogram``), else
    Welch's method (``scipy.signal.welch``) with Hann segments of ``segment`` seconds (the whole
    window if shorter) overlapping by half; each segment's mean removed; one-sided density.
    Columns ``frequency_hz`` [Hz, from 0 in steps of the bin width] and one per suspension (its
    name) in (m/s^2)^2/Hz; ``attrs``: the plan (`psd_plan`)."""
    from scipy.signal import periodogram, welch

    from railride.analysis.metrics import select_window

    if "controller" not in ds.dims or "time" not in ds.dims:
        raise InputError(
            "expected the combined() Dataset of a railride.studies.comparison.Comparison (dims controller, time)"
        )
    if "carbody_acceleration" not in ds.variables:
        raise InputError("the dataset lacks the channel carbody_acceleration")
    part = select_window(ds, None if window is None else tuple(window))
    plan = psd_plan(ds, window, segment)
    fs, n = plan["fs_hz"], plan["samples"]
    columns = {}
    freq = None
    for i, name in enumerate(controller_names(ds)):
        x = part["carbody_acceleration"].isel(controller=i).values
        if plan["method"] == "periodic":
            freq, pxx = periodogram(x[-n:], fs=fs, window="hann", detrend="constant", scaling="density")
        else:
            freq, pxx = welch(
                x, fs=fs, window="hann", nperseg=n, noverlap=n // 2, detrend="constant", scaling="density"
            )
        columns[name] = pxx
    frame = pd.DataFrame({"frequency_hz": freq, **columns})
    frame.attrs.update(plan)
    return frame


def frf_frame(responses: dict) -> pd.DataFrame:
    """The carbody frequency responses of `Vehicle.frequency_response` as one long table.

    ``responses`` maps a rail pattern ("in-phase", "anti-phase") to its Dataset. One row per
    pattern and frequency, the patterns one after another: ``pattern``, ``frequency_hz``, then
    per response the magnitude per metre of rail amplitude and the phase [deg, (-180, 180],
    against the left rail at the leading wheelset]: ``bounce_m_per_m``, ``bounce_phase_deg``,
    ``pitch_rad_per_m``, ``pitch_deg_per_m``, ``pitch_phase_deg``, ``roll_rad_per_m``,
    ``roll_deg_per_m``, ``roll_phase_deg``, ``acceleration_m_s2_per_m`` [(m/s^2)/m],
    ``acceleration_phase_deg``."""
    frames = []
    for pattern, ds in responses.items():
        columns = {"pattern": pattern, "frequency_hz": ds["frequency"].values.astype(float)}
        for name, channel, mags, _, _ in FRF_RESPONSES:
            h = np.asarray(ds[channel].values, dtype=complex)
            for column, factor in mags:
                columns[column] = np.abs(h) * factor
            # a zero response (roll on in-phase rails) has phase 0, not -0 or 180
            columns[f"{name}_phase_deg"] = np.where(np.abs(h) > 0, np.angle(h, deg=True), 0.0) + 0.0
        frames.append(pd.DataFrame(columns))
    return pd.concat(frames, ignore_index=True)


def frf_excited(values, top: float) -> bool:
    """Whether a pattern excites a response: its largest magnitude among ``values`` is positive
    and above `FRF_NOT_EXCITED` times ``top``, the largest over every pattern."""
    peak = float(np.max(values))
    return top > 0 and peak > FRF_NOT_EXCITED * top and peak > 0


def frf_peaks(frame: pd.DataFrame) -> dict:
    """Per pattern and magnitude column of `frf_frame`: {"magnitude", "frequency_hz"} at the
    largest magnitude on the grid; a response the pattern does not excite (`frf_excited`)
    has "frequency_hz" None."""
    out: dict[str, dict] = {}
    top = {c: float(frame[c].max()) for c in FRF_MAGNITUDES}
    for pattern, part in frame.groupby("pattern", sort=False):
        out[pattern] = {}
        for c in FRF_MAGNITUDES:
            values = part[c].values
            k = int(np.argmax(values))
            out[pattern][c] = {
                "magnitude": float(values[k]),
                "frequency_hz": (float(part["frequency_hz"].values[k]) if frf_excited(values, top[c]) else None),
            }
    return out
