"""The carbody responses of a ride result (`railride.run.ride.RideResult`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from railride.errors import InputError
from railride.validation import shown
from railride.analysis.labels import CARBODY_RESPONSES, describe_scenario, describe_suspension, json_records
from railride.plots._style import (
    PAGE_WIDTH,
    frame_window,
    new_figure,
    save_to,
    say_not_excited,
    set_title,
    styled,
    window_note,
)

#: how a scenario field that differs between the samples of a batch is named in the legend
SCENARIO_WORDS = {
    "speed_m_s": lambda v: f"V = {v:g} m/s",
    "seed": lambda v: f"seed {v}",
    "amplitude_m": lambda v: f"A = {v:g} m",
    "wavelength_m": lambda v: f"wavelength {v:g} m",
    "rail_phase_deg": lambda v: f"rail phase {v:g} deg",
    "height_m": lambda v: f"h = {v:g} m",
    "length_m": lambda v: f"length {v:g} m",
    "duration_s": lambda v: f"{v:g} s",
    "min_wavelength_m": lambda v: f"wavelengths from {v:g} m",
    "max_wavelength_m": lambda v: f"wavelengths to {v:g} m",
}
#: the carbody fields a load factor scales (`VehicleParams.loaded`)
LOAD_FIELDS = ("m_c", "I_cx", "I_cy", "I_cz")


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


def _differing(records: list[dict]) -> list[str]:
    """The keys every record holds whose values are not the same in every record, in the first
    record's order (a key some records lack belongs to another kind of track: its name tells)."""
    keys = [k for k in dict.fromkeys(k for r in records for k in r) if all(k in r for r in records)]
    return [k for k in keys if len({repr(r[k]) for r in records}) > 1]


def _scenario_words(records: list[dict]) -> list[list[str]]:
    """Per sample, the scenario fields that differ between the samples, in words."""
    keys = _differing(records)
    if "name" in keys:  # the name says the profile and the spectrum
        keys = [k for k in keys if k not in ("profile", "spectrum")]
    if any(r.get("profile") == "random" for r in records):  # its length follows speed and duration
        keys = [k for k in keys if k not in ("length_m", "lead_in_m")]
    words: list[list[str]] = [[] for _ in records]
    for key in keys:
        for w, r in zip(words, records):
            say = SCENARIO_WORDS.get(key)
            w.append(say(r[key]) if say else str(r[key]) if key == "name" else f"{key} {r[key]}")
    return words


def _vehicle_words(records: list[dict]) -> list[list[str]]:
    """Per sample, the vehicle parameters that differ: "load x1.3" when only the carbody's mass
    and inertias differ, by one factor, from a preset's; else "c_sz = 6e+04 N s/m"."""
    from railride.model.params import PRESETS, VehicleParams

    keys = _differing(records)
    if not keys:
        return [[] for _ in records]
    if set(keys) <= set(LOAD_FIELDS):
        for preset in PRESETS.values():
            base = dataclasses.asdict(preset)
            factors = []
            for r in records:
                ratio = {r.get(k, np.nan) / base[k] for k in LOAD_FIELDS}
                same = all(r.get(k) == v for k, v in base.items() if k not in LOAD_FIELDS)
                factors.append(ratio.pop() if len(ratio) == 1 and same else None)
            if all(f is not None for f in factors):
                return [[f"load x{f:.4g}"] for f in factors]
    units = {f.name: f.metadata.get("unit", "") for f in dataclasses.fields(VehicleParams)}
    return [[f"{k} = {r[k]:.4g} {units.get(k, '')}".rstrip() for k in keys if k in r] for r in records]


def _voltage_words(ds: xr.Dataset, samples) -> list[list[str]]:
    """Per sample, its constant command voltage ("2.25 V") when the samples' voltages differ."""
    if "damper_command_voltage" not in ds.variables or "sample" not in ds["damper_command_voltage"].dims:
        return [[] for _ in samples]
    volts = []
    for s in samples:
        v = np.unique(np.round(np.asarray(ds["damper_command_voltage"].sel(sample=s).values, dtype=float), 9))
        volts.append(float(v[0]) if v.size == 1 else None)
    if None in volts or len(set(volts)) < 2:
        return [[] for _ in samples]
    return [[f"{v:g} V"] for v in volts]


def sample_labels(ds: xr.Dataset) -> list[str]:
    """The legend text of each sample of a batch: what differs between them (the scenario's
    speed, track seed or name, a load factor or a vehicle parameter, the command voltage), or
    "sample k" where nothing recorded differs."""
    samples = list(ds["sample"].values)
    scenarios = json_records(ds, "scenario")
    vehicles = json_records(ds, "vehicle_params")
    parts: list[list[str]] = [[] for _ in samples]
    if len(scenarios) == len(samples):
        parts = [p + w for p, w in zip(parts, _scenario_words(scenarios))]
    if len(vehicles) == len(samples):
        parts = [p + w for p, w in zip(parts, _vehicle_words(vehicles))]
    parts = [p + w for p, w in zip(parts, _voltage_words(ds, samples))]
    labels = [", ".join(p) for p in parts]
    if len(set(labels)) < len(labels) or not all(labels):
        return [f"sample {s}" + (f": {text}" if text else "") for s, text in zip(samples, labels)]
    return labels


#: a response is "not excited" in a run when its largest absolute value, as the vertical motion
#: it makes at the carbody's secondary corners, is at most this fraction of the carbody's largest
#: motion of the same kind (displacement, or acceleration) in that run (`excited`). The value of
#: the FRF's panels (`railride.analysis.spectra.FRF_NOT_EXCITED`): float64 rounding (epsilon
#: 2.2e-16) leaves a response that the input cannot reach at 1e-20 to 1e-14 of the largest in
#: the paper sine's 10 s runs (roll on in-phase rails, bounce and pitch on anti-phase rails,
#: passive and MR dampers), while a response of a billionth of centimetres is no ride motion
NOT_EXCITED = 1e-9


def _responses(response) -> list[str]:
    """The names of the responses to draw: all four for None, else one name or a sequence."""
    allowed = ", ".join(CARBODY_RESPONSES)
    names = [response] if isinstance(response, str) else response
    try:
        names = list(CARBODY_RESPONSES) if response is None else list(names)
    except TypeError:
        names = [response]
    bad = [n for n in names if not isinstance(n, str) or n not in CARBODY_RESPONSES]
    if bad or not names or len(set(names)) < len(names):
        why = f"{shown(bad[0])} is not a response" if bad else "no response given" if not names else "a repeat"
        raise InputError(f"response = {shown(response)}: {why}; allowed one of {allowed}, or a list of them")
    return names


def _given_axes(ax, names: list[str], chosen: bool) -> list:
    """The Axes of ``ax`` (a matplotlib Axes, or a sequence of them, any shape), one per name."""
    from matplotlib.axes import Axes

    allowed = (
        f"None (a figure of its own), {len(CARBODY_RESPONSES)} Axes (one per response: "
        f"{', '.join(CARBODY_RESPONSES)}) or one Axes with response= one of them"
    )
    axes = [ax] if isinstance(ax, Axes) else list(np.ravel(np.asarray(ax, dtype=object)))
    if not axes or not all(isinstance(a, Axes) for a in axes):
        raise InputError(f"ax = {shown(ax)}: not matplotlib Axes; allowed {allowed}")
    if len(axes) == 1 and len(names) > 1 and not chosen:
        raise InputError(
            f"ax = {shown(ax)}: one Axes draws one response; pass response= one of "
            f'{", ".join(CARBODY_RESPONSES)} (e.g. response="pitch"), or give {len(names)} Axes'
        )
    if len(axes) != len(names):
        raise InputError(
            f"ax: {len(names)} Axes (one per response: {', '.join(names)}), got {len(axes)} Axes; allowed {allowed}"
        )
    return axes


def _peak(values) -> float:
    """The largest absolute finite value of ``values``; NaN when none is finite."""
    values = np.abs(np.asarray(values, dtype=float))
    values = values[np.isfinite(values)]
    return float(values.max()) if values.size else math.nan


def excited(ds: xr.Dataset) -> dict[str, bool]:
    """Per carbody response (`CARBODY_RESPONSES`), whether some sample of ``ds`` moves it beyond
    rounding noise. Each response is taken as the vertical motion it makes at the carbody's
    secondary corners: bounce z, pitch l theta, roll d_s phi (l, d_s from the sample's
    ``vehicle_params``; 1 m where it records none) and the CG acceleration z''. A sample does
    not excite a response whose largest absolute value is at most `NOT_EXCITED` times the
    largest of the same kind in that sample: displacement against max(|z|, l |theta|,
    d_s |phi|), acceleration against max(|z''|, l |theta''|, d_s |phi''|) (the pitch and roll
    accelerations where the Dataset holds them). A run that does not move at all excites
    nothing; a sample with no finite value counts as exciting every response."""
    samples = list(ds["sample"].values) if "sample" in ds.dims else [None]
    records = json_records(ds, "vehicle_params")
    out = dict.fromkeys(CARBODY_RESPONSES, False)
    for k, s in enumerate(samples):
        part = ds if s is None else ds.isel(sample=k)
        record = records[k] if k < len(records) else {}
        lever = {}
        for name, key in (("pitch", "l"), ("roll", "d_s")):
            value = record.get(key)
            lever[name] = abs(float(value)) if isinstance(value, (int, float)) and value else 1.0
        motion = {
            "displacement": _peak(part["carbody_bounce"].values),
            "pitch": lever["pitch"] * _peak(part["carbody_pitch"].values),
            "roll": lever["roll"] * _peak(part["carbody_roll"].values),
        }
        acceleration = [_peak(part["carbody_acceleration"].values)]
        for name, channel in (("pitch", "carbody_pitch_acceleration"), ("roll", "carbody_roll_acceleration")):
            if channel in part.variables:
                acceleration.append(lever[name] * _peak(part[channel].values))
        scale = max(motion.values())
        for name, peak in motion.items():
            out[name] = out[name] or not peak <= NOT_EXCITED * scale  # NaN: excited
        out["acceleration"] = out["acceleration"] or not acceleration[0] <= NOT_EXCITED * max(acceleration)
    return out


@styled
def plot_body_responses(ds: xr.Dataset, path=None, *, ax=None, window=None, response=None):
    """Plot carbody CG vertical acceleration (m/s^2), bounce displacement (m), pitch (deg) and
    roll (deg) of a result Dataset (`RideResult.dataset`) against time in four stacked panels
    sharing the time axis; ``response`` one of acceleration, displacement, pitch, roll (or a
    list of them) draws that one alone (None: all four).

    A batch gets one line per sample, labelled by what differs between the samples
    (`sample_labels`). ``window`` (start, end) s, the metric window: the whole run is drawn, the
    part outside the window shaded, and each panel's y-axis fits the values inside it, so that
    a start-up transient does not flatten the rest (None: the whole run). A response the run
    does not excite (`excited`: at most `NOT_EXCITED` of the largest carbody motion of its kind,
    e.g. roll on symmetric rails, rounding noise below 1e-19 rad) is not drawn scaled up from its
    noise: its panel keeps its axes and says "not excited". The title describes the scenario
    when the dataset records one.

    ``ax``: None for a new figure; one matplotlib Axes per response drawn (four Axes for all of
    them, one Axes with ``response`` naming one); the caller owns that figure (no title). If
    ``path`` is given the figure is saved there (format from its suffix, else PNG), atomically.
    Returns the `matplotlib.figure.Figure` (the given Axes' figure, as before: the Axes drawn
    are ``fig.axes`` of a figure of its own, or those given)."""
    missing = [channel for channel, _, _, _ in CARBODY_RESPONSES.values() if channel not in ds.variables]
    if missing:
        raise InputError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    names = _responses(response)
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 1.0 + 1.5 * len(names)))
        axes = list(np.ravel(fig.subplots(len(names), 1, sharex=True, squeeze=False)))
    else:
        axes = _given_axes(ax, names, response is not None)
        fig = axes[0].figure
    time = ds["time"].values
    batch = "sample" in ds.dims
    samples = list(ds["sample"].values) if batch else [None]
    legend = dict(zip(samples, sample_labels(ds))) if batch else {}
    moves = excited(ds)
    clipped = False
    drawn = []
    for a, name in zip(axes, names):
        channel, factor, label, _ = CARBODY_RESPONSES[name]
        da = ds[channel]
        ys = []
        if moves[name]:
            for s in samples:
                y = (da.sel(sample=s) if s is not None and "sample" in da.dims else da).values * factor
                a.plot(time, y, label=legend.get(s))
                ys.append(y)
            drawn.append(a)
        else:
            say_not_excited(a)
        a.set_ylabel(label)
        a.set_xlim(time[0], time[-1])
        clipped = frame_window([a], time, ys, window) or clipped
    axes[-1].set_xlabel("time (s)")
    if 1 < len(samples) <= 12 and drawn:  # above the first panel, the lines of the first drawn
        handles, labels = drawn[0].get_legend_handles_labels()
        axes[0].legend(
            handles, labels, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncols=min(3, len(samples)), frameon=False
        )
    if ax is None:
        set_title(fig, ride_title(ds) + (f"\n{window_note(window)}" if clipped else ""))
    save_to(fig, path)
    return fig
