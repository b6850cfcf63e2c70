"""A damper on a test rig: prescribed extension, constant or commanded voltage, or the force-
tracking inner loop (paper eq. 12-14, Fig. 6).

Sign convention (railride.secondary.dampers): x is the extension [m], F the force the damper resists with,
positive in tension [N]. A desired force for the inner loop uses the same convention.

The rig uses the vehicle's integrator: classical RK4 at a fixed step dt (default 1e-4 s), split
into 2^k sub-steps where the damper's internal states are stiff, with the motion tabulated on a
grid of whole steps and interpolated by cubic Hermite polynomials (railride.model.track explains why).

`drive` returns the time histories as a Dataset; the two studies return result objects with the
result protocol (``to_dict``, ``to_pandas``, ``plot(ax=None)``, ``save(folder)``): `cycles` the
steady-state hysteresis `Cycles`, `track` the force `Tracking` with its `TrackingMetrics`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from railride.secondary import dampers
from railride.engine import kernels, layout
from railride import limits, validation
from railride.defaults import DEFAULT_DAMPER, DEFAULT_DT
from railride.errors import DivergenceError, InputError
from railride.plots import PNG_DPI, FigureOptions

#: motion-table nodes per cycle of the fastest motion
_NODES_PER_CYCLE = 400
#: the desired forces of `track` (`desired_force_signal`)
DESIRED_SIGNALS = ("sine", "sawtooth")
#: the schemas of the documents of `Cycles.to_dict` and `Tracking.to_dict`
SCHEMA_DAMPER = "railride.damper/1"
SCHEMA_TRACKING = "railride.tracking/1"
#: why the first cycle does not count (in the error for too few cycles)
START_UP = "the first cycle is start-up"


@dataclass(frozen=True)
class SineMotion:
    """x(t) = amplitude sin(2 pi frequency t + phase)."""

    amplitude: float  # m
    frequency: float  # Hz
    phase_deg: float = 0.0

    def __post_init__(self):
        _check_number("amplitude", self.amplitude, "nonnegative", "m")
        _check_number("frequency", self.frequency, "positive", "Hz")
        _check_number("phase", self.phase_deg, "finite", "deg")

    def evaluate(self, t):
        w = 2 * np.pi * self.frequency
        ph = np.deg2rad(self.phase_deg)
        return self.amplitude * np.sin(w * t + ph), self.amplitude * w * np.cos(w * t + ph)

    def spacing(self) -> float:
        return 1.0 / (self.frequency * _NODES_PER_CYCLE)


@dataclass(frozen=True, eq=False)
class SampledMotion:
    """A sampled extension history (t [s] increasing, x [m]), interpolated by PCHIP."""

    t: np.ndarray
    x: np.ndarray
    _interp: tuple = field(default=(), repr=False)

    def __post_init__(self):
        from scipy.interpolate import PchipInterpolator

        t = np.asarray(self.t, dtype=float)
        x = np.asarray(self.x, dtype=float)
        if t.ndim != 1 or t.shape != x.shape or t.size < 2:
            raise InputError("motion: t and x must be 1-D arrays of equal length >= 2")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
            raise InputError("motion: t and x must be finite")
        if np.any(np.diff(t) <= 0) or t[0] > 0:
            raise InputError("motion: t must increase strictly and start at or before 0 s")
        p = PchipInterpolator(t, x)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "_interp", (p, p.derivative()))

    def evaluate(self, t):
        t = np.minimum(t, self.t[-1])
        return self._interp[0](t), self._interp[1](t)

    def spacing(self) -> float:
        return float(np.min(np.diff(self.t))) / 2

    def end(self) -> float:
        return float(self.t[-1])


def _check_number(name, value, rule, unit):
    return validation.number(name, value, rule, unit)


#: the largest rig amplitudes taken: a displacement [m] far beyond a damper's stroke (tens of mm)
#: and a demanded force [N] far beyond its capacity (about 20 kN), below where squares overflow
MAX_STROKE_M = 10.0
MAX_DEMAND_N = 1e9
#: the smallest demanded force [N]: far below a damper's friction (tens of N), and above where
#: the squares of the tracking metrics underflow (their ratio would be NaN)
MIN_DEMAND_N = 1.0


def _at_most(name: str, value: float, limit: float, unit: str, why: str) -> float:
    if value > limit:
        raise InputError(f"{name} = {value:g} {unit}: at most {limit:g} {unit} ({why})")
    return value


def _check_cycle_steps(frequency: float, n_cycles: int, dt: float) -> None:
    """`railride.limits.check_steps` on n_cycles periods of dt steps, before any count of them
    is made an int (a period of 1e308 s has more steps than any int of a float can hold)."""
    limits.check_steps(
        f"frequency = {frequency:g} Hz",
        n_cycles / frequency / dt,
        "raise the frequency, drive fewer cycles or raise dt",
    )


def _motion_table(motion, duration: float, dt: float):
    ratio = motion.spacing() / dt
    m = 1 << max(0, int(math.floor(math.log2(ratio)))) if ratio >= 1 else 1
    interval = m * dt
    n = int(math.ceil((duration + dt) / interval)) + 2
    t = np.arange(n) * interval
    x, xd = motion.evaluate(t)
    return np.ascontiguousarray(np.column_stack([x, xd])), interval


def _check_size(motion, duration: float, dt: float, n_steps: int, stride: int, runs: int, series: bool) -> None:
    """`railride.limits.check` before `drive` allocates: the time grid of the steps and a
    command on it, the motion table and the stored histories (runs x rows x 9)."""
    limits.check_steps("dt", n_steps, "raise dt, or drive fewer or shorter cycles")
    nodes = duration / max(dt, motion.spacing() / 2) + 3  # `_motion_table`: a node every 2**k steps
    rows = n_steps / stride + 2
    need = 8.0 * ((2 if series else 1) * (n_steps + 1) + 2 * nodes + runs * rows * 9)
    limits.check(
        need,
        f"the damper rig's {n_steps:.4g} steps of {dt:.4g} s ({duration:.4g} s)",
        "drive fewer cycles, raise the frequency or raise dt",
    )


def _resolve(damper):
    damper = dampers.preset(damper) if isinstance(damper, str) else damper
    if getattr(damper, "law", None) == dampers.LAW_IDEAL:
        # its force is a controller's demand, not a function of the motion: nothing to test
        raise InputError(
            "damper = 'ideal': the ideal actuator has no force law of its own to "
            "drive on the rig (it applies a vehicle controller's demand); allowed: "
            f"{', '.join(dampers.PRESETS)} or a model from railride.secondary.dampers"
        )
    return damper


def drive(
    damper,
    motion,
    *,
    duration: float,
    voltage=None,
    command=None,
    desired_force=None,
    B: float = 1.0,
    G: float | None = None,
    dt: float = DEFAULT_DT,
    output_rate: float | None = None,
) -> xr.Dataset:
    """Drive one damper through ``motion`` (SineMotion or SampledMotion) for ``duration`` s.

    Give exactly one of: ``voltage`` (a constant [V], or a list: one run per voltage along the
    ``voltage`` dimension), ``command`` (a function of time [s] -> command voltage [V], held
    over each step) or ``desired_force`` (a function of time -> desired force [N], tension +;
    the inner loop sets the voltage with gains B [-] and G [V/N]). Returns a Dataset with
    time histories of x, x', F, z, y, u (coil voltage), v (command) and the energy dissipated
    since t = 0.
    """
    damper = _resolve(damper)
    duration = _check_number("duration", duration, "positive", "s")
    dt = _check_number("dt", dt, "positive", "s")
    given = [
        k for k, v in (("voltage", voltage), ("command", command), ("desired_force", desired_force)) if v is not None
    ]
    if len(given) != 1:
        raise InputError("give exactly one of voltage, command or desired_force")
    if hasattr(motion, "end") and motion.end() < duration - 1e-12:
        raise InputError(f"motion: the samples end at {motion.end():g} s, before the run's {duration:g} s")
    n_steps = int(round(duration / dt))
    if abs(n_steps * dt - duration) > 1e-9 * duration or n_steps < 1:
        raise InputError(f"duration = {duration:g} s must be a whole number of steps dt = {dt:g} s")
    output_rate = 1.0 / dt if output_rate is None else _check_number("output_rate", output_rate, "positive", "Hz")
    stride = int(round(1.0 / (output_rate * dt)))
    if stride < 1 or abs(stride * output_rate * dt - 1) > 1e-6:
        raise InputError(f"output_rate = {output_rate:g} Hz: 1/(output_rate dt) must be a whole number")
    _check_size(motion, duration, dt, n_steps, stride, np.size(voltage) if voltage is not None else 1, voltage is None)
    xtab, interval = _motion_table(motion, duration, dt)
    t_steps = np.arange(n_steps + 1) * dt

    if voltage is not None:
        volts = [damper.check_voltage(v) for v in np.atleast_1d(voltage).tolist()]
        mode, n = layout.RIG_CONSTANT, len(volts)
        series = np.zeros((n, 1))
        vconst = np.array(volts)
    else:
        n, vconst = 1, np.zeros(1)
        fn = command if command is not None else desired_force
        series = np.asarray(np.broadcast_to(fn(t_steps), t_steps.shape), dtype=float)[None, :].copy()
        if not np.all(np.isfinite(series)):
            raise InputError(f"{given[0]}: the function returned a non-finite value")
        mode = layout.RIG_COMMANDED if command is not None else layout.RIG_TRACKING
    if mode == layout.RIG_TRACKING:
        B = _check_number("B", B, "nonnegative", "")
        G = _check_number("G", default_gain(damper) if G is None else G, "nonnegative", "V/N")
    rows = n_steps // stride + (1 if n_steps % stride == 0 else 2)
    out = np.zeros((n, rows, len(layout.RIG_COLUMNS)))  # the kernel's columns, layout.R_*
    kernels.run_parallel(  # the voltages of a set of cycles on threads, one range per core
        kernels.rig_batch,
        n,
        damper.law,
        np.tile(damper.pack(), (n, 1)),
        n_steps,
        stride,
        dt,
        xtab,
        interval,
        mode,
        vconst,
        series,
        np.full(n, float(B)),
        np.full(n, float(G or 0.0)),
        out,
    )
    if not np.all(np.isfinite(out)):
        raise DivergenceError("the damper rig run diverged: a state stopped being finite")
    names = ("x", "xd", "F", "z", "y", "u", "v", "E")
    attrs = {
        "x": ("m", "extension"),
        "xd": ("m/s", "extension rate"),
        "F": ("N", "damper force, tension +"),
        "z": ("m", "hysteretic variable"),
        "y": ("m", "Spencer internal displacement"),
        "u": ("V", "coil voltage after the lag"),
        "v": ("V", "command voltage"),
        "E": ("J", "energy dissipated since t = 0"),
    }
    time = out[0, :, 0]
    dims = ("voltage", "time") if voltage is not None else ("time",)
    data: dict[str, tuple] = {}
    for j, name in enumerate(names, start=1):
        values = out[:, :, j] if voltage is not None else out[0, :, j]
        unit, long = attrs[name]
        data[name] = (dims, values, {"units": unit, "long_name": long})
    coords = {"time": ("time", time, {"long_name": "time", "units": "s"})}
    if voltage is not None:
        coords["voltage"] = ("voltage", vconst, {"long_name": "constant command voltage of the run", "units": "V"})
    else:
        fn_name = "desired_force" if desired_force is not None else "command"
        data[fn_name] = (
            "time",
            np.broadcast_to(fn(time), time.shape).astype(float),
            {"units": "N", "long_name": "desired damper force, tension +"}
            if desired_force is not None
            else {"units": "V", "long_name": "command voltage as the function gives it"},
        )
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(damper=json.dumps(damper.to_dict()), dt_s=dt, integrator="RK4 with stiffness sub-steps")
    if mode == layout.RIG_TRACKING:
        ds.attrs.update(B=float(B), G_v_per_n=float(G or 0.0))
    return ds


def default_gain(damper) -> float:
    """G [V/N] that saturates the voltage at a force error of a tenth of the damper's range
    (hand-set; the tuning study replaces it)."""
    f_max = abs(yield_force(damper, damper.v_max))
    return damper.v_max / (0.1 * f_max) if f_max > 0 else 0.0


def yield_force(damper, v: float) -> float:
    """The yield force alpha(v) z_bound of a hysteretic damper (0 for a dashpot)."""
    if damper.law == dampers.LAW_VISCOUS:
        return 0.0
    return (damper.alpha_a + damper.alpha_b * v) * damper.z_bound


# -- hysteresis cycles ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Cycles:
    """Steady-state cycles of a damper driven by a sine at several constant voltages, the result
    of `cycles`: ``dataset`` holds the last of ``n_cycles`` cycles of each voltage (dims
    voltage, time; channels as `drive` gives them).

    The result protocol: `to_dict` (the ``railride.damper/1`` document), `to_pandas` (the
    cycles as one long table, cycles.csv), `plot` (the force-displacement and force-velocity
    loops), `save` (loops.png, cycles.csv, damper.json); `table` the summary per voltage.
    """

    damper: Any  # a damper model of railride.secondary.dampers
    motion: SineMotion
    dataset: xr.Dataset
    n_cycles: int  # cycles driven per voltage; the last is kept

    def table(self) -> list[dict]:
        """Per voltage: maximum and minimum force [N] and energy dissipated per cycle [J]."""
        ds = self.dataset
        rows = []
        for v in ds.voltage.values:
            cyc = ds.sel(voltage=v)
            rows.append(
                {
                    "voltage_v": float(v),
                    "force_max_n": float(cyc.F.max()),
                    "force_min_n": float(cyc.F.min()),
                    "energy_per_cycle_j": float(cyc.E.values[-1] - cyc.E.values[0]),
                }
            )
        return rows

    def to_dict(self) -> dict:
        """The ``railride.damper/1`` document (docs/cli.md): the damper's parameters, the motion
        and `table`."""
        from railride._version import __version__, versions

        return {
            "schema": SCHEMA_DAMPER,
            "railride_version": __version__,
            "versions": versions(),
            "damper": self.damper.to_dict(),
            "amplitude_m": float(self.motion.amplitude),
            "frequency_hz": float(self.motion.frequency),
            "cycles": self.table(),
        }

    def to_pandas(self):
        """The last cycle of each voltage as one long table (`railride.output.tables.cycles_frame`):
        voltage, time and the rig channels."""
        from railride.output.tables import cycles_frame

        return cycles_frame(self.dataset)

    def plot(self, ax=None):
        """The loops (`railride.plots.rig.plot_hysteresis`); ``ax`` None for a new figure, or
        two Axes. Returns the figure."""
        from railride.plots.rig import plot_hysteresis

        return plot_hysteresis(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """loops.png, cycles.csv and damper.json into ``folder``, all or nothing (other files
        stay); the figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``.
        Returns the paths."""
        from railride.output.files import write_damper_outputs

        figures = FigureOptions(figure_formats, dpi)
        return write_damper_outputs(self, folder, self.to_dict(), figures=figures)


def cycles(
    damper,
    amplitude: float,
    frequency: float,
    voltages,
    *,
    n_cycles: int = 4,
    dt: float = DEFAULT_DT,
    points_per_cycle: int = 400,
) -> Cycles:
    """Drive ``damper`` with x = amplitude sin(2 pi frequency t) at each constant voltage for
    ``n_cycles`` cycles and keep the last one, a steady state: the hysteretic and coil states
    forget their start within a cycle or two."""
    damper = _resolve(damper)
    amplitude = _check_number("amplitude", amplitude, "positive", "m")
    _at_most("amplitude", amplitude, MAX_STROKE_M, "m", "a damper's stroke is tens of mm")
    motion = SineMotion(amplitude, frequency)
    n_cycles = validation.count("n_cycles", n_cycles, 2, START_UP)
    dt = _check_number("dt", dt, "positive", "s")
    _check_cycle_steps(motion.frequency, n_cycles, dt)
    if np.ndim(voltages) == 0:
        voltages = [voltages]
    if len(set(float(v) for v in voltages)) != len(voltages):
        raise InputError(f"voltages = {list(voltages)!r}: each voltage once")
    period = 1.0 / motion.frequency
    steps_per_cycle = int(round(period / dt))
    if steps_per_cycle < 100:
        raise InputError(
            f"frequency = {frequency!r} Hz: a cycle of {period:.3g} s is under 100 steps of "
            f"dt = {dt:g} s; lower the frequency or dt"
        )
    if abs(steps_per_cycle * dt - period) > 1e-9 * period:
        # keep a whole number of steps per cycle so the last cycle is exact
        dt = period / max(steps_per_cycle, 1)
    stride = max(1, steps_per_cycle // points_per_cycle)
    # the largest stride that divides the cycle, searched over at most 10**4 strides: a slow
    # cycle (--frequency 1e-300) has more steps than any search could try. Where none divides
    # it, the cycle gets the next whole number of strides (dt shorter by under 1/points_per_cycle)
    divisor = next((s for s in range(stride, max(stride - 10**4, 0), -1) if steps_per_cycle % s == 0), None)
    if divisor is None:
        steps_per_cycle = -(-steps_per_cycle // stride) * stride
        dt = period / steps_per_cycle
    else:
        stride = divisor
    ds = drive(
        damper, motion, duration=n_cycles * period, voltage=list(voltages), dt=dt, output_rate=1.0 / (stride * dt)
    )
    last = ds.isel(time=slice(-(steps_per_cycle // stride) - 1, None))
    return Cycles(damper, motion, last, n_cycles)


# -- force tracking (paper Fig. 6) ----------------------------------------------------------------
@dataclass(frozen=True)
class TrackingMetrics:
    """How well the inner loop followed the demand over ``window_s`` (start, end) [s]: the RMS
    of the tracking error F - f_d and of the demand f_d [N], and their ratio (0 is perfect
    tracking, 1 as bad as no force at all; NaN for a zero demand)."""

    rms_error_n: float
    rms_demand_n: float
    normalised_rms_error: float
    window_s: tuple[float, float]

    def __post_init__(self):
        for name in ("rms_error_n", "rms_demand_n", "normalised_rms_error"):
            object.__setattr__(self, name, float(getattr(self, name)))
        start, end = self.window_s
        object.__setattr__(self, "window_s", (float(start), float(end)))

    def to_dict(self) -> dict:
        """The ``metrics`` of the ``railride.tracking/1`` document."""
        return {
            "rms_error_n": self.rms_error_n,
            "rms_demand_n": self.rms_demand_n,
            "normalised_rms_error": self.normalised_rms_error,
            "window_s": list(self.window_s),
        }


@dataclass(frozen=True, eq=False)
class Tracking:
    """Force tracking by the inner loop (paper eq. 12-14), the result of `track`: the
    ``desired`` signal (`DESIRED_SIGNALS`) of ``amplitude`` [N] at ``frequency`` [Hz] on a
    ``stroke`` [m] of the ``damper``, with the gains the loop used, ``B`` [-] and ``G`` [V/N]
    (the default filled in); ``dataset`` the time histories of `drive` with ``desired_force``,
    ``window`` (start, end) [s] the span of the metrics (every cycle but the first).

    The result protocol: `to_dict` (the ``railride.tracking/1`` document), `to_pandas` (the
    time histories, tracking.csv), `plot` (forces and voltages), `save` (tracking.png,
    tracking.csv, tracking.json); `metrics` the `TrackingMetrics`.
    """

    damper: Any  # a damper model of railride.secondary.dampers
    desired: str
    amplitude: float
    frequency: float
    stroke: float
    B: float
    G: float
    dataset: xr.Dataset
    window: tuple[float, float]

    def metrics(self) -> TrackingMetrics:
        """The tracking error over `window`."""
        ds = self.dataset.sel(time=slice(*self.window))
        err = ds.F.values - ds.desired_force.values
        rms_demand = float(np.sqrt(np.mean(ds.desired_force.values**2)))
        rms_err = float(np.sqrt(np.mean(err**2)))
        return TrackingMetrics(rms_err, rms_demand, rms_err / rms_demand if rms_demand > 0 else math.nan, self.window)

    def to_dict(self) -> dict:
        """The ``railride.tracking/1`` document (docs/cli.md): the damper's parameters, the
        demand, the stroke, the gains and `metrics`."""
        from railride._version import __version__, versions

        return {
            "schema": SCHEMA_TRACKING,
            "railride_version": __version__,
            "versions": versions(),
            "damper": self.damper.to_dict(),
            "desired": self.desired,
            "amplitude_n": float(self.amplitude),
            "frequency_hz": float(self.frequency),
            "stroke_m": float(self.stroke),
            "B": float(self.B),
            "G_v_per_n": float(self.G),
            "metrics": self.metrics().to_dict(),
        }

    def to_pandas(self):
        """The time histories as one table indexed by time (`railride.output.tables.to_frame`): the rig
        channels and ``desired_force``."""
        from railride.output.tables import to_frame

        return to_frame(self.dataset)

    def plot(self, ax=None):
        """Forces and voltages against time (`railride.plots.rig.plot_tracking`); ``ax`` None
        for a new figure, or two Axes. Returns the figure."""
        from railride.plots.rig import plot_tracking

        return plot_tracking(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """tracking.png, tracking.csv and tracking.json into ``folder``, all or nothing (other
        files stay); the figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``.
        Returns the paths."""
        from railride.output.files import write_tracking_outputs

        figures = FigureOptions(figure_formats, dpi)
        return write_tracking_outputs(self, folder, self.to_dict(), figures=figures)


def desired_force_signal(kind: str, amplitude: float, frequency: float):
    """f_d(t) [N]: "sine" A sin(2 pi f t) or "sawtooth" rising from -A to A each period,
    crossing 0 upwards at t = 0, 1/f, ..."""
    amplitude = _check_number("amplitude", amplitude, "nonnegative", "N")
    frequency = _check_number("frequency", frequency, "positive", "Hz")
    validation.choice("desired", kind, DESIRED_SIGNALS)
    if kind == "sine":
        return lambda t: amplitude * np.sin(2 * np.pi * frequency * t)
    return lambda t: amplitude * (2.0 * np.mod(frequency * t + 0.5, 1.0) - 1.0)


def track(
    damper=DEFAULT_DAMPER,
    desired: str = "sine",
    amplitude: float = 10e3,
    frequency: float = 1.0,
    *,
    B: float = 1.0,
    G: float | None = None,
    stroke: float = 0.02,
    n_cycles: int = 3,
    dt: float = DEFAULT_DT,
) -> Tracking:
    """The inner loop (paper eq. 12-14) tracking a sine or sawtooth desired force (amplitude
    [N], frequency [Hz]) while the damper is stroked by x = -stroke cos(2 pi f t), whose
    velocity is in phase with a sine demand, so that the demand is dissipative where the
    damper's range allows. ``G`` None: `default_gain`. Metrics leave out the first cycle
    (start-up)."""
    damper = _resolve(damper)
    amplitude = _check_number("amplitude", amplitude, "positive", "N")
    _at_most("amplitude", amplitude, MAX_DEMAND_N, "N", "an MR damper gives tens of kN")
    if amplitude < MIN_DEMAND_N:
        raise InputError(
            f"amplitude = {amplitude:g} N: at least {MIN_DEMAND_N:g} N (a damper's friction alone is tens of N)"
        )
    fd = desired_force_signal(desired, amplitude, frequency)
    frequency = float(frequency)
    stroke = _check_number("stroke", stroke, "positive", "m")
    _at_most("stroke", stroke, MAX_STROKE_M, "m", "a damper's stroke is tens of mm")
    n_cycles = validation.count("n_cycles", n_cycles, 2, START_UP)
    dt = _check_number("dt", dt, "positive", "s")
    _check_cycle_steps(frequency, n_cycles, dt)
    motion = SineMotion(stroke, frequency, phase_deg=-90.0)
    period = 1.0 / frequency
    if period < 100 * dt:
        raise InputError(
            f"frequency = {frequency!r} Hz: a cycle of {period:.3g} s is under 100 steps of "
            f"dt = {dt:g} s; lower the frequency or dt"
        )
    steps_per_cycle = int(round(period / dt))
    if abs(steps_per_cycle * dt - period) > 1e-9 * period:
        # as `cycles`: a whole number of steps per cycle, so that any frequency (1.5 Hz: a
        # period of 0.6667 s) gives a run of whole steps and an exact metric window
        dt = period / steps_per_cycle
    # record at about 1 kHz, at least 200 points per cycle, on whole steps
    stride = max(1, min(int(round(1e-3 / dt)), int(period / (200 * dt))))
    ds = drive(
        damper, motion, duration=n_cycles * period, desired_force=fd, B=B, G=G, dt=dt, output_rate=1.0 / (stride * dt)
    )
    # the gains as the loop used them (G filled in when None)
    return Tracking(
        damper,
        desired,
        amplitude,
        frequency,
        stroke,
        float(ds.attrs["B"]),
        float(ds.attrs["G_v_per_n"]),
        ds,
        (period, n_cycles * period),
    )
