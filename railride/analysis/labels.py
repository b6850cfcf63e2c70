"""Text shared by the plots and the command line: descriptions of scenarios, dampers and
comparisons, gain units, axis labels, and the labels read back from a result Dataset.

Nothing here draws or writes; every function returns a string (or strings) for a title, a
legend, a table or a line of output.
"""

from __future__ import annotations

import json
import math
import textwrap

import numpy as np
import xarray as xr

#: per carbody response: (channel, factor from the channel's SI unit to the plotted unit,
#: axis label, long name); angles are plotted in degrees
CARBODY_RESPONSES = {
    "acceleration": ("carbody_acceleration", 1.0, "acceleration (m/s$^2$)", "carbody CG vertical acceleration"),
    "displacement": ("carbody_bounce", 1.0, "displacement (m)", "carbody bounce displacement"),
    "pitch": ("carbody_pitch", 180.0 / math.pi, "pitch (deg)", "carbody pitch angle"),
    "roll": ("carbody_roll", 180.0 / math.pi, "roll (deg)", "carbody roll angle"),
}
#: axis labels of the grid columns of a sweep (gains: "table.entry (unit)", see `grid_axis_label`)
GRID_AXIS_LABELS = {
    "speed_m_s": "speed (m/s)",
    "wavelength_m": "wavelength (m)",
    "amplitude_m": "amplitude (m)",
    "rail_phase_deg": "rail phase (deg)",
    "track_seed": "track seed",
    "voltage_v": "command voltage (V)",
    "damper_scale": "damper force scale (-)",
    "seed": "sensor noise seed",
}


def coordinate_label(value) -> str:
    """A coordinate value as text: bytes decoded, whole floats without ".0" (wheelset 1, not 1.0)."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        return str(int(value))
    return str(value)


def controller_names(ds: xr.Dataset) -> list[str]:
    """The suspensions of a combined comparison Dataset, in its ``controller`` order."""
    return [coordinate_label(v) for v in ds["controller"].values]


def json_records(ds: xr.Dataset, name: str) -> list[dict]:
    """The JSON records of variable ``name`` (``scenario``, ``vehicle_params``), one per sample;
    [] if the variable is absent, {} for a record that does not read as a JSON object."""
    if name not in ds.variables:
        return []
    out = []
    for text in np.atleast_1d(ds[name].values).ravel():
        try:
            rec = json.loads(text.decode("utf-8") if isinstance(text, bytes) else str(text))
        except ValueError:
            rec = None
        out.append(rec if isinstance(rec, dict) else {})
    return out


def damper_model_name(ds: xr.Dataset) -> str | None:
    """The damper model name recorded in a Dataset's ``damper`` attribute, if readable."""
    import ast

    text = ds.attrs.get("damper")
    if not isinstance(text, str):
        return None
    for parse in (json.loads, ast.literal_eval):
        try:
            record = parse(text)
        except (ValueError, SyntaxError):
            continue
        if isinstance(record, dict) and isinstance(record.get("model"), str):
            return record["model"]
    return None


def _num(record: dict, key: str) -> str:
    value = record.get(key)
    return f"{value:g}" if isinstance(value, (int, float)) else "?"


def describe_scenario(record: dict) -> str:
    """A one-line human description of a `Scenario.describe()` record."""
    if not record:
        return ""
    parts = []
    profile = record.get("profile")
    if profile == "sine":
        parts.append(
            f"sine A = {_num(record, 'amplitude_m')} m, wavelength {_num(record, 'wavelength_m')} m, "
            f"rail phase {_num(record, 'rail_phase_deg')} deg"
        )
    elif profile == "cosine-bump":
        parts.append(
            f"cosine bump h = {_num(record, 'height_m')} m, length {_num(record, 'length_m')} m "
            f"at s = {_num(record, 'start_m')} m ({record.get('rails', 'both')} rails)"
        )
    elif profile == "measured":
        parts.append(f"measured profile {record.get('source', '?')}")
    elif profile == "random":
        spectrum = str(record.get("spectrum", "?"))
        if spectrum.startswith("fra"):
            text = f"random track, FRA class {spectrum[3:]}"
        elif spectrum.startswith("german-"):
            text = f"random track, German {spectrum.split('-', 1)[1]} interference"
        elif spectrum.startswith("psd:"):
            text = f"random track of the spectrum table {spectrum[4:]}"
        else:
            text = f"random track {spectrum}"
        if "seed" in record:
            text += f", seed {record['seed']}"
        text += f", wavelengths {_num(record, 'min_wavelength_m')}-{_num(record, 'max_wavelength_m')} m"
        parts.append(text)
    elif profile:
        parts.append(str(profile))
    if "speed_m_s" in record:
        parts.append(f"V = {_num(record, 'speed_m_s')} m/s")
    name = record.get("name")
    body = ", ".join(parts)
    return f"{name}: {body}" if name and body else (name or body)


def describe_dampers(settings: dict, detail: bool = False) -> str:
    """The controlled suspensions' dampers of a compare, sweep or tune ``settings`` record:
    "railway MR dampers (force x 4)", "ideal actuators"; ``detail`` adds what an ideal device
    does."""
    from railride.secondary.dampers import record_name

    ideal = {
        "ideal": ("ideal actuators", "force = demand"),
        "ideal-damper": ("ideal semi-active dampers", "force = demand where it dissipates, else 0"),
    }
    damper = settings.get("damper")
    if isinstance(damper, dict):  # a model given as such (a damper file): its record
        damper = record_name(damper)
    if damper in ideal:
        words, what = ideal[damper]
        return f"{words} ({what})" if detail else words
    scale = settings.get("damper_scale") or 1.0
    return f"{damper} MR dampers" + (f" (force x {scale:g})" if scale != 1.0 else "")


def describe_suspension(ds: xr.Dataset) -> str:
    """ "MR <model> dampers at <v> V" for a ride result Dataset with damper models, else ""."""
    if "damper_command_voltage" not in ds.variables:
        return ""
    model = damper_model_name(ds) or "damper"
    volts = np.unique(np.round(np.asarray(ds["damper_command_voltage"].values, dtype=float), 9))
    if volts.size == 1:
        return f"MR {model} dampers at {volts[0]:g} V"
    return f"MR {model} dampers at {volts.min():g}-{volts.max():g} V"


def comparison_title(ds: xr.Dataset) -> str:
    """One line naming the scenario, the dampers and the gains of a comparison, from its
    combined Dataset (`Comparison.combined()`)."""
    parts = []
    records = json_records(ds, "scenario")
    if records and records[0]:
        parts.append(describe_scenario(records[0]))
    try:
        settings = json.loads(ds.attrs.get("settings", "{}"))
    except (TypeError, ValueError):
        settings = {}
    controlled = any(n != "passive" for n in controller_names(ds))
    if isinstance(settings, dict) and settings.get("damper") and controlled:
        parts.append(describe_dampers(settings))
    if ds.attrs.get("gains_source") and controlled:
        parts.append(f"gains {ds.attrs['gains_source']}")
    return ", ".join(p for p in parts if p)


def psd_title(ds: xr.Dataset, window, segment: float) -> str:
    """The title of the acceleration spectra of a comparison (combined Dataset ``ds``) over
    ``window`` (start, end) [s] (None: the whole run), as `railride.analysis.psd_plan.psd_plan`
    takes them (Welch segments of at most ``segment`` s where the track is not periodic): the
    method and the bin width."""
    from railride.analysis.psd_plan import psd_plan

    start, end = window if window is not None else (float(ds["time"][0]), float(ds["time"][-1]))
    method = psd_plan(ds, window, segment)["text"]
    title = f"PSD of the carbody CG vertical acceleration, {start:g}-{end:g} s\n" + textwrap.fill(method, 120)
    context = comparison_title(ds)
    if context:
        title += "\n" + textwrap.fill(context, 120)
    return title


def gain_unit(parameter: str) -> str | None:
    """The unit of a "table.entry" gain (`railride.secondary.control.GainSet.TABLES`), or None for an
    unknown table or entry."""
    from railride.secondary.control import GainSet  # here, not above: control pulls in the vehicle model

    return GainSet.entry_unit(parameter)


def grid_axis_label(column: str) -> str:
    """The axis label of a sweep's grid column: `GRID_AXIS_LABELS`, a gain with its unit
    ("pid.kd (N s/m)"), else the column's name."""
    if column in GRID_AXIS_LABELS:
        return GRID_AXIS_LABELS[column]
    unit = gain_unit(column) if "." in column else None
    return f"{column} ({unit})" if unit else column
