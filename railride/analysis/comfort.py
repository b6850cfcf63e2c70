"""Ride comfort: ISO 2631-1 frequency weightings, weighted RMS and VDV, the vertical part of the
EN 12299 mean comfort index N_MV, and Sperling's ride index Wz.

Formulas, constants, sources, conventions and what is not modelled: docs/comfort.md.

Every signal function takes a vertical acceleration in m/s^2 as an array whose last axis is
time, sampled at ``rate_hz``; leading axes (a batch) are carried through, so the result has the
signal's shape without its last axis. ``window`` = (start, end) in seconds from the first sample
(end may be inf) selects the samples start <= t < end *after* weighting: the filters always run
over the whole signal from its first sample, from rest.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import warnings
from typing import Any
from collections.abc import Mapping

import numpy as np
import xarray as xr
from scipy import signal as sp_signal

from railride.errors import InputError
from railride import validation
from railride.analysis.metrics import check_window
from railride.model.vehicle import LABEL_ATTRS

# -- frequency weightings ---------------------------------------------------------------------

#: quality factor of the band-limiting high- and low-pass (second-order Butterworth)
Q_BAND = 1.0 / math.sqrt(2.0)
#: lowest sample rate accepted by `weight`, as a multiple of the weighting's f2 (docs/comfort.md)
MIN_RATE_FACTOR = 5.0


@dataclasses.dataclass(frozen=True)
class Weighting:
    """Parameters of W(s) = K Hh(s) Hl(s) Ht(s) Hs(s) (ISO 2631-1 Annex A, ISO 8041).

    Frequencies in Hz. ``f3`` = inf drops the zero of the a-v transition; ``f5`` = None drops the
    upward step (Hs = 1).
    """

    name: str
    f1: float
    f2: float
    f3: float
    f4: float
    Q4: float
    f5: float | None
    Q5: float | None
    f6: float | None
    Q6: float | None
    K: float
    use: str
    source: str


_ISO = "ISO 2631-1:1997 Annex A Table A.1 / ISO 8041; checked against ISO 2631-1 Table 3 (Wk, Wd) and Table 4 (Wc, We)"
WEIGHTINGS = {
    w.name: w
    for w in (
        Weighting(
            "Wk",
            0.4,
            100.0,
            12.5,
            12.5,
            0.63,
            2.37,
            0.91,
            3.35,
            0.91,
            1.0,
            "vertical (z), seat surface and feet of a seated person (ISO 2631-1)",
            _ISO,
        ),
        Weighting(
            "Wd",
            0.4,
            100.0,
            2.0,
            2.0,
            0.63,
            None,
            None,
            None,
            None,
            1.0,
            "horizontal (x, y); EN 12299 lateral and longitudinal floor weighting",
            _ISO,
        ),
        Weighting(
            "Wc", 0.4, 100.0, 8.0, 8.0, 0.63, None, None, None, None, 1.0, "seat-back, fore-and-aft (ISO 2631-1)", _ISO
        ),
        Weighting(
            "We", 0.4, 100.0, 1.0, 1.0, 0.63, None, None, None, None, 1.0, "rotational vibration (ISO 2631-1)", _ISO
        ),
        Weighting(
            "Wb",
            0.4,
            100.0,
            16.0,
            16.0,
            0.63,
            2.5,
            0.8,
            4.0,
            0.8,
            1.024,
            "vertical (z) floor weighting of EN 12299 (railway ride comfort)",
            "EN 12299 (parameters as two third-party implementations give them, not read "
            "from the standard; ISO 8041 / ISO 2631-4 Wb differs: docs/comfort.md)",
        ),
        Weighting(
            "Wb8041",
            0.4,
            100.0,
            16.0,
            16.0,
            0.55,
            2.5,
            0.9,
            4.0,
            0.95,
            1.024,
            "vertical (z) railway weighting Wb in the ISO 8041 / ISO 2631-4 form",
            "ISO 8041 as tabulated in the Larson Davis HVM200 manual (Table 3.1, 'source: "
            "ISO 8041'); not read from the standard itself; docs/comfort.md",
        ),
    )
}


def get_weighting(name: str) -> Weighting:
    """The `Weighting` called ``name`` (Wk, Wd, Wc, We, Wb; case-insensitive)."""
    if isinstance(name, str):
        for key, w in WEIGHTINGS.items():
            if key.lower() == name.strip().lower():
                return w
    raise InputError(f"unknown frequency weighting {name!r}; allowed: {', '.join(WEIGHTINGS)}")


def _check_frequency(frequency_hz) -> np.ndarray:
    try:
        f = np.asarray(frequency_hz, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"frequency_hz = {frequency_hz!r}: must be numbers in Hz") from None
    bad = ~np.isfinite(f) | (f < 0)
    if np.any(bad):
        raise InputError(f"frequency_hz = {f[bad].ravel()[0]!r}: frequencies must be finite numbers >= 0 Hz")
    return f


def _quadratic(w: float, q: float) -> np.ndarray:
    """Roots of s^2 + w s / q + w^2."""
    return np.roots([1.0, w / q, w * w])


def _analog_zpk(w: Weighting, omega=lambda f: 2.0 * math.pi * f):
    """Zeros, poles and gain of W(s); ``omega(f)`` maps each characteristic frequency to its
    angular frequency (the bilinear design passes its pre-warped one)."""
    w1, w2, w4 = omega(w.f1), omega(w.f2), omega(w.f4)
    zeros = [0.0, 0.0]  # Hh: s^2
    poles = [*_quadratic(w1, Q_BAND), *_quadratic(w2, Q_BAND)]
    gain = w.K * w2 * w2  # Hl: w2^2
    poles += list(_quadratic(w4, w.Q4))  # Ht denominator, times w4^2
    if math.isinf(w.f3):
        gain *= w4 * w4
    else:  # (1 + s/w3) = (s + w3) / w3
        w3 = omega(w.f3)
        zeros.append(-w3)
        gain *= w4 * w4 / w3
    if w.f5 is not None and w.f6 is not None and w.Q5 is not None and w.Q6 is not None:  # Hs (Annex A)
        zeros += list(_quadratic(omega(w.f5), w.Q5))
        poles += list(_quadratic(omega(w.f6), w.Q6))
    return np.array(zeros, complex), np.array(poles, complex), gain


def weighting(name: str, frequency_hz) -> np.ndarray:
    """|W(f)| of the analog weighting ``name`` at ``frequency_hz`` (Hz, >= 0; any shape).

    W(s) = K Hh(s) Hl(s) Ht(s) Hs(s), s = j 2 pi f, with

    * Hh = s^2 / (s^2 + w1 s / Q1 + w1^2), Hl = w2^2 / (s^2 + w2 s / Q2 + w2^2), Q1 = Q2 = 1/sqrt 2
    * Ht = (1 + s/w3) / (1 + s/(Q4 w4) + s^2/w4^2)
    * Hs = (s^2 + w5 s/Q5 + w5^2) / (s^2 + w6 s/Q6 + w6^2)  [= 1 without a step]

    and w_i = 2 pi f_i. Hs tends to (f5/f6)^2 at low and to 1 at high frequency.
    """
    w = get_weighting(name)
    f = _check_frequency(frequency_hz)
    z, p, k = _analog_zpk(w)
    s = 2j * math.pi * f[..., None]
    h = k * np.prod(s - z, axis=-1) / np.prod(s - p, axis=-1)
    return np.abs(h)


def min_rate_hz(name: str) -> float:
    """Lowest sample rate (Hz) `weight` accepts for the weighting: 5 f2."""
    return MIN_RATE_FACTOR * get_weighting(name).f2


def _check_rate(rate_hz) -> float:
    return validation.number("rate_hz", rate_hz, "positive", allowed="a finite number > 0 (Hz, the sample rate)")


@functools.lru_cache(maxsize=64)
def _sos(name: str, rate_hz: float) -> np.ndarray:
    """Second-order sections of the digital weighting: bilinear transform of W(s) with every
    characteristic frequency pre-warped, w_i = 2 fs tan(pi f_i / fs)."""
    w = get_weighting(name)
    z, p, k = _analog_zpk(w, omega=lambda f: 2.0 * rate_hz * math.tan(math.pi * f / rate_hz))
    zd, pd, kd = sp_signal.bilinear_zpk(z, p, k, rate_hz)
    return sp_signal.zpk2sos(zd, pd, kd)


def _check_signal(signal, what: str = "acceleration") -> np.ndarray:
    try:
        x = np.asarray(signal, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: must be an array of numbers (m/s^2)") from None
    if x.ndim == 0 or x.shape[-1] < 2:
        raise InputError(f"{what}: needs at least two samples along its last (time) axis")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{what}: holds NaN or infinite values")
    return x


def weight(name: str, signal, rate_hz: float) -> np.ndarray:
    """The signal (last axis time, sampled at ``rate_hz``) filtered by the weighting ``name``,
    from rest, as a digital filter: bilinear transform of the exact W(s) with pre-warping.

    Refuses rate_hz < 5 f2 (500 Hz for every weighting here): the bilinear transform compresses
    the band near the Nyquist frequency, and at 5 f2 the digital |W| is within 1 % of the analog
    one up to 31.5 Hz (6 % low at 80 Hz); at railride's default 1 kHz within 1 % up to 63 Hz.
    """
    w = get_weighting(name)
    rate = _check_rate(rate_hz)
    if rate < MIN_RATE_FACTOR * w.f2:
        raise InputError(
            f"rate_hz = {rate:g} Hz is too low for weighting {w.name}: its upper band limit is "
            f"f2 = {w.f2:g} Hz, and the digital filter needs rate_hz >= {MIN_RATE_FACTOR:g} f2 = "
            f"{MIN_RATE_FACTOR * w.f2:g} Hz (docs/comfort.md, 'Digital filter')"
        )
    x = _check_signal(signal)
    return sp_signal.sosfilt(_sos(w.name, rate), x, axis=-1)


# -- windows ------------------------------------------------------------------------------------


def _window_slice(n: int, rate: float, window) -> slice:
    """Samples start <= i / rate < end of a signal of n samples (t = 0 at the first one)."""
    if window is None:
        return slice(0, n)
    start, end = check_window(window, n / rate)
    i0 = int(math.ceil(start * rate - 1e-9))
    i1 = min(n, int(math.ceil(end * rate - 1e-9)))
    if i1 - i0 < 2:
        raise InputError(f"window = {start:g}:{end:g} s holds fewer than two samples")
    return slice(i0, i1)


def _weighted_part(acceleration, rate_hz, weighting_name, window) -> tuple[np.ndarray, float]:
    x = weight(weighting_name, acceleration, rate_hz)
    rate = float(rate_hz)
    return x[..., _window_slice(x.shape[-1], rate, window)], rate


# -- ISO 2631-1 ---------------------------------------------------------------------------------


def weighted_rms(acceleration, rate_hz: float, weighting: str = "Wk", window=None):
    """Frequency-weighted RMS acceleration a_w [m/s^2] (ISO 2631-1, 6.1):
    a_w = [ (1/T) integral a_w(t)^2 dt ]^(1/2), the mean over the samples in ``window``.

    ``weighting``: Wk (default; vertical, seated passenger, ISO 2631-1) or Wb (EN 12299 railway
    vertical); any name of `WEIGHTINGS`. Returns a float, or an array for a batch.
    """
    x, _ = _weighted_part(acceleration, rate_hz, weighting, window)
    return _scalar(_rms(x))


def _rms(x: np.ndarray) -> np.ndarray:
    """The RMS along the last axis of a weighted signal's window."""
    return np.sqrt(np.mean(x * x, axis=-1))


def vdv(acceleration, rate_hz: float, weighting: str = "Wk", window=None):
    """Vibration dose value VDV [m/s^1.75] (ISO 2631-1, 6.3.2):
    VDV = [ integral a_w(t)^4 dt ]^(1/4), the integral a rectangle sum with dt = 1/rate_hz."""
    x, rate = _weighted_part(acceleration, rate_hz, weighting, window)
    return _scalar(_fourth_power_sum(x) / rate) ** 0.25


def _fourth_power_sum(x: np.ndarray) -> np.ndarray:
    x2 = x * x  # (x^2)^2: two products, far cheaper than a power
    return np.sum(x2 * x2, axis=-1)


def _scalar(v):
    v = np.asarray(v, dtype=float)
    return float(v) if v.ndim == 0 else v


# -- EN 12299 -----------------------------------------------------------------------------------

#: length of the EN 12299 RMS intervals [s]
INTERVAL_S = 5.0
#: (upper bound, label) of the EN 12299 mean comfort scale, N below the bound
COMFORT_SCALE = (
    (1.0, "very comfortable"),
    (2.0, "comfortable"),
    (4.0, "medium"),
    (5.0, "uncomfortable"),
    (math.inf, "very uncomfortable"),
)


class ShortRunWarning(UserWarning):
    """A comfort index was evaluated on less signal than its method asks for."""


def comfort_intervals(acceleration, rate_hz: float, window=None) -> np.ndarray:
    """RMS values [m/s^2] of the Wb-weighted acceleration over consecutive 5 s intervals from
    the start of ``window`` (last axis: interval). An incomplete last interval is dropped; a
    signal shorter than 5 s gives one interval over all of it, with a `ShortRunWarning`."""
    x, rate = _weighted_part(acceleration, rate_hz, "Wb", window)
    return _intervals(x, rate)


#: the end of the note of a signal shorter than one interval (`_intervals`), which the record reads
WHOLE_SIGNAL = "one interval over the whole signal is used"


def _intervals(x: np.ndarray, rate: float) -> np.ndarray:
    """`comfort_intervals` of the window ``x`` of a Wb-weighted signal."""
    per = int(round(INTERVAL_S * rate))
    n = x.shape[-1] // per
    if n == 0:
        warnings.warn(
            f"only {x.shape[-1] / rate:g} s of signal: EN 12299 takes RMS values over "
            f"{INTERVAL_S:g} s intervals; {WHOLE_SIGNAL}",
            ShortRunWarning,
            stacklevel=3,
        )
        return np.sqrt(np.mean(x * x, axis=-1))[..., None]
    parts = x[..., : n * per].reshape(x.shape[:-1] + (n, per))
    return np.sqrt(np.mean(parts * parts, axis=-1))


def mean_comfort_vertical(acceleration, rate_hz: float, window=None):
    """Vertical part of the EN 12299 mean comfort index, standard (simplified) method:
    N_MV,z = 6 a_ZP95^Wb, with a_ZP95 the 95th percentile of the 5 s RMS values of the
    Wb-weighted vertical floor acceleration (`comfort_intervals`; percentile with linear
    interpolation between order statistics). Lateral and longitudinal terms are not modelled."""
    rms = comfort_intervals(acceleration, rate_hz, window)
    return _scalar(6.0 * np.percentile(rms, 95.0, axis=-1))


def comfort_class(n_mv: float) -> str:
    """The EN 12299 label of a mean comfort index N."""
    n = float(n_mv)
    if not (math.isfinite(n) and n >= 0):
        raise InputError(f"N = {n_mv!r}: a comfort index is a finite number >= 0")
    return next(label for bound, label in COMFORT_SCALE if n < bound)


# -- Sperling -----------------------------------------------------------------------------------


def sperling_correction(frequency_hz) -> np.ndarray:
    """Sperling's vertical frequency correction F(f): 0.325 f^2 up to 5.9 Hz (the source gives it
    from 0.5 Hz; continued below), 400/f^2 from 5.9 to 20 Hz, 1 above 20 Hz."""
    f = _check_frequency(frequency_hz)
    return np.where(f <= 5.9, 0.325 * f * f, np.where(f <= 20.0, 400.0 / np.maximum(f, 5.9) ** 2, 1.0))


def sperling_wz(acceleration, rate_hz: float, window=None):
    """Sperling's ride index Wz (vertical) of the samples in ``window``.

    Each line k >= 1 of the one-sided amplitude spectrum (rectangular window, amplitude
    a_k = 2 |X_k| / N, |X_k| / N at the Nyquist line; in cm/s^2) at f_k = k rate/N contributes
    Wz_k = 0.896 (a_k^3 F(f_k) / f_k)^(1/10), and Wz = (sum Wz_k^10)^(1/10). The mean (k = 0)
    does not contribute. A sine with a whole number of periods in the window falls on one line
    with its exact amplitude."""
    rate = _check_rate(rate_hz)
    x = _check_signal(acceleration)
    x = x[..., _window_slice(x.shape[-1], rate, window)]
    n = x.shape[-1]
    spectrum = np.abs(np.fft.rfft(x, axis=-1))[..., 1:] / n
    f = np.arange(1, spectrum.shape[-1] + 1) * rate / n
    amplitude = 2.0 * spectrum
    if n % 2 == 0:
        amplitude[..., -1] = spectrum[..., -1]  # the Nyquist line has no mirror image
    a_cm = 100.0 * amplitude
    total = np.sum(a_cm**3 * sperling_correction(f) / f, axis=-1)
    return _scalar(0.896 * total**0.1)


# -- on the simulated carbody -------------------------------------------------------------------

#: name -> unit of the indices `ride_comfort` returns (aw_/vdv_ for each weighting asked for)
INDEX_UNITS = {"aw": "m/s^2", "vdv": "m/s^1.75", "N_MV_z": "1", "Wz": "1"}
POSITION_KEYWORDS = ("centre", "front", "rear")
#: the floor points of the frequency-domain ride (`railride.frequency.ride_spectrum`)
FLOOR = POSITION_KEYWORDS


def _rate_of(time: np.ndarray) -> float:
    if time.size < 2:
        raise InputError("the run holds fewer than two output samples")
    step = np.diff(time)
    dt = float(np.median(step))
    if not (dt > 0 and np.allclose(step, dt, rtol=1e-6, atol=0)):
        raise InputError("the time coordinate is not uniformly sampled: comfort indices need a constant output rate")
    return 1.0 / dt


def _half_lengths(ds: xr.Dataset) -> np.ndarray:
    """l [m] of every run (one per sample in a batch), from the ``vehicle_params`` record."""
    if "vehicle_params" not in ds:
        raise InputError(
            "the Dataset has no vehicle_params record: give positions as {name: x in m} instead of 'front'/'rear'"
        )
    records = np.atleast_1d(ds["vehicle_params"].values)
    return np.array([float(json.loads(str(r))["l"]) for r in records])


def _carbody_lengths(ds: xr.Dataset) -> np.ndarray:
    """L_c [m] of every run (one per sample in a batch) from the ``vehicle_params`` record; NaN
    where a run's carbody is rigid (no bending frequency) or the record is missing."""
    if "vehicle_params" not in ds:
        raise InputError(
            "the Dataset has a carbody_bending_acceleration channel but no vehicle_params record: the "
            "carbody length L_c that places the floor points on the bending mode is unknown"
        )
    out = []
    for r in np.atleast_1d(ds["vehicle_params"].values):
        record = json.loads(str(r))
        flexible = record.get("f_bend") is not None or record.get("EI_c") is not None
        length = record.get("L_c")
        out.append(float(length) if flexible and length is not None else math.nan)
    return np.array(out)


def _bending(ds: xr.Dataset, lead: list, x: np.ndarray) -> np.ndarray | None:
    """phi(x / L_c) eta'' (samples, positions, time) of the carbody's bending at the floor points
    x (samples, positions) [m], from the ``carbody_bending_acceleration`` channel; None where the
    Dataset has none or it is 0 throughout (rigid carbodies). A rigid run's share is 0; a point
    beyond a bending carbody's ends is an InputError."""
    if "carbody_bending_acceleration" not in ds:
        return None
    from railride.model.beam import mode_shape

    bend = np.atleast_2d(ds["carbody_bending_acceleration"].transpose(*lead, "time").values)
    if not np.any(bend):  # rigid carbodies (the engine holds their bending at 0)
        return None
    lengths = np.broadcast_to(_carbody_lengths(ds), (x.shape[0],))
    phi = np.zeros_like(x)
    for s, length in enumerate(lengths):
        if math.isnan(length):
            continue
        beyond = np.abs(x[s]) > 0.5 * length * (1.0 + 1e-12)
        if np.any(beyond):
            raise InputError(
                f"position x = {validation.shown(float(x[s][beyond][0]))} m: beyond the bending carbody's ends, "
                f"+-L_c/2 = {validation.shown(0.5 * length)} m"
            )
        phi[s] = mode_shape(x[s], length)
    return phi[:, :, None] * bend[:, None, :]


def _positions(ds: xr.Dataset, positions, n_sample: int) -> tuple[list[str], np.ndarray]:
    """Position names and x [m] per (sample, position)."""
    if isinstance(positions, str):
        positions = (positions,)
    items = list(positions.items()) if isinstance(positions, Mapping) else [(p, p) for p in positions]
    if not items:
        raise InputError("positions: give at least one position")
    names, xs, half = [], [], None
    for name, spec in items:
        if isinstance(spec, str):
            key = spec.strip().lower().replace("center", "centre")
            if key not in POSITION_KEYWORDS:
                raise InputError(
                    f"position {spec!r}: allowed keywords are {', '.join(POSITION_KEYWORDS)}, or give {{name: x in m}}"
                )
            if key == "centre":
                x = np.zeros(n_sample)
            else:
                half = _half_lengths(ds) if half is None else half
                x = np.broadcast_to(half if key == "front" else -half, (n_sample,))
        else:
            ok = not isinstance(spec, bool) and isinstance(spec, (int, float, np.number)) and math.isfinite(spec)
            if not ok:
                raise InputError(
                    f"position {name!r} = {spec!r}: x must be a finite number of "
                    "metres from the carbody centre (front +)"
                )
            x = np.full(n_sample, float(spec))
        names.append(str(name))
        xs.append(x)
    if len(set(names)) != len(names):
        raise InputError(f"positions: names repeat ({', '.join(names)})")
    return names, np.stack(xs, axis=-1)


def floor_acceleration(ds: xr.Dataset, positions=POSITION_KEYWORDS) -> xr.DataArray:
    """Vertical acceleration [m/s^2] of carbody floor points at (x, 0): a = z'' - x phi'', plus
    phi_b(x / L_c) eta'' where the carbody bends, dims ([sample,] position, time).
    ``positions``: keywords centre (x = 0), front (x = +l), rear (x = -l), or {name: x in m}.
    phi'' is the ``carbody_pitch_acceleration`` channel if the Dataset has one, else the central
    difference of ``carbody_pitch_velocity``. eta'' is the ``carbody_bending_acceleration``
    channel where the Dataset has one, phi_b the carbody's first bending mode
    (`railride.model.beam.mode_shape`, 1 at the centre) on the length L_c of the run's vehicle
    record (a rigid run: no bending)."""
    out, _ = _floor(ds, positions)
    return out


def _floor(ds, positions):
    lead = ["sample"] if "sample" in ds.dims else []
    time = np.asarray(ds["time"].values, dtype=float)
    rate = _rate_of(time)
    acc = np.atleast_2d(ds["carbody_acceleration"].transpose(*lead, "time").values)
    if "carbody_pitch_acceleration" in ds:
        pitch = np.atleast_2d(ds["carbody_pitch_acceleration"].transpose(*lead, "time").values)
        source = "carbody_pitch_acceleration channel"
    else:
        vel = np.atleast_2d(ds["carbody_pitch_velocity"].transpose(*lead, "time").values)
        pitch = np.gradient(vel, 1.0 / rate, axis=-1, edge_order=2)
        source = "central difference of carbody_pitch_velocity"
    names, x = _positions(ds, positions, acc.shape[0])
    floor = acc[:, None, :] - x[:, :, None] * pitch[:, None, :]
    bending = _bending(ds, lead, x)
    if bending is not None:
        floor = floor + bending
    coords: dict[str, Any] = {
        "position": ("position", names, LABEL_ATTRS["position"]),
        "time": ("time", ds["time"].values, LABEL_ATTRS["time"]),
    }
    x_attrs = {"long_name": "x of the floor position from the carbody centre (front +)", "units": "m"}
    x_coord = (lead + ["position"], x if lead else x[0], x_attrs)
    if lead:
        coords["sample"] = ("sample", ds["sample"].values, LABEL_ATTRS["sample"])
    else:
        floor = floor[0]
    da = xr.DataArray(
        floor,
        dims=lead + ["position", "time"],
        coords=coords,
        name="floor_acceleration",
        attrs={
            "units": "m/s^2",
            "pitch_acceleration": source,
            "long_name": "carbody floor vertical acceleration at (x, 0)",
        },
    )
    if bending is not None:
        da.attrs["bending_acceleration"] = "carbody_bending_acceleration channel times the bending mode"
    da = da.assign_coords(x_m=x_coord)
    return da, rate


def ride_comfort(ds: xr.Dataset, positions=POSITION_KEYWORDS, window=None, weightings=("Wk", "Wb")) -> xr.DataArray:
    """Comfort indices on the carbody floor, dims ([sample,] position, index).

    Positions: see `floor_acceleration` (default: centre, front and rear bogie centres).
    Indices: aw_<W> [m/s^2] and vdv_<W> [m/s^1.75] for each weighting in ``weightings``, the
    vertical EN 12299 mean comfort N_MV_z and Sperling's Wz. ``window`` = (start, end) s of the
    run's time keeps the samples start <= t <= end (as `railride.analysis.metrics.ride_metrics`); the
    weighting filters still run from the start of the run.
    Coordinates ``unit`` (per index) and ``x_m`` (per position); attrs ``n_intervals`` (5 s
    intervals behind N_MV_z) and ``notes``. `to_dict` gives {position: {index: value}}.
    """
    for w in weightings:
        get_weighting(w)
    floor, rate = _floor(ds, positions)
    time = floor["time"].values
    t0, t1 = float(time[0]), float(time[-1])
    start, end = (t0, t1) if window is None else check_window(window, t1, t0)
    # start <= t <= end, as railride.analysis.metrics selects a window: in seconds from the first
    # sample, half-open half a sample beyond the end
    rel = None if window is None else (start - t0, end - t0 + 0.5 / rate)
    a = floor.values
    values, names, units = [], [], []
    # each weighting filters the floor once: its a_w, VDV and (Wb) the 5 s intervals read it
    weighted: dict[str, np.ndarray] = {}
    for w in dict.fromkeys([*(get_weighting(w).name for w in weightings), "Wb"]):
        weighted[w], _ = _weighted_part(a, rate, w, rel)
    for w in weightings:
        name = get_weighting(w).name
        x = weighted[name]
        values += [_rms(x), (_fourth_power_sum(x) / rate) ** 0.25]
        names += [f"aw_{name}", f"vdv_{name}"]
        units += [INDEX_UNITS["aw"], INDEX_UNITS["vdv"]]
    notes = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ShortRunWarning)
        rms = _intervals(weighted["Wb"], rate)
    notes += [str(c.message) for c in caught if issubclass(c.category, ShortRunWarning)]
    values.append(6.0 * np.percentile(rms, 95.0, axis=-1))
    names.append("N_MV_z")
    units.append(INDEX_UNITS["N_MV_z"])
    values.append(np.asarray(sperling_wz(a, rate, window=rel)))
    names.append("Wz")
    units.append(INDEX_UNITS["Wz"])
    data = np.stack(values, axis=-1)
    if not np.all(np.isfinite(data)):
        raise RuntimeError("a comfort index is not finite: the run did not produce finite responses")
    notes.append("N_MV_z is the vertical term of EN 12299 only: the model has no lateral or longitudinal motion")
    dims = list(floor.dims[:-1]) + ["index"]
    coords = {k: v for k, v in floor.coords.items() if "time" not in v.dims}
    coords["index"] = ("index", names, {"long_name": "comfort index", "units": ""})
    out = xr.DataArray(data, dims=dims, coords=coords, name="ride_comfort")
    out = out.assign_coords(unit=("index", units, {"long_name": "unit of each index", "units": ""}))
    out.attrs = {
        "long_name": "ride comfort on the carbody floor",
        "units": "per index, as the coordinate unit gives",
        "n_intervals": int(rms.shape[-1]),
        "notes": "; ".join(notes),
        "pitch_acceleration": floor.attrs["pitch_acceleration"],
        "window_s": json.dumps([float(start), float(end)]),
    }
    return out


def to_dict(comfort: xr.DataArray) -> dict:
    """{position: {index: value}} of one run's `ride_comfort`."""
    if "sample" in comfort.dims:
        raise InputError("to_dict takes the comfort indices of one run; select a sample first")
    return {
        str(p): {str(i): float(comfort.sel(position=p, index=i)) for i in comfort["index"].values}
        for p in comfort["position"].values
    }
