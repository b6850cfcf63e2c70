"""The report layer: flat tables, plots and the output folder of a run.

* `to_frame` turns the time histories of a result Dataset into a pandas DataFrame.
* `plot_body_responses` draws the four carbody responses (acceleration, bounce, pitch, roll).
* `write_outputs` writes ``ride.nc``, ``ride.csv``, ``metrics.json`` and ``body_responses.png``
  into a folder, all or nothing.
* `plot_hysteresis` and `plot_tracking` draw the damper rig results of `railride.rig`;
  `write_damper_outputs` and `write_tracking_outputs` write their folders.
* `plot_comparison_response`, `plot_comparison_damper_forces`, `plot_comparison_voltages` and
  `comparison_frame` draw and tabulate a controller comparison (`railride.comparison`, the combined
  Dataset with a ``controller`` dimension); `comparison_psd` and `plot_comparison_psd` give the
  Welch spectra of its carbody acceleration; `write_compare_outputs` writes its folder.
* `curves_frame` and `plot_sensitivity` tabulate and draw the sensitivity curves of a tuning
  study (`railride.tuning`); `write_tune_outputs` writes its folder (beside the run table
  ``runs.csv`` that the library keeps up to date), `write_sweep_outputs` that of a sweep (with
  `plot_sweep`, the RMS against its one numeric axis).
* `frf_frame`, `frf_peaks`, `modes_frame` and `plot_frf` tabulate and draw the frequency
  responses of `railride.vehicle.Vehicle`; `write_frf_outputs` writes their folder.
* `write_folder` is the all-or-nothing folder writer behind the ``write_*`` functions.

Figures are built on matplotlib's object API with the Agg canvas: nothing here touches pyplot's
global figure list or the user's backend, so no window ever opens and saved figures do not pile
up in memory.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from ._io import atomic_write

#: string variables of a result that hold JSON records, not time histories
RECORD_VARIABLES = ("scenario", "vehicle_params")

#: the files `write_outputs` produces, in the order they are written
OUTPUT_FILES = ("ride.nc", "ride.csv", "metrics.json", "body_responses.png")
#: the files `write_damper_outputs` produces, in the order they are written
DAMPER_FILES = ("loops.png", "cycles.csv", "damper.json")
#: the files `write_tracking_outputs` produces, in the order they are written
TRACKING_FILES = ("tracking.png", "tracking.csv", "tracking.json")
#: the files `write_compare_outputs` produces, in the order they are written
COMPARE_FILES = ("compare.json", "compare.nc", "compare.csv", "acceleration.png", "displacement.png",
                 "pitch.png", "roll.png", "damper_forces.png", "voltages.png", "psd.png", "psd.csv")
#: the files `write_tune_outputs` produces, in the order they are written
TUNE_FILES = ("gains.toml", "sensitivity.png", "curves.csv", "tune.json")
#: the files `write_sweep_outputs` always produces (the run table runs.csv is the library's);
#: ``sweep.png`` is added when the sweep has one numeric axis (`sweep_plot_axis`), and with it
#: ``comfort.png`` when the rows hold the comfort indices (`railride sweep --comfort`)
SWEEP_FILES = ("sweep.json",)
#: the files `write_frf_outputs` produces, in the order they are written
FRF_FILES = ("frf.csv", "frf.json", "frf.png", "modes.csv")
#: the Welch segment length of the acceleration spectra of `write_compare_outputs` [s]
PSD_SEGMENT_S = 4.0
#: the columns of `curves_frame` (curves.csv)
CURVE_COLUMNS = ("phase", "pass", "parameter", "value", "objective", "chosen")
#: the time histories of a damper rig run (railride.rig), in CSV column order
RIG_CHANNELS = ("x", "xd", "F", "z", "y", "u", "v", "E")

#: (channel, factor to the plotted unit, axis label) of the four panels
_PANELS = (
    ("carbody_acceleration", 1.0, "acceleration (m/s$^2$)"),
    ("carbody_bounce", 1.0, "displacement (m)"),
    ("carbody_pitch", 180.0 / math.pi, "pitch (deg)"),
    ("carbody_roll", 180.0 / math.pi, "roll (deg)"),
)


def _dataset(result) -> xr.Dataset:
    """A `RideResult` or a Dataset -> the Dataset."""
    ds = getattr(result, "dataset", result)
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"expected a RideResult or an xarray Dataset, got {type(result).__name__}")
    return ds


# -- tables -----------------------------------------------------------------------------------
def _label(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        return str(int(value))
    return str(value)


def to_frame(ds: xr.Dataset) -> pd.DataFrame:
    """The time histories of a result Dataset as one flat table.

    Single run: the index is ``time`` [s] and there is one column per channel, in the units of
    the Dataset (SI; angles in rad). A channel with extra dimensions gets one column per
    element, named after the channel and the labels of its extra coordinates joined in order:
    ``secondary_deflection_1R`` (``corner`` = 1R), ``rail_displacement_1L`` (``wheelset`` = 1,
    ``rail`` = L).

    Batch (a ``sample`` dimension): a long table with a two-level index (``sample``, ``time``),
    the samples stacked one after another; ``df.reset_index()`` gives plain columns, and
    ``df.loc[k]`` the table of sample k. ``to_csv`` writes both levels as the first columns.

    The JSON record variables ``scenario`` and ``vehicle_params``, any other non-numeric
    variable and any variable without a ``time`` dimension are left out.
    """
    ds = _dataset(ds)
    if "time" not in ds.dims:
        raise ValueError("the dataset has no time dimension: not a result of railride.simulation")
    lead = ["sample"] if "sample" in ds.dims else []
    n_rows = ds.sizes["time"] * (ds.sizes["sample"] if lead else 1)
    columns: dict[str, np.ndarray] = {}
    for name, da in ds.data_vars.items():
        if name in RECORD_VARIABLES or "time" not in da.dims or da.dtype.kind not in "biuf":
            continue
        extra = [d for d in da.dims if d not in ("sample", "time")]
        if lead and "sample" not in da.dims:  # shared by every sample: repeat it
            da = da.expand_dims(sample=ds.sizes["sample"])
        values = da.transpose(*lead, "time", *extra).values.reshape(n_rows, -1)
        if not extra:
            columns[str(name)] = values[:, 0]
            continue
        labels = [[_label(v) for v in (ds[d].values if d in ds.coords else range(ds.sizes[d]))]
                  for d in extra]
        for j, combo in enumerate(np.ndindex(*[len(lab) for lab in labels])):
            suffix = "".join(labels[k][i] for k, i in enumerate(combo))
            columns[f"{name}_{suffix}"] = values[:, j]
    time = ds["time"].values
    if lead:
        index = pd.MultiIndex.from_product([ds["sample"].values, time], names=["sample", "time"])
    else:
        index = pd.Index(time, name="time")
    return pd.DataFrame(columns, index=index)


# -- plots ------------------------------------------------------------------------------------
def _records(ds: xr.Dataset, name: str) -> list[dict]:
    """The JSON records of variable ``name``, one per sample ([] if absent or unreadable)."""
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
        parts.append(f"sine A = {_num(record, 'amplitude_m')} m, wavelength {_num(record, 'wavelength_m')} m, "
                     f"rail phase {_num(record, 'rail_phase_deg')} deg")
    elif profile == "cosine-bump":
        parts.append(f"cosine bump h = {_num(record, 'height_m')} m, length {_num(record, 'length_m')} m "
                     f"at s = {_num(record, 'start_m')} m ({record.get('rails', 'both')} rails)")
    elif profile == "measured":
        parts.append(f"measured profile {record.get('source', '?')}")
    elif profile == "random":
        spectrum = str(record.get("spectrum", "?"))
        if spectrum.startswith("fra"):
            text = f"random track, FRA class {spectrum[3:]}"
        elif spectrum.startswith("german-"):
            text = f"random track, German {spectrum.split('-', 1)[1]} interference"
        else:
            text = f"random track {spectrum}"
        if "seed" in record:
            text += f", seed {record['seed']}"
        text += (f", wavelengths {_num(record, 'min_wavelength_m')}-"
                 f"{_num(record, 'max_wavelength_m')} m")
        parts.append(text)
    elif profile:
        parts.append(str(profile))
    if "speed_m_s" in record:
        parts.append(f"V = {_num(record, 'speed_m_s')} m/s")
    name = record.get("name")
    body = ", ".join(parts)
    return f"{name}: {body}" if name and body else (name or body)


def _title(ds: xr.Dataset) -> str:
    records = _records(ds, "scenario")
    if not records:
        suspension = _suspension_text(ds)
        return f"carbody responses - {suspension}" if suspension else "carbody responses"
    texts = [describe_scenario(r) for r in records]
    if len(set(texts)) == 1:
        title = texts[0]
    else:
        names = sorted({r.get("name", "?") for r in records})
        title = "scenarios " + ", ".join(names)
    if "sample" in ds.dims:
        title = f"{title} ({ds.sizes['sample']} samples)"
    suspension = _suspension_text(ds)
    if suspension:
        return (f"carbody responses - {title}\n{suspension}" if title
                else f"carbody responses - {suspension}")
    return f"carbody responses - {title}" if title else "carbody responses"


def _suspension_text(ds: xr.Dataset) -> str:
    """"MR <model> dampers at <v> V" for a run with damper models, else ""."""
    if "damper_command_voltage" not in ds.variables:
        return ""
    model = _rig_damper_model(ds) or "damper"
    volts = np.unique(np.round(np.asarray(ds["damper_command_voltage"].values, dtype=float), 9))
    if volts.size == 1:
        return f"MR {model} dampers at {volts[0]:g} V"
    return f"MR {model} dampers at {volts.min():g}-{volts.max():g} V"


def plot_body_responses(ds: xr.Dataset, path=None):
    """Plot carbody CG vertical acceleration (m/s^2), bounce displacement (m), pitch (deg) and
    roll (deg) against time in four stacked panels sharing the time axis.

    A batch gets one line per sample. The title describes the scenario when the dataset records
    one. If ``path`` is given the figure is saved there as PNG, atomically (a reader never sees
    a half-written file). Returns the `matplotlib.figure.Figure`; it is drawn on an Agg canvas
    and never registered with pyplot, so it opens no window and is freed once unreferenced.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    ds = _dataset(ds)
    missing = [c for c, _, _ in _PANELS if c not in ds.variables]
    if missing:
        raise ValueError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    fig = Figure(figsize=(9.0, 9.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(_PANELS), 1, sharex=True)
    time = ds["time"].values
    samples = list(ds["sample"].values) if "sample" in ds.dims else [None]
    names = [r.get("name") for r in _records(ds, "scenario")]
    legend = {s: f"sample {s}" + (f": {names[i]}" if len(names) == len(samples) and names[i] else "")
              for i, s in enumerate(samples)}
    for ax, (channel, factor, label) in zip(axes, _PANELS):
        da = ds[channel]
        for s in samples:
            y = (da.sel(sample=s) if s is not None and "sample" in da.dims else da).values * factor
            ax.plot(time, y, linewidth=0.9, label=None if s is None else legend[s])
        ax.set_ylabel(label)
        ax.grid(True, linewidth=0.4, alpha=0.6)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(time[0], time[-1])
    if 1 < len(samples) <= 12:
        axes[0].legend(loc="upper right", fontsize="small", ncols=min(4, len(samples)))
    fig.suptitle(_title(ds), fontsize="medium")
    if path is not None:
        atomic_write(Path(path), lambda tmp: fig.savefig(tmp, format="png", dpi=120))
    return fig


# -- damper rig (railride.rig) ----------------------------------------------------------------
def _new_figure(figsize):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save_png(fig, path) -> None:
    if path is not None:
        atomic_write(Path(path), lambda tmp: fig.savefig(tmp, format="png", dpi=120))


def _rig_damper_model(ds: xr.Dataset) -> str | None:
    """The damper model name recorded in a rig Dataset's ``damper`` attribute, if readable."""
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


def cycles_frame(cycles) -> pd.DataFrame:
    """The steady-state cycles of `railride.rig.cycles` as one long table: columns ``voltage``
    [V, the constant command of the run], ``time`` [s], then x [m], xd [m/s], F [N, tension +],
    z, y [m], u, v [V], E [J, dissipated since the start of the run]; the voltages one after
    another, in the order they were given."""
    ds = _dataset(cycles)
    missing = [c for c in RIG_CHANNELS if c not in ds.variables]
    if missing or "voltage" not in ds.dims:
        raise ValueError("expected the dataset of railride.rig.cycles (dims voltage, time; "
                         f"channels {', '.join(RIG_CHANNELS)})")
    frame = ds[list(RIG_CHANNELS)].to_dataframe(dim_order=["voltage", "time"])
    return frame.reset_index()[["voltage", "time", *RIG_CHANNELS]]


def plot_hysteresis(cycles, path=None, *, title: str | None = None):
    """Force-displacement and force-velocity loops of `railride.rig.cycles`: the steady-state
    (last) cycle at each voltage, one line per voltage, force in kN (tension +), extension in
    mm, extension rate in m/s.

    Saved as PNG at ``path`` when given (atomically). ``title`` replaces the default title
    (the damper model and the motion). Returns the Agg `Figure` (never registered with pyplot).
    """
    from matplotlib import colormaps

    ds = _dataset(cycles)
    missing = [c for c in ("x", "xd", "F") if c not in ds.variables]
    if missing or "voltage" not in ds.dims:
        raise ValueError("expected the result of railride.rig.cycles (dims voltage, time; x, xd, F)")
    fig = _new_figure((11.0, 4.8))
    ax_x, ax_v = fig.subplots(1, 2, sharey=True)
    volts = [float(v) for v in ds["voltage"].values]
    cmap = colormaps["viridis"]
    for i, v in enumerate(volts):
        cyc = ds.isel(voltage=i)
        colour = cmap(0.85 * i / max(1, len(volts) - 1))
        force = cyc["F"].values / 1e3
        ax_x.plot(cyc["x"].values * 1e3, force, color=colour, linewidth=1.2, label=f"{v:g} V")
        ax_v.plot(cyc["xd"].values, force, color=colour, linewidth=1.2, label=f"{v:g} V")
    ax_x.set_xlabel("extension x (mm)")
    ax_v.set_xlabel("extension rate x' (m/s)")
    ax_x.set_ylabel("damper force F (kN, tension +)")
    ax_x.set_title("force - displacement", fontsize="medium")
    ax_v.set_title("force - velocity", fontsize="medium")
    for ax in (ax_x, ax_v):
        ax.axhline(0.0, color="0.6", linewidth=0.5)
        ax.axvline(0.0, color="0.6", linewidth=0.5)
        ax.grid(True, linewidth=0.4, alpha=0.6)
    ax_v.legend(title="command voltage", fontsize="small", loc="upper left")
    if title is None:
        damper = getattr(cycles, "damper", None)
        motion = getattr(cycles, "motion", None)
        model = getattr(damper, "model", None) or _rig_damper_model(ds) or "damper"
        title = f"{model} damper, steady-state cycle"
        if motion is not None:
            title += (f", x = {motion.amplitude * 1e3:g} mm sin(2 pi {motion.frequency:g} Hz t)")
    fig.suptitle(title, fontsize="medium")
    _save_png(fig, path)
    return fig


def plot_tracking(tracking, path=None, *, title: str | None = None):
    """Force tracking of `railride.rig.track`: top, the desired and the actual damper force
    (kN, tension +) against time; bottom, the command voltage v and the coil voltage u (V).
    The first cycle, left out of the metrics (start-up), is shaded.

    Saved as PNG at ``path`` when given (atomically). ``title`` replaces the default title.
    Returns the Agg `Figure`.
    """
    ds = _dataset(tracking)
    missing = [c for c in ("F", "desired_force", "v", "u") if c not in ds.variables]
    if missing:
        raise ValueError(f"expected the result of railride.rig.track; missing {', '.join(missing)}")
    fig = _new_figure((10.0, 6.5))
    ax_f, ax_v = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    time = ds["time"].values
    ax_f.plot(time, ds["desired_force"].values / 1e3, color="0.15", linewidth=1.1,
              linestyle="--", label="desired")
    ax_f.plot(time, ds["F"].values / 1e3, color="tab:red", linewidth=1.1, label="actual")
    ax_f.set_ylabel("damper force (kN, tension +)")
    ax_f.legend(loc="upper right", fontsize="small", ncols=2)
    ax_v.plot(time, ds["v"].values, color="tab:blue", linewidth=0.9, label="command v")
    ax_v.plot(time, ds["u"].values, color="tab:orange", linewidth=1.2, label="coil u")
    ax_v.set_ylabel("voltage (V)")
    ax_v.set_xlabel("time (s)")
    ax_v.legend(loc="upper right", fontsize="small", ncols=2)
    window = getattr(tracking, "window", None)
    for ax in (ax_f, ax_v):
        ax.grid(True, linewidth=0.4, alpha=0.6)
        if window is not None and window[0] > time[0]:
            ax.axvspan(time[0], window[0], color="0.9", zorder=0)
    ax_v.set_xlim(time[0], time[-1])
    if title is None:
        parts = [f"{getattr(tracking, 'desired', 'desired')} force tracking"]
        model = _rig_damper_model(ds)
        if model:
            parts.append(f"{model} damper")
        if "B" in ds.attrs and "G_v_per_n" in ds.attrs:
            parts.append(f"B = {float(ds.attrs['B']):g}, G = {float(ds.attrs['G_v_per_n']):.3g} V/N")
        if hasattr(tracking, "metrics"):
            m = tracking.metrics()
            if isinstance(m.get("normalised_rms_error"), float) and math.isfinite(m["normalised_rms_error"]):
                parts.append(f"normalised RMS error {m['normalised_rms_error']:.3f}")
        title = ", ".join(parts)
    if window is not None and window[0] > time[0]:
        title += "\n(shaded: start-up, left out of the metrics)"
    fig.suptitle(title, fontsize="medium")
    _save_png(fig, path)
    return fig


# -- controller comparison (railride.comparison) --------------------------------------------------
#: response file stem -> (channel, factor to the plotted unit, axis label, title word)
COMPARE_RESPONSES = {
    "acceleration": ("carbody_acceleration", 1.0, "acceleration (m/s$^2$)", "carbody CG vertical acceleration"),
    "displacement": ("carbody_bounce", 1.0, "displacement (m)", "carbody bounce displacement"),
    "pitch": ("carbody_pitch", 180.0 / math.pi, "pitch (deg)", "carbody pitch angle"),
    "roll": ("carbody_roll", 180.0 / math.pi, "roll (deg)", "carbody roll angle"),
}
#: line style and colour per suspension, as in the paper's Figs. 8-11 (passive dash-dot, PID
#: dotted, SAS (attitude) dashed, SAS (attitude+ride) solid)
COMPARE_STYLES = {
    "passive": {"linestyle": "-.", "color": "0.25"},
    "pid": {"linestyle": ":", "color": "tab:blue"},
    "sas-attitude": {"linestyle": "--", "color": "tab:orange"},
    "sas-attitude-ride": {"linestyle": "-", "color": "tab:red"},
}
#: the per-corner channels of `comparison_frame`, after the body responses
COMPARE_CORNER_CHANNELS = ("secondary_damper_force", "damper_demand_force", "damper_command_voltage")


def _comparison_dataset(comparison) -> xr.Dataset:
    """A `Comparison` (its ``combined()``) or a combined Dataset -> the Dataset, checked."""
    ds = comparison.combined() if hasattr(comparison, "combined") else comparison
    if not isinstance(ds, xr.Dataset) or "controller" not in ds.dims or "time" not in ds.dims:
        raise ValueError("expected a railride.comparison.Comparison or its combined() Dataset "
                         "(dims controller, time)")
    return ds


def describe_dampers(settings: dict, detail: bool = False) -> str:
    """The controlled suspensions' dampers of a compare, sweep or tune ``settings`` record:
    "railway MR dampers (force x 4)", "ideal actuators"; ``detail`` adds what an ideal device
    does."""
    ideal = {"ideal": ("ideal actuators", "force = demand"),
             "ideal-damper": ("ideal semi-active dampers", "force = demand where it dissipates, else 0")}
    if settings.get("damper") in ideal:
        words, what = ideal[settings["damper"]]
        return f"{words} ({what})" if detail else words
    scale = settings.get("damper_scale") or 1.0
    return f"{settings['damper']} MR dampers" + (f" (force x {scale:g})" if scale != 1.0 else "")


def _controller_names(ds: xr.Dataset) -> list[str]:
    return [_label(v) for v in ds["controller"].values]


def _controller_label(name: str) -> str:
    from .control import LABELS

    return LABELS.get(name, name)


def _style(name: str) -> dict:
    return COMPARE_STYLES.get(name, {"linestyle": "-"})


def comparison_title(ds: xr.Dataset) -> str:
    """One line naming the scenario, the dampers and the gains of a combined comparison."""
    ds = _comparison_dataset(ds)
    parts = []
    records = _records(ds, "scenario")
    if records and records[0]:
        parts.append(describe_scenario(records[0]))
    try:
        settings = json.loads(ds.attrs.get("settings", "{}"))
    except (TypeError, ValueError):
        settings = {}
    if isinstance(settings, dict) and settings.get("damper") and any(
            n != "passive" for n in _controller_names(ds)):
        parts.append(describe_dampers(settings))
    if ds.attrs.get("gains_source") and any(n != "passive" for n in _controller_names(ds)):
        parts.append(f"gains {ds.attrs['gains_source']}")
    return ", ".join(p for p in parts if p)


def plot_comparison_response(comparison, response: str, path=None, ax=None):
    """One carbody response against time, one line per suspension in the paper's style (Figs.
    8-11: passive dash-dot, PID dotted, SAS (attitude) dashed, SAS (attitude+ride) solid).

    ``response`` is ``acceleration`` (m/s^2), ``displacement`` (bounce, m), ``pitch`` or
    ``roll`` (both in degrees). ``comparison`` is a `railride.comparison.Comparison` or its
    ``combined()`` Dataset. Drawn into ``ax`` when given (no title then: the caller owns the
    figure); saved as PNG at ``path`` when given (atomically); returns the `Figure`.
    """
    if response not in COMPARE_RESPONSES:
        raise ValueError(f"response = {response!r}: allowed {', '.join(COMPARE_RESPONSES)}")
    ds = _comparison_dataset(comparison)
    channel, factor, ylabel, what = COMPARE_RESPONSES[response]
    if channel not in ds.variables:
        raise ValueError(f"the dataset lacks the channel {channel}")
    own = ax is None
    fig = _new_figure((10.0, 4.6)) if own else ax.figure
    if own:
        ax = fig.subplots()
    time = ds["time"].values
    for i, name in enumerate(_controller_names(ds)):
        y = ds[channel].isel(controller=i).values * factor
        ax.plot(time, y, linewidth=1.1, label=_controller_label(name), **_style(name))
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.set_xlim(time[0], time[-1])
    ax.grid(True, linewidth=0.4, alpha=0.6)
    # above the axes, not over the lines
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize="small", frameon=False,
              ncols=min(4, ds.sizes["controller"]))
    title = comparison_title(ds)
    if own:
        fig.suptitle(f"{what}" + (f"\n{title}" if title else ""), fontsize="medium")
    _save_png(fig, path)
    return fig


def _corner_grid(ds: xr.Dataset, rows: list[str], figsize_row: float = 2.0):
    corners = [_label(c) for c in ds["corner"].values]
    fig = _new_figure((13.0, 1.2 + figsize_row * len(rows)))
    axes = np.atleast_2d(fig.subplots(len(rows), len(corners), sharex=True, sharey=True,
                                      squeeze=False))
    for j, corner in enumerate(corners):
        axes[0, j].set_title(f"corner {corner}", fontsize="medium")
        axes[-1, j].set_xlabel("time (s)")
    return fig, axes, corners


def plot_comparison_damper_forces(comparison, path=None):
    """The secondary damper force on the carbody (kN, up +) at each corner against time: one
    row per suspension (passive: the viscous dampers), one column per corner (1R, 1L, 2R, 2L),
    all panels on the same scale, solid lines in each suspension's colour. Saved as PNG at
    ``path`` when given; returns the `Figure`."""
    ds = _comparison_dataset(comparison)
    if "secondary_damper_force" not in ds.variables:
        raise ValueError("the dataset lacks the channel secondary_damper_force")
    names = _controller_names(ds)
    fig, axes, corners = _corner_grid(ds, names)
    time = ds["time"].values
    force = ds["secondary_damper_force"].transpose("controller", "time", "corner").values / 1e3
    for i, name in enumerate(names):
        for j in range(len(corners)):
            ax = axes[i, j]
            ax.plot(time, force[i, :, j], linewidth=0.8, color=_style(name).get("color"))
            ax.axhline(0.0, color="0.6", linewidth=0.5)
            ax.grid(True, linewidth=0.4, alpha=0.6)
        axes[i, 0].set_ylabel(f"{_controller_label(name)}\nforce (kN)")
    axes[0, 0].set_xlim(time[0], time[-1])
    title = comparison_title(ds)
    fig.suptitle("secondary damper force on the carbody (kN, up +)" + (f"\n{title}" if title else ""),
                 fontsize="medium")
    _save_png(fig, path)
    return fig


def plot_comparison_voltages(comparison, path=None):
    """The command voltage v (V) of each MR damper against time: one row per controlled
    suspension, one column per corner. A comparison without a controlled suspension gets one
    panel saying so. Saved as PNG at ``path`` when given; returns the `Figure`."""
    ds = _comparison_dataset(comparison)
    names = [n for n in _controller_names(ds) if n != "passive"]
    title = comparison_title(ds)
    if not names or "damper_command_voltage" not in ds.variables:
        fig = _new_figure((8.0, 3.0))
        ax = fig.subplots()
        why = "passive suspension only" if not names else "ideal actuators"
        ax.text(0.5, 0.5, f"{why}: no command voltages", ha="center",
                va="center", transform=ax.transAxes)
        ax.set_axis_off()
        fig.suptitle("MR damper command voltage" + (f"\n{title}" if title else ""),
                     fontsize="medium")
        _save_png(fig, path)
        return fig
    fig, axes, corners = _corner_grid(ds, names)
    time = ds["time"].values
    volts = ds["damper_command_voltage"].transpose("controller", "time", "corner")
    all_names = _controller_names(ds)
    top = np.nanmax(volts.values) if np.isfinite(volts.values).any() else 1.0
    for i, name in enumerate(names):
        v = volts.isel(controller=all_names.index(name)).values
        for j in range(len(corners)):
            ax = axes[i, j]
            ax.plot(time, v[:, j], linewidth=0.7, color=_style(name).get("color"))
            ax.grid(True, linewidth=0.4, alpha=0.6)
        axes[i, 0].set_ylabel(f"{_controller_label(name)}\nvoltage (V)")
    axes[0, 0].set_xlim(time[0], time[-1])
    axes[0, 0].set_ylim(-0.05 * max(top, 1e-9), 1.08 * max(top, 1e-9))
    fig.suptitle("MR damper command voltage v (V)" + (f"\n{title}" if title else ""),
                 fontsize="medium")
    _save_png(fig, path)
    return fig


def comparison_frame(comparison) -> pd.DataFrame:
    """A comparison as one long table, the suspensions one after another: columns
    ``controller``, ``time`` [s], the carbody responses ``carbody_acceleration`` [m/s^2],
    ``carbody_bounce`` [m], ``carbody_pitch``, ``carbody_roll`` [rad], then per corner
    (1R, 1L, 2R, 2L) ``secondary_damper_force_<corner>`` [N, on the carbody, up +],
    ``damper_demand_force_<corner>`` [N, the outer loop's desired force, up +] and
    ``damper_command_voltage_<corner>`` [V]; the last two are empty (NaN) for the passive
    suspension and absent when no controlled suspension was run."""
    ds = _comparison_dataset(comparison)
    body = [c for c, _, _, _ in COMPARE_RESPONSES.values()]
    missing = [c for c in body if c not in ds.variables]
    if missing:
        raise ValueError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    channels = body + [c for c in COMPARE_CORNER_CHANNELS if c in ds.variables]
    frames = []
    for i, name in enumerate(_controller_names(ds)):
        frame = to_frame(ds[channels].isel(controller=i, drop=True)).reset_index()
        frame.insert(0, "controller", name)
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def comparison_psd(comparison, window=None, segment: float = PSD_SEGMENT_S) -> pd.DataFrame:
    """The PSD of the carbody CG vertical acceleration of each suspension, by Welch's method.

    ``scipy.signal.welch`` over the time ``window`` (start, end) [s] (None: the whole run):
    Hann-windowed segments of ``segment`` seconds (the whole window if shorter), overlapping by
    half, each with its mean removed; one-sided density. Columns ``frequency_hz`` [Hz, from 0 in
    steps of 1/segment] and one per suspension (its name) in (m/s^2)^2/Hz."""
    from scipy.signal import welch

    from .metrics import select_window

    ds = _comparison_dataset(comparison)
    if "carbody_acceleration" not in ds.variables:
        raise ValueError("the dataset lacks the channel carbody_acceleration")
    part = select_window(ds, None if window is None else tuple(window))
    time = part["time"].values
    # the output rate, without the float noise of the time stamps' differences
    fs = float(f"{(time.size - 1) / (time[-1] - time[0]):.9g}")
    nperseg = max(2, min(time.size, int(round(segment * fs))))
    columns = {}
    freq = None
    for i, name in enumerate(_controller_names(ds)):
        x = part["carbody_acceleration"].isel(controller=i).values
        freq, pxx = welch(x, fs=fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                          detrend="constant", scaling="density")
        columns[name] = pxx
    return pd.DataFrame({"frequency_hz": freq, **columns})


def plot_comparison_psd(psd: pd.DataFrame, path=None, *, title: str | None = None):
    """The acceleration spectra of `comparison_psd` on log-log axes, one line per suspension in
    the paper's style; the 0 Hz bin is left out. Saved as PNG at ``path`` when given; returns
    the `Figure`."""
    fig = _new_figure((10.0, 5.4))
    ax = fig.subplots()
    f = psd["frequency_hz"].values
    keep = f > 0
    top = 0.0
    for name in [c for c in psd.columns if c != "frequency_hz"]:
        y = psd[name].values[keep]
        y = np.where(y > 0, y, np.nan)  # a log axis cannot show 0
        if np.isfinite(y).any():
            top = max(top, float(np.nanmax(y)))
        ax.loglog(f[keep], y, linewidth=1.1, label=_controller_label(name), **_style(name))
    if top > 0:  # twelve decades below the highest peak: a pure sine's numerical floor is not news
        ax.set_ylim(bottom=max(ax.get_ylim()[0], top * 1e-12))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD of acceleration ((m/s$^2$)$^2$/Hz)")
    if keep.any():
        ax.set_xlim(f[keep][0], f[keep][-1])
    ax.grid(True, which="major", linewidth=0.5, alpha=0.7)
    ax.grid(True, which="minor", linewidth=0.3, alpha=0.4)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize="small", frameon=False,
              ncols=min(4, max(1, len(psd.columns) - 1)))
    fig.suptitle(title or "PSD of the carbody CG vertical acceleration", fontsize="medium")
    _save_png(fig, path)
    return fig


def write_compare_outputs(comparison, out_dir, doc: dict) -> list[Path]:
    """Write a controller comparison into ``out_dir``, all or nothing (`write_folder`):
    ``compare.json`` (``doc``, the ``Comparison.to_dict()`` document, strict JSON),
    ``compare.nc`` (``combined()`` as NetCDF, see `netcdf_ready`), ``compare.csv``
    (`comparison_frame`), ``acceleration.png``, ``displacement.png``, ``pitch.png``,
    ``roll.png`` (`plot_comparison_response`), ``damper_forces.png``
    (`plot_comparison_damper_forces`), ``voltages.png`` (`plot_comparison_voltages`), and the
    acceleration spectra over the metric window ``doc["settings"]["window_s"]`` (None: the
    whole run): ``psd.png`` (`plot_comparison_psd`) and ``psd.csv`` (`comparison_psd`).
    ``comparison`` is a `railride.comparison.Comparison` or its combined Dataset. Returns the
    written paths."""
    text = _json_text(doc)
    ds = _comparison_dataset(comparison)
    settings = doc.get("settings") if isinstance(doc.get("settings"), dict) else {}
    window = settings.get("window_s")
    psd = comparison_psd(ds, window)
    start, end = window if window is not None else (float(ds["time"][0]), float(ds["time"][-1]))
    segment = min(PSD_SEGMENT_S, end - start)
    psd_title = (f"PSD of the carbody CG vertical acceleration, {start:g}-{end:g} s (Welch, "
                 f"{segment:g} s Hann segments, 50 % overlap)")
    context = comparison_title(ds)
    if context:
        import textwrap

        psd_title += "\n" + textwrap.fill(context, 120)
    writers = {
        "psd.png": lambda path: plot_comparison_psd(psd, path, title=psd_title),
        "psd.csv": lambda path: psd.to_csv(path, index=False),
        "compare.json": lambda path: path.write_text(text, encoding="utf-8"),
        "compare.nc": lambda path: write_netcdf(ds, path),
        "compare.csv": lambda path: comparison_frame(ds).to_csv(path, index=False),
        "damper_forces.png": lambda path: plot_comparison_damper_forces(ds, path),
        "voltages.png": lambda path: plot_comparison_voltages(ds, path),
    }
    for response in COMPARE_RESPONSES:
        writers[f"{response}.png"] = (lambda r: lambda path: plot_comparison_response(ds, r, path))(response)
    return write_folder(out_dir, [(name, writers[name]) for name in COMPARE_FILES])


# -- tuning and sweeps (railride.tuning, railride.sweep) ------------------------------------
def curves_frame(curves) -> pd.DataFrame:
    """The sensitivity curves of `railride.tuning.tune` (its ``curves``) as one long table:
    columns ``phase``, ``pass`` (1, 2, ... within the phase), ``parameter`` ("table.entry"),
    ``value`` (SI), ``objective`` (the tuning objective of that run; the normalised force
    tracking error for the inner phase) and ``chosen`` (True on the value kept after that
    parameter's sweep in that pass). One row per value, the curves in the order they ran."""
    rows = []
    for c in curves:
        values = np.asarray(c.values, dtype=float)
        objective = np.asarray(c.objective, dtype=float)
        for v, o in zip(values, objective):
            rows.append((str(c.phase), int(c.sweep_pass), str(c.parameter), float(v), float(o),
                         bool(v == float(c.chosen))))
    return pd.DataFrame(rows, columns=list(CURVE_COLUMNS))


def _gain_unit(parameter: str) -> str | None:
    """The unit of a "table.entry" gain (from railride.control), or None."""
    import dataclasses

    from . import control

    classes = {"inner": control.InnerLoop, "pid": control.PID, "attitude": control.Attitude,
               "ride": control.Ride}
    table, _, entry = parameter.partition(".")
    for f in dataclasses.fields(classes[table]) if table in classes else ():
        if f.name == entry:
            return f.metadata.get("unit")
    return None


def _zero_axis(ax, zero_x: float, edge: float, right: float) -> None:
    """A log x axis whose left edge (below ``edge``) stands for the value 0, plotted at
    ``zero_x``: shaded, with a tick "0"; decade ticks above ``edge``."""
    from matplotlib.ticker import FixedLocator, NullFormatter

    ax.axvspan(ax.get_xlim()[0], edge, color="0.9", zorder=0, linewidth=0)
    lo, hi = math.ceil(math.log10(edge)), math.floor(math.log10(right))
    decades = [10.0 ** k for k in range(lo, hi + 1)]
    labels = [f"$10^{{{k}}}$" for k in range(lo, hi + 1)]
    if not decades:  # a range within one decade: label its ends
        decades = [edge * 2.0, right / 1.6]
        labels = [f"{v:.3g}" for v in decades]
    ax.set_xticks([zero_x, *decades], ["0", *labels])
    minor = [j * 10.0 ** k for k in range(math.floor(math.log10(edge)), hi + 1) for j in range(2, 10)
             if edge < j * 10.0 ** k < right]
    ax.xaxis.set_minor_locator(FixedLocator(minor))
    ax.xaxis.set_minor_formatter(NullFormatter())


def plot_sensitivity(curves, path=None, *, title: str | None = None, ax=None):
    """The sensitivity curves of a tuning study: one panel per parameter (in the order tuned),
    the objective against the parameter's value on a log axis, one line per pass (coloured by
    pass). The value 0 (the gain switched off) cannot sit on a log axis: it is plotted at the
    shaded left edge, on a tick labelled 0, as an open square joined by a dotted line. The value
    kept after each pass is a star; a dashed red line marks the final choice, which the panel's
    title gives. The inner-loop panels (B, G) show the normalised force-tracking error.

    ``ax``: one Axes per parameter to draw in (the legend goes into the first, and ``title``
    is left out), or None for a new Agg figure. Saved as PNG at ``path`` when given
    (atomically); returns the figure.
    """
    from matplotlib import colormaps
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    curves = list(curves)
    if not curves:
        raise ValueError("no sensitivity curves to plot")
    parameters = list(dict.fromkeys(c.parameter for c in curves))
    new_figure = ax is None
    if new_figure:
        ncols = min(4, len(parameters))
        nrows = math.ceil(len(parameters) / ncols)
        fig = _new_figure((3.3 * ncols + 0.6, 2.6 * nrows + 1.0))
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    else:
        axes = list(np.ravel(ax))
        if len(axes) != len(parameters):
            raise ValueError(f"ax: {len(parameters)} Axes (one per parameter: "
                             f"{', '.join(parameters)}), got {len(axes)}")
        fig = axes[0].figure
    max_pass = max(int(c.sweep_pass) for c in curves)
    cmap = colormaps["viridis"]

    def colour(sweep_pass):
        return cmap(0.85 * (sweep_pass - 1) / max(1, max_pass - 1))

    any_zero = False
    for ax, parameter in zip(axes, parameters):
        mine = [c for c in curves if c.parameter == parameter]
        values = [np.asarray(c.values, dtype=float) for c in mine]
        chosen = [float(c.chosen) for c in mine]
        positive = np.concatenate([v[v > 0] for v in values] + [np.array([x for x in chosen if x > 0])])
        has_zero = any((v == 0).any() for v in values) or any(x == 0 for x in chosen)
        any_zero = any_zero or has_zero
        lo, hi = (positive.min(), positive.max()) if positive.size else (1.0, 1.0)
        zero_x, edge = lo / 5.0, lo / 2.2

        def x(v):
            v = np.asarray(v, dtype=float)
            return np.where(v > 0, v, zero_x)

        for c, vals in zip(mine, values):
            order = np.argsort(vals)
            vals, obj = vals[order], np.asarray(c.objective, dtype=float)[order]
            col, pos = colour(int(c.sweep_pass)), vals > 0
            ax.plot(vals[pos], obj[pos], "-o", color=col, markersize=2.5, linewidth=1.1)
            if (~pos).any():
                ax.plot(x(vals[~pos]), obj[~pos], "s", color=col, markerfacecolor="none",
                        markersize=4.5)
                if pos.any():
                    ax.plot([zero_x, vals[pos][0]], [obj[~pos][0], obj[pos][0]], ":", color=col,
                            linewidth=1.0)
            k = np.flatnonzero(vals == float(c.chosen))
            if k.size:
                ax.plot(x(c.chosen), obj[k[0]], "*", color=col, markersize=10,
                        markeredgecolor="k", markeredgewidth=0.5, zorder=5)
        final = chosen[-1]
        ax.axvline(float(x(final)), color="tab:red", linestyle="--", linewidth=0.9, zorder=1)
        ax.set_xscale("log")
        ax.set_xlim((zero_x if has_zero else lo) / 1.8, hi * 1.8)
        if has_zero:
            _zero_axis(ax, zero_x, edge, hi * 1.8)
        unit = _gain_unit(parameter)
        ax.set_title(f"{parameter}" + (f" ({unit})" if unit else "") + f"\nchosen {final:.3g}",
                     fontsize="small")
        ax.set_ylabel("tracking error" if parameter.startswith("inner.") else "objective",
                      fontsize="small")
        ax.tick_params(labelsize="small")
        ax.grid(True, which="major", linewidth=0.4, alpha=0.6)
    for ax in axes[len(parameters):]:
        ax.set_visible(False)
    handles = [Line2D([], [], color=colour(k), marker="o", markersize=3, label=f"pass {k}")
               for k in range(1, max_pass + 1)]
    handles.append(Line2D([], [], color="0.3", marker="*", linestyle="none", markersize=9,
                          markeredgecolor="k", markeredgewidth=0.5, label="kept in that pass"))
    handles.append(Line2D([], [], color="tab:red", linestyle="--", label="final value"))
    if any_zero:
        handles.append(Patch(color="0.9", label="value 0 (gain off)"))
    if not new_figure:
        axes[0].legend(handles=handles, loc="best", fontsize="x-small")
        _save_png(fig, path)
        return fig
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 6),
               fontsize="small", frameon=False)
    fig.suptitle(title or "Sensitivity of the tuning objective, one parameter at a time",
                 fontsize="medium")
    _save_png(fig, path)
    return fig


def write_tune_outputs(curves, out_dir, doc: dict, gains_text: str, *,
                       title: str | None = None) -> list[Path]:
    """Write the results of a tuning study into ``out_dir``, all or nothing (`write_folder`;
    other files there, such as the run table ``runs.csv``, stay): ``gains.toml``
    (``gains_text``, a gains file), ``sensitivity.png`` (`plot_sensitivity` of ``curves``),
    ``curves.csv`` (`curves_frame`) and ``tune.json`` (``doc`` as indented strict JSON).
    Returns the written paths."""
    text = _json_text(doc)  # refuse NaN before any file is written
    curves = list(curves)
    frame = curves_frame(curves)
    writers = {
        "gains.toml": lambda path: path.write_text(gains_text, encoding="utf-8"),
        "sensitivity.png": lambda path: plot_sensitivity(curves, path, title=title),
        "curves.csv": lambda path: frame.to_csv(path, index=False),
        "tune.json": lambda path: path.write_text(text, encoding="utf-8"),
    }
    return write_folder(out_dir, [(name, writers[name]) for name in TUNE_FILES])


#: axis labels of the sweep plot per grid column (gains: "table.entry (unit)")
_SWEEP_AXIS_LABELS = {"speed_m_s": "speed (m/s)", "wavelength_m": "wavelength (m)",
                      "amplitude_m": "amplitude (m)", "rail_phase_deg": "rail phase (deg)",
                      "track_seed": "track seed", "voltage_v": "command voltage (V)",
                      "damper_scale": "damper force scale (-)",
                      "seed": "sensor noise seed"}
#: (RMS column, axis label) of the four panels of the sweep plot
_SWEEP_PANELS = (("acceleration_m_s2_rms", "acceleration RMS (m/s$^2$)"),
                 ("displacement_m_rms", "displacement RMS (m)"),
                 ("pitch_deg_rms", "pitch RMS (deg)"), ("roll_deg_rms", "roll RMS (deg)"))


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def sweep_plot_axis(doc: dict) -> str | None:
    """The grid column `plot_sweep` draws against: the one axis of ``doc["settings"]["grid"]``
    besides ``suspension`` with more than one value, if there is exactly one and its values are
    numbers; else None."""
    grid = (doc.get("settings") or {}).get("grid") or {}
    several = [c for c, values in grid.items() if c != "suspension" and len(values) > 1]
    if len(several) != 1 or not all(_is_number(v) for v in grid[several[0]]):
        return None
    return several[0]


def _log_axis(axis: str, xs: list) -> bool:
    """A logarithmic x axis for values spanning 100:1, or 4:1 for a factor (damper_scale, whose
    grids are geometric)."""
    ratio = 4 if axis == "damper_scale" else 100
    return bool(xs) and min(xs) > 0 and max(xs) / min(xs) >= ratio


def _sweep_axis_label(column: str) -> str:
    if column in _SWEEP_AXIS_LABELS:
        return _SWEEP_AXIS_LABELS[column]
    unit = _gain_unit(column) if "." in column else None
    return f"{column} ({unit})" if unit else column


#: (column, axis label) of the two panels of the sweep's comfort plot
_SWEEP_COMFORT_PANELS = (("centre_N_MV_z", "N$_{MV,z}$, carbody centre (EN 12299, vertical part)"),
                         ("centre_aw_Wk", "a$_w$ Wk, carbody centre (m/s$^2$)"))


def _sweep_lines(ax, rows, axis, column, suspensions):
    """One line per suspension of ``column`` against ``axis`` (a horizontal line for a
    suspension the axis does not act on)."""
    styles = {**COMPARE_STYLES, "mr": {"linestyle": "-", "color": "tab:green"}}
    labels = {"mr": "MR (constant voltage)"}
    for name in suspensions:
        mine = [r for r in rows if r["suspension"] == name]
        style = styles.get(name, {"linestyle": "-"})
        label = labels.get(name) or _controller_label(name)
        # a run that diverged has no metrics (None): it leaves a gap, not a point
        on = sorted((float(r[axis]), float(r[column])) for r in mine
                    if r.get(axis) is not None and r[column] is not None)
        off = [float(r[column]) for r in mine if r.get(axis) is None and r[column] is not None]
        if on:
            x, y = zip(*on)
            ax.plot(x, y, marker="o", markersize=3.5, linewidth=1.3, label=label, **style)
        elif off:
            ax.axhline(float(np.mean(off)), linewidth=1.0, alpha=0.8,
                       label=f"{label} (not swept)", **style)


def plot_sweep_comfort(doc: dict, path=None, *, axis: str | None = None):
    """The ride comfort of a sweep with comfort columns (``railride sweep --comfort``) against
    its swept axis: N_MV,z and a_w (Wk) at the carbody centre, two panels, one line per
    suspension as in `plot_sweep`; the N_MV,z panel marks the EN 12299 class bounds. Saved as
    PNG at ``path`` when given; returns the `Figure`."""
    from .comfort import COMFORT_SCALE

    axis = axis or sweep_plot_axis(doc)
    if axis is None:
        raise ValueError("the sweep has no single numeric axis with several values to plot against")
    rows = doc.get("rows") or []
    if not rows or any(c not in rows[0] for c, _ in _SWEEP_COMFORT_PANELS):
        raise ValueError("the sweep's rows hold no comfort indices (railride sweep --comfort)")
    suspensions = list(dict.fromkeys(r["suspension"] for r in rows))
    fig = _new_figure((10.0, 4.4))
    axes = fig.subplots(1, 2, sharex=True)
    xs = [float(r[axis]) for r in rows if r.get(axis) is not None]
    log_x = _log_axis(axis, xs)
    for ax, (column, ylabel) in zip(axes, _SWEEP_COMFORT_PANELS):
        _sweep_lines(ax, rows, axis, column, suspensions)
        ax.set_ylabel(ylabel, fontsize="small")
        ax.set_ylim(bottom=0)
        ax.grid(True, linewidth=0.4, alpha=0.6)
        ax.set_xlabel(_sweep_axis_label(axis))
        if log_x:
            ax.set_xscale("log")
    top = axes[0].get_ylim()[1]
    for bound, label in COMFORT_SCALE:
        if math.isfinite(bound) and bound < top:
            axes[0].axhline(bound, color="0.5", linewidth=0.6, linestyle=":")
            axes[0].annotate(f"{label} below", (0.99, bound), xycoords=("axes fraction", "data"),
                             fontsize="x-small", color="0.4", va="top", ha="right")
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncols=min(5, max(1, len(names))),
               fontsize="small", frameon=False)
    settings = doc.get("settings") or {}
    context = describe_scenario(settings.get("scenario") or {})
    title = f"Ride comfort against {_sweep_axis_label(axis)}"
    if context:
        import textwrap

        title += "\n" + textwrap.fill(context, 110)
    fig.suptitle(title, fontsize="medium")
    _save_png(fig, path)
    return fig


def plot_sweep(doc: dict, path=None, *, axis: str | None = None):
    """The RMS of the four carbody responses against the swept axis of a sweep (the
    ``railride.sweep/1`` document ``doc``): four panels, one line per suspension in the paper's
    style. A suspension the axis does not act on (passive against --voltage, say) ran once: a
    thin horizontal line at its value. ``axis`` defaults to `sweep_plot_axis`. Saved as PNG at
    ``path`` when given; returns the `Figure`."""
    axis = axis or sweep_plot_axis(doc)
    if axis is None:
        raise ValueError("the sweep has no single numeric axis with several values to plot against")
    rows = doc.get("rows") or []
    suspensions = list(dict.fromkeys(r["suspension"] for r in rows))
    fig = _new_figure((10.0, 7.2))
    axes = fig.subplots(2, 2, sharex=True).ravel()
    xs = [float(r[axis]) for r in rows if r.get(axis) is not None]
    log_x = _log_axis(axis, xs)
    for ax, (column, ylabel) in zip(axes, _SWEEP_PANELS):
        _sweep_lines(ax, rows, axis, column, suspensions)
        ax.set_ylabel(ylabel)
        ax.set_ylim(bottom=0)
        ax.grid(True, linewidth=0.4, alpha=0.6)
        if log_x:
            ax.set_xscale("log")
    for ax in axes[2:]:
        ax.set_xlabel(_sweep_axis_label(axis))
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncols=min(5, max(1, len(names))),
               fontsize="small", frameon=False)
    settings = doc.get("settings") or {}
    context = describe_scenario(settings.get("scenario") or {})
    duration = (settings.get("scenario") or {}).get("duration_s")
    extra = [p for p in (f"{duration:g} s" if _is_number(duration) else "",
                         describe_dampers(settings) if settings.get("damper") else "") if p]
    if extra:
        context = ", ".join([context, *extra]) if context else ", ".join(extra)
    title = f"RMS of the carbody responses against {_sweep_axis_label(axis)}"
    if context:
        import textwrap

        title += "\n" + textwrap.fill(context, 110)
    fig.suptitle(title, fontsize="medium")
    _save_png(fig, path)
    return fig


def write_sweep_outputs(out_dir, doc: dict) -> list[Path]:
    """Write the summary of a sweep into ``out_dir`` beside the run table ``runs.csv`` that
    `railride.sweep.run_cases` keeps there: ``sweep.json`` (``doc``) and, when the grid has one
    numeric axis with several values (`sweep_plot_axis`), ``sweep.png`` (`plot_sweep`) and, if
    the rows hold the comfort indices, ``comfort.png`` (`plot_sweep_comfort`). Returns the
    written paths."""
    text = _json_text(doc)
    files = [("sweep.json", lambda path: path.write_text(text, encoding="utf-8"))]
    axis = sweep_plot_axis(doc)
    if axis is not None:
        files.append(("sweep.png", lambda path: plot_sweep(doc, path, axis=axis)))
        rows = doc.get("rows") or []
        if rows and all(c in rows[0] for c, _ in _SWEEP_COMFORT_PANELS):
            files.append(("comfort.png", lambda path: plot_sweep_comfort(doc, path, axis=axis)))
    return write_folder(out_dir, files)


# -- frequency responses (railride.vehicle.Vehicle.frequency_response) ---------------------------
#: the rail patterns of `frf_frame`, in order
FRF_PATTERNS = ("in-phase", "anti-phase")
#: per carbody response: (name, channel of the frequency response, magnitude columns with their
#: factor from the channel's unit, axis label of the plot (its unit), magnitude column plotted)
FRF_RESPONSES = (
    ("bounce", "carbody_bounce", (("bounce_m_per_m", 1.0),), "bounce (m/m)", "bounce_m_per_m"),
    ("pitch", "carbody_pitch", (("pitch_rad_per_m", 1.0), ("pitch_deg_per_m", 180.0 / math.pi)),
     "pitch (deg/m)", "pitch_deg_per_m"),
    ("roll", "carbody_roll", (("roll_rad_per_m", 1.0), ("roll_deg_per_m", 180.0 / math.pi)),
     "roll (deg/m)", "roll_deg_per_m"),
    ("acceleration", "carbody_acceleration", (("acceleration_m_s2_per_m", 1.0),),
     "acceleration ((m/s$^2$)/m)", "acceleration_m_s2_per_m"),
)
#: the magnitude columns of `frf_frame`, in order
FRF_MAGNITUDES = tuple(c for *_, columns, _, _ in FRF_RESPONSES for c, _ in columns)
#: a response whose largest magnitude is below this fraction of the largest over the patterns
#: is "not excited" by that pattern (e.g. roll by in-phase rails: exactly 0 on a symmetric car)
FRF_NOT_EXCITED = 1e-9
#: the columns of `modes_frame` (modes.csv)
MODE_COLUMNS = ("mode", "label", "frequency_hz", "damped_frequency_hz", "damping_ratio")


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


def frf_peaks(frame: pd.DataFrame) -> dict:
    """Per pattern and magnitude column of `frf_frame`: {"magnitude", "frequency_hz"} at the
    largest magnitude on the grid; a response the pattern does not excite (`FRF_NOT_EXCITED`)
    has "frequency_hz" None."""
    out = {}
    top = {c: float(frame[c].max()) for c in FRF_MAGNITUDES}
    for pattern, part in frame.groupby("pattern", sort=False):
        out[pattern] = {}
        for c in FRF_MAGNITUDES:
            values = part[c].values
            k = int(np.argmax(values))
            excited = values[k] > FRF_NOT_EXCITED * top[c] and values[k] > 0
            out[pattern][c] = {"magnitude": float(values[k]),
                               "frequency_hz": float(part["frequency_hz"].values[k]) if excited else None}
    return out


def modes_frame(modes) -> pd.DataFrame:
    """The modes of `Vehicle.modes()` (Mode objects or their ``to_dict()``) as a table: ``mode``
    (1, 2, ... by undamped frequency), ``label``, ``frequency_hz`` (undamped),
    ``damped_frequency_hz``, ``damping_ratio``."""
    rows = []
    for i, m in enumerate(modes, start=1):
        d = m if isinstance(m, dict) else m.to_dict()
        rows.append((i, d["label"], float(d["frequency_hz"]), float(d["damped_frequency_hz"]),
                     float(d["damping_ratio"])))
    return pd.DataFrame(rows, columns=list(MODE_COLUMNS))


#: line style per rail pattern of the frequency-response plot
FRF_STYLES = {"in-phase": {"color": "tab:blue", "linestyle": "-"},
              "anti-phase": {"color": "tab:red", "linestyle": "--"}}


def plot_frf(frame: pd.DataFrame, modes=None, path=None, *, title: str | None = None):
    """Magnitudes of the carbody frequency responses (`frf_frame`) against frequency on log-log
    axes: one panel per response (bounce m/m, pitch and roll deg/m, acceleration (m/s^2)/m),
    one line per rail pattern. ``modes`` (`modes_frame`, or Mode objects) are marked as dotted
    vertical lines at their undamped natural frequencies, numbered at the top of each panel
    (modes within 1 % of each other share a line) and listed below the plot. A response a
    pattern does not excite is not drawn; the panel says so. Saved as PNG at ``path`` when
    given; returns the `Figure`."""
    if modes is not None and not isinstance(modes, pd.DataFrame):
        modes = modes_frame(modes)
    fig = _new_figure((11.0, 8.2))
    axes = fig.subplots(2, 2, sharex=True).ravel()
    patterns = list(dict.fromkeys(frame["pattern"]))
    f_all = frame["frequency_hz"].values
    lo, hi = float(f_all.min()), float(f_all.max())
    groups = []  # (frequency, [mode numbers]) of the modes inside the plotted range
    if modes is not None:
        for _, m in modes.sort_values("frequency_hz").iterrows():
            f = float(m["frequency_hz"])
            if not lo <= f <= hi:
                continue
            if groups and f <= groups[-1][0] * 1.01:
                groups[-1][1].append(int(m["mode"]))
            else:
                groups.append((f, [int(m["mode"])]))
    # one label per cluster of lines closer than 10 % (they would overlap on the log axis)
    labels_at = []  # (frequency, [mode numbers])
    for f, numbers in groups:
        if labels_at and f <= labels_at[-1][2] * 1.10:
            labels_at[-1] = (labels_at[-1][0], labels_at[-1][1] + numbers, f)
        else:
            labels_at.append((f, list(numbers), f))
    labels_at = [(math.sqrt(first * last), numbers) for first, numbers, last in labels_at]
    for ax, (name, _, _, ylabel, column) in zip(axes, FRF_RESPONSES):
        top = float(frame[column].max())
        silent = []
        for pattern in patterns:
            part = frame[frame["pattern"] == pattern]
            y = part[column].values
            if not (top > 0 and y.max() > FRF_NOT_EXCITED * top):
                silent.append(pattern)
                continue
            ax.loglog(part["frequency_hz"].values, np.where(y > 0, y, np.nan), linewidth=1.3,
                      label=pattern, **FRF_STYLES.get(pattern, {}))
        ax.set_xscale("log")
        ax.set_xlim(lo, hi)
        if all(p in silent for p in patterns):
            ax.set_yscale("linear")
        for f, _ in groups:
            ax.axvline(f, color="0.45", linestyle=":", linewidth=0.9, zorder=0)
        for f, numbers in labels_at:
            ax.annotate(_mode_numbers(numbers), (f, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(0, 2), textcoords="offset points", ha="center", va="bottom",
                        fontsize="x-small", color="0.3")
        if silent:
            everywhere = all(p in silent for p in patterns)
            ax.text(0.5 if everywhere else 0.02, 0.5 if everywhere else 0.03,
                    f"not excited by {' or '.join(silent)} rails", transform=ax.transAxes,
                    fontsize="medium" if everywhere else "small", color="0.35",
                    ha="center" if everywhere else "left")
            if everywhere:
                ax.set_yticks([])
        ax.set_ylabel(ylabel)
        ax.set_title(f"carbody {name}", fontsize="medium", pad=12)
        ax.grid(True, which="major", linewidth=0.5, alpha=0.7)
        ax.grid(True, which="minor", linewidth=0.3, alpha=0.35)
    for ax in axes[2:]:
        ax.set_xlabel("frequency (Hz)")
    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    labels = [f"{lab} rails" if lab in FRF_PATTERNS else lab for lab in labels]
    if groups:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], color="0.45", linestyle=":", linewidth=0.9))
        labels.append("undamped natural frequencies:")
        shown = {n for _, numbers in groups for n in numbers}
        for _, m in modes.iterrows():  # the modes in the plotted range, as text entries
            if int(m["mode"]) in shown:
                handles.append(Line2D([], [], linestyle="none"))
                labels.append(f"{int(m['mode'])}: {m['label']}, {float(m['frequency_hz']):.3g} Hz")
    fig.legend(handles, labels, loc="outside lower center", ncols=min(4, len(labels)),
               fontsize="small", frameon=False, handlelength=2.2)
    fig.suptitle(title or "Carbody frequency responses per metre of rail amplitude",
                 fontsize="medium")
    _save_png(fig, path)
    return fig


def _mode_numbers(numbers) -> str:
    """[4, 5, 6, 7] -> "4-7", [8, 9] -> "8,9", [1] -> "1"."""
    numbers = sorted(numbers)
    if len(numbers) > 2 and numbers == list(range(numbers[0], numbers[-1] + 1)):
        return f"{numbers[0]}-{numbers[-1]}"
    return ",".join(str(n) for n in numbers)


def write_frf_outputs(frame: pd.DataFrame, modes, out_dir, doc: dict, *,
                      title: str | None = None) -> list[Path]:
    """Write the frequency responses of `railride frf` into ``out_dir``, all or nothing:
    ``frf.csv`` (`frf_frame` ``frame``), ``frf.json`` (``doc``, strict JSON), ``frf.png``
    (`plot_frf`) and ``modes.csv`` (`modes_frame` of ``modes``). Returns the written paths."""
    text = _json_text(doc)
    table = modes if isinstance(modes, pd.DataFrame) else modes_frame(modes)
    writers = {
        "frf.csv": lambda path: frame.to_csv(path, index=False),
        "frf.json": lambda path: path.write_text(text, encoding="utf-8"),
        "frf.png": lambda path: plot_frf(frame, table, path, title=title),
        "modes.csv": lambda path: table.to_csv(path, index=False),
    }
    return write_folder(out_dir, [(name, writers[name]) for name in FRF_FILES])


# -- NetCDF -----------------------------------------------------------------------------------
def netcdf_ready(ds: xr.Dataset) -> xr.Dataset:
    """A copy of ``ds`` that scipy's netCDF3 writer accepts without losing data.

    netCDF3 has no 64-bit integers: integer variables (the ``sample`` and ``wheelset``
    coordinates) are stored as int32, which holds them exactly. Text (the JSON records
    ``scenario`` and ``vehicle_params``) is stored as UTF-8 and reads back unchanged.
    """
    out = ds.copy()
    for name, var in ds.variables.items():
        if var.dtype.kind in "iu" and var.dtype != np.int32:
            if var.size and (var.values.min() < np.iinfo(np.int32).min
                             or var.values.max() > np.iinfo(np.int32).max):
                raise ValueError(f"{name}: integers beyond int32 cannot be stored in netCDF3")
            out[name] = var.astype(np.int32)
    return out


def write_netcdf(ds: xr.Dataset, path: Path) -> None:
    """Write ``ds`` to ``path`` as netCDF3 (scipy engine, no extra dependency)."""
    netcdf_ready(ds).to_netcdf(path, engine="scipy")


# -- the output folder ------------------------------------------------------------------------
def check_out_dir(out_dir) -> Path:
    """Reject an output location that cannot be a folder, before any work is done."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"output folder {out_dir} exists and is not a folder")
    for parent in out_dir.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise ValueError(f"output folder {out_dir}: {parent} is not a folder")
            break
    return out_dir


def _json_text(doc: dict) -> str:
    """``doc`` as indented strict JSON (NaN or infinity raises ValueError)."""
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


def _move_into(stage: Path, out_dir: Path, names) -> None:
    """Move the staged files ``names`` into an existing ``out_dir``; on failure put everything
    back."""
    backup = stage / ".previous"
    backup.mkdir()
    moved, saved = [], []
    try:
        for name in names:
            target = out_dir / name
            if target.exists() or target.is_symlink():
                os.replace(target, backup / name)
                saved.append(name)
            os.replace(stage / name, target)
            moved.append(name)
    except BaseException:
        for name in moved:
            try:
                os.replace(out_dir / name, stage / name)
            except OSError:
                pass
        for name in saved:
            try:
                os.replace(backup / name, out_dir / name)
            except OSError:
                pass
        raise


def write_folder(out_dir, files) -> list[Path]:
    """Write a set of files into ``out_dir``, all or nothing.

    ``files`` is a sequence of ``(name, write)`` pairs: ``write(path)`` must create the file
    ``path``. Everything is first written, in the given order, into a hidden staging folder
    beside ``out_dir`` (``.NAME.staging-XXXXXXXX``, same parent, so renames are atomic). Only
    when every file exists are they moved in: a missing ``out_dir`` is created by renaming the
    staging folder; in an existing one, files of the same names are replaced (other files stay)
    and restored if a move fails. On any error the staging folder is removed and ``out_dir`` is
    left as it was. Returns the written paths, in the given order.
    """
    files = list(files)
    names = [name for name, _ in files]
    if len(set(names)) != len(names) or any(Path(n).name != n or n.startswith(".") for n in names):
        raise ValueError(f"write_folder: file names must be distinct plain names, got {names}")
    out_dir = check_out_dir(out_dir)
    parent = out_dir.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    stage = None
    for _ in range(100):
        candidate = parent / f".{out_dir.name}.staging-{secrets.token_hex(4)}"
        try:
            candidate.mkdir()
        except FileExistsError:
            continue
        stage = candidate
        break
    if stage is None:
        raise OSError(f"cannot create a staging folder in {parent}")
    try:
        for name, write in files:
            write(stage / name)
            if not (stage / name).is_file():
                raise OSError(f"the writer of {name} created no file")
        if not out_dir.exists():
            try:
                os.rename(stage, out_dir)  # a new folder appears complete, in one step
                stage = None
            except OSError:
                if not out_dir.is_dir():  # not a race with another writer: a real failure
                    raise
        if stage is not None:
            _move_into(stage, out_dir, names)
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
    return [out_dir / name for name in names]


def write_outputs(result, out_dir, metrics_doc: dict) -> list[Path]:
    """Write the files of a run into ``out_dir``, all or nothing (`write_folder`).

    Files: ``ride.nc`` (the Dataset as NetCDF, see `netcdf_ready`), ``ride.csv`` (`to_frame`),
    ``metrics.json`` (``metrics_doc`` as indented JSON; NaN or infinity is refused) and
    ``body_responses.png`` (`plot_body_responses`). ``result`` is a `RideResult` or its Dataset.
    Returns the written paths.
    """
    ds = _dataset(result)
    text = _json_text(metrics_doc)  # refuse NaN before any file is written
    writers = {
        "ride.nc": lambda path: write_netcdf(ds, path),
        "ride.csv": lambda path: to_frame(ds).to_csv(path),
        "metrics.json": lambda path: path.write_text(text, encoding="utf-8"),
        "body_responses.png": lambda path: plot_body_responses(ds, path),
    }
    return write_folder(out_dir, [(name, writers[name]) for name in OUTPUT_FILES])


def write_damper_outputs(cycles, out_dir, doc: dict, *, title: str | None = None) -> list[Path]:
    """Write the hysteresis cycles of `railride.rig.cycles` into ``out_dir``, all or nothing:
    ``loops.png`` (`plot_hysteresis`), ``cycles.csv`` (`cycles_frame`) and ``damper.json``
    (``doc`` as indented strict JSON). Returns the written paths."""
    text = _json_text(doc)
    writers = {
        "loops.png": lambda path: plot_hysteresis(cycles, path, title=title),
        "cycles.csv": lambda path: cycles_frame(cycles).to_csv(path, index=False),
        "damper.json": lambda path: path.write_text(text, encoding="utf-8"),
    }
    return write_folder(out_dir, [(name, writers[name]) for name in DAMPER_FILES])


def write_tracking_outputs(tracking, out_dir, doc: dict, *, title: str | None = None) -> list[Path]:
    """Write a force-tracking run of `railride.rig.track` into ``out_dir``, all or nothing:
    ``tracking.png`` (`plot_tracking`), ``tracking.csv`` (`to_frame` of its Dataset: time, the
    rig channels and ``desired_force``) and ``tracking.json`` (``doc``). Returns the paths."""
    text = _json_text(doc)
    writers = {
        "tracking.png": lambda path: plot_tracking(tracking, path, title=title),
        "tracking.csv": lambda path: to_frame(tracking.dataset).to_csv(path),
        "tracking.json": lambda path: path.write_text(text, encoding="utf-8"),
    }
    return write_folder(out_dir, [(name, writers[name]) for name in TRACKING_FILES])
