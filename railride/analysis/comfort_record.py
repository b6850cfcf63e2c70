"""The record of a run's ride comfort for the JSON documents (`comfort_record`) and the words
on what its N_MV,z rests on (`n_mv_basis`): the indices themselves are `railride.analysis.comfort`."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from railride.analysis.comfort import INTERVAL_S, WHOLE_SIGNAL, comfort_class, to_dict


def intervals_in(window, duration: float) -> int:
    """The whole 5 s intervals of EN 12299 that N_MV,z reads in the window (start, end) [s] of
    a run ``duration`` s long (end None or past the run: its end); 0 where it is shorter than
    one (`comfort_intervals` then takes the whole signal)."""
    start, end = (0.0, duration) if window is None else window
    end = duration if end is None else min(float(end), duration)
    return max(0, int(np.floor((end - float(start)) / INTERVAL_S + 1e-9)))


def n_mv_basis(n: int) -> str:
    """What N_MV,z rests on, in words, for ``n`` intervals of 5 s (`intervals_in`; 0: the whole
    signal, shorter than one): EN 12299 evaluates 60, so fewer make it an indication only."""
    text = (
        "N_MV_z from one interval, the whole signal" if n == 0 else f"N_MV_z from {n} interval{'s' * (n != 1)} of 5 s"
    )
    return text + (" (EN 12299 evaluates 60, 5 minutes): an indication only" if n < 60 else "")


#: indices whose reduction against passive is given: a_w, VDV and N_MV_z scale with the
#: acceleration; Sperling's Wz (a power 0.3 of it) does not, so a percentage says little
COMFORT_REDUCED = ("aw_Wk", "vdv_Wk", "aw_Wb", "vdv_Wb", "N_MV_z")


def comfort_record(comfort: xr.DataArray, passive: xr.DataArray | None = None) -> dict:
    """The JSON record of one run's `railride.analysis.comfort.ride_comfort` (docs/cli.md): per position
    its x and indices, with the EN 12299 label of N_MV_z; units, window, the number of 5 s
    intervals behind N_MV_z and the notes. With ``passive`` (the baseline's indices), also
    ``reduction_percent`` per position for `COMFORT_REDUCED`."""
    values = to_dict(comfort)
    positions = {}
    for p, indices in values.items():
        entry: dict[str, Any] = {"x_m": float(comfort["x_m"].sel(position=p))}
        for i, v in indices.items():
            entry[i] = v
            if i == "N_MV_z":
                entry["N_MV_z_class"] = comfort_class(v)
        positions[p] = entry
    n = int(comfort.attrs.get("n_intervals", 0))
    # ride_comfort joins its notes with "; ": a short-run warning (which holds "; " itself)
    # and, always last, that N_MV_z is the vertical term only
    text = str(comfort.attrs.get("notes", ""))
    cut = text.find("N_MV_z is the vertical term")
    notes = [text] if cut < 0 else [t for t in (text[:cut].rstrip("; "), text[cut:]) if t]
    short = WHOLE_SIGNAL in text  # shorter than one interval of 5 s
    notes.append(n_mv_basis(0 if short else n))
    record = {
        "positions": positions,
        "units": {str(i): str(u) for i, u in zip(comfort["index"].values, comfort["unit"].values)},
        "window_s": json.loads(comfort.attrs["window_s"]),
        "n_intervals": n,
        "notes": notes,
    }
    if passive is not None:
        base = to_dict(passive)
        record["reduction_percent"] = {
            p: {
                i: (base[p][i] - v) / base[p][i] * 100.0 if base[p][i] > 0 else None
                for i, v in indices.items()
                if i in COMFORT_REDUCED
            }
            for p, indices in values.items()
        }
    return record
