"""Ride in the frequency domain: the response PSDs, RMS values and ISO 2631-1 weighted RMS of
the carbody on a random track, from the frequency response and the track spectrum, without a
time simulation (docs/ride_spectrum.md).

For a standard spectrum (`railride.model.track.spectrum`: FRA classes, German low/high) the track
model has two independent components, the vertical profile z_v and the cross-level z_x, with
z_L = z_v + z_x/2 and z_R = z_v - z_x/2; every wheelset sees the same profile delayed by its
distance behind the leading one over the speed. So for any output y of a linear vehicle

    S_y(f) = |H_v(f)|^2 S_v(f) + |H_x(f)|^2 S_x(f),

with H_v the response to rails moving together (c_L = c_R = 1) and H_x to rails moving
against each other (c_L = 1/2, c_R = -1/2), and S(f) = S(Omega) 2 pi / V the one-sided
temporal PSD [m^2/Hz] at Omega = 2 pi f / V over the wavelength band of the random tracks.
RMS values are sqrt(integral S_y df) and weighted RMS sqrt(integral |W(f)|^2 S_y df), by the
trapezoid rule on a log grid.

Linear suspensions only: passive, or an outer loop on the ideal actuator (`railride.frequency.linear`).
A loop's demand is applied continuously, or, with ``control_rate``, through the engine's
sample-and-hold and delay, e^{-s T d} (1 - e^{-s T}) / (s T), T the controller period and d
the delay in periods (the fundamental of the held signal; aliasing is not modelled).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from railride.errors import InputError
from railride import limits, validation
from railride.defaults import DEFAULT_SPEED
from railride.analysis.comfort import FLOOR
from railride.frequency.frf import FMAX_LIMIT
from railride.frequency.linear import LinearModel, linear_model, linear_suspensions
from railride.model.params import VehicleParams, resolve_vehicle
from railride.model import psd_table
from railride.model.track import MAX_WAVELENGTH, RANDOM_NAMES, frequency_speed, is_random, spectrum
from railride.model.vehicle import CORNER_NAMES, Vehicle

SCHEMA = "railride.ride-spectrum/1"
#: the responses whose PSDs are computed: the floor points and the carbody
RESPONSES = (
    "floor_acceleration_centre",
    "floor_acceleration_front",
    "floor_acceleration_rear",
    "carbody_bounce_acceleration",
    "carbody_pitch_acceleration",
    "carbody_roll_acceleration",
    *(f"secondary_deflection_{c}" for c in CORNER_NAMES),
)
#: the ISO 2631-1 weightings applied at the floor points
WEIGHTINGS = ("Wb", "Wk")
#: the slowest controller rate of a sampled loop [Hz]
MIN_CONTROL_RATE = 1.0
#: the device that makes each suspension's secondary force: the passive vehicle's viscous
#: dashpots, or the ideal actuator (force = demand) under an outer loop; never the MR dampers,
#: which switch and clip and so have no frequency response (`railride compare` runs them)
PASSIVE_DEVICE = "passive viscous dampers"
ACTUATOR_DEVICE = "ideal actuator"
#: the plant: the vehicle with no secondary dampers, its secondary springs alone
NO_DAMPER_DEVICE = "no secondary dampers"


def reduction_percent(passive: float, value: float) -> float | None:
    """The reduction against passive as `railride compare` gives it, (passive - value) /
    passive x 100: positive where the suspension is better, negative where worse; None where
    the passive value is not positive."""
    return (passive - value) / passive * 100.0 if passive > 0 else None


def rail_patterns(vehicle: Vehicle, frequency: np.ndarray, speed: float) -> dict[str, np.ndarray]:
    """The rail inputs (n_f, 16: heights z_1L ... z_4R, then their rates) of the vertical
    profile (both rails 1) and of the cross-level (left 1/2, right -1/2), per unit amplitude,
    every wheelset delayed by its lag distance over the speed."""
    s = 2j * np.pi * frequency[:, None]
    delay = np.exp(-s * vehicle.wheelset_lag_distance / speed)  # (n_f, 4)
    out = {}
    for name, (cl, cr) in (("vertical", (1.0, 1.0)), ("cross-level", (0.5, -0.5))):
        u = np.empty((frequency.size, 16), complex)
        u[:, 0:8:2], u[:, 1:8:2] = cl * delay, cr * delay
        u[:, 8:16] = s * u[:, 0:8]
        out[name] = u
    return out


def hold(frequency: np.ndarray, control_rate: float | None, delay: int) -> np.ndarray:
    """The sample-and-hold with a delay of ``delay`` periods at ``control_rate`` [Hz] on a
    sinusoid's fundamental: e^{-sTd} (1 - e^{-sT}) / (sT); 1 everywhere without a rate."""
    if control_rate is None:
        return np.ones(frequency.size, complex)
    T = 1.0 / control_rate
    sT = 2j * np.pi * frequency * T
    with np.errstate(invalid="ignore", divide="ignore"):
        zoh = np.where(sT == 0, 1.0, (1 - np.exp(-sT)) / np.where(sT == 0, 1.0, sT))
    return np.exp(-sT * delay) * zoh


def responses(plant: LinearModel, gain: np.ndarray | None, u: np.ndarray, h: np.ndarray, frequency) -> np.ndarray:
    """The outputs (n_f, outputs) of ``plant`` ("plant" or "passive" model) to rail inputs
    ``u`` (n_f, 16), its corner forces being ``h`` times gain @ (x, xi) (gain 4 x 21 over
    (q, q', xi), None for none)."""
    n = plant.A.shape[0]
    s = 2j * np.pi * frequency
    Bw, Bf = plant.B[:, :16], plant.B[:, 16:20]
    Z = s[:, None, None] * np.eye(n) - plant.A
    K = np.zeros((frequency.size, 4, n), complex)
    if gain is not None:
        # xi = q_carbody / s: the integrals fold into the displacement columns
        K[:] = gain[:, :n]
        k = gain.shape[1] - n  # 3 integrals of the carbody displacements, or none
        K[:, :, :k] += gain[None, :, n:] / s[:, None, None]
        K *= h[:, None, None]
        Z = Z - Bf @ K
    x = np.linalg.solve(Z, (Bw @ u[..., None]))[..., 0]
    f = np.einsum("fcn,fn->fc", K, x)
    return np.einsum("on,fn->fo", plant.C, x) + u @ plant.D[:, :16].T + f @ plant.D[:, 16:20].T


def track_psd(name: str, frequency: np.ndarray, speed: float, band: tuple[float, float]) -> dict[str, np.ndarray]:
    """One-sided temporal PSDs [m^2/Hz] of the vertical profile and the cross-level of spectrum
    ``name`` at ``frequency`` [Hz] and ``speed`` [m/s], zero outside the wavelength ``band``
    (min, max) [m]."""
    wavenumber = 2 * np.pi * frequency / speed
    inside = (wavenumber >= 2 * np.pi / band[1] * (1 - 1e-12)) & (wavenumber <= 2 * np.pi / band[0] * (1 + 1e-12))
    out = {}
    for component in ("vertical", "cross-level"):
        S = np.zeros_like(frequency)
        S[inside] = spectrum(name, wavenumber[inside], component) * 2 * np.pi / speed
        out[component] = S
    return out


@dataclass(frozen=True, eq=False)
class RideSpectrum:
    """The frequency-domain ride of one or more linear suspensions on a track spectrum.

    ``psd``: a Dataset over (suspension, frequency) with one variable per response of
    `RESPONSES`, one-sided PSDs in (unit)^2/Hz, and the coordinate ``device`` (per suspension:
    `PASSIVE_DEVICE`, `ACTUATOR_DEVICE` or `NO_DAMPER_DEVICE`); ``rms`` and ``weighted``: DataArrays over
    (suspension, response) and (suspension, position, weighting); ``settings``: what made it.
    Every variable and coordinate carries ``long_name`` and ``units`` (CF; "1" where there is
    no unit). The result protocol: `to_dict`, `to_pandas` (one row per suspension and response:
    its device, RMS and, at the floor points, the weighted RMS, with their reductions against
    passive), `plot` (PSDs at the floor points), `save`.
    """

    psd: xr.Dataset
    rms: xr.DataArray
    weighted: xr.DataArray
    settings: dict
    params: VehicleParams

    @property
    def suspensions(self) -> tuple[str, ...]:
        return tuple(str(s) for s in self.psd["suspension"].values)

    @property
    def devices(self) -> dict[str, str]:
        """Per suspension, the device that makes its secondary force: `PASSIVE_DEVICE`,
        `ACTUATOR_DEVICE` or, for the plant, `NO_DAMPER_DEVICE`."""
        return {s: str(d) for s, d in zip(self.suspensions, self.psd["device"].values)}

    @property
    def reductions(self) -> tuple[dict, dict]:
        """The reductions against passive (`reduction_percent`, positive where better) of every
        suspension but passive: ({suspension: {response: % of RMS}}, {suspension: {point:
        {weighting: % of weighted RMS}}}); both empty when passive did not run."""
        if "passive" not in self.suspensions:
            return {}, {}
        rms, weighted = {}, {}
        for s in self.suspensions:
            if s == "passive":
                continue
            rms[s] = {
                r: reduction_percent(
                    float(self.rms.sel(suspension="passive", response=r)), float(self.rms.sel(suspension=s, response=r))
                )
                for r in RESPONSES
            }
            weighted[s] = {
                p: {
                    w: reduction_percent(
                        float(self.weighted.sel(suspension="passive", position=p, weighting=w)),
                        float(self.weighted.sel(suspension=s, position=p, weighting=w)),
                    )
                    for w in WEIGHTINGS
                }
                for p in FLOOR
            }
        return rms, weighted

    def to_pandas(self):
        import pandas as pd

        rms_red, weighted_red = self.reductions
        devices = self.devices
        rows = []
        for s in self.suspensions:
            for r in RESPONSES:
                row = {"suspension": s, "device": devices[s], "response": r, "unit": self.psd[r].attrs["rms_units"]}
                row["rms"] = float(self.rms.sel(suspension=s, response=r))
                row["rms_reduction_percent"] = rms_red.get(s, {}).get(r)
                point = r.removeprefix("floor_acceleration_")
                for w in WEIGHTINGS:
                    row[f"aw_{w}"] = (
                        float(self.weighted.sel(suspension=s, position=point, weighting=w)) if point in FLOOR else None
                    )
                    row[f"aw_{w}_reduction_percent"] = weighted_red.get(s, {}).get(point, {}).get(w)
                rows.append(row)
        return pd.DataFrame(rows)

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import ride_spectrum_contents

        return ride_spectrum_contents(self)

    def to_dict(self) -> dict:
        from railride._version import __version__, versions

        rms_red, weighted_red = self.reductions
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "vehicle_params": self.params.to_dict(),
            "settings": dict(self.settings),
            "rms": {s: {r: float(self.rms.sel(suspension=s, response=r)) for r in RESPONSES} for s in self.suspensions},
            "weighted_rms_m_s2": {
                s: {
                    p: {w: float(self.weighted.sel(suspension=s, position=p, weighting=w)) for w in WEIGHTINGS}
                    for p in FLOOR
                }
                for s in self.suspensions
            },
            "devices": self.devices,
            "rms_reduction_percent": rms_red,
            "weighted_rms_reduction_percent": weighted_red,
        }

    def title(self) -> str:
        st = self.settings
        return (
            f"Carbody floor acceleration PSD - {st['track']} at V = {st['speed_m_s']:g} m/s, frequency domain; "
            "controllers on the ideal actuator (force = demand), not the MR dampers"
        )

    def plot(self, ax=None):
        """The acceleration PSDs at the floor points, one panel per point, one line per
        suspension (`railride.plots.ride_spectrum`). Returns the figure."""
        from railride.plots.ride_spectrum import plot_ride_spectrum

        return plot_ride_spectrum(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = 120.0) -> list:
        """ride_spectrum.json, ride_spectrum.csv (the RMS table), ride_spectrum_psd.csv (the
        PSDs) and the figure ride_spectrum in each of ``figure_formats`` (png, pdf, svg; PNG at
        ``dpi``) into ``folder``, all or nothing. Returns the paths."""
        from railride.output.files import write_ride_spectrum_outputs
        from railride.plots import FigureOptions

        return write_ride_spectrum_outputs(self, folder, figures=FigureOptions(figure_formats, dpi))


def ride_spectrum(
    track: str = "fra4",
    *,
    speed: float | None = None,
    vehicle=None,
    params=None,
    load: float = 1.0,
    controllers=("passive", "pid", "sas-attitude", "sas-attitude-ride"),
    gains=None,
    min_wavelength: float = 1.0,
    max_wavelength: float = 100.0,
    points: int = 2000,
    control_rate: float | None = None,
    delay: int | None = None,
) -> RideSpectrum:
    """The ride on spectrum ``track`` (`railride.model.track.SPECTRA`, or a user's table psd:PATH)
    at ``speed`` [m/s] (default the scenarios' 55.56) of ``vehicle`` (``params`` is an alias:
    `VehicleParams`, a `Vehicle`, a preset name or a parameters file; default "paper") with the
    load factor ``load`` on its carbody, recorded in ``settings["vehicle"]``, for each of
    ``controllers``: "passive", "plant", outer-loop names (on the ideal actuator, gains from
    ``gains``, default the shipped) or linear `Suspension` values. The spectrum is taken over
    [min_wavelength, max_wavelength] m (as the random tracks are synthesised) on ``points``
    log-spaced frequencies. Without ``control_rate`` a loop acts continuously; with it, through
    the sample-and-hold and ``delay`` periods (0 to 64, default 1; given without
    ``control_rate``, an InputError). A closed loop that is unstable is not run:
    ``settings["not_run"]`` gives the reason (ValueError when none is left).
    ``settings["gains_mismatch"]``: one line (`GainSet.mismatch`) when the gains of the outer
    loops run by name were tuned for another vehicle, load or track (`gains_mismatch`).
    ``settings["gains_source"]``, ``["gains_provenance"]`` and ``["gains_values"]``: the gains
    those loops ran, their source, how they were found and every value per suspension
    (`GainSet.record`; ``["gains"]`` says "given" or "shipped")."""
    if not is_random(track):
        validation.choice("track", track, RANDOM_NAMES)  # its error names every spectrum
    speed = DEFAULT_SPEED if speed is None else frequency_speed(speed)
    lo = validation.number("min_wavelength", min_wavelength, "positive", "m")
    hi = validation.number("max_wavelength", max_wavelength, "positive", "m")
    if not hi > lo:
        raise InputError(f"max_wavelength = {hi:g} m: must be above min_wavelength = {lo:g} m")
    if speed / lo > FMAX_LIMIT:  # before a grid to inf Hz (1e-308 m) is made
        raise InputError(
            f"min_wavelength = {lo:g} m: at {speed:.4g} m/s it passes at {speed / lo:.4g} Hz, above the "
            f"{FMAX_LIMIT:g} Hz of any frequency response (the vehicle's modes are below 100 Hz); the "
            f"shortest allowed is {speed / FMAX_LIMIT:.4g} m"
        )
    points = validation.integer("points", points, 16, 200_000)
    if hi > MAX_WAVELENGTH:  # the spectra's 1 / wavenumber**2 overflow far beyond (1e308 m)
        raise InputError(
            f"max_wavelength = {hi:g} m: at most {MAX_WAVELENGTH:g} m (the track spectra are fitted to "
            "wavelengths of metres to hundreds of metres)"
        )
    if control_rate is not None:
        control_rate = validation.number("control_rate", control_rate, "positive", "Hz")
        if control_rate < MIN_CONTROL_RATE:  # a hold of 1e308 s overflows the sampled loop
            raise InputError(
                f"control_rate = {control_rate:g} Hz: at least {MIN_CONTROL_RATE:g} Hz (a loop sampled less "
                "than once a second cannot act on the carbody's modes of about 1 Hz)"
            )
    if delay is not None and control_rate is None:  # the loops act continuously: no period to delay by
        raise InputError(
            f"delay = {validation.shown(delay)}: applies with control_rate only (without it the loops act continuously)"
        )
    delay = 1 if delay is None else validation.integer("delay", delay, 0, 64, "controller periods")
    vehicle_params, record = resolve_vehicle(vehicle, params, load)
    vehicle = Vehicle(vehicle_params)
    # the peak is the closed loop's (points, 18, 18) complex system (20 x 20 where the carbody
    # bends), about three copies of it
    n_state = 2 * vehicle.n_dof
    runs = len(controllers) if isinstance(controllers, (list, tuple)) else 1
    per_point = 8.0 * (3 * 2 * n_state * n_state + 2 * 2 * 16 + len(RESPONSES) * runs)
    limits.check(points * per_point, f"the ride spectrum on {points} frequencies", "use fewer points")
    frequency = np.geomspace(speed / hi, speed / lo, points)
    inputs = rail_patterns(vehicle, frequency, speed)
    S = track_psd(track, frequency, speed, (lo, hi))
    h = hold(frequency, control_rate, delay)
    plant = linear_model(vehicle_params, "plant")
    psd: dict[str, list] = {r: [] for r in RESPONSES}
    names: list[str] = []
    devices: list[str] = []
    not_run = {}
    from railride.secondary.control import GainSet

    given = gains is not None
    gains = GainSet.of(gains, track)  # a random track: the robust set unless given
    for name, suspension in linear_suspensions(controllers, gains).items():
        model = linear_model(vehicle_params, suspension)
        try:
            _check_stable(name, model, plant, control_rate, delay)
        except ValueError as exc:  # the others go on; the result names it
            not_run[name] = str(exc)
            continue
        names.append(name)
        passive = model.secondary in ("passive", "plant")
        devices.append({"passive": PASSIVE_DEVICE, "plant": NO_DAMPER_DEVICE}.get(model.secondary, ACTUATOR_DEVICE))
        base, gain = (model, None) if passive else (plant, model.corner_forces())
        y = {k: responses(base, gain, u, h, frequency) for k, u in inputs.items()}
        for r in RESPONSES:
            i = base.index("outputs", r)
            psd[r].append(
                np.abs(y["vertical"][:, i]) ** 2 * S["vertical"]
                + np.abs(y["cross-level"][:, i]) ** 2 * S["cross-level"]
            )
    if not names:
        raise InputError("; ".join(not_run.values()))
    ds = xr.Dataset(coords=_coords(names, devices))
    ds.coords["frequency"] = ("frequency", frequency, {"long_name": "frequency", "units": "Hz"})
    for r in RESPONSES:
        unit = plant.units[r]
        ds[r] = (
            ("suspension", "frequency"),
            np.array(psd[r]),
            {
                "long_name": f"one-sided power spectral density of {r.replace('_', ' ')}",
                "units": f"({unit})^2/Hz",
                "rms_units": unit,
            },
        )
    rms = xr.DataArray(
        np.sqrt(np.array([[np.trapezoid(ds[r].values[k], frequency) for r in RESPONSES] for k in range(len(names))])),
        dims=("suspension", "response"),
        coords={
            **_coords(names, devices),
            "response": (
                "response",
                list(RESPONSES),
                {"long_name": "response (output of the linear model)", "units": ""},
            ),
            "unit": (
                "response",
                [plant.units[r] for r in RESPONSES],
                {"long_name": "unit of the response's RMS", "units": ""},
            ),
        },
        name="rms",
        # one array over responses of different units: each its own, in the coordinate "unit"
        attrs={"long_name": "RMS of each response", "units": "see the coordinate unit (per response)"},
    )
    from railride.analysis.comfort import weighting

    weighted = np.empty((len(names), len(FLOOR), len(WEIGHTINGS)))
    for j, w in enumerate(WEIGHTINGS):
        W2 = weighting(w, frequency) ** 2
        for p, point in enumerate(FLOOR):
            weighted[:, p, j] = np.sqrt(np.trapezoid(W2 * ds[f"floor_acceleration_{point}"].values, frequency, axis=-1))
    weighted_da = xr.DataArray(
        weighted,
        dims=("suspension", "position", "weighting"),
        coords={
            **_coords(names, devices),
            "position": ("position", list(FLOOR), {"long_name": "point on the carbody floor", "units": ""}),
            "weighting": (
                "weighting",
                list(WEIGHTINGS),
                {"long_name": "frequency weighting (EN 12299 Wb, ISO 2631-1 Wk)", "units": ""},
            ),
        },
        name="weighted_rms",
        attrs={"long_name": "frequency-weighted RMS of the floor's vertical acceleration", "units": "m/s^2"},
    )
    by_name = _by_name(controllers, names)
    ran = gains.record([n for n in names if n == "passive" or n in by_name])
    settings = {
        "vehicle": record,
        "track": track,
        # a user's table: which version of the file the spectrum was read from
        **({"spectrum_sha256": psd_table.table(track).sha256} if psd_table.is_table(track) else {}),
        "speed_m_s": speed,
        "min_wavelength_m": lo,
        "max_wavelength_m": hi,
        "fmin_hz": float(frequency[0]),
        "fmax_hz": float(frequency[-1]),
        "points": points,
        "control_rate_hz": control_rate,
        "delay_periods": delay if control_rate is not None else None,
        "actuator": "ideal (force = demand)",
        "gains": "given" if given else "shipped",
        # the gains the outer loops named ran (`GainSet.record`): their source as far as it is
        # still true, their [provenance] and every value per suspension run by name
        "gains_source": ran["source"],
        "gains_provenance": ran["provenance"],
        "gains_values": ran["values"],
        "not_run": not_run,
    }
    mismatch = gains_mismatch(gains, by_name, record, track, speed, (lo, hi))
    if mismatch:
        settings["gains_mismatch"] = mismatch
    return RideSpectrum(ds, rms, weighted_da, settings, vehicle_params)


def _coords(names: list[str], devices: list[str]) -> dict:
    """The coordinates along ``suspension`` of every array of a `RideSpectrum`: the names and
    the device of each (CF attributes; "1": a label, no unit)."""
    return {
        "suspension": ("suspension", names, {"long_name": "suspension (passive or controller)", "units": ""}),
        "device": (
            "suspension",
            devices,
            {"long_name": "device that makes the secondary force", "units": ""},
        ),
    }


def gains_mismatch(gains, controllers, vehicle: dict, track: str, speed: float, band) -> str | None:
    """One line (`GainSet.mismatch`) when ``gains`` (None: the shipped gains) were tuned for
    another vehicle, load or track than the ride of ``controllers`` (names; none that reads the
    gains, no line) on ``vehicle`` (its `vehicle_record`): the track is spectrum ``track`` at
    ``speed`` [m/s] over the wavelength ``band`` (min, max) [m], which every realisation of the
    random track shares; so gains tuned on one realisation (seed) of it, of any duration, were
    tuned on it. Its scenario record is that of the realisation they were tuned on (of this
    spectrum; else the defaults, seed 0), at this speed and band."""
    from railride.model.track import scenario
    from railride.secondary.control import GainSet
    from railride.secondary.provenance import tuned_tracks

    gains = GainSet.of(gains, track)
    options = {"speed": speed, "min_wavelength": band[0], "max_wavelength": band[1]}
    records = []
    for tuned in tuned_tracks(gains.provenance or {}):
        if tuned.get("name") != track:
            continue
        realisation = {"seed": tuned.get("seed", 0), "duration": tuned.get("duration_s")}
        try:
            made = scenario(track, **options, **{k: v for k, v in realisation.items() if v is not None})
        except InputError:  # a realisation this ride's band or speed cannot have: not this track
            continue
        # a spectrum has no length: the realisation's, which grows with the speed, is not this ride's
        records.append({**made.describe(), "length_m": tuned.get("length_m")})
    described = [{k: v for k, v in r.items() if v is not None} for r in records]
    # the realisation they were tuned on, else the first of this spectrum: a seed is no difference
    ride = next((r for r in described if gains.tuned_on(r)), described[0] if described else None)
    return gains.mismatch(vehicle, ride or scenario(track, **options).describe(), list(controllers))


def _by_name(controllers, names: list[str]) -> list[str]:
    """The suspensions of ``names`` (those run) that ``controllers`` named, and so took their
    gains from the gain set (a `Suspension` value brings its own)."""
    from railride.secondary.control import OUTER_LOOPS
    from railride.secondary.suspension import Suspension

    if isinstance(controllers, str):
        given = [c.strip() for c in controllers.split(",")]
    else:
        given = [] if isinstance(controllers, Suspension) else [c for c in controllers if isinstance(c, str)]
    named = set(OUTER_LOOPS) if "all" in given else set(given)
    return [n for n in names if n in named and n in OUTER_LOOPS]


def _check_stable(name: str, model: LinearModel, plant: LinearModel, control_rate, delay: int) -> None:
    """Refuse a loop that is unstable: the continuous loop by the eigenvalues of A; with a
    control rate, the sampled loop as the engine runs it (the plant discretised exactly over a
    period with the demand held, the demand taking effect ``delay`` periods after its sample)
    by the eigenvalues of its transition matrix."""
    if model.secondary in ("passive", "plant") or control_rate is None:
        worst = float(np.max(np.linalg.eigvals(model.A).real))
        unstable, where = worst >= 0, f"a pole at Re = {worst:.3g} 1/s"
    else:
        radius = float(np.max(np.abs(np.linalg.eigvals(_sampled_loop(model, plant, 1.0 / control_rate, delay)))))
        unstable = radius >= 1
        where = f"sampled at {control_rate:g} Hz with a delay of {delay} periods, a pole at |z| = {radius:.4g}"
    if unstable:
        raise InputError(
            f"controller {name!r} on the ideal actuator is unstable on this vehicle ({where}): "
            "its frequency response has no steady state"
        )


def _sampled_loop(model: LinearModel, plant: LinearModel, period: float, delay: int) -> np.ndarray:
    """The transition matrix over one controller period of the loop the engine runs: the
    state (x, the demands of the last ``delay`` samples), x_{k+1} = Phi x_k + Gamma f_k with
    f_k the demand sampled ``delay`` periods before (0 periods: the demand of this sample)."""
    import scipy.linalg

    n = model.A.shape[0]
    F = model.corner_forces()
    Bf = np.zeros((n, 4))
    Bf[: plant.A.shape[0]] = plant.B[:, 16:20]  # the corner forces' inputs
    A0 = model.A - Bf @ F  # the open loop (with its integrators)
    # Phi = e^{A0 T} and Gamma = int_0^T e^{A0 s} ds Bf in one exponential (Van Loan)
    E = scipy.linalg.expm(np.block([[A0, Bf], [np.zeros((4, n + 4))]]) * period)
    Phi, Gamma = E[:n, :n], E[:n, n:]
    if delay == 0:
        return Phi + Gamma @ F
    m = n + 4 * delay
    out = np.zeros((m, m))
    out[:n, :n] = Phi
    out[:n, m - 4 :] = Gamma  # the oldest stored demand acts now
    out[n : n + 4, :n] = F  # this sample's demand enters the store
    for k in range(1, delay):  # and each stored demand moves one place older
        out[n + 4 * k : n + 4 * (k + 1), n + 4 * (k - 1) : n + 4 * k] = np.eye(4)
    return out
