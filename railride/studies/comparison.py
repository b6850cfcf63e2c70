"""The paper's comparison (its Table 1, Figs. 8-11): passive against PID, SAS (attitude) and
SAS (attitude+ride) on one scenario, with what each controller asks of the dampers; on request
also the other semi-active laws (`railride.secondary.controllers`) and the MR dampers held at v_max or
v_min (passive-on, passive-off).

`compare` runs the passive vehicle (viscous dashpots) and, in one batch, the controlled vehicles
(MR dampers closed by their voltage law), the constant-voltage ones in another. The result keeps
one Dataset per suspension and the metrics along a ``controller`` dimension.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from railride.errors import InputError
from railride._version import __version__, utc_now, versions
from railride.secondary import dampers
from railride.secondary.control import CONSTANT_VOLTAGE, CONTROLLERS, LABELS, PAPER_CONTROLLERS, GainSet
from railride.defaults import DEFAULT_DAMPER
from railride.secondary.faults import check_faults, degradation
from railride.secondary.provenance import IN_SAMPLE, judged_on
from railride.analysis.comfort_record import comfort_record
from railride.model.params import VehicleParams, resolve_vehicle, vehicle_argument
from railride.model.plausible import notes
from railride.analysis.metrics import STATISTICS, reduction, ride_metrics, select_window, still_passive
from railride.plots import PNG_DPI, FigureOptions
from railride.run.checks import check
from railride.run.simulation import run as run_plan, simulate
from railride.model.track import as_scenario
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension, damper_model, damper_record
from railride.studies.progress import shows_progress

#: Table 1 of Harun et al. (RMS values): for display beside railride's results.
PAPER_TABLE1 = {
    "acceleration_m_s2": {"passive": 0.3195, "pid": 0.2601, "sas-attitude": 0.2567, "sas-attitude-ride": 0.2063},
    "displacement_m": {"passive": 0.0349, "pid": 0.0265, "sas-attitude": 0.0225, "sas-attitude-ride": 0.0201},
    "pitch_deg": {"passive": 0.9422, "pid": 0.3763, "sas-attitude": 0.2933, "sas-attitude-ride": 0.2273},
    "roll_deg": {"passive": 2.005, "pid": 1.701, "sas-attitude": 1.2001, "sas-attitude-ride": 1.0035},
}
PAPER_REDUCTION = {
    "acceleration_m_s2": {"pid": 18.6, "sas-attitude": 19.7, "sas-attitude-ride": 35.4},
    "displacement_m": {"pid": 24.1, "sas-attitude": 35.5, "sas-attitude-ride": 42.4},
    "pitch_deg": {"pid": 60.1, "sas-attitude": 68.9, "sas-attitude-ride": 75.9},
    "roll_deg": {"pid": 15.2, "sas-attitude": 40.1, "sas-attitude-ride": 50.0},
}


#: two RMS values that differ by less than this fraction of the larger are level (1 %, a choice):
#: a list of "beats" read off the fourth digit of one run hides the trade-offs that matter
LEVEL_TOLERANCE = 0.01


def is_level(x: float, y: float, tolerance: float) -> bool:
    """Whether two non-negative RMS values are level: |x - y| <= tolerance x max(|x|, |y|)
    (two zeros are level; a NaN is level with nothing)."""
    return bool(abs(x - y) <= tolerance * max(abs(x), abs(y)))


def _check_level(value) -> float:
    """``level_tolerance`` as a float in [0, 1)."""
    from railride.validation import number

    allowed = "a finite number >= 0 and < 1 (a fraction of the larger RMS; 0.01 is 1 %)"
    tol = number("level_tolerance", value, "nonnegative", allowed=allowed)
    if tol >= 1.0:
        raise InputError(f"level_tolerance = {value!r}: must be {allowed}")
    return tol


def check_controllers(names) -> list[str]:
    """The requested controllers in the order of `CONTROLLERS`; passive is always the baseline;
    "all" is every one. ``names``: a sequence of names, or one string of comma-separated names."""
    from railride import arguments

    if isinstance(names, str):
        names = names.split(",")
    names = [n.strip() for n in arguments.names("controllers", names, "controller names") if n.strip()]
    # every name checked, "all" beside others too: a misspelt name is never dropped silently
    unknown = [n for n in names if n not in CONTROLLERS and n != "all"]
    if unknown:
        raise InputError(f"unknown controller {unknown[0]!r}; allowed: {', '.join(CONTROLLERS)}, or all")
    if "all" in names:
        names = list(CONTROLLERS)
    if not names:
        raise InputError(f"no controller given; allowed: {', '.join(CONTROLLERS)}")
    return [n for n in CONTROLLERS if n in names or n == "passive"]


@dataclass(frozen=True, eq=False)
class Comparison:
    """Results of `compare`: ``datasets[name]`` per suspension, ``metrics`` (controller,
    response, statistic), RMS ``reductions`` against passive, and ``demands``: what each
    suspension asks of its dampers. ``comfort``: per suspension, the ride comfort indices
    (`railride.analysis.comfort.ride_comfort` over the metrics window) when `compare` computed them,
    else None."""

    names: list[str]
    datasets: dict
    metrics: xr.DataArray
    window: tuple | None
    gains: GainSet
    damper: Any  # a name or a model of railride.secondary.dampers, as given
    settings: dict = field(default_factory=dict)
    comfort: dict | None = None
    #: per ideal device ("ideal-damper", "ideal") and controller: the ride metrics of the same
    #: gains on that device, and the time it diverged (NaN if it did not); None if not run
    bounds: dict | None = None
    #: how the runs were integrated (also in ``settings``: dt_s, output_rate_hz, control_rate_hz)
    solver: SolverSettings | None = None
    #: with damper faults: the same comparison with healthy dampers (`railride.secondary.faults.degradation`)
    healthy: "Comparison | None" = None
    #: when it was made (UTC, ISO 8601)
    date: str = ""

    @property
    def reductions(self) -> xr.DataArray:
        """RMS reduction in % against passive, (passive - controlled) / passive x 100."""
        return self._reduction(self.metrics.sel(controller="passive"))

    def _reduction(self, base) -> xr.DataArray:
        """`reduction` against ``base``, or an error that says why passive did not move."""
        try:
            return reduction(self.metrics, base)
        except InputError:
            raise InputError(still_passive(self.settings.get("scenario") or {})) from None

    def demands(self) -> dict:
        """Per suspension, over the metrics window: RMS and peak damper force on the carbody [N],
        RMS and peak secondary deflection (suspension travel) [m], the bump stops' clearance [m]
        (None: none), their stiffness [N/m] (0: the clearance is only marked) and whether the
        travel reached the clearance, and for the controlled ones
        with MR dampers the mean command voltage [V] and the fraction of time at v_max (the
        ideal actuator has no voltage: those two entries are absent, as for passive)."""
        # the damper's own v_max (a preset's or a damper file's; the scale leaves it), inf for a
        # device without a voltage, which records none
        model = damper_model(self.damper)
        v_max = model.v_max if model.law not in (dampers.LAW_IDEAL, dampers.LAW_VISCOUS) else np.inf
        vehicle = self.settings.get("vehicle_params") or VehicleParams.preset("paper").to_dict()
        clearance = vehicle.get("z_stop")  # None: no bump stops
        stiffness = vehicle.get("k_stop", 0.0)  # 0: the clearance is marked, no stop force
        out = {}
        for name, ds in self.datasets.items():
            part = select_window(ds, self.window)
            f = np.abs(part["secondary_damper_force"].values)
            travel = np.abs(part["secondary_deflection"].values)
            row = {
                "force_rms_n": float(np.sqrt(np.mean(f**2))),
                "force_max_n": float(f.max()),
                "travel_rms_m": float(np.sqrt(np.mean(travel**2))),
                "travel_max_m": float(travel.max()),
                # the bump stops' clearance, and whether the travel reached it (then the stops
                # bound the travel and carry force: the result is the vehicle on its stops)
                "clearance_m": clearance,
                "stop_stiffness_n_per_m": stiffness,
                "reached_stops": bool(clearance is not None and travel.max() >= clearance),
            }
            if "damper_demand_force" in part:  # what the outer loop asked for
                fd = np.abs(part["damper_demand_force"].values)
                row["demand_rms_n"] = float(np.sqrt(np.mean(fd**2)))
                row["demand_max_n"] = float(fd.max())
            if "damper_command_voltage" in part:
                v = part["damper_command_voltage"].values
                row["voltage_mean_v"] = float(v.mean())
                row["voltage_at_max_fraction"] = float((v >= v_max - 1e-12).mean())
            out[name] = row
        return out

    def trade_offs(self) -> list[dict]:
        """Where a suspension wins one response by losing another: for each controller, the
        responses (RMS) it makes better and worse than passive, and for each pair of controllers,
        the responses on which each beats the other. Two RMS values within the comparison's
        level tolerance (``settings["level_tolerance"]``, relative to the larger, `is_level`) are
        level: on ``level_on``, neither better nor worse. Pairs where one is at least as good on
        every response are listed with an empty ``worse_on``. The same by peak-to-peak values
        in ``ptp_better_on``, ``ptp_worse_on`` and ``ptp_level_on``."""
        responses = [str(r) for r in self.metrics.response.values]
        tol = self.level_tolerance
        controlled = [n for n in self.names if n != "passive"]
        pairs = [(n, "passive") for n in controlled]
        pairs += [(a, b) for i, a in enumerate(controlled) for b in controlled[i + 1 :]]

        def sides(statistic: str, a: str, b: str, prefix: str = "") -> dict:
            values = self.metrics.sel(statistic=statistic)
            va, vb = values.sel(controller=a).values, values.sel(controller=b).values
            level = [r for r, x, y in zip(responses, va, vb) if is_level(x, y, tol)]
            return {
                f"{prefix}better_on": [r for r, x, y in zip(responses, va, vb) if r not in level and x < y],
                f"{prefix}worse_on": [r for r, x, y in zip(responses, va, vb) if r not in level and x > y],
                f"{prefix}level_on": level,
            }

        # the peaks too: a law that lowers a response's RMS may raise its peak-to-peak
        return [{"controller": a, "than": b, **sides("rms", a, b), **sides("ptp", a, b, "ptp_")} for a, b in pairs]

    @property
    def level_tolerance(self) -> float:
        """The relative difference of two RMS values below which they count as level (a
        fraction; `LEVEL_TOLERANCE` unless `compare` was given another)."""
        return float(self.settings.get("level_tolerance", LEVEL_TOLERANCE))

    def bounds_record(self) -> dict | None:
        """The JSON of `bounds`: per device and controller, the RMS of each response and its
        reduction against passive (None for a run that diverged), and diverged_at_s."""
        if not self.bounds:
            return None
        responses = [str(r) for r in self.metrics.response.values]
        base = self.metrics.sel(controller="passive", statistic="rms").values
        out: dict[str, dict] = {}
        for device, runs in self.bounds.items():
            out[device] = {}
            for name in (n for n in self.names if n in CONSTANT_VOLTAGE):  # no bound: said, not run
                none = {r: None for r in responses}
                out[device][name] = {"rms": none, "reduction_percent": none, "diverged_at_s": None, "note": NO_VOLTAGE}
            for name, run in runs.items():
                rms = run["metrics"].sel(statistic="rms").values  # in the order of `responses`
                ok = not np.isfinite(run["diverged_at_s"])
                red = (base - rms) / base * 100.0
                out[device][name] = {
                    "rms": {r: float(v) if ok else None for r, v in zip(responses, rms)},
                    "reduction_percent": {r: float(v) if ok else None for r, v in zip(responses, red)},
                    "diverged_at_s": None if ok else run["diverged_at_s"],
                }
        return out

    def _gains_record(self, name: str):
        """The gains of the outer loop ``name``; None for passive and the constant voltages."""
        controller = self.gains.controller(name)
        return None if controller is None else controller.to_dict()

    @property
    def paper_case(self) -> bool:
        """Whether this is the case of the paper's Table 1: its scenario (`paper-sine` with its
        settings, any duration) at its speed, with its vehicle and healthy dampers. Only then is
        the paper's table a reference for these numbers."""
        from railride.model.track import scenario as make_scenario

        def track(record):
            return {k: v for k, v in (record or {}).items() if k != "duration_s"}

        paper = make_scenario("paper-sine").describe()
        vehicle = self.settings.get("vehicle_params")
        if self.settings.get("faults"):  # the paper's dampers never fail
            return False
        return track(self.settings.get("scenario")) == track(paper) and (
            vehicle is None or vehicle == VehicleParams.preset("paper").to_dict()
        )

    def paper_ranking(self) -> dict | None:
        """How this comparison's order of the paper's three controllers agrees with the paper's
        Table 1, response by response: ``{response: {"paper": names, "railride": names,
        "agrees": bool}}`` (names best first, by RMS reduction), plus ``reduction_ratio``, the
        least and largest of railride's reduction over the paper's. An order agrees when every
        pair the paper ranks is ranked alike here or level (`is_level`, the comparison's
        tolerance). None unless this is the paper's case with its three controllers."""
        laws = [n for n in PAPER_CONTROLLERS if n != "passive"]
        if not self.paper_case or not all(n in self.names for n in laws):
            return None
        rms = self.metrics.sel(statistic="rms")
        red = self.reductions.sel(statistic="rms")
        out: dict = {}
        ratios = []
        for r in PAPER_REDUCTION:
            paper = sorted(laws, key=lambda n: -PAPER_REDUCTION[r][n])
            here = {n: float(rms.sel(controller=n, response=r)) for n in laws}
            agrees = all(
                here[a] < here[b] or is_level(here[a], here[b], self.level_tolerance)
                for i, a in enumerate(paper)
                for b in paper[i + 1 :]
            )
            out[r] = {"paper": paper, "railride": sorted(laws, key=lambda n: here[n]), "agrees": agrees}
            ratios += [float(red.sel(controller=n, response=r)) / PAPER_REDUCTION[r][n] for n in laws]
        out["reduction_ratio"] = [min(ratios), max(ratios)]
        return out

    @property
    def judged(self) -> tuple[str, str] | None:
        """How this run's track stands to the tracks the gains were tuned on, (kind, sentence)
        (`railride.secondary.provenance.judged_on`: in-sample, the tuned track at another
        speed, or held out); None where their provenance names no track."""
        return judged_on(self.gains, self.settings.get("scenario"))

    @property
    def in_sample(self) -> bool:
        """Whether the gains were tuned on this track at this speed (their provenance says so),
        whatever the duration and load (`GainSet.tuned_on`)."""
        return self.gains.tuned_on(self.settings.get("scenario"))

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import comparison_contents

        return comparison_contents(self)

    def to_dict(self) -> dict:
        """The JSON summary (schema railride.comparison/1, docs/cli.md)."""
        paper_case = self.paper_case
        red = self.reductions
        rows = []
        demands = self.demands()
        for name in self.names:
            m = self.metrics.sel(controller=name)
            row = {
                "name": name,
                "label": LABELS[name],
                "metrics": {
                    str(r): {s: float(m.sel(response=r, statistic=s)) for s in STATISTICS} for r in m.response.values
                },
                "damper": demands[name],
            }
            if name != "passive":
                row["reduction_percent"] = {
                    str(r): float(red.sel(controller=name, response=r, statistic="rms")) for r in m.response.values
                }
            row["paper"] = (  # None: a controller the paper does not have
                {
                    r: {
                        "rms": PAPER_TABLE1[r][name],
                        **({"reduction_percent": PAPER_REDUCTION[r][name]} if name != "passive" else {}),
                    }
                    for r in PAPER_TABLE1
                }
                if name in PAPER_CONTROLLERS and paper_case
                else None
            )
            if self.comfort is not None:  # only when computed: the schema stays as it was
                row["comfort"] = comfort_record(
                    self.comfort[name], None if name == "passive" else self.comfort["passive"]
                )
            rows.append(row)
        ran = self.gains.record(self.names)  # the gains the runs ran (GainSet.record)
        return {
            "schema": "railride.comparison/1",
            "railride_version": __version__,
            "versions": versions(),
            "date": self.date,
            # the gains record as every result's settings hold it: their source as far as it is
            # still true, their [provenance] and every value per suspension run
            "settings": {
                **self.settings,
                "gains": ran["source"],
                "gains_provenance": ran["provenance"],
                "gains_values": ran["values"],
            },
            "paper_case": paper_case,
            # only in the paper's case: the paper's comparison's order against its Table 1's
            **({"paper_ranking": pr} if (pr := self.paper_ranking()) else {}),
            "controllers": rows,
            "trade_offs": self.trade_offs(),
            "bounds": self.bounds_record(),
            # only with faults: the paper's comparison's document stays as it was
            **({"faults": degradation(self, self.healthy)} if self.healthy is not None else {}),
            "tuning": {
                "objective": self.gains.provenance.get("objective"),
                "command": self.gains.provenance.get("command"),
                # where the gains name the tracks they were tuned on: is this one of them
                "in_sample": (j := self.judged) is not None and j[0] == IN_SAMPLE,
                **({"track": {"kind": j[0], "note": j[1]}} if j else {}),
                # only when there are some: the paper's comparison's document stays as it was
                **({"untuned": u} if (u := self.gains.untuned(self.names)) else {}),
                **({"alike": a} if (a := self.gains.tuning_budget(self.names)) else {}),
            },
            "gains": {
                "source": ran["source"],  # a file changed since it was read is not that file
                "inner": self.gains.inner.to_dict(),
                **{n: self._gains_record(n) for n in self.names if n != "passive"},
            },
        }

    def to_pandas(self):
        """The metrics as one long table: a row per suspension, response and statistic, with
        the reduction against passive (NaN for passive itself)."""
        import pandas as pd

        keys = ["controller", "response", "statistic"]
        values = self.metrics.to_dataframe(name="value").reset_index()[keys + ["value"]]
        red = self._reduction(self.metrics.sel(controller="passive", drop=True))
        red = red.to_dataframe(name="reduction_percent").reset_index()[keys + ["reduction_percent"]]
        frame = pd.merge(values, red, on=keys, how="left")
        frame.loc[frame["controller"] == "passive", "reduction_percent"] = float("nan")
        return frame

    def plot(self, ax=None, response: str = "acceleration"):
        """One carbody response against time, one line per suspension (the paper's Figs. 8-11);
        into ``ax`` when given. Returns the figure."""
        from railride.plots.comparison import plot_comparison_response

        return plot_comparison_response(self, response, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI, history_formats=("nc", "csv")):
        """The `railride compare --out` folder (JSON, the time histories in each of
        ``history_formats``: nc, csv, mat, and the figures, each in every one of
        ``figure_formats``: png, pdf, svg; PNG at ``dpi``), written all or nothing. Returns the
        written paths."""
        from railride.output.files import write_compare_outputs

        figures = FigureOptions(figure_formats, dpi)
        return write_compare_outputs(self, folder, self.to_dict(), figures=figures, histories=history_formats)

    def combined(self) -> xr.Dataset:
        """All suspensions in one Dataset along ``controller`` (damper channels NaN for passive)."""
        parts = []
        for name in self.names:
            ds = self.datasets[name].drop_vars(
                ["scenario", "vehicle_params", "controller", "controller_gains"], errors="ignore"
            )
            parts.append(ds.expand_dims(controller=[name]))
        gains = [json.dumps(self._gains_record(n)) for n in self.names]
        out = xr.concat(parts, dim="controller", join="outer", data_vars="all", combine_attrs="drop_conflicts")
        first = self.datasets[self.names[0]]
        out["scenario"] = first["scenario"]
        out["vehicle_params"] = first["vehicle_params"]
        out["controller_gains"] = ("controller", np.array(gains), {"long_name": GAINS_NAME, "units": ""})
        out["inner_loop_gains"] = ((), json.dumps(self.gains.inner.to_dict()), {"long_name": INNER_NAME, "units": ""})
        out["controller"].attrs.update(SUSPENSION_ATTRS)
        out.attrs.update(
            title="railride controller comparison", gains_source=self.gains.source, settings=json.dumps(self.settings)
        )
        if "vehicle" in self.settings:  # the vehicle record, as ride.nc holds it too
            out.attrs["vehicle"] = json.dumps(self.settings["vehicle"])
        # the runs' times differ when they straddle a second (drop_conflicts drops them): the first
        # run's, so that the file always says when it was made
        if "created_utc" in first.attrs:
            out.attrs.setdefault("created_utc", first.attrs["created_utc"])
        return out


@shows_progress("compare", fraction=True)
def compare(
    scenario,
    vehicle=None,
    *,
    params=None,
    load: float = 1.0,
    controllers=PAPER_CONTROLLERS,
    gains: GainSet | None = None,
    damper=DEFAULT_DAMPER,
    damper_scale: float = 1.0,
    window=None,
    solver=None,
    sensor_noise=None,
    progress=True,
    comfort: bool = False,
    bounds: bool = True,
    faults=(),
    delay: int = 1,
    sensing=None,
    level_tolerance: float = LEVEL_TOLERANCE,
) -> Comparison:
    """Run the passive vehicle and each controller on ``scenario`` and collect the metrics.

    ``vehicle`` (``params`` is an alias): a preset name, the path of a parameters file or
    `VehicleParams` (default "paper"; `VehicleParams.resolve`), with the load factor ``load``
    on its carbody (`VehicleParams.loaded`); ``settings["vehicle"]`` records both
    (`railride.model.params.vehicle_record`).

    ``controllers`` names from `railride.secondary.control.CONTROLLERS` or "all" (default the paper's
    four, `PAPER_CONTROLLERS`; passive is always run as the baseline; passive-on and passive-off,
    MR dampers at a constant voltage, are not run on the ideal devices, which have none:
    ``settings["not_run"]`` says so); ``gains`` a `GainSet` (default: the shipped gains; tuned
    for another vehicle, load or track, ``settings["gains_mismatch"]`` says so in one line,
    `GainSet.mismatch`); ``damper`` the name of the controlled suspensions' dampers
    (`railride.secondary.dampers.NAMES`: an MR preset or "ideal", the
    ideal actuator) and ``damper_scale`` the factor on an MR damper's force capacity
    (`BoucWen.scaled`; 1 for the ideal actuator); passive stays the viscous baseline. Each
    suspension is `Suspension.named` (controller name, gains, damper, scale, ``sensor_noise``).
    ``window`` (start, end) s for the metrics; ``solver`` the `SolverSettings` of every run
    (default: the defaults), recorded in ``settings``. ``comfort``: also the ride comfort
    indices of each suspension over the same window (`Comparison.comfort`;
    ``controllers[i].comfort`` in `Comparison.to_dict`). ``bounds`` (with MR dampers): also
    run the same control laws and gains on the two ideal devices, the ideal semi-active damper
    ("ideal-damper") and the ideal actuator ("ideal"), so that every reduction is shown beside
    what those would reach (`Comparison.bounds`). ``faults``: dampers that fail in every
    controlled suspension (`railride.secondary.faults.DamperFault` or their text, e.g. "1R-off@2"); passive
    stays the healthy baseline, the comparison is also run with healthy dampers
    (`Comparison.healthy`; ``to_dict()["faults"]`` holds the degradation), and the bounds are
    not run (they are those of the healthy design). ``delay``: every controller's computation
    and communication delay in controller periods (`Suspension.delay`; the bounds have it too).
    ``sensing``: what every controller measures (`railride.secondary.sensing.Accelerometers`; None: the
    exact states; the bounds measure the same); a law that reads the bogies' states is not run
    with it (``settings["not_run"]`` says why). ``level_tolerance``: two RMS values closer than
    this fraction of the larger are level in `Comparison.trade_offs` (default 0.01, 1 %;
    recorded in ``settings``). ``progress``: True (the fraction done, shown on stderr after 2 s),
    False, or a callable taking the fraction done (`railride.studies.progress`). Every setting
    is checked before the first run."""
    from railride import arguments

    window = arguments.window("window", window)
    level_tolerance = _check_level(level_tolerance)
    comfort, bounds = arguments.flag("comfort", comfort), arguments.flag("bounds", bounds)
    given = vehicle_argument(vehicle, params)
    car, record = resolve_vehicle(given, load=load)
    solver = SolverSettings.of(solver)
    model = damper_model(damper, damper_scale)
    damper_scale = float(damper_scale)
    names = check_controllers(controllers)
    scenario = as_scenario(scenario)
    gains = GainSet.of(gains, scenario)
    # gains tuned for another vehicle, load or track: one line (the command line warns with it)
    mismatch = gains.mismatch(record, scenario.describe(), names, damper, damper_scale)
    faults = check_faults(faults, model)
    ideal = model.law == dampers.LAW_IDEAL
    # a constant voltage means nothing to the ideal devices: said in the settings, not run
    not_run = {n: NO_VOLTAGE for n in names if n in CONSTANT_VOLTAGE and ideal}
    if sensing is not None:
        from railride.secondary.sensing import reads_bogies
        from railride.model.vehicle import Vehicle

        body = Vehicle(car)
        for n in names:
            c = gains.controller(n)
            if c is not None and reads_bogies(c.gains(body)[0]):
                not_run[n] = "reads the bogies' states; the accelerometers are on the carbody only"
    names = [n for n in names if n not in not_run]
    closed = [n for n in names if n != "passive" and n not in CONSTANT_VOLTAGE]
    constant = [n for n in names if n in CONSTANT_VOLTAGE]
    bound_devices = [d for d in BOUND_DEVICES if bounds and closed and not ideal and not faults]
    # progress by sample-steps: the passive run is one sample, the other batches the rest
    share = 1.0 / (1 + len(constant) + len(closed) * (1 + len(bound_devices)))
    part = (lambda lo, w: lambda done: progress(lo + w * done)) if progress is not None else None
    # the batches, each checked by the check every simulation makes (railride.run.checks.check),
    # all of them before the first runs
    batches = [
        (group, [_named(n, gains, damper, damper_scale, noise, delay, sensing).with_faults(faults) for n in group])
        for group, noise in ((closed, sensor_noise), (constant, None))
        if group
    ]
    bound_batches = [
        [_named(n, gains, device, 1.0, sensor_noise, delay, sensing) for n in closed] for device in bound_devices
    ]
    passive = check(scenario, car, Suspension.passive(), solver)
    plans = [(group, check(scenario, car, suspensions, solver, "mark")) for group, suspensions in batches]
    for suspensions in bound_batches:  # run below with the laws that did not diverge
        check(scenario, car, suspensions, solver, "mark")
    datasets = {"passive": run_plan(passive, part and part(0.0, share)).dataset}
    done = 1
    # closed and open loops run as separate batches (a batch is all one or the other)
    for group, plan in plans:
        # a law whose gains are not stable on this device is said, not fatal: the others go on
        res = run_plan(plan, part and part(share * done, share * len(group)))
        for i, n in enumerate(group):
            if np.isfinite(res.diverged_at[i]):
                not_run[n] = (
                    f"diverged at t = {res.diverged_at[i]:.4g} s: these gains are not stable on damper "
                    f"{damper!r} at dt = {solver.dt:g} s"
                    + (
                        f" with a delay of {delay} controller periods (a shorter delay, other gains)"
                        if delay != 1 and n in closed
                        else " (another dt, or other gains)"
                    )
                )
            else:
                datasets[n] = res.dataset.isel(sample=i, drop=True)
        done += len(group)
    names = [n for n in names if n not in not_run]
    closed = [n for n in closed if n not in not_run]
    bound_values = {}
    for k, device in enumerate(bound_devices):
        # the ideal actuator may not be stable with gains tuned for a damper: marked, not fatal
        res = simulate(
            scenario,
            car,
            [_named(n, gains, device, 1.0, sensor_noise, delay, sensing) for n in closed],
            solver=solver,
            on_divergence="mark",
            progress=part and part(share * (done + len(closed) * k), share * len(closed)),
        )
        m = res.metrics(window)
        bound_values[device] = {
            n: {"metrics": m.isel(sample=i, drop=True), "diverged_at_s": float(res.diverged_at[i])}
            for i, n in enumerate(closed)
        }
    metrics = xr.concat([ride_metrics(datasets[n], window) for n in names], dim="controller")
    metrics = metrics.assign_coords(controller=("controller", names, SUSPENSION_ATTRS))
    # the settings from the objects, not read back from the runs
    settings = {
        "scenario": scenario.describe(),
        "vehicle": record,
        "vehicle_params": car.to_dict(),
        **({"warnings": warned} if (warned := notes(car)) else {}),
        "damper": damper_record(damper),
        "damper_scale": damper_scale,
        **solver.to_dict(),
        "window_s": None if window is None else [float(w) for w in window],
        "sensor_noise": None if sensor_noise is None else sensor_noise.__dict__,
        "level_tolerance": level_tolerance,
        **({"not_run": not_run} if not_run else {}),
        **({"faults": [f.label for f in faults]} if faults else {}),
        **({"delay_periods": int(delay)} if delay != 1 else {}),
        **({"sensing": sensing.to_dict()} if sensing is not None else {}),
        **({"gains_mismatch": mismatch} if mismatch else {}),
    }
    comfort_values = None
    if comfort:
        from railride.analysis.comfort import ride_comfort

        comfort_values = {n: ride_comfort(datasets[n], window=window) for n in names}
    healthy = None
    if faults:
        healthy = compare(
            scenario,
            given,
            load=load,
            controllers=names,
            gains=gains,
            damper=damper,
            damper_scale=damper_scale,
            window=window,
            solver=solver,
            sensor_noise=sensor_noise,
            comfort=comfort,
            bounds=False,
            delay=delay,
            sensing=sensing,
            level_tolerance=level_tolerance,
            progress=False,
        )
    return Comparison(
        names,
        datasets,
        metrics,
        window,
        gains,
        damper,
        settings,
        comfort_values,
        bound_values or None,
        solver,
        healthy,
        utc_now(),
    )


def _named(name, gains, damper, damper_scale, sensor_noise, delay, sensing=None) -> Suspension:
    """`Suspension.named`, with the controller's ``delay`` and ``sensing`` for a closed loop."""
    s = Suspension.named(name, gains, damper, damper_scale, sensor_noise=sensor_noise)
    return s.with_delay(delay).with_sensing(sensing) if s.closed_loop else s


#: the ``controller`` coordinate's attributes (CF: "" for a label) and the gains' record names
SUSPENSION_ATTRS = {"long_name": "suspension (passive or controller)", "units": ""}
GAINS_NAME, INNER_NAME = "the gains of each suspension (JSON)", "the inner loop's gains (JSON)"

#: the ideal devices `compare` runs beside the MR dampers: the best a damper could do with the
#: same control laws and gains, and what a force actuator would do
BOUND_DEVICES = ("ideal-damper", "ideal")
#: why passive-on and passive-off have no run on, and no bound from, the ideal devices
NO_VOLTAGE = "MR dampers at a constant voltage: no meaning on the ideal devices, which have no voltage"
