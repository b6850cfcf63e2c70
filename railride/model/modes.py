"""The modes of the passive vehicle as numbers a table or JSON can hold (`checked_modes`), by
undamped natural frequency, with their table (`modes_frame`, modes.csv) and their document
(`Modes.to_dict`, ``railride.modes/1``: ``railride modes --format json``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride import validation
from railride.model.params import resolve_vehicle
from railride.model.plausible import notes
from railride.model.vehicle import Vehicle

#: the schema of `Modes.to_dict` (``railride modes --format json``)
SCHEMA = "railride.modes/1"
#: the columns of the modal table
MODE_COLUMNS = ("mode", "label", "frequency_hz", "damped_frequency_hz", "damping_ratio")


def modes_frame(modes) -> pd.DataFrame:
    """The modes of `Vehicle.modes()` as a table, from their records (``[m.to_dict() for m in
    vehicle.modes()]``): ``mode`` (1, 2, ... by undamped frequency), ``label``,
    ``frequency_hz`` (undamped), ``damped_frequency_hz``, ``damping_ratio``."""
    rows = []
    for i, d in enumerate(modes, start=1):
        rows.append(
            (i, d["label"], float(d["frequency_hz"]), float(d["damped_frequency_hz"]), float(d["damping_ratio"]))
        )
    return pd.DataFrame(rows, columns=list(MODE_COLUMNS))


@dataclass(frozen=True, eq=False)
class Modes:
    """The modes of the passive vehicle (`railride.model.vehicle.Mode`), by undamped frequency: a
    sequence of `Mode` with its table (`to_pandas`), records (`to_list`) and document
    (`to_dict`). ``vehicle``: the record of the vehicle they are the modes of
    (`railride.model.params.vehicle_record`: name, load, values)."""

    modes: tuple
    vehicle: dict | None = None

    def __iter__(self):
        return iter(self.modes)

    def __len__(self) -> int:
        return len(self.modes)

    def __getitem__(self, index):
        return self.modes[index]

    def to_list(self) -> list[dict]:
        """The records of the modes (``Mode.to_dict()``): the ``modes`` of the ``railride.modes/1``
        document (`to_dict`), of the ``railride.frf/1`` document and of each preset of
        ``railride.vehicles/1``."""
        return [m.to_dict() for m in self.modes]

    def to_dict(self) -> dict:
        """The ``railride.modes/1`` document (``railride modes --format json``): ``schema``,
        ``railride_version``, ``versions`` (`railride._version.versions`), ``vehicle`` (the record of
        the vehicle) and ``modes`` (`to_list`)."""
        from railride._version import __version__, versions

        if self.vehicle is None:
            raise ValueError("these modes carry no vehicle record (Modes.vehicle): make them with modes(vehicle)")
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "vehicle": self.vehicle,
            "modes": self.to_list(),
        }

    def to_pandas(self):
        """The modal table (`modes_frame`, modes.csv): mode number, label,
        undamped and damped frequency [Hz], damping ratio."""
        return modes_frame(self.to_list())


def modes(vehicle=None, *, params=None, load: float = 1.0) -> Modes:
    """The modes of the passive ``vehicle`` (``params`` is an alias: `VehicleParams`, a preset
    name or the path of a parameters file; default "paper") with the load factor ``load`` on its
    carbody (`VehicleParams.loaded`), by undamped natural frequency (`checked_modes`): nine, ten
    where the carbody bends (`Vehicle.n_dof`). They carry the vehicle's record (``vehicle``:
    name, load, values), which their document (`Modes.to_dict`) holds."""
    loaded, record = resolve_vehicle(vehicle, params, load)
    return checked_modes(Vehicle(loaded), record)


#: a damping ratio this far below 0 is the rounding of an undamped mode (a passive vehicle
#: with dampings >= 0 has none below 0); further below, the eigenvalues are not to be trusted
ROUNDING_ZETA = 1e-6


def checked_modes(vehicle, record: dict | None = None) -> Modes:
    """`Vehicle.modes` as numbers a table or JSON can hold: one mode per DOF (`Vehicle.n_dof`:
    nine, ten where the carbody bends), every frequency and damping ratio finite and >= 0
    (rounding below 0 shown as 0), with ``record``, the vehicle's record (`vehicle_record`;
    None: none, and no document). A vehicle whose bodies and
    springs are so far apart in size that double precision cannot separate its modes (a
    bogie of a gram on a stiff primary, a carbody of a billion tonnes: a mode not
    `Mode.resolved`, whose numbers are bounds) is a ValueError naming what went wrong and the
    parameters outside the typical ranges."""
    problem = None
    try:
        with np.errstate(all="ignore"):  # the failures are reported below, not as NumPy warnings
            found = vehicle.modes()
    except (ValueError, np.linalg.LinAlgError) as exc:
        found, problem = [], f"the eigenvalue solver failed ({exc})"
    out = []
    for i, m in enumerate(found, 1):
        values = (m.frequency_hz, m.damped_frequency_hz, m.damping_ratio)
        if not m.resolved or not all(np.isfinite(values)) or min(values) < -ROUNDING_ZETA:
            lost = "" if m.resolved else ", within the rounding of the vehicle's fastest root"
            problem = problem or (
                f"mode {i} ({m.label}) came out at {validation.shown(m.frequency_hz)} Hz with a damping "
                f"ratio of {validation.shown(m.damping_ratio)}{lost}"
            )
            continue
        out.append(dataclasses.replace(m, damping_ratio=max(m.damping_ratio, 0.0)))
    if problem is None and len(out) != vehicle.n_dof:
        problem = f"{len(out)} modes came out, not {vehicle.n_dof}"
    if problem is not None:
        outside = [n.split("'")[1] for n in notes(vehicle.params)]
        hint = f"; outside the typical ranges: {', '.join(outside)}" if outside else ""
        raise InputError(
            f"the modes of this vehicle cannot be computed in double precision: {problem}; its masses and "
            f"stiffnesses are too far apart in size{hint}"
        )
    return Modes(tuple(out), record)
