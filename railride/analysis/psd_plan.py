"""How the acceleration spectra of a comparison are taken (`psd_plan`): on a periodic track (the
paper's sine) one Hann-windowed segment of whole periods of the input, resolving it; on any
other track Welch's method. Used by `railride.analysis.spectra.comparison_psd`, which takes them,
and by `railride.analysis.labels.psd_title`, which says how (docs/cli.md, the result folder of
compare).
"""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

#: the Welch segment length of the acceleration spectra of a comparison on a track that is not
#: periodic [s]: 0.25 Hz bins
PSD_SEGMENT_S = 4.0
#: on a periodic track, the spectrum's segment holds at least this many periods of the input
#: where the window does, so that its bins are at most 1/PSD_MIN_PERIODS of the input frequency
PSD_MIN_PERIODS = 5


def periodic_input_hz(ds: xr.Dataset) -> float | None:
    """The frequency [Hz] of a comparison's periodic track input, speed / wavelength, from the
    scenario its combined Dataset records (a sine: the paper's); None for any other track."""
    scenario = None
    texts = [ds.attrs.get("settings")]
    if "scenario" in ds.variables:  # per controller, the same track
        texts.append(np.atleast_1d(ds["scenario"].values).ravel()[0])
    for text in texts:
        try:
            record = json.loads(text.decode() if isinstance(text, bytes) else str(text))
        except (TypeError, ValueError):
            continue
        if isinstance(record, dict) and isinstance(record.get("scenario"), dict):
            record = record["scenario"]
        if isinstance(record, dict) and "profile" in record:
            scenario = record
            break
    if not isinstance(scenario, dict) or scenario.get("profile") != "sine":
        return None
    try:
        f0 = float(scenario["speed_m_s"]) / float(scenario["wavelength_m"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return None
    return f0 if math.isfinite(f0) and f0 > 0 else None


def psd_plan(ds: xr.Dataset, window=None, segment: float = PSD_SEGMENT_S) -> dict:
    """How `comparison_psd` takes the spectra of ``ds`` over ``window`` (start, end) [s] (None:
    the whole run).

    On a periodic track (`periodic_input_hz` f0; below half the output rate) whose window holds
    at least one period: one segment of the largest whole number N of periods in the window,
    its last N (the most settled), Hann-windowed: the input and its harmonics fall on bins
    (f0 = N bins), and the bins are f0/N wide, at most f0/`PSD_MIN_PERIODS` once the window
    holds that many periods. Otherwise Welch's method with Hann segments of ``segment`` s (the
    whole window if shorter), overlapping by half.

    Returns {"method": "periodic" | "welch", "fs_hz", "samples" (per segment), "bin_hz",
    "start_s", "end_s" (of the samples used), "input_hz" and "periods" (None for Welch),
    "text" (the method in words, with the bin width)}."""
    from railride.analysis.metrics import select_window

    time = select_window(ds[["time"]], None if window is None else tuple(window))["time"].values
    # the output rate, without the float noise of the time stamps' differences
    fs = float(f"{(time.size - 1) / (time[-1] - time[0]):.9g}")
    f0 = periodic_input_hz(ds)
    periods = 0 if f0 is None or f0 >= fs / 2 else int(math.floor(time.size * f0 / fs + 1e-9))
    if f0 is not None and periods >= 1:
        n = min(time.size, int(round(periods * fs / f0)))
        text = (
            f"{fs / n:.3g} Hz bins: one Hann-windowed segment, the last {periods} whole "
            f"period{'s' * (periods != 1)} of the {f0:.3g} Hz input ({time[-n]:g} s to {time[-1]:g} s)"
        )
        if periods < PSD_MIN_PERIODS:
            text += f", coarser than f/{PSD_MIN_PERIODS}: a longer window resolves the input better"
        return {
            "method": "periodic",
            "fs_hz": fs,
            "samples": n,
            "bin_hz": fs / n,
            "start_s": float(time[-n]),
            "end_s": float(time[-1]),
            "input_hz": f0,
            "periods": periods,
            "text": text,
        }
    n = max(2, min(time.size, int(round(segment * fs))))
    return {
        "method": "welch",
        "fs_hz": fs,
        "samples": n,
        "bin_hz": fs / n,
        "start_s": float(time[0]),
        "end_s": float(time[-1]),
        "input_hz": None,
        "periods": None,
        "text": f"{fs / n:.3g} Hz bins: Welch, {n / fs:g} s Hann segments, 50 % overlap",
    }
