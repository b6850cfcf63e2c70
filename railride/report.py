"""The report layer: flat tables, plots and the output folder of a run.

* `to_frame` turns the time histories of a result Dataset into a pandas DataFrame.
* `plot_body_responses` draws the four carbody responses (acceleration, bounce, pitch, roll).
* `write_outputs` writes ``ride.nc``, ``ride.csv``, ``metrics.json`` and ``body_responses.png``
  into a folder, all or nothing.

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
        raise ValueError("the dataset has no time dimension: not a result of railride.simulate")
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
        return "carbody responses"
    texts = [describe_scenario(r) for r in records]
    if len(set(texts)) == 1:
        title = texts[0]
    else:
        names = sorted({r.get("name", "?") for r in records})
        title = "scenarios " + ", ".join(names)
    if "sample" in ds.dims:
        title = f"{title} ({ds.sizes['sample']} samples)"
    return f"carbody responses - {title}" if title else "carbody responses"


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


def _write_staged(ds: xr.Dataset, stage: Path, metrics_doc: dict) -> None:
    write_netcdf(ds, stage / "ride.nc")
    to_frame(ds).to_csv(stage / "ride.csv")
    text = json.dumps(metrics_doc, indent=2, allow_nan=False) + "\n"
    (stage / "metrics.json").write_text(text, encoding="utf-8")
    plot_body_responses(ds, stage / "body_responses.png")


def _move_into(stage: Path, out_dir: Path) -> None:
    """Move the staged files into an existing ``out_dir``; on failure put everything back."""
    backup = stage / ".previous"
    backup.mkdir()
    moved, saved = [], []
    try:
        for name in OUTPUT_FILES:
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


def write_outputs(result, out_dir, metrics_doc: dict) -> list[Path]:
    """Write the files of a run into ``out_dir``, all or nothing.

    Files: ``ride.nc`` (the Dataset as NetCDF, see `netcdf_ready`), ``ride.csv`` (`to_frame`),
    ``metrics.json`` (``metrics_doc`` as indented JSON; NaN or infinity is refused) and
    ``body_responses.png`` (`plot_body_responses`). ``result`` is a `RideResult` or its Dataset.

    Everything is first written into a hidden staging folder beside ``out_dir`` (same parent,
    so renames are atomic). Only when all four files exist are they moved in: a missing
    ``out_dir`` is created by renaming the staging folder; in an existing one, files of the
    same names are replaced (other files stay) and restored if a move fails. On any error the
    staging folder is removed and ``out_dir`` is left as it was. Returns the written paths.
    """
    ds = _dataset(result)
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
        _write_staged(ds, stage, metrics_doc)
        if not out_dir.exists():
            try:
                os.rename(stage, out_dir)  # a new folder appears complete, in one step
                stage = None
            except OSError:
                if not out_dir.is_dir():  # not a race with another writer: a real failure
                    raise
        if stage is not None:
            _move_into(stage, out_dir)
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
    return [out_dir / name for name in OUTPUT_FILES]
