"""The ``railride`` command line: ``railride compare``, ``railride modes``, ``railride simulate``,
``railride damper`` and ``railride tracking``.

A thin layer over the library: it parses options, calls `railride.vehicle`, `railride.track`,
`railride.simulation`, `railride.metrics`, `railride.dampers`, `railride.rig`,
`railride.control`, `railride.comparison` and `railride.report`, and prints. See docs/cli.md.

Exit statuses: 0 success, 1 the simulation diverged, 2 bad input (usage errors, invalid values,
unreadable files, an output folder that cannot be written). Errors print one line
``error: <message>`` on stderr, never a traceback.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from enum import Enum
from pathlib import Path
from typing import Annotated, Optional

import typer

from . import __version__

SCHEMA_SIMULATE = "railride.simulation/1"
SCHEMA_DAMPER = "railride.damper/1"
SCHEMA_TRACKING = "railride.tracking/1"

#: --suspension values of `simulate`
SUSPENSIONS = ("passive", "mr")
#: --desired values of `tracking` (the signals of railride.rig.desired_force_signal)
DESIRED_SIGNALS = ("sine", "sawtooth")
#: the damper preset used when --model / --damper is not given
DEFAULT_DAMPER = "railway"

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
    help="Vertical ride of a 9-DOF railway vehicle: the paper's comparison of passive, PID and "
         "SAS suspensions (start with `railride compare`), modes, simulated ride metrics, and MR "
         "damper rig tests (hysteresis cycles, force tracking).",
)


class OutputFormat(str, Enum):
    table = "table"
    json = "json"


class CliError(Exception):
    """A problem to report as ``error: ...`` with an exit status."""

    def __init__(self, message: str, status: int):
        super().__init__(message)
        self.status = status


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


@contextlib.contextmanager
def _errors():
    """ValueError -> status 2, RuntimeError -> 1, OSError -> 2: one line on stderr, no traceback."""
    try:
        yield
    except CliError as exc:
        status, message = exc.status, _one_line(exc)
    except ValueError as exc:
        status, message = 2, _one_line(exc)
    except RuntimeError as exc:
        status, message = 1, _one_line(exc)
    except OSError as exc:
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        status, message = 2, f"{exc.strerror or exc}{where}"
    else:
        return
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(status)


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def _stdout_console():
    from rich.console import Console

    return Console(file=sys.stdout, highlight=False)


def _wide_stdout_console(width: int = 120):
    """The stdout console for wide tables: the terminal's width on a terminal, else ``width``
    columns (rich would assume 80 for a pipe or a file) unless COLUMNS says otherwise."""
    import os

    from rich.console import Console

    try:
        terminal = sys.stdout.isatty()
    except (AttributeError, ValueError):
        terminal = False
    fixed = None if terminal or os.environ.get("COLUMNS") else width
    return Console(file=sys.stdout, highlight=False, width=fixed)


def _stderr_console():
    from rich.console import Console

    return Console(file=sys.stderr, highlight=False)


def _vehicle_params(params_file: Optional[Path], preset: Optional[str]):
    """(VehicleParams, the record for the JSON document)."""
    from .params import VehicleParams

    if params_file is not None and preset is not None:
        raise ValueError("give either --params FILE or --preset NAME, not both")
    if params_file is not None:
        return VehicleParams.load(params_file), {"vehicle_params_file": str(params_file)}
    name = "paper" if preset is None else preset
    return VehicleParams.preset(name), {"vehicle_preset": name}


def _check_number(option: str, value: float, unit: str, *, allow_zero: bool = False) -> float:
    """A finite number > 0 (>= 0 with ``allow_zero``), else ValueError naming the option."""
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        rule = ">= 0" if allow_zero else "> 0"
        unit = f" {unit}" if unit else ""
        raise ValueError(f"{option} = {value:g}{unit}: must be a finite number {rule}")
    return float(value)


def _check_cycles(option: str, value: int) -> int:
    if value < 2:
        raise ValueError(f"{option} = {value}: must be a whole number >= 2 (the first cycle is "
                         "start-up)")
    return value


def _damper_preset(option: str, name: str):
    """The damper preset ``name`` (railride.dampers.PRESETS), else ValueError naming the option."""
    from . import dampers

    if name not in dampers.PRESETS:
        raise ValueError(f"{option} = {name!r}: unknown damper model; allowed: "
                         f"{', '.join(dampers.PRESETS)}")
    return dampers.preset(name)


def _voltage(option: str, text: str, damper) -> float:
    """One voltage [V]: a number, ``passive-off`` (v_min) or ``passive-on`` (v_max), checked
    against the damper's range."""
    text = text.strip()
    keywords = {"passive-off": damper.v_min, "passive-on": damper.v_max}
    if text in keywords:
        return float(keywords[text])
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{option} = {text!r}: not a number of volts (nor passive-off, "
                         "passive-on)") from None
    return damper.check_voltage(value, option)


def _voltage_list(option: str, text: str, damper) -> list[float]:
    """A comma-separated list of distinct voltages [V], each checked against the damper's range."""
    items = text.split(",")
    if any(not item.strip() for item in items):
        raise ValueError(f"{option} = {text!r}: an empty item; give volts separated by commas, "
                         "e.g. 0,1,2.25")
    values = [_voltage(option, item, damper) for item in items]
    seen = set()
    for v in values:
        if v in seen:
            raise ValueError(f"{option} = {text!r}: {v:g} V is listed twice")
        seen.add(v)
    return values


def _write_folder(out: Path, write) -> None:
    """Run ``write()`` (a report.write_* call) with a status note; OSError -> status 2."""
    try:
        with _status(f"writing outputs to {out}..."):
            paths = write()
    except OSError as exc:
        raise CliError(f"cannot write the output folder {out}: {exc.strerror or exc}", 2) from None
    typer.echo(f"wrote {', '.join(p.name for p in paths)} to {out}", err=True)


def _print_json(doc) -> None:
    typer.echo(json.dumps(doc, indent=2, allow_nan=False))


# -- options shared by both commands ------------------------------------------------------------
ParamsOption = Annotated[Optional[Path], typer.Option(
    "--params", metavar="FILE.toml",
    help="Vehicle parameters from a TOML file with a [vehicle] table (see docs/cli.md). "
         "Exclusive with --preset.")]
PresetOption = Annotated[Optional[str], typer.Option(
    "--preset", metavar="NAME",
    help="Named vehicle parameter set (available: paper). Default: paper.")]
FormatOption = Annotated[OutputFormat, typer.Option(
    "--format", case_sensitive=False, help="Output on stdout: a table or a JSON document.")]


# -- compare ------------------------------------------------------------------------------------
#: table labels of the four ride responses (keys of railride.metrics.RESPONSES)
RESPONSE_LABELS = {"acceleration_m_s2": "acceleration (m/s^2)", "displacement_m": "displacement (m)",
                   "pitch_deg": "pitch (deg)", "roll_deg": "roll (deg)"}


def _controller_list(text: str) -> list[str]:
    """--controllers: comma-separated names -> the suspensions to run, passive first."""
    from .comparison import check_controllers
    from .control import CONTROLLERS

    items = [item.strip() for item in text.split(",")]
    if any(not item for item in items):
        raise ValueError(f"--controllers = {text!r}: an empty item; give names separated by "
                         f"commas from {', '.join(CONTROLLERS)}")
    try:
        return check_controllers(items)
    except ValueError as exc:
        raise ValueError(f"--controllers = {text!r}: {exc}") from None


def _gain_set(path: Optional[Path]):
    """The shipped gains, or --gains FILE with the library's message (file, table, entry)."""
    from .control import GainSet

    if path is None:
        return GainSet.default()
    try:
        return GainSet.load(path)
    except ValueError as exc:
        raise ValueError(f"--gains: {exc}") from None


#: --sensor-noise items: (name, unit)
_NOISE_ITEMS = (("Z", "m"), ("ANGLE", "rad"), ("VEL", "m/s"), ("RATE", "rad/s"))


def _sensor_noise(text: Optional[str], seed: Optional[int]):
    """--sensor-noise Z,ANGLE,VEL,RATE and --seed -> a control.SensorNoise, or None."""
    from .control import SensorNoise

    if text is None:
        if seed is not None:
            raise ValueError(f"--seed = {seed}: applies with --sensor-noise only (without it the "
                             "measurements are ideal)")
        return None
    form = ",".join(n for n, _ in _NOISE_ITEMS)
    units = ", ".join(u for _, u in _NOISE_ITEMS)
    items = [item.strip() for item in text.split(",")]
    if len(items) != len(_NOISE_ITEMS):
        raise ValueError(f"--sensor-noise = {text!r}: expected four numbers {form} ({units}), "
                         f"got {len(items)} item(s)")
    values = []
    for (name, unit), item in zip(_NOISE_ITEMS, items):
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"--sensor-noise = {text!r}: {name} = {item!r} is not a number "
                             f"({unit})") from None
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"--sensor-noise = {text!r}: {name} = {item}: must be a finite "
                             f"number >= 0 ({unit}, a standard deviation)")
        values.append(value)
    if seed is not None and seed < 0:
        raise ValueError(f"--seed = {seed}: must be a whole number >= 0")
    return SensorNoise(*values, seed=0 if seed is None else seed)


def _check_control_rate(rate: float, dt: float) -> float:
    """--control-rate: > 0 and a whole number of RK4 steps per controller period."""
    rate = _check_number("--control-rate", rate, "Hz")
    stride = 1.0 / (rate * dt)
    if round(stride) < 1 or abs(round(stride) - stride) > 1e-6 * stride:
        raise ValueError(f"--control-rate = {rate:g} Hz with --dt = {dt:g} s: the controller "
                         "period 1/rate must be a whole number of steps dt")
    return rate


def _fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def _reduction_text(value, spec: str = ".1f") -> str:
    if value is None:
        return ""
    text = format(value, spec)
    return f"[red]{text}[/red]" if value < 0 else text


def _compare_tables(doc: dict, vehicle: str, shipped: bool):
    """The three tables of `compare`: Table 1 beside the paper, peak-to-peak, damper demands."""
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    from .report import describe_scenario

    rows = doc["controllers"]
    settings = doc["settings"]
    controlled = [r for r in rows if r["name"] != "passive"]

    # 1. the paper's Table 1: RMS and reduction, railride above the paper
    start, end = settings["window_s"] or (0.0, settings["scenario"].get("duration_s", 0.0))
    info = [describe_scenario(settings["scenario"]),
            f"dt {settings['dt_s']:g} s, RMS over {start:g}-{end:g} s, vehicle {vehicle}"]
    if controlled:
        noise = settings.get("sensor_noise")
        noise_text = ("ideal measurements" if not noise else
                      "sensor noise z {displacement:g} m, angle {angle:g} rad, velocity {velocity:g} m/s, "
                      "rate {angular_rate:g} rad/s, seed {seed}".format(**noise))
        info.append(f"{settings['damper']} MR dampers, controller {settings['control_rate_hz']:g} Hz, "
                    f"{noise_text}")
        info.append(f"gains file {doc['gains']['source']}" + (" (shipped)" if shipped else ""))
    info.append("The paper's absolute values depend on settings it does not give (sine wavelength, "
                "rail phase, damper, gains): compare the ranking and the size of the reductions, "
                "not the digits. red. % = (passive - controlled) / passive x 100 (negative: worse "
                "than passive, in red).")
    table = Table(title="Ride comparison: RMS of the carbody responses beside the paper's Table 1")
    table.add_column("response", min_width=12)
    table.add_column("", no_wrap=True)
    for r in rows:
        table.add_column(escape(r["label"].replace(" (", "\n(")), justify="right", min_width=8)
        if r["name"] != "passive":
            table.add_column("red. %", justify="right", min_width=5)
    for key, label in RESPONSE_LABELS.items():
        ours, paper = [label, "railride"], ["", "[dim]paper[/dim]"]
        for r in rows:
            ours.append(f"{r['metrics'][key]['rms']:#.4g}")
            p = r["paper"][key]
            paper.append(f"[dim]{p['rms']:g}[/dim]")
            if r["name"] != "passive":
                ours.append(_reduction_text(r["reduction_percent"][key]))
                paper.append(f"[dim]{p['reduction_percent']:.1f}[/dim]")
        table.add_row(*ours)
        table.add_row(*paper, end_section=True)

    # 2. peak-to-peak
    ptp = Table(title="Peak-to-peak of the carbody responses (railride)")
    ptp.add_column("response")
    for r in rows:
        ptp.add_column(escape(r["label"]), justify="right", min_width=8)
    for key, label in RESPONSE_LABELS.items():
        ptp.add_row(label, *[f"{r['metrics'][key]['ptp']:#.4g}" for r in rows])

    # 3. what each suspension asks of its dampers
    demands = Table(title="What each suspension asks of its dampers")
    demands.add_column("suspension", no_wrap=True)
    for heading in ("RMS force\n(kN)", "max force\n(kN)", "RMS travel\n(mm)", "max travel\n(mm)",
                    "mean voltage\n(V)", "time at v_max\n(%)"):
        demands.add_column(heading, justify="right", min_width=6)
    for r in rows:
        d = r["damper"]
        at_max = d.get("voltage_at_max_fraction")
        demands.add_row(escape(r["label"]), f"{d['force_rms_n'] / 1e3:.2f}",
                        f"{d['force_max_n'] / 1e3:.2f}", f"{d['travel_rms_m'] * 1e3:.1f}",
                        f"{d['travel_max_m'] * 1e3:.1f}", _fmt(d.get("voltage_mean_v"), ".2f"),
                        "-" if at_max is None else f"{at_max * 100:.1f}")
    demands_note = ("All four corners, over the metric window. force: the secondary damper force on "
                    "the carbody; travel: the secondary deflection (suspension travel); passive: "
                    "the viscous dampers c_sz.")
    return [table, Text("\n".join(info)), "", ptp, "", demands, Text(demands_note)]


@app.command()
def compare(
    controllers: Annotated[str, typer.Option(
        "--controllers", metavar="NAME[,NAME...]",
        help="Suspensions to compare, comma-separated: passive, pid, sas-attitude, "
             "sas-attitude-ride. Passive always runs as the baseline.")]
        = "passive,pid,sas-attitude,sas-attitude-ride",
    gains: Annotated[Optional[Path], typer.Option(
        "--gains", metavar="FILE.toml",
        help="Controller gains from a TOML file with [inner], [pid], [sas.attitude] and "
             "[sas.ride] (default: the shipped railride/data/gains.toml).")] = None,
    damper: Annotated[str, typer.Option(
        "--damper", metavar="MODEL",
        help="MR damper model of the controlled suspensions: railway, dyke1996 or "
             "spencer1997.")] = DEFAULT_DAMPER,
    control_rate: Annotated[float, typer.Option(
        "--control-rate", metavar="HZ",
        help="Sample rate of the outer-loop controllers [Hz]; 1/(rate x dt) must be a whole "
             "number.")] = 1000.0,
    sensor_noise: Annotated[Optional[str], typer.Option(
        "--sensor-noise", metavar="Z,ANGLE,VEL,RATE",
        help="White noise on the measured carbody states, standard deviations: heave [m], "
             "pitch and roll angle [rad], heave velocity [m/s], pitch and roll rate [rad/s] "
             "(default: ideal measurements).")] = None,
    seed: Annotated[Optional[int], typer.Option(
        "--seed", metavar="N",
        help="Seed of the sensor noise, >= 0 (default 0); needs --sensor-noise.")] = None,
    scenario: Annotated[str, typer.Option(
        "--scenario", metavar="NAME",
        help="paper-sine (the paper's sine rails), bump or file:PATH, as for simulate.")]
        = "paper-sine",
    amplitude: Annotated[Optional[float], typer.Option(
        "--amplitude", metavar="M",
        help="paper-sine: sine amplitude [m] (default 0.05). bump: bump height [m] "
             "(default 0.02).")] = None,
    wavelength: Annotated[Optional[float], typer.Option(
        "--wavelength", metavar="M",
        help="paper-sine: wavelength [m] (default 60). bump: bump length [m] (default 10).")] = None,
    rail_phase: Annotated[Optional[float], typer.Option(
        "--rail-phase", metavar="DEG",
        help="paper-sine only: phase lag of the right rail [deg] (default 90).")] = None,
    speed: Annotated[Optional[float], typer.Option(
        "--speed", metavar="M/S", help="Vehicle speed [m/s] (default 55.56).")] = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time [s] (default 10).")] = None,
    dt: Annotated[Optional[float], typer.Option(
        "--dt", metavar="S", help="Fixed RK4 time step [s] (default 1e-4).")] = None,
    output_rate: Annotated[Optional[float], typer.Option(
        "--output-rate", metavar="HZ",
        help="Sampling rate of the stored time histories [Hz] (default 1000).")] = None,
    window: Annotated[Optional[str], typer.Option(
        "--window", metavar="START:END",
        help="Time window of the metrics [s], e.g. 2:10 (default: the whole run).")] = None,
    params: ParamsOption = None,
    preset: PresetOption = None,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write compare.json, compare.nc, compare.csv and the plots acceleration.png, "
             "displacement.png, pitch.png, roll.png, damper_forces.png, voltages.png into DIR "
             "(created if missing; all or nothing).")] = None,
) -> None:
    """Compare passive, PID and SAS suspensions on one scenario, as in the paper's Table 1.

    Runs the passive vehicle (the baseline) and each controller (MR dampers closed by the
    force-tracking inner loop) with the shipped gains, and prints the RMS of the carbody
    responses with the reduction against passive beside the paper's values, the peak-to-peak
    values and what each suspension asks of its dampers. Without options: the paper's
    scenario paper-sine.
    """
    with _errors():
        from . import report
        from .comparison import compare as run_compare
        from .metrics import check_window, parse_window
        from .simulation import DEFAULT_DT, DEFAULT_OUTPUT_RATE
        from .track import scenario as make_scenario

        names = _controller_list(controllers)
        gain_set = _gain_set(gains)
        _damper_preset("--damper", damper)
        noise = _sensor_noise(sensor_noise, seed)
        dt = DEFAULT_DT if dt is None else dt
        output_rate = DEFAULT_OUTPUT_RATE if output_rate is None else output_rate
        control_rate = _check_control_rate(control_rate, _check_number("--dt", dt, "s"))
        vehicle_params, vehicle_record = _vehicle_params(params, preset)
        window_value = parse_window(window) if window is not None else None
        scen = make_scenario(scenario, amplitude=amplitude, wavelength=wavelength,
                             rail_phase=rail_phase, speed=speed, duration=duration)
        if out is not None:
            report.check_out_dir(out)
        # check the window before the runs, and record it resolved
        window_value = check_window(window_value or (0.0, math.inf), scen.duration)

        controlled = [n for n in names if n != "passive"]

        def describe(done: float) -> str:
            if done < 0.5 or not controlled:
                return "running the passive baseline..."
            return f"running {', '.join(controlled)}..."

        with _Progress(_stderr_is_terminal(), describe) as progress:
            result = run_compare(scen, vehicle_params, controllers=names, gains=gain_set,
                                 damper=damper, window=window_value, dt=dt,
                                 output_rate=output_rate, control_rate=control_rate,
                                 sensor_noise=noise,
                                 progress=progress if progress.enabled else None)
        doc = result.to_dict()
        text = json.dumps(doc, indent=2, allow_nan=False)  # refuses NaN before anything is written
        if out is not None:
            _write_folder(out, lambda: report.write_compare_outputs(result, out, doc))
    if format is OutputFormat.json:
        typer.echo(text)
        return
    vehicle = vehicle_record.get("vehicle_preset") or vehicle_record.get("vehicle_params_file")
    console = _wide_stdout_console()
    for part in _compare_tables(doc, vehicle, shipped=gains is None):
        console.print(part)


# -- modes --------------------------------------------------------------------------------------
@app.command()
def modes(
    format: FormatOption = OutputFormat.table,
    params: ParamsOption = None,
    preset: PresetOption = None,
) -> None:
    """Natural frequencies and damping of the passive vehicle (9 modes, ascending frequency)."""
    with _errors():
        from .vehicle import Vehicle

        vehicle_params, _ = _vehicle_params(params, preset)
        rows = [m.to_dict() for m in Vehicle(vehicle_params).modes()]
    if format is OutputFormat.json:
        typer.echo(json.dumps(rows, indent=2, allow_nan=False))
        return
    from rich.table import Table

    from rich.markup import escape

    table = Table(title="Modes of the passive vehicle")
    table.add_column("#", justify="right")
    table.add_column("mode", no_wrap=True)
    table.add_column("undamped (Hz)", justify="right")
    table.add_column("damped (Hz)", justify="right")
    table.add_column("damping ratio", justify="right")
    for i, r in enumerate(rows, start=1):
        table.add_row(str(i), escape(r["label"]), f"{r['frequency_hz']:.3f}",
                      f"{r['damped_frequency_hz']:.3f}", f"{r['damping_ratio']:.3f}")
    _stdout_console().print(table)


# -- simulate -----------------------------------------------------------------------------------
class _Progress:
    """A progress bar on stderr, only when stderr is a terminal.

    ``describe(done)`` gives the bar's text for a done fraction (default: "simulating"); until
    the first report, a stepper not yet compiled in this process says that it compiles."""

    def __init__(self, enabled: bool, describe=None):
        self.enabled = enabled
        self._describe = describe or (lambda done: "simulating")
        self._progress = None
        self._task = None

    def __enter__(self):
        if not self.enabled:
            return self
        from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        from . import kernels

        compiled = bool(getattr(kernels.run_batch, "signatures", True))
        first = (self._describe(0.0) if compiled
                 else "loading the stepper (the first run compiles it, up to a minute)...")
        self._progress = Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                                  TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                                  console=_stderr_console(), transient=True)
        self._progress.__enter__()
        self._task = self._progress.add_task(first, total=1.0)
        return self

    def __call__(self, done: float) -> None:
        if self._progress is not None:
            self._progress.update(self._task, completed=done, description=self._describe(done))

    def __exit__(self, *exc):
        if self._progress is not None:
            self._progress.__exit__(*exc)
        return False


def _status(message: str):
    if not _stderr_is_terminal():
        return contextlib.nullcontext()
    return _stderr_console().status(message)


def _describe_suspension(record: dict) -> str:
    if record.get("type") == "mr":
        return f"MR, {record['damper']} dampers at {record['voltage_v']:g} V"
    return "passive (viscous c_sz)"


def _metrics_table(doc: dict):
    from rich.markup import escape
    from rich.table import Table

    labels = {"acceleration_m_s2": "acceleration (m/s^2)", "displacement_m": "displacement (m)",
              "pitch_deg": "pitch (deg)", "roll_deg": "roll (deg)"}
    sc, st = doc["scenario"], doc["settings"]
    start, end = st["window_s"]
    vehicle = doc.get("vehicle_preset") or doc.get("vehicle_params_file")
    caption = "\n".join([
        f"scenario {sc.get('name')}, speed {sc.get('speed_m_s'):g} m/s",
        f"duration {sc.get('duration_s'):g} s, dt {st['dt_s']:g} s, window {start:g}-{end:g} s",
        f"vehicle {vehicle}",
        f"suspension {_describe_suspension(doc.get('suspension') or {'type': 'passive'})}",
    ])
    table = Table(title="Ride metrics (carbody CG)", caption=escape(caption))
    table.add_column("response")
    table.add_column("RMS", justify="right")
    table.add_column("peak-to-peak", justify="right")
    for key, values in doc["metrics"].items():
        table.add_row(labels.get(key, key), f"{values['rms']:.5g}", f"{values['ptp']:.5g}")
    return table


@app.command()
def simulate(
    scenario: Annotated[str, typer.Option(
        "--scenario", metavar="NAME",
        help="paper-sine (the paper's sine rails), bump (a cosine bump on both rails) or "
             "file:PATH (a measured CSV with columns s, z_L, z_R in metres).")] = "paper-sine",
    amplitude: Annotated[Optional[float], typer.Option(
        "--amplitude", metavar="M",
        help="paper-sine: sine amplitude [m] (default 0.05). bump: bump height [m], negative "
             "for a dip (default 0.02).")] = None,
    wavelength: Annotated[Optional[float], typer.Option(
        "--wavelength", metavar="M",
        help="paper-sine: wavelength [m] (default 60). bump: bump length [m] (default 10).")] = None,
    rail_phase: Annotated[Optional[float], typer.Option(
        "--rail-phase", metavar="DEG",
        help="paper-sine only: phase lag of the right rail [deg] (default 90).")] = None,
    speed: Annotated[Optional[float], typer.Option(
        "--speed", metavar="M/S", help="Vehicle speed [m/s] (default 55.56).")] = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time [s] (default 10).")] = None,
    dt: Annotated[Optional[float], typer.Option(
        "--dt", metavar="S", help="Fixed RK4 time step [s] (default 1e-4).")] = None,
    output_rate: Annotated[Optional[float], typer.Option(
        "--output-rate", metavar="HZ",
        help="Sampling rate of the stored time histories [Hz] (default 1000); 1/(rate x dt) "
             "must be a whole number.")] = None,
    window: Annotated[Optional[str], typer.Option(
        "--window", metavar="START:END",
        help="Time window of the metrics [s], e.g. 2:10; either side may be empty "
             "(default: the whole run).")] = None,
    suspension: Annotated[str, typer.Option(
        "--suspension", metavar="passive|mr",
        help="Secondary vertical dampers: passive (viscous c_sz) or mr (an MR damper model at "
             "each corner, constant command voltage).")] = "passive",
    damper: Annotated[Optional[str], typer.Option(
        "--damper", metavar="MODEL",
        help="--suspension mr only: damper model railway, dyke1996 or spencer1997 "
             "(default railway).")] = None,
    voltage: Annotated[Optional[str], typer.Option(
        "--voltage", metavar="V",
        help="--suspension mr only: constant command voltage [V] within the damper's range, or "
             "passive-off (v_min, the default) or passive-on (v_max).")] = None,
    params: ParamsOption = None,
    preset: PresetOption = None,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write ride.nc, ride.csv, metrics.json and body_responses.png into DIR "
             "(created if missing; all or nothing).")] = None,
) -> None:
    """Simulate the vehicle on a track and print the ride metrics."""
    with _errors():
        doc, result = _run(scenario, amplitude, wavelength, rail_phase, speed, duration, dt,
                           output_rate, window, params, preset, out, suspension, damper, voltage)
    if format is OutputFormat.json:
        _print_json(doc)
    else:
        _stdout_console().print(_metrics_table(doc))


def _suspension(suspension: str, damper_name, voltage_text):
    """(damper model or None, command voltage or None, the record for the JSON document)."""
    if suspension not in SUSPENSIONS:
        raise ValueError(f"--suspension = {suspension!r}: allowed {', '.join(SUSPENSIONS)}")
    if suspension == "passive":
        given = [o for o, v in (("--damper", damper_name), ("--voltage", voltage_text)) if v is not None]
        if given:
            verb = "applies" if len(given) == 1 else "apply"
            raise ValueError(f"{' and '.join(given)} {verb} to --suspension mr only (the passive "
                             "suspension has viscous dampers)")
        return None, None, {"type": "passive"}
    name = DEFAULT_DAMPER if damper_name is None else damper_name
    model = _damper_preset("--damper", name)
    volts = model.v_min if voltage_text is None else _voltage("--voltage", voltage_text, model)
    return model, float(volts), {"type": "mr", "damper": name, "voltage_v": float(volts)}


def _run(scenario_name, amplitude, wavelength, rail_phase, speed, duration, dt, output_rate,
         window_text, params_file, preset, out, suspension="passive", damper_name=None,
         voltage_text=None):
    from . import report
    from .metrics import check_window, parse_window, to_dict
    from .simulation import DEFAULT_DT, DEFAULT_OUTPUT_RATE, simulate as run_simulation
    from .track import scenario as make_scenario

    dt = DEFAULT_DT if dt is None else dt
    output_rate = DEFAULT_OUTPUT_RATE if output_rate is None else output_rate
    vehicle_params, vehicle_record = _vehicle_params(params_file, preset)
    damper, voltage, suspension_record = _suspension(suspension, damper_name, voltage_text)
    window = parse_window(window_text) if window_text is not None else None
    scen = make_scenario(scenario_name, amplitude=amplitude, wavelength=wavelength,
                         rail_phase=rail_phase, speed=speed, duration=duration)
    if out is not None:
        report.check_out_dir(out)
    # check the window before the run, not after it
    start, end = (0.0, scen.duration) if window is None else check_window(window, scen.duration)

    with _Progress(_stderr_is_terminal()) as progress:
        result = run_simulation(scen, vehicle_params, dt=dt, output_rate=output_rate,
                                damper=damper, voltage=voltage,
                                progress=progress if progress.enabled else None)
    metrics = result.metrics(window)
    doc = {
        "schema": SCHEMA_SIMULATE,
        "railride_version": __version__,
        "scenario": scen.describe(),
        **vehicle_record,
        "suspension": suspension_record,
        "settings": {"dt_s": float(dt), "output_rate_hz": float(output_rate),
                     "window_s": [float(start), float(end)]},
        "metrics": to_dict(metrics),
    }
    if out is not None:
        _write_folder(out, lambda: report.write_outputs(result, out, doc))
    return doc, result


# -- damper -------------------------------------------------------------------------------------
@app.command()
def damper(
    model: Annotated[str, typer.Option(
        "--model", metavar="MODEL",
        help="Damper model: railway, dyke1996 or spencer1997.")] = DEFAULT_DAMPER,
    amplitude: Annotated[float, typer.Option(
        "--amplitude", metavar="M", help="Amplitude of the sine extension x [m], > 0.")] = ...,
    frequency: Annotated[float, typer.Option(
        "--frequency", metavar="HZ", help="Frequency of the sine extension [Hz], > 0.")] = ...,
    voltage: Annotated[str, typer.Option(
        "--voltage", metavar="V[,V...]",
        help="Constant command voltages [V], comma-separated, each within the damper's range "
             "(passive-off and passive-on stand for its lowest and highest voltage).")] = ...,
    cycles: Annotated[int, typer.Option(
        "--cycles", metavar="N",
        help="Cycles driven per voltage, >= 2; the last one is reported (steady state).")] = 4,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write loops.png, cycles.csv and damper.json into DIR (created if missing; "
             "all or nothing).")] = None,
) -> None:
    """Hysteresis cycles of an MR damper on a test rig.

    The damper is stroked by x = A sin(2 pi f t) at each constant voltage; per voltage the
    command prints the force range and the energy dissipated in the last (steady-state) cycle.
    """
    with _errors():
        from . import report, rig

        damper_model = _damper_preset("--model", model)
        amplitude = _check_number("--amplitude", amplitude, "m")
        frequency = _check_number("--frequency", frequency, "Hz")
        volts = _voltage_list("--voltage", voltage, damper_model)
        n_cycles = _check_cycles("--cycles", cycles)
        if out is not None:
            report.check_out_dir(out)
        with _status("driving the damper..."):
            result = rig.cycles(damper_model, amplitude, frequency, volts, n_cycles=n_cycles)
        record = result.to_dict()
        doc = {
            "schema": SCHEMA_DAMPER,
            "railride_version": __version__,
            "damper": record["damper"],
            "amplitude_m": float(record["amplitude_m"]),
            "frequency_hz": float(record["frequency_hz"]),
            "cycles": [{key: float(row[key]) for key in ("voltage_v", "force_max_n", "force_min_n",
                                                       "energy_per_cycle_j")}
                       for row in record["cycles"]],
        }
        title = (f"{model} damper ({damper_model.model} model), x = {amplitude * 1e3:g} mm "
                 f"sin(2 pi {frequency:g} Hz t), cycle {n_cycles} of {n_cycles}")
        if not all(math.isfinite(v) for row in doc["cycles"] for v in row.values()):
            raise RuntimeError("the damper rig run gave a non-finite force or energy")
        if out is not None:
            _write_folder(out, lambda: report.write_damper_outputs(result, out, doc, title=title))
    if format is OutputFormat.json:
        _print_json(doc)
        return
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(f"Damper cycles: {model} ({damper_model.model} model)"),
                  caption=escape(f"x = {amplitude:g} m sin(2 pi {frequency:g} Hz t); cycle "
                                 f"{n_cycles} of {n_cycles} (steady state)\nforce F: tension +"))
    table.add_column("voltage (V)", justify="right")
    table.add_column("max force (kN)", justify="right")
    table.add_column("min force (kN)", justify="right")
    table.add_column("energy per cycle (J)", justify="right")
    for row in doc["cycles"]:
        table.add_row(f"{row['voltage_v']:g}", f"{row['force_max_n'] / 1e3:.3f}",
                      f"{row['force_min_n'] / 1e3:.3f}", f"{row['energy_per_cycle_j']:.4g}")
    _stdout_console().print(table)


# -- tracking -----------------------------------------------------------------------------------
@app.command()
def tracking(
    desired: Annotated[str, typer.Option(
        "--desired", metavar="sine|sawtooth",
        help="Desired force: sine, or sawtooth (rising from -A to A each period).")] = "sine",
    amplitude: Annotated[float, typer.Option(
        "--amplitude", metavar="N", help="Amplitude of the desired force [N], > 0.")] = 10e3,
    frequency: Annotated[float, typer.Option(
        "--frequency", metavar="HZ",
        help="Frequency of the desired force and of the stroke [Hz], > 0.")] = 1.0,
    gain_b: Annotated[float, typer.Option(
        "--B", metavar="B", help="Inner-loop gain B on the measured force [-], >= 0.")] = 1.0,
    gain_g: Annotated[Optional[float], typer.Option(
        "--G", metavar="V/N",
        help="Inner-loop gain G [V/N], >= 0 (default: the damper's default gain, which "
             "saturates the voltage at a force error of a tenth of its range).")] = None,
    model: Annotated[str, typer.Option(
        "--model", metavar="MODEL",
        help="Damper model: railway, dyke1996 or spencer1997.")] = DEFAULT_DAMPER,
    stroke: Annotated[float, typer.Option(
        "--stroke", metavar="M",
        help="Amplitude of the prescribed extension x = -stroke cos(2 pi f t) [m], > 0.")] = 0.02,
    cycles: Annotated[int, typer.Option(
        "--cycles", metavar="N",
        help="Cycles simulated, >= 2; the metrics leave out the first (start-up).")] = 3,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write tracking.png, tracking.csv and tracking.json into DIR (created if "
             "missing; all or nothing).")] = None,
) -> None:
    """Force tracking of an MR damper by the inner loop.

    The inner loop of spec section 6 sets the voltage so that a damper stroked by
    x = -stroke cos(2 pi f t) follows a desired force; prints the RMS tracking error.
    """
    with _errors():
        from . import report, rig

        if desired not in DESIRED_SIGNALS:
            raise ValueError(f"--desired = {desired!r}: allowed {', '.join(DESIRED_SIGNALS)}")
        damper_model = _damper_preset("--model", model)
        amplitude = _check_number("--amplitude", amplitude, "N")
        frequency = _check_number("--frequency", frequency, "Hz")
        gain_b = _check_number("--B", gain_b, "", allow_zero=True)
        if gain_g is not None:
            gain_g = _check_number("--G", gain_g, "V/N", allow_zero=True)
        stroke = _check_number("--stroke", stroke, "m")
        n_cycles = _check_cycles("--cycles", cycles)
        if out is not None:
            report.check_out_dir(out)
        with _status("tracking..."):
            result = rig.track(damper_model, desired, amplitude, frequency, B=gain_b, G=gain_g,
                               stroke=stroke, n_cycles=n_cycles)
        metrics = result.metrics()
        attrs = result.dataset.attrs
        doc = {
            "schema": SCHEMA_TRACKING,
            "railride_version": __version__,
            "damper": damper_model.to_dict(),
            "desired": desired,
            "amplitude_n": amplitude,
            "frequency_hz": frequency,
            "stroke_m": stroke,
            "B": float(attrs["B"]),  # the gains the inner loop used (G filled in if default)
            "G_v_per_n": float(attrs["G_v_per_n"]),
            "metrics": {
                "rms_error_n": float(metrics["rms_error_n"]),
                "rms_demand_n": float(metrics["rms_demand_n"]),
                "normalised_rms_error": float(metrics["normalised_rms_error"]),
                "window_s": [float(t) for t in metrics["window_s"]],
            },
        }
        bad = [k for k, v in doc["metrics"].items() if k != "window_s" and not math.isfinite(v)]
        if bad:  # checked before anything is written
            raise RuntimeError(f"the tracking run gave a non-finite {', '.join(bad)}")
        title = (f"{desired} demand {amplitude / 1e3:g} kN at {frequency:g} Hz, {model} damper, "
                 f"B = {doc['B']:g}, G = {doc['G_v_per_n']:.3g} V/N: normalised RMS error "
                 f"{doc['metrics']['normalised_rms_error']:.3f}")
        if out is not None:
            _write_folder(out, lambda: report.write_tracking_outputs(result, out, doc, title=title))
    if format is OutputFormat.json:
        _print_json(doc)
        return
    from rich.markup import escape
    from rich.table import Table

    m = doc["metrics"]
    start, end = m["window_s"]
    caption = "\n".join([
        f"desired force amplitude {amplitude:g} N at {frequency:g} Hz",
        f"stroke x = -{stroke:g} m cos(2 pi f t); force tension +",
        f"metrics over {start:g}-{end:g} s (after the first cycle)",
    ])
    table = Table(title=escape(f"Force tracking: {desired} demand, {model} damper"),
                  caption=escape(caption), min_width=56)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("RMS tracking error (N)", f"{m['rms_error_n']:.5g}")
    table.add_row("RMS demand (N)", f"{m['rms_demand_n']:.5g}")
    table.add_row("normalised error (-)", f"{m['normalised_rms_error']:.4f}")
    table.add_row("B (-)", f"{doc['B']:g}")
    table.add_row("G (V/N)" + (" default" if gain_g is None else ""), f"{doc['G_v_per_n']:.4g}")
    _stdout_console().print(table)


def main() -> None:
    """Entry point of the ``railride`` console script."""
    app(prog_name="railride")


if __name__ == "__main__":
    main()
