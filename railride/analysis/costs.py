"""What a suspension asks of its dampers, run by run: the columns a run table holds when a study
asks for them (`railride.studies.sweep.run_cases` with ``costs``; `railride.design`).

Per run, over the metrics window and the four corners: the RMS and the largest damper force on
the carbody [N], the largest secondary deflection (suspension travel) [m] and, for MR dampers
under a voltage law, the fraction of the time the command sits at the damper's v_max (NaN
where there is no command voltage: passive, the ideal devices), and the electrical power the
coils draw as a fraction of their power at v_max, mean(u^2) / v_max^2 with u the coil's
voltage (after its lag): a coil is a resistance, whose power goes as the square of its
voltage, so the fraction needs no coil data; times a coil's rated power it is that coil's mean
power. The first four are the quantities of `railride.studies.comparison.Comparison.demands`,
for many runs at once.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

#: the columns, in order: RMS and largest damper force [N], largest travel [m], the fraction of
#: time at v_max (0 to 1), the mean coil power as a fraction of the coil's power at v_max
COST_COLUMNS = ("force_rms_n", "force_max_n", "travel_max_m", "voltage_at_max_fraction", "coil_power_fraction")
#: the revision of the columns, part of a run's key in a run table (`run_cases`): a table written
#: with other columns is not taken for this one's on resume
COSTS_REVISION = 2


#: the channels of a run's Dataset that `damper_costs` reads (the last two only where the dampers
#: have a voltage)
COST_CHANNELS = ("secondary_damper_force", "secondary_deflection", "damper_command_voltage", "damper_voltage")


def damper_costs(ds: xr.Dataset, v_max=None) -> np.ndarray:
    """`COST_COLUMNS` of every sample of ``ds`` (a run's Dataset, with or without a ``sample``
    dimension, already cut to its window): an array (sample, 4). ``v_max``: the dampers'
    largest voltage [V] (None or inf: no voltage column, NaN)."""
    if "sample" not in ds.dims:
        ds = ds.expand_dims(sample=[0])

    def per_sample(name: str) -> np.ndarray:
        return np.abs(ds[name].transpose("sample", ...).values.reshape(ds.sizes["sample"], -1))

    force = per_sample("secondary_damper_force")
    travel = per_sample("secondary_deflection")
    out = np.full((ds.sizes["sample"], len(COST_COLUMNS)), np.nan)
    out[:, 0] = np.sqrt(np.mean(force**2, axis=1))
    out[:, 1] = force.max(axis=1)
    out[:, 2] = travel.max(axis=1)
    if "damper_command_voltage" in ds and v_max is not None and np.isfinite(v_max):
        volts = ds["damper_command_voltage"].transpose("sample", ...).values.reshape(ds.sizes["sample"], -1)
        out[:, 3] = np.mean(volts >= float(v_max) - 1e-12, axis=1)
    if "damper_voltage" in ds and v_max is not None and np.isfinite(v_max) and v_max > 0:
        coil = ds["damper_voltage"].transpose("sample", ...).values.reshape(ds.sizes["sample"], -1)
        out[:, 4] = np.mean((coil / float(v_max)) ** 2, axis=1)
    return out
