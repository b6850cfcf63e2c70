"""Flat tables (pandas DataFrames) of railride's results, the CSV files of the output folders.

Each builder reshapes one kind of result without computing anything new:

* `to_frame`: the time histories of a ride result Dataset (``ride.csv``, ``tracking.csv``);
* `cycles_frame`: the steady-state cycles of the damper rig (``cycles.csv``);
* `comparison_frame`: a controller comparison's responses and damper channels (``compare.csv``);
* `curves_frame`: the sensitivity curves of a tuning study (``curves.csv``);
* `modes_frame`: the vehicle's modes (``modes.csv``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from railride.errors import InputError
from railride.analysis.labels import CARBODY_RESPONSES, controller_names, coordinate_label
from railride.model.modes import MODE_COLUMNS as MODE_COLUMNS, modes_frame as modes_frame  # the modal table

#: string variables of a result that hold JSON records, not time histories
RECORD_VARIABLES = ("scenario", "vehicle_params")
#: the time histories of a damper rig run (railride.run.rig), in CSV column order
RIG_CHANNELS = ("x", "xd", "F", "z", "y", "u", "v", "E")
#: the per-corner channels of `comparison_frame`, after the body responses
COMPARE_CORNER_CHANNELS = ("secondary_damper_force", "damper_demand_force", "damper_command_voltage")
#: the columns of `curves_frame` (curves.csv)
CURVE_COLUMNS = ("controller", "pass", "parameter", "value", "objective", "chosen")
#: the columns of `modes_frame` (modes.csv)


def to_frame(ds: xr.Dataset) -> pd.DataFrame:
    """The time histories of a result Dataset (`RideResult.dataset`) as one flat table.

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
    if not isinstance(ds, xr.Dataset):
        raise InputError(f"ds: expected an xarray Dataset (RideResult.dataset), got {type(ds).__name__}")
    if "time" not in ds.dims:
        raise InputError("the dataset has no time dimension: not a result of railride.run.simulation")
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
        labels = [
            [coordinate_label(v) for v in (ds[d].values if d in ds.coords else range(ds.sizes[d]))] for d in extra
        ]
        for j, combo in enumerate(np.ndindex(*[len(lab) for lab in labels])):
            suffix = "".join(labels[k][i] for k, i in enumerate(combo))
            columns[f"{name}_{suffix}"] = values[:, j]
    time = ds["time"].values
    if lead:
        index = pd.MultiIndex.from_product([ds["sample"].values, time], names=["sample", "time"])
    else:
        index = pd.Index(time, name="time")
    return pd.DataFrame(columns, index=index)


def cycles_frame(ds: xr.Dataset) -> pd.DataFrame:
    """The steady-state cycles of `railride.run.rig.cycles` (its ``Cycles.dataset``) as one long
    table: columns ``voltage`` [V, the constant command of the run], ``time`` [s], then x [m],
    xd [m/s], F [N, tension +], z, y [m], u, v [V], E [J, dissipated since the start of the
    run]; the voltages one after another, in the order they were given."""
    missing = [c for c in RIG_CHANNELS if c not in ds.variables]
    if missing or "voltage" not in ds.dims:
        raise InputError(
            f"expected the dataset of railride.run.rig.cycles (dims voltage, time; channels {', '.join(RIG_CHANNELS)})"
        )
    frame = ds[list(RIG_CHANNELS)].to_dataframe(dim_order=["voltage", "time"])
    return frame.reset_index()[["voltage", "time", *RIG_CHANNELS]]


def comparison_frame(ds: xr.Dataset) -> pd.DataFrame:
    """A comparison's combined Dataset (`Comparison.combined()`) as one long table, the
    suspensions one after another: columns ``controller``, ``time`` [s], the carbody responses
    ``carbody_acceleration`` [m/s^2], ``carbody_bounce`` [m], ``carbody_pitch``,
    ``carbody_roll`` [rad], then per corner (1R, 1L, 2R, 2L)
    ``secondary_damper_force_<corner>`` [N, on the carbody, up +],
    ``damper_demand_force_<corner>`` [N, the outer loop's desired force, up +] and
    ``damper_command_voltage_<corner>`` [V]; the last two are empty (NaN) for the passive
    suspension and absent when no controlled suspension was run."""
    if "controller" not in ds.dims or "time" not in ds.dims:
        raise InputError(
            "expected the combined() Dataset of a railride.studies.comparison.Comparison (dims controller, time)"
        )
    body = [channel for channel, _, _, _ in CARBODY_RESPONSES.values()]
    missing = [c for c in body if c not in ds.variables]
    if missing:
        raise InputError(f"the dataset lacks the channel(s) {', '.join(missing)}")
    channels = body + [c for c in COMPARE_CORNER_CHANNELS if c in ds.variables]
    frames = []
    for i, name in enumerate(controller_names(ds)):
        frame = to_frame(ds[channels].isel(controller=i, drop=True)).reset_index()
        frame.insert(0, "controller", name)
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def curves_frame(curves) -> pd.DataFrame:
    """The sensitivity curves of `railride.studies.tuning.tune` (``TuneResult.curves``, a sequence of
    `railride.studies.tune_result.Curve`) as one long table: columns ``controller`` (the law whose
    study it is, or "inner"), ``pass`` (1, 2, ... within the study), ``parameter``
    ("table.entry"), ``value`` (SI), ``objective`` (the tuning objective of that run; the
    normalised force tracking error for the inner loop) and
    ``chosen`` (True on the value kept after that parameter's sweep in that pass). One row per
    value, the curves in the order they ran."""
    rows = []
    for c in curves:
        values = np.asarray(c.values, dtype=float)
        objective = np.asarray(c.objective, dtype=float)
        for v, o in zip(values, objective):
            rows.append(
                (str(c.controller), int(c.sweep_pass), str(c.parameter), float(v), float(o), bool(v == float(c.chosen)))
            )
    return pd.DataFrame(rows, columns=list(CURVE_COLUMNS))
