"""The result of `railride.simulate`: the time histories as an xarray Dataset, built on first
use from the stepper's arrays (`build_dataset`), and `RideResult` with its metrics, comfort and
the result protocol."""

from __future__ import annotations

import dataclasses
import json
import platform
from typing import Any

import numpy as np
import xarray as xr

from railride.errors import InputError
from railride.secondary import dampers
from railride.model.params import PRESETS, VehicleParams
from railride.plots import PNG_DPI, FigureOptions
from railride.run.solver import SolverSettings
from railride.model.vehicle import (
    BENDING_LONG_NAME,
    CORNER_NAMES,
    DOF_LONG_NAMES,
    DOF_NAMES,
    DOF_RATE_LONG_NAMES,
    DOF_UNITS,
    LABEL_ATTRS,
    RAILS,
    WHEELSETS,
)

#: the schema of `RideResult.to_dict`, the document of ``railride simulate``
SCHEMA = "railride.simulation/1"


#: the attributes of the text variables of a result (per sample in a batch); CF conventions:
#: text has the units ""
TEXT_ATTRS = {
    "scenario": {"long_name": "the scenario's record (JSON)", "units": ""},
    "vehicle_params": {"long_name": "the vehicle's parameters (JSON)", "units": ""},
    "damper_faults": {"long_name": "damper faults (corner-kind[@time s], comma-separated; empty: none)", "units": ""},
    "controller": {"long_name": "outer-loop controller", "units": ""},
    "controller_gains": {"long_name": "the controller's gains (JSON)", "units": ""},
}


def has_damper_states(damper) -> bool:
    """Damper models with internal states and a voltage (not passive, not the ideal actuator)."""
    return damper is not None and damper.law != dampers.LAW_IDEAL


def build_dataset(
    out,
    vehicles,
    param_sets,
    scenarios,
    dt,
    output_rate,
    rows,
    batch,
    created,
    suspension,
    vcmd,
    closed=None,
    faults=(),
    integrator: str = "classical RK4, fixed step",
) -> xr.Dataset:
    """Named channels in SI units; a ``sample`` dimension only for a batch. ``faults``: each
    sample's damper faults (`railride.secondary.faults.DamperFault`), recorded as ``damper_faults`` when
    any sample has one."""
    import numba
    import scipy

    from railride._version import __version__

    damper = suspension.damper
    time = np.arange(rows) / output_rate
    channels = ride_channels(out, vehicles, param_sets, damper, vcmd, closed)
    scen = np.array([json.dumps(s.describe()) for s in scenarios])
    records = _records(param_sets)
    pars = np.array([records[id(p)] for p in param_sets])
    if closed is not None:
        ctrl = closed["controllers"]
        inner = None if closed["inner"] is None else closed["inner"].to_dict()  # the ideal devices: none
        attrs_ctrl = {
            "control_rate_hz": closed["rate"],
            "inner_loop": json.dumps(inner),
            "sensor_noise": json.dumps(
                None if closed["sensor_noise"] is None else dataclasses.asdict(closed["sensor_noise"])
            ),
        }
        controller_names = np.array([c.name for c in ctrl])
        controller_gains = np.array([json.dumps(c.to_dict()) for c in ctrl])
    texts = {"scenario": scen, "vehicle_params": pars}
    if any(faults):  # e.g. "1R-off@2.5,2L-disconnected"; empty for a healthy sample
        texts["damper_faults"] = np.array([",".join(f.label for f in fs) for fs in faults])
    if closed is not None:
        texts["controller"] = controller_names
        texts["controller_gains"] = controller_gains
    data: dict[str, tuple]  # name -> (dims, values, attrs), as xr.Dataset takes them
    if batch:
        data = {k: (("sample", "time") + d, v, a) for k, (d, v, a) in channels.items()}
        data.update({k: ("sample", v, TEXT_ATTRS[k]) for k, v in texts.items()})
    else:
        data = {k: (("time",) + d, v[0], a) for k, (d, v, a) in channels.items()}
        data.update({k: ((), v[0], TEXT_ATTRS[k]) for k, v in texts.items()})
    coords = {
        "time": ("time", time, LABEL_ATTRS["time"]),
        "corner": ("corner", list(CORNER_NAMES), LABEL_ATTRS["corner"]),
        "wheelset": ("wheelset", list(WHEELSETS), LABEL_ATTRS["wheelset"]),
        "rail": ("rail", list(RAILS), LABEL_ATTRS["rail"]),
    }
    if batch:
        coords["sample"] = ("sample", np.arange(len(param_sets)), LABEL_ATTRS["sample"])
    attrs = {
        "title": "railride ride simulation",
        "railride_version": __version__,
        "numpy_version": np.__version__,
        "numba_version": numba.__version__,
        "scipy_version": scipy.__version__,
        "xarray_version": xr.__version__,
        "python_version": platform.python_version(),
        "created_utc": created,
        "integrator": integrator,
        "dt_s": dt,
        "output_rate_hz": output_rate,
        "suspension": suspension.describe(),
        "damper": json.dumps(None if damper is None else damper.to_dict()),
        "sign_convention": "z up; pitch + lowers the front; roll + raises the left side; forces on the carbody, up +",
    }
    if closed is not None:
        attrs.update(attrs_ctrl)
    warned = plausibility_notes(param_sets)
    if warned:  # the vehicle outside full-size rail vehicles' ranges: kept with the result
        attrs["plausibility_warnings"] = json.dumps(warned)
    return xr.Dataset(data, coords=coords, attrs=attrs)


def ride_channels(out, vehicles, param_sets, damper, vcmd, closed, names=None) -> dict:
    """The time-history channels of a run's Dataset (`build_dataset`) from the stepper's arrays
    ``out``: name -> (extra dims, values with leading (sample, time), attrs). ``names``: only
    those of them the run has, computing none of the others (a study's costs read four of
    them: `RideResult.channels`)."""
    from railride.run.inputs import engine_matrices

    # T at the engine's size (a rigid carbody's bending row is 0): (n, N_DOF, 4)
    T = np.stack([engine_matrices(vehicles[id(p)])["T"] for p in param_sets])
    ksz = np.array([p.k_sz for p in param_sets])[:, None, None]
    want = (lambda name: True) if names is None else set(names).__contains__
    # (n, time, N_DOF) @ (n, N_DOF, 4): T^T q at every sample; the products only where asked for
    deflection = out["q"] @ T if want("secondary_deflection") or want("secondary_spring_force") else None
    flexible = any(vehicles[id(p)].M.shape[0] > len(DOF_NAMES) for p in param_sets)
    shape = out["w"].shape[:2] + (4, 2)
    # name -> (extra dims, values with leading (sample, time), attrs)
    channels: dict[str, tuple[tuple[str, ...], Any, dict[str, str]]] = {}
    for i, name in enumerate(DOF_NAMES):
        channels[name] = ((), out["q"][:, :, i], {"units": DOF_UNITS[i], "long_name": DOF_LONG_NAMES[i]})
        channels[f"{name}_velocity"] = (
            (),
            out["v"][:, :, i],
            {"units": f"{DOF_UNITS[i]}/s", "long_name": DOF_RATE_LONG_NAMES[i]},
        )
    if flexible:  # the carbody's first vertical bending mode (a rigid sample's is 0)
        b = len(DOF_NAMES)
        long = BENDING_LONG_NAME
        channels["carbody_bending"] = ((), out["q"][:, :, b], {"units": "m", "long_name": long})
        channels["carbody_bending_velocity"] = (
            (),
            out["v"][:, :, b],
            {"units": "m/s", "long_name": f"{long}, its rate"},
        )
        channels["carbody_bending_acceleration"] = (
            (),
            out["a"][:, :, b],
            {"units": "m/s^2", "long_name": f"{long}, its acceleration"},
        )
    channels["carbody_acceleration"] = (
        (),
        out["a"][:, :, 0],
        {"units": "m/s^2", "long_name": "carbody CG vertical acceleration"},
    )
    channels["carbody_pitch_acceleration"] = (
        (),
        out["a"][:, :, 1],
        {"units": "rad/s^2", "long_name": "carbody pitch acceleration"},
    )
    channels["carbody_roll_acceleration"] = (
        (),
        out["a"][:, :, 2],
        {"units": "rad/s^2", "long_name": "carbody roll acceleration"},
    )
    if want("carbody_corner_displacement"):
        channels["carbody_corner_displacement"] = (
            ("corner",),
            out["q"][:, :, :3] @ T[:, :3] + out["q"][:, :, len(DOF_NAMES) :] @ T[:, len(DOF_NAMES) :],
            {"units": "m", "long_name": "carbody vertical displacement above each secondary corner"},
        )
    if want("secondary_deflection"):
        channels["secondary_deflection"] = (
            ("corner",),
            deflection,
            {"units": "m", "long_name": "secondary vertical deflection, carbody minus bogie (extension +)"},
        )
    if want("secondary_deflection_velocity"):
        channels["secondary_deflection_velocity"] = (
            ("corner",),
            out["v"] @ T,
            {"units": "m/s", "long_name": "secondary vertical deflection rate, carbody minus bogie (extension +)"},
        )
    if want("secondary_spring_force"):
        channels["secondary_spring_force"] = (
            ("corner",),
            -ksz * deflection,
            {"units": "N", "long_name": "secondary vertical spring force on the carbody (up +)"},
        )
    channels["secondary_damper_force"] = (
        ("corner",),
        out["f"],
        {"units": "N", "long_name": "secondary vertical damper force on the carbody (up +)"},
    )
    if has_damper_states(damper):  # the ideal actuator has no states and no voltage
        d = out["d"]
        channels["damper_hysteretic_z"] = (
            ("corner",),
            d[:, :, 0::3],
            {"units": "m", "long_name": "Bouc-Wen hysteretic variable z of each damper"},
        )
        if damper.law == dampers.LAW_SPENCER:
            channels["damper_internal_displacement"] = (
                ("corner",),
                d[:, :, 1::3],
                {"units": "m", "long_name": "Spencer model internal displacement y"},
            )
        channels["damper_voltage"] = (
            ("corner",),
            d[:, :, 2::3],
            {"units": "V", "long_name": "damper coil voltage u after the coil lag"},
        )
        command = out["vc"] if closed is not None else np.broadcast_to(vcmd[:, None, :], d[:, :, 2::3].shape)
        channels["damper_command_voltage"] = (
            ("corner",),
            command,
            {"units": "V", "long_name": "commanded damper voltage v"},
        )
    if closed is not None:
        channels["damper_demand_force"] = (
            ("corner",),
            out["fd"],
            {"units": "N", "long_name": "desired damper force on the carbody (up +) from the outer loop"},
        )
    channels["rail_displacement"] = (
        ("wheelset", "rail"),
        out["w"].reshape(shape),
        {"units": "m", "long_name": "rail height under each wheel"},
    )
    channels["rail_velocity"] = (
        ("wheelset", "rail"),
        out["wd"].reshape(shape),
        {"units": "m/s", "long_name": "rail vertical velocity under each wheel"},
    )
    return channels if names is None else {k: v for k, v in channels.items() if want(k)}


def _records(param_sets) -> dict[int, str]:
    """The JSON record of each distinct vehicle object of a batch, by id: its runs share a few."""
    distinct = {id(p): p for p in param_sets}
    return {key: json.dumps(p.to_dict()) for key, p in distinct.items()}


def plausibility_notes(param_sets) -> list[str]:
    """The plausibility warnings (`railride.model.plausible.notes`) of the vehicles, each once."""
    from railride.model.plausible import notes

    return list(dict.fromkeys(n for p in param_sets for n in notes(p)))


@dataclasses.dataclass(frozen=True, eq=False, init=False, repr=False)
class RideResult:
    """Time histories (``.dataset``, an xarray Dataset) and the ride metrics of a run.

    The Dataset is assembled on first use, so a sweep that keeps only a few numbers per run
    does not pay for building it. A single run follows the result protocol (`railride.Result`):
    `to_dict` (the JSON document), `to_pandas`, `plot` and `save`. Frozen: its fields cannot
    be assigned (the Dataset built on first use is its only change, made once, here).
    """

    _dataset: xr.Dataset | None
    _build: Any
    _raw: dict | None
    #: the `Suspension` of the run (a list of them for a batch) and its `SolverSettings`
    suspension: Any
    solver: Any
    #: the `Scenario` and `VehicleParams` of the run (lists for a batch)
    scenario: Any
    params: Any

    def __init__(
        self,
        dataset: xr.Dataset | None = None,
        *,
        build=None,
        raw=None,
        suspension=None,
        solver=None,
        scenario=None,
        params=None,
    ):
        if (dataset is None) == (build is None):
            raise InputError("RideResult needs a dataset or a build function, not both")
        for name, value in (
            ("_dataset", dataset),
            ("_build", build),
            ("_raw", raw),
            ("suspension", suspension),
            ("solver", solver),
            ("scenario", scenario),
            ("params", params),
        ):
            object.__setattr__(self, name, value)

    @property
    def dataset(self) -> xr.Dataset:
        dataset = self._dataset
        if dataset is None:  # built once, on first use (frozen: past the dataclass's guard)
            dataset = self._build()
            object.__setattr__(self, "_dataset", dataset)
            object.__setattr__(self, "_build", None)
        return dataset

    def __getitem__(self, name):
        return self.dataset[name]

    def __repr__(self):
        return f"RideResult(\n{self.dataset!r}\n)"

    @property
    def diverged_at(self) -> np.ndarray:
        """Per sample, the time [s] at which the run diverged, NaN where it did not (only a run
        with ``on_divergence="mark"`` can hold a diverged sample)."""
        if self._raw is not None and "diverged_at" in self._raw:
            return self._raw["diverged_at"]
        return np.full(self.dataset.sizes.get("sample", 1), np.nan)

    @property
    def is_batch(self) -> bool:
        if self._raw is not None:
            return bool(self._raw["batch"])
        return "sample" in self.dataset.dims

    def metrics(self, window=None) -> xr.DataArray:
        """RMS and peak-to-peak of the four body responses; see `railride.analysis.metrics.ride_metrics`.
        Computed from the raw arrays when the Dataset has not been built (sweeps)."""
        from railride.analysis.metrics import check_window, metrics_from_arrays, ride_metrics

        diverged = np.isfinite(self.diverged_at)  # NaN: did not diverge
        if self._dataset is not None or self._raw is None:
            return ride_metrics(self.dataset, window, diverged=diverged)
        t, q, a = self._raw["time"], self._raw["q"], self._raw["a"]
        if window is not None:
            start, end = check_window(window, float(t[-1]), float(t[0]))
            keep = (t >= start - 1e-12) & (t <= end + 1e-12)
            if keep.sum() < 2:
                raise InputError(f"window = {start:g}:{end:g} s holds fewer than two output samples")
            q, a = q[:, keep], a[:, keep]
        out = metrics_from_arrays(a[..., 0], q[..., 0], q[..., 1], q[..., 2], diverged=diverged)
        return out if self._raw["batch"] else out.isel(sample=0, drop=True)

    def comfort(self, window=None, positions=("centre", "front", "rear"), weightings=("Wk", "Wb")):
        """Ride comfort on the carbody floor (ISO 2631-1 a_w and VDV, EN 12299 N_MV vertical
        part, Sperling Wz); see `railride.analysis.comfort.ride_comfort` and docs/comfort.md."""
        from railride.analysis.comfort import ride_comfort

        return ride_comfort(self.comfort_channels(), positions=positions, window=window, weightings=weightings)

    def comfort_channels(self) -> xr.Dataset:
        """What `railride.analysis.comfort.ride_comfort` reads (`channels`): the carbody's
        vertical, pitch and, where it bends, bending accelerations, and each run's vehicle
        record. A study's comfort then does not build every channel of every run (0.8 s of a
        1,000-run study's serial work, docs/performance.md)."""
        names = ("carbody_acceleration", "carbody_pitch_acceleration", "carbody_bending_acceleration")
        return self.channels(names, texts=("vehicle_params",))

    def channels(self, names, texts=()) -> xr.Dataset:
        """A Dataset of the channels ``names`` alone (those of them the run has) and the text
        variables ``texts`` ("vehicle_params"): the Dataset's where it is built, else from the
        stepper's arrays, computing no other channel (`ride_channels`). A study reads a few
        channels of every run: its comfort and its damper costs."""
        raw = self._raw
        if self._dataset is not None or raw is None or "channels" not in raw:
            ds = self.dataset
            return ds[[name for name in (*names, *texts) if name in ds.variables]]
        batch = bool(raw["batch"])
        lead = ("sample",) if batch else ()
        found = raw["channels"](names)
        data: dict[str, tuple] = {}
        for name in (n for n in names if n in found):  # in the order asked, as ``Dataset[names]``
            dims, values, attrs = found[name]
            data[name] = (lead + ("time",) + dims, values if batch else values[0], attrs)
        if "vehicle_params" in texts:
            params = list(self.params) if batch else [self.params]
            records = _records(params)
            text = np.array([records[id(p)] for p in params])
            data["vehicle_params"] = (lead, text if batch else text[0], TEXT_ATTRS["vehicle_params"])
        labels = {"corner": CORNER_NAMES, "wheelset": WHEELSETS, "rail": RAILS}
        used = {dim for dims, *_ in data.values() for dim in dims}
        coords = {"time": ("time", raw["time"], LABEL_ATTRS["time"])}
        coords.update({dim: (dim, list(values), LABEL_ATTRS[dim]) for dim, values in labels.items() if dim in used})
        if batch:
            coords["sample"] = ("sample", np.arange(len(self.params)), LABEL_ATTRS["sample"])
        return xr.Dataset(data, coords=coords)

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import ride_contents

        return ride_contents(self)

    def to_dict(self, window=None, *, comfort: bool = False, vehicle: dict | None = None) -> dict:
        """The JSON document of a single run (`SCHEMA`, docs/cli.md): the scenario, the vehicle,
        the suspension, the step and output rate with the metrics window, and the ride metrics
        over ``window`` (start, end) s (default: the whole run); with ``comfort`` also the ride
        comfort indices over it. ``vehicle`` names the vehicle as the caller chose it (e.g.
        ``{"vehicle_params_file": "car.toml"}``); by default ``{"vehicle_preset": name}`` for a
        preset's parameters, else ``{"vehicle_params": {...}}``. A batch has no such document:
        select a sample first."""
        from railride._version import __version__, versions
        from railride.analysis.metrics import check_window, to_dict

        if self.is_batch:
            raise InputError(
                f"to_dict describes a single run; this result is a batch of {self.dataset.sizes['sample']} samples"
            )
        record = self._record("scenario", self.scenario)
        duration = float(record["duration_s"]) if "duration_s" in record else float(self.dataset["time"][-1])
        start, end = (0.0, duration) if window is None else check_window(window, duration)
        solver = (
            self.solver
            if self.solver is not None
            else SolverSettings(self.dataset.attrs["dt_s"], self.dataset.attrs["output_rate_hz"])
        )
        doc = {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "scenario": record,
            **(self._vehicle_record() if vehicle is None else vehicle),
            "suspension": _suspension_record(self.suspension),
            "settings": {
                "dt_s": float(solver.dt),
                "output_rate_hz": float(solver.output_rate),
                "window_s": [float(start), float(end)],
            },
            "metrics": to_dict(self.metrics(window)),
            "travel": self.travel((start, end)),
        }
        if comfort:
            from railride.analysis.comfort_record import comfort_record

            doc["comfort"] = comfort_record(self.comfort(window))
        return doc

    def travel(self, window=None) -> dict:
        """The largest secondary deflection (suspension travel, any corner) over ``window``
        (start, end) s, the bump stops' clearance (None: none), their stiffness (0: the clearance
        is only marked) and whether the travel reached the clearance (stops with a stiffness
        then bound it and carry force): ``max_m``, ``clearance_m``, ``stop_stiffness_n_per_m``,
        ``reached_stops``. A single run (select a sample of a batch first)."""
        from railride.analysis.metrics import select_window

        if self.is_batch:
            raise InputError("travel describes a single run; select a sample of the batch first")
        params = self.params if self.params is not None else VehicleParams(**self._record("vehicle_params", None))
        part = select_window(self.dataset, window)
        top = float(np.nanmax(np.abs(part["secondary_deflection"].values)))
        z = params.z_stop  # with a stiffness of 0 the stops are only marked: reported, no force
        return {
            "max_m": top,
            "clearance_m": z,
            "stop_stiffness_n_per_m": params.k_stop,
            "reached_stops": bool(z is not None and top >= z),
        }

    def _record(self, name: str, value) -> dict:
        """The JSON record of the run's scenario or parameters: from the value the run kept,
        else from the Dataset."""
        if value is not None:
            return value.describe() if name == "scenario" else value.to_dict()
        return json.loads(str(self.dataset[name].values))

    def _vehicle_record(self) -> dict:
        """The vehicle's record (`railride.model.params.vehicle_record`: a preset's name, or
        "custom"; load 1, the values as run), then the keys of railride 0.4 (``vehicle_preset``
        or ``vehicle_params``)."""
        from railride.model.params import vehicle_record

        params = self.params
        if params is None:
            params = VehicleParams(**self._record("vehicle_params", None))
        name = next((k for k, v in PRESETS.items() if v == params), None)
        record = {"vehicle": vehicle_record(params, name)}
        if name is not None:
            return {**record, "vehicle_preset": name}
        return {**record, "vehicle_params": self._record("vehicle_params", params)}

    def to_pandas(self):
        """The time histories as a DataFrame, one column per scalar channel."""
        from railride.output.tables import to_frame

        return to_frame(self.dataset)

    def plot(self, ax=None, window=None, *, response=None):
        """The four body responses against time (`railride.plots.ride.plot_body_responses`),
        the y-axes fitting the metric ``window`` (start, end) s (None: the whole run).
        ``response``: one of "acceleration", "displacement", "pitch", "roll" (the names of
        `metrics` without their units), or a list of them, to draw only those (None: all four).
        ``ax``: None for a new figure, or one matplotlib Axes per response drawn: four Axes,
        or one Axes with ``response`` naming one (``plot(ax=ax, response="pitch")``; one Axes
        without it is an InputError). A response the run does not excite (roll on symmetric
        rails) says "not excited" in its panel instead of a trace of rounding noise. Returns the
        matplotlib Figure (the given Axes' figure), as every result's ``plot`` does."""
        from railride.plots.ride import plot_body_responses

        return plot_body_responses(self.dataset, ax=ax, window=window, response=response)

    def save(
        self,
        folder,
        window=None,
        *,
        comfort: bool = False,
        vehicle: dict | None = None,
        figure_formats=("png",),
        dpi: float = PNG_DPI,
        history_formats=("nc", "csv"),
    ) -> list:
        """Write ride.nc, ride.csv, metrics.json (`to_dict` with these arguments) and
        body_responses.png into ``folder``, all or nothing (`railride.output.files.write_outputs`).
        The figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``; the time
        histories in each of ``history_formats`` (nc, csv, mat: MATLAB). Returns the written
        paths."""
        from railride.output.files import write_outputs

        figures = FigureOptions(figure_formats, dpi)
        doc = self.to_dict(window, comfort=comfort, vehicle=vehicle)
        return write_outputs(self, folder, doc, figures=figures, histories=history_formats)


def _suspension_record(suspension) -> dict:
    """The ``suspension`` of the simulation document: ``{"type": "passive"}``, or for MR dampers
    at a constant voltage the type "mr", the damper's name (its record, every parameter, where it
    is no preset), the voltage and, when the preset was scaled, its ``damper_scale``; a closed
    loop is typed by its outer loop's name and adds its controller, inner loop and sensor noise
    (`Suspension.to_dict`)."""
    if suspension is None:
        return {"type": "passive"}
    if suspension.kind == "passive":
        return (
            {"type": "passive"}
            if suspension.damper is None
            else {"type": "passive", "damper": suspension.damper.to_dict()}
        )
    name = suspension.damper_name
    # a damper of the user's own parameters (a damper file): every parameter, as the studies record it
    damper = name if name in dampers.NAMES else suspension.damper.to_dict()
    record: dict[str, Any] = {"type": suspension.name, "damper": damper}
    if suspension.faults:
        record["faults"] = [f.label for f in suspension.faults]
    if suspension.delay != 1:
        record["delay_periods"] = suspension.delay
    if suspension.voltage is not None:
        record["voltage_v"] = float(suspension.voltage)
    if suspension.damper_scale != 1.0:
        record["damper_scale"] = suspension.damper_scale
    if suspension.closed_loop:
        full = suspension.to_dict()
        record.update({k: full[k] for k in ("controller", "inner_loop", "sensor_noise")})
    return record
