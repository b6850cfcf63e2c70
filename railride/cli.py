"""The ``railride`` command line: ``railride compare``, ``railride modes``, ``railride frf``,
``railride simulate``, ``railride damper``, ``railride tracking``, ``railride tune``,
``railride pareto`` and ``railride sweep``.

A thin layer over the library: it parses options, calls `railride.vehicle`, `railride.track`,
`railride.simulation`, `railride.metrics`, `railride.dampers`, `railride.rig`,
`railride.control`, `railride.comparison`, `railride.sweep`, `railride.tuning` and
`railride.report`, and prints. See docs/cli.md.

Exit statuses: 0 success, 1 the simulation diverged, 2 bad input (usage errors, invalid values,
unreadable files, an output folder that cannot be written), 130 `tune`, `pareto` or `sweep`
interrupted by Ctrl-C (the finished runs stay in DIR/runs.csv for --resume). Errors print one line
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
from .dampers import IDEAL_NAMES
from .defaults import DEFAULT_CONTROL_RATE, DEFAULT_DAMPER

SCHEMA_SIMULATE = "railride.simulation/1"
SCHEMA_DAMPER = "railride.damper/1"
SCHEMA_TRACKING = "railride.tracking/1"

#: --suspension values of `simulate`
SUSPENSIONS = ("passive", "mr")
#: --desired values of `tracking` (the signals of railride.rig.desired_force_signal)
DESIRED_SIGNALS = ("sine", "sawtooth")

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
    help="Vertical ride of a 9-DOF railway vehicle: the paper's comparison of passive, PID and "
         "SAS suspensions (start with `railride compare`), modes and frequency responses, "
         "simulated ride metrics on sine, bump, measured or random tracks, and MR damper rig "
         "tests (hysteresis cycles, force tracking).",
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


def _damper_preset(option: str, name: str, *, rig: bool = False):
    """The damper ``name`` (railride.dampers.NAMES: the MR presets and "ideal"), else ValueError
    naming the option. ``rig``: the MR presets only (the ideal actuator has no force law to
    drive on the rig)."""
    from . import dampers

    allowed = dampers.PRESETS if rig else dampers.NAMES
    if name not in allowed:
        why = (": the ideal actuator applies a vehicle controller's demand and has no force law "
               "to drive on the rig" if name in dampers.IDEAL_NAMES else ": unknown damper model")
        raise ValueError(f"{option} = {name!r}{why}; allowed: {', '.join(allowed)}")
    return dampers.preset(name)


def _damper_scale(option: str, value: Optional[str], damper_name: str) -> float:
    """--damper-scale: a finite number > 0 (default 1), not for the ideal actuator."""
    if value is None:
        return 1.0
    try:  # read as text, so that a word gets the one-line error too
        number = float(value)
    except ValueError:
        raise ValueError(f"{option} = {value!r}: must be a finite number > 0") from None
    scale = _check_number(option, number, "")
    if damper_name in IDEAL_NAMES:
        raise ValueError(f"{option} = {scale:g}: the ideal device (--damper {damper_name}) applies "
                         "the demand itself and has no force capacity to scale")
    return scale


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


# -- random-track scenarios (fra1..fra6, german-low, german-high) ---------------------------------
#: the options of the random-track scenarios: (option, keyword of track.scenario, unit)
TRACK_OPTIONS = (("--track-seed", "seed", ""), ("--min-wavelength", "min_wavelength", "m"),
                 ("--max-wavelength", "max_wavelength", "m"))
#: a random track's shortest wavelength must pass at speed / min_wavelength <= output rate /
#: RESOLUTION (the rule railride.simulation.simulate applies; checked here first so that the
#: message names the options and a sweep or tuning study fails before its first run)
RESOLUTION = 2.5


def _random_tracks() -> tuple:
    from .track import SPECTRA

    return SPECTRA


def _track_options(scenario_name: str, seed: Optional[int], min_wavelength: Optional[float],
                   max_wavelength: Optional[float]) -> dict:
    """--track-seed, --min-wavelength, --max-wavelength -> the keyword arguments of
    track.scenario that were given, checked with the options' names."""
    given = {"seed": seed, "min_wavelength": min_wavelength, "max_wavelength": max_wavelength}
    out = {}
    for option, keyword, unit in TRACK_OPTIONS:
        value = given[keyword]
        if value is None:
            continue
        if keyword == "seed":
            out[keyword] = _check_track_seed(option, value)
        else:
            out[keyword] = _check_number(option, value, unit)
    if out and scenario_name not in _random_tracks():
        option, keyword, unit = next(o for o in TRACK_OPTIONS if o[1] in out)
        value = f"{out[keyword]:g}" + (f" {unit}" if unit else "")
        raise ValueError(f"{option} = {value}: applies to the random-track scenarios "
                         f"({', '.join(_random_tracks())}) only, not to --scenario "
                         f"{scenario_name}")
    return out


def _check_track_seed(option: str, value) -> int:
    if isinstance(value, bool) or int(value) != value or value < 0:
        raise ValueError(f"{option} = {value}: must be a whole number >= 0 (the seed of the "
                         "random track)")
    return int(value)


def _make_scenario(name: str, options: dict, output_rate: Optional[float] = None,
                   rate_option: str = "--output-rate"):
    """track.scenario(name, **options); a wavelength-band error names the options given, and a
    random track whose shortest wavelength the output rate cannot resolve is refused here."""
    from .track import scenario as make_scenario

    if name in _random_tracks():
        for option, keyword, unit in (("--amplitude", "amplitude", "m"),
                                      ("--wavelength", "wavelength", "m"),
                                      ("--rail-phase", "rail_phase", "deg")):
            if options.get(keyword) is not None:
                raise ValueError(f"{option} = {options[keyword]:g} {unit}: does not apply to a "
                                 f"random track ({name}); its options are --track-seed, "
                                 "--min-wavelength and --max-wavelength")
    try:
        scen = make_scenario(name, **options)
    except ValueError as exc:
        band = [(o, k, u) for o, k, u in TRACK_OPTIONS if k != "seed" and k in options]
        if band and "wavelength" in str(exc):
            given = ", ".join(f"{o} = {options[k]:g} {u}" for o, k, u in band)
            raise ValueError(f"{given}: {exc}") from None
        if str(exc).startswith("unknown scenario"):
            raise ValueError(f"--scenario: {exc}") from None
        raise
    if output_rate is not None:
        _check_resolvable(scen, options, output_rate, rate_option)
    return scen


def _check_resolvable(scen, options: dict, output_rate: float, rate_option: str) -> None:
    lam = getattr(scen.track, "min_wavelength", None)
    if lam is None or not (math.isfinite(output_rate) and output_rate > 0):
        return  # not a random track; a bad rate is the library's to report
    if scen.speed / lam > output_rate / RESOLUTION:
        default = "" if "min_wavelength" in options else " (the default)"
        raise ValueError(
            f"--min-wavelength = {lam:g} m{default} at --speed {scen.speed:g} m/s is "
            f"{scen.speed / lam:g} Hz, more than {rate_option} {output_rate:g} Hz / "
            f"{RESOLUTION:g} = {output_rate / RESOLUTION:g} Hz can resolve: raise --min-wavelength "
            f"or lower --speed" + (f" or raise {rate_option}" if rate_option.startswith("--") else ""))


def _case_options(options: dict) -> dict:
    """Scenario options for a sweep.Case: the track seed as a NumPy integer.

    Case stores Python ints as floats, and a random track refuses a float seed; a NumPy
    integer passes through Case unchanged (a workaround until Case keeps whole numbers)."""
    import numpy as np

    return {k: (np.int64(v) if k == "seed" else v) for k, v in options.items()}


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
# executor options shared by tune and sweep
WorkersOption = Annotated[Optional[int], typer.Option(
    "--workers", metavar="N",
    help="Local executor: threads of each batch, 1..cores (default: every core).")]
SchedulerOption = Annotated[Optional[str], typer.Option(
    "--scheduler", metavar="ADDRESS",
    help="Run on a Dask cluster: the scheduler's address, e.g. tcp://host:8786.")]
SchedulerFileOption = Annotated[Optional[Path], typer.Option(
    "--scheduler-file", metavar="FILE",
    help="Run on a Dask cluster whose scheduler wrote FILE (dask scheduler --scheduler-file "
         "FILE).")]
# scenario and step options shared by simulate, compare and tune
AmplitudeOption = Annotated[Optional[float], typer.Option(
    "--amplitude", metavar="M",
    help="paper-sine: sine amplitude [m] (default 0.05). bump: bump height [m], negative for a "
         "dip (default 0.02).")]
WavelengthOption = Annotated[Optional[float], typer.Option(
    "--wavelength", metavar="M",
    help="paper-sine: wavelength [m] (default 60). bump: bump length [m] (default 10).")]
RailPhaseOption = Annotated[Optional[float], typer.Option(
    "--rail-phase", metavar="DEG",
    help="paper-sine only: phase lag of the right rail [deg] (default 90).")]
SpeedOption = Annotated[Optional[float], typer.Option(
    "--speed", metavar="M/S", help="Vehicle speed [m/s] (default 55.56).")]
DtOption = Annotated[Optional[float], typer.Option(
    "--dt", metavar="S", help="Fixed RK4 time step [s] (default 1e-4).")]
OutputRateOption = Annotated[Optional[float], typer.Option(
    "--output-rate", metavar="HZ",
    help="Sampling rate of the stored time histories [Hz] (default 1000); 1/(rate x dt) must "
         "be a whole number.")]
TrackSeedOption = Annotated[Optional[int], typer.Option(
    "--track-seed", metavar="N",
    help="Random tracks (fra1..fra6, german-low, german-high) only: the seed of the track's "
         "realisation, a whole number >= 0; the same seed gives the same track (default 0).")]
MinWavelengthOption = Annotated[Optional[float], typer.Option(
    "--min-wavelength", metavar="M",
    help="Random tracks only: shortest wavelength of the irregularity [m] (default 1); "
         "speed / M must not exceed the output rate / 2.5.")]
MaxWavelengthOption = Annotated[Optional[float], typer.Option(
    "--max-wavelength", metavar="M",
    help="Random tracks only: longest wavelength of the irregularity [m] (default 100).")]
SCENARIO_HELP = ("paper-sine (the paper's sine rails), bump (a cosine bump on both rails), "
                 "file:PATH (a measured CSV with columns s, z_L, z_R in metres), or a random "
                 "track: fra1..fra6 (FRA classes; 6 is the best track) or german-low, "
                 "german-high (see --track-seed, --min-wavelength, --max-wavelength).")


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
    values = _noise_items("--sensor-noise", text)
    if seed is not None and seed < 0:
        raise ValueError(f"--seed = {seed}: must be a whole number >= 0")
    return SensorNoise(*values, seed=0 if seed is None else seed)


def _noise_items(option: str, text: str) -> list[float]:
    """Z,ANGLE,VEL,RATE: four standard deviations >= 0, else ValueError naming the option."""
    form = ",".join(n for n, _ in _NOISE_ITEMS)
    units = ", ".join(u for _, u in _NOISE_ITEMS)
    items = [item.strip() for item in text.split(",")]
    if len(items) != len(_NOISE_ITEMS):
        raise ValueError(f"{option} = {text!r}: expected four numbers {form} ({units}), "
                         f"got {len(items)} item(s)")
    values = []
    for (name, unit), item in zip(_NOISE_ITEMS, items):
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"{option} = {text!r}: {name} = {item!r} is not a number "
                             f"({unit})") from None
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{option} = {text!r}: {name} = {item}: must be a finite "
                             f"number >= 0 ({unit}, a standard deviation)")
        values.append(value)
    return values


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


#: (index, row label, format) of the comfort tables of `simulate` and `compare`
COMFORT_ROWS = (("aw_Wk", "a_w Wk (m/s^2)", ".4f"), ("vdv_Wk", "VDV Wk (m/s^1.75)", ".4f"),
                ("aw_Wb", "a_w Wb (m/s^2)", ".4f"), ("N_MV_z", "N_MV,z (EN 12299)", ".3f"),
                ("Wz", "Wz (Sperling)", ".3f"))
#: where the comfort tables' positions are on the carbody floor
POSITION_LABELS = {"centre": "carbody centre", "front": "above the front bogie",
                   "rear": "above the rear bogie"}
SHORT_POSITION_LABELS = {"centre": "centre", "front": "front bogie", "rear": "rear bogie"}
ComfortOption = Annotated[bool, typer.Option(
    "--comfort",
    help="Also evaluate the ride comfort indices on the carbody floor at the centre and above "
         "the bogies (ISO 2631-1 a_w and VDV, the vertical part of EN 12299 N_MV, Sperling's "
         "Wz; docs/comfort.md) over the metrics window.")]


def _comfort_caption(record: dict) -> str:
    start, end = record["window_s"]
    return "\n".join(["floor points at x = " + ", ".join(
        f"{p['x_m']:g} m" for p in record["positions"].values()) + f"; window {start:g}-{end:g} s",
                      *record["notes"]])


def _comfort_table(record: dict):
    """The comfort table of `simulate`: one row per index, one column per position."""
    from rich.markup import escape
    from rich.table import Table

    positions = record["positions"]
    table = Table(title="Ride comfort (carbody floor)", caption=escape(_comfort_caption(record)))
    table.add_column("index")
    for name in positions:
        table.add_column(escape(POSITION_LABELS.get(name, name)), justify="right")
    for key, label, spec in COMFORT_ROWS:
        table.add_row(escape(label), *[format(p[key], spec) for p in positions.values()])
    table.add_row("comfort class (N_MV,z)", *[p["N_MV_z_class"] for p in positions.values()])
    return table


def _compare_comfort_table(rows: list[dict]):
    """The "ride comfort" table of `compare`: the indices at each position (rows), the
    suspensions (columns) with the reduction against passive where meaningful."""
    from rich.markup import escape
    from rich.table import Table

    first = rows[0]["comfort"]
    table = Table(title="Ride comfort on the carbody floor: centre and above the bogies",
                  caption=escape(_comfort_caption(first) + "\nred. % = (passive - controlled) / "
                                 "passive x 100; none for Wz, which is not proportional to the "
                                 "acceleration"))
    table.add_column("position", no_wrap=True)
    table.add_column("index", no_wrap=True)
    for r in rows:
        table.add_column(escape(r["label"].replace(" (", "\n(")), justify="right", min_width=8)
        if r["name"] != "passive":
            table.add_column("red. %", justify="right", min_width=5)
    for pos in first["positions"]:
        for n, (key, label, spec) in enumerate(COMFORT_ROWS):
            cells = [escape(SHORT_POSITION_LABELS.get(pos, pos)) if n == 0 else "", escape(label)]
            for r in rows:
                cells.append(format(r["comfort"]["positions"][pos][key], spec))
                if r["name"] != "passive":
                    red = r["comfort"].get("reduction_percent", {}).get(pos, {}).get(key)
                    cells.append(_reduction_text(red))
            table.add_row(*cells)
        cells = ["", "class (N_MV,z)"]
        for r in rows:
            cells.append(r["comfort"]["positions"][pos]["N_MV_z_class"])
            if r["name"] != "passive":
                cells.append("")
        table.add_row(*cells, end_section=True)
    return table


def _damper_text(settings: dict) -> str:
    from .report import describe_dampers

    return describe_dampers(settings, detail=True)


def _trade_off_lines(doc: dict) -> list[str]:
    """One line per trade-off of `Comparison.trade_offs`: what a controller loses for what it
    wins, against passive and against each other controller."""
    labels = {r["name"]: r["label"] for r in doc["controllers"]}
    words = {k: v.split(" (")[0] for k, v in RESPONSE_LABELS.items()}
    lines = []
    for t in doc.get("trade_offs", []):
        if not t["worse_on"]:
            continue
        a, b = labels[t["controller"]], labels.get(t["than"], t["than"])
        better = ", ".join(words[r] for r in t["better_on"]) or "nothing"
        worse = ", ".join(words[r] for r in t["worse_on"])
        lines.append(f"trade-off: {a} beats {b} on {better} but is worse on {worse}")
    return lines


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
        info.append(f"{_damper_text(settings)}, controller {settings['control_rate_hz']:g} Hz, "
                    f"{noise_text}")
        info.append(f"gains file {doc['gains']['source']}" + (" (shipped)" if shipped else ""))
        tuning = doc.get("tuning") or {}
        if tuning.get("objective"):
            info.append((f"gains tuned by `{tuning['command']}`, " if tuning.get("command") else
                         "gains tuned ") + f"objective {tuning['objective']}")
        if tuning.get("in_sample"):
            info.append("The gains were tuned on this same single track: the reductions are "
                        "in-sample, not a test on another track.")
        info += _trade_off_lines(doc)
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

    # 1b. the same gains on the ideal devices: what a damper, and an actuator, could reach
    bounds_parts = []
    if doc.get("bounds"):
        bt = Table(title="RMS reduction % beside the bounds: the same control laws and gains on "
                         "ideal devices")
        bt.add_column("response", min_width=20, no_wrap=True)
        short = {"pid": "PID", "sas-attitude": "SAS att.", "sas-attitude-ride": "SAS att.+ride"}
        for r in controlled:
            for head in ("MR", "ideal\ndamper", "ideal\nactuator"):
                name = short.get(r["name"], r["label"])
                bt.add_column(escape(f"{name}\n{head}") if head == "MR" else f"\n{head}",
                              justify="right", min_width=7)
        for key, label in RESPONSE_LABELS.items():
            cells = [label]
            for r in controlled:
                cells.append(_reduction_text(r["reduction_percent"][key]))
                for device in ("ideal-damper", "ideal"):
                    value = doc["bounds"][device][r["name"]]["reduction_percent"][key]
                    cells.append("diverged" if value is None else _reduction_text(value))
            bt.add_row(*cells)
        bounds_parts = ["", bt, Text(
            "ideal damper: the demand where it dissipates energy, no force where it would push "
            "energy in (no force limit, no lag, no hysteresis): the best any semi-active damper "
            "could do with these gains. ideal actuator: the demand, always (an active "
            "suspension). The gains were tuned for the MR dampers; tuned for the ideal devices "
            "the bounds lie further out (docs/results.md).")]

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
    for heading in ("RMS demand\n(kN)", "RMS force\n(kN)", "max force\n(kN)", "RMS travel\n(mm)",
                    "max travel\n(mm)", "mean voltage\n(V)", "time at v_max\n(%)"):
        demands.add_column(heading, justify="right", min_width=6)
    for r in rows:
        d = r["damper"]
        at_max = d.get("voltage_at_max_fraction")
        demand = d.get("demand_rms_n")
        demands.add_row(escape(r["label"]), "-" if demand is None else f"{demand / 1e3:.2f}",
                        f"{d['force_rms_n'] / 1e3:.2f}",
                        f"{d['force_max_n'] / 1e3:.2f}", f"{d['travel_rms_m'] * 1e3:.1f}",
                        f"{d['travel_max_m'] * 1e3:.1f}", _fmt(d.get("voltage_mean_v"), ".2f"),
                        "-" if at_max is None else f"{at_max * 100:.1f}")
    demands_note = ("All four corners, over the metric window. demand: the force the outer loop "
                    "asks for; force: the secondary damper force on the carbody; travel: the "
                    "secondary deflection (suspension travel); passive: the viscous dampers c_sz."
                    + (" The ideal devices have no voltage." if settings.get("damper")
                       in IDEAL_NAMES and controlled else ""))
    parts = [table, Text("\n".join(info)), *bounds_parts, "", ptp, "", demands, Text(demands_note)]
    if all("comfort" in r for r in rows):
        parts += ["", _compare_comfort_table(rows)]
    return parts


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
        help="Dampers of the controlled suspensions: the MR models railway, dyke1996 or "
             "spencer1997; ideal-damper (the ideal semi-active damper: the demand where it "
             "dissipates, else 0, the bound of any damper) or ideal (an ideal actuator: force = "
             "the outer loop's demand).")] = DEFAULT_DAMPER,
    damper_scale: Annotated[Optional[str], typer.Option(
        "--damper-scale", metavar="X",
        help="Factor on the MR damper's force capacity, a finite number > 0 (every force "
             "parameter times X; default 1). Not with --damper ideal.")] = None,
    control_rate: Annotated[float, typer.Option(
        "--control-rate", metavar="HZ",
        help="Sample rate of the outer-loop controllers [Hz]; 1/(rate x dt) must be a whole "
             "number.")] = DEFAULT_CONTROL_RATE,
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
        help="paper-sine (the paper's sine rails), bump, file:PATH, fra1..fra6, german-low or "
             "german-high, as for simulate.")]
        = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time [s] (default 10).")] = None,
    dt: DtOption = None,
    output_rate: OutputRateOption = None,
    window: Annotated[Optional[str], typer.Option(
        "--window", metavar="START:END",
        help="Time window of the metrics [s], e.g. 2:10 (default: the whole run).")] = None,
    params: ParamsOption = None,
    preset: PresetOption = None,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write compare.json, compare.nc, compare.csv and the plots acceleration.png, "
             "displacement.png, pitch.png, roll.png, damper_forces.png, voltages.png, and the "
             "acceleration spectra psd.png, psd.csv into DIR (created if missing; all or "
             "nothing).")] = None,
    bounds: Annotated[bool, typer.Option(
        "--bounds/--no-bounds",
        help="Also run the same control laws and gains on the ideal semi-active damper and the "
             "ideal actuator, and print their reductions beside the MR dampers' (default on; "
             "MR dampers only).")] = True,
    comfort: ComfortOption = False,
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
        from .defaults import DEFAULT_DT, DEFAULT_OUTPUT_RATE
        from .metrics import check_window, parse_window

        names = _controller_list(controllers)
        gain_set = _gain_set(gains)
        _damper_preset("--damper", damper)
        scale = _damper_scale("--damper-scale", damper_scale, damper)
        noise = _sensor_noise(sensor_noise, seed)
        dt = DEFAULT_DT if dt is None else dt
        output_rate = DEFAULT_OUTPUT_RATE if output_rate is None else output_rate
        control_rate = _check_control_rate(control_rate, _check_number("--dt", dt, "s"))
        vehicle_params, vehicle_record = _vehicle_params(params, preset)
        window_value = parse_window(window) if window is not None else None
        track = _track_options(scenario, track_seed, min_wavelength, max_wavelength)
        scen = _make_scenario(scenario, dict(amplitude=amplitude, wavelength=wavelength,
                                             rail_phase=rail_phase, speed=speed,
                                             duration=duration, **track), output_rate)
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
                                 damper=damper, damper_scale=scale, window=window_value, dt=dt,
                                 output_rate=output_rate, control_rate=control_rate,
                                 sensor_noise=noise, comfort=comfort, bounds=bounds,
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
    _stdout_console().print(_modes_table(rows))


def _modes_table(rows: list[dict]):
    from rich.markup import escape
    from rich.table import Table

    table = Table(title="Modes of the passive vehicle")
    table.add_column("#", justify="right")
    table.add_column("mode", no_wrap=True)
    table.add_column("undamped (Hz)", justify="right")
    table.add_column("damped (Hz)", justify="right")
    table.add_column("damping ratio", justify="right")
    for i, r in enumerate(rows, start=1):
        table.add_row(str(i), escape(r["label"]), f"{r['frequency_hz']:.3f}",
                      f"{r['damped_frequency_hz']:.3f}", f"{r['damping_ratio']:.3f}")
    return table


# -- frf ----------------------------------------------------------------------------------------
SCHEMA_FRF = "railride.frf/1"
#: --rails values of `frf`
FRF_RAILS = ("in-phase", "anti-phase", "both")


class FrfFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


#: table labels of the magnitudes `frf` summarises (keys of report.FRF_MAGNITUDES)
FRF_LABELS = {"bounce_m_per_m": "bounce (m/m)", "pitch_deg_per_m": "pitch (deg/m)",
              "roll_deg_per_m": "roll (deg/m)", "acceleration_m_s2_per_m": "acceleration ((m/s^2)/m)"}


def _default_speed() -> float:
    import dataclasses

    from .track import Scenario

    return float(next(f.default for f in dataclasses.fields(Scenario) if f.name == "speed"))


@app.command()
def frf(
    speed: Annotated[Optional[float], typer.Option(
        "--speed", metavar="M/S",
        help="Vehicle speed [m/s]: sets the delays between the wheelsets (default 55.56).")] = None,
    rails: Annotated[str, typer.Option(
        "--rails", metavar="in-phase|anti-phase|both",
        help="Rail pattern: in-phase (z_L = z_R: bounce and pitch), anti-phase (z_L = -z_R: "
             "roll) or both.")] = "both",
    fmin: Annotated[float, typer.Option(
        "--fmin", metavar="HZ", help="Lowest frequency [Hz], > 0.")] = 0.1,
    fmax: Annotated[float, typer.Option(
        "--fmax", metavar="HZ", help="Highest frequency [Hz], > --fmin.")] = 30.0,
    points: Annotated[int, typer.Option(
        "--points", metavar="N", help="Frequencies, log-spaced from --fmin to --fmax, >= 2.")] = 400,
    params: ParamsOption = None,
    preset: PresetOption = None,
    format: Annotated[FrfFormat, typer.Option(
        "--format", case_sensitive=False,
        help="Output on stdout: a summary table (peaks and modes), the JSON document, or the "
             "CSV table of magnitudes and phases.")] = FrfFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write frf.csv, frf.json, frf.png and modes.csv into DIR (created if missing; "
             "all or nothing).")] = None,
) -> None:
    """Frequency responses of the passive vehicle: carbody bounce, pitch, roll and acceleration
    per metre of rail amplitude, for in-phase and anti-phase rails.

    Every wheelset sees the same rail pattern, delayed by its distance behind the leading one
    divided by the speed. Prints the peak of each response and the modes.
    """
    with _errors():
        import numpy as np

        from . import report
        from .vehicle import Vehicle

        speed = _default_speed() if speed is None else _check_number("--speed", speed, "m/s")
        if rails not in FRF_RAILS:
            raise ValueError(f"--rails = {rails!r}: allowed {', '.join(FRF_RAILS)}")
        fmin = _check_number("--fmin", fmin, "Hz")
        fmax = _check_number("--fmax", fmax, "Hz")
        if not fmax > fmin:
            raise ValueError(f"--fmax = {fmax:g} Hz: must be above --fmin = {fmin:g} Hz")
        _check_int("--points", points, 2)
        vehicle_params, vehicle_record = _vehicle_params(params, preset)
        if out is not None:
            report.check_out_dir(out)
        patterns = list(report.FRF_PATTERNS) if rails == "both" else [rails]
        vehicle = Vehicle(vehicle_params)
        frequency = np.geomspace(fmin, fmax, points)
        frequency[0], frequency[-1] = fmin, fmax  # exactly, without rounding
        frame = report.frf_frame({p: vehicle.frequency_response(frequency, speed, p)
                                  for p in patterns})
        modes = [m.to_dict() for m in vehicle.modes()]
        magnitudes = [c for c in report.FRF_MAGNITUDES]
        doc = {
            "schema": SCHEMA_FRF,
            "railride_version": __version__,
            **vehicle_record,
            "settings": {"speed_m_s": speed, "rails": patterns, "fmin_hz": fmin, "fmax_hz": fmax,
                         "points": points},
            "frequency_hz": [float(f) for f in frequency],
            "responses": {p: {c: [float(v) for v in frame.loc[frame["pattern"] == p, c]]
                              for c in magnitudes} for p in patterns},
            "peaks": report.frf_peaks(frame),
            "modes": modes,
        }
        text = json.dumps(doc, indent=2, allow_nan=False)  # refuses NaN before writing
        if out is not None:
            vehicle_name = vehicle_record.get("vehicle_preset") or vehicle_record.get(
                "vehicle_params_file")
            title = (f"Carbody frequency responses per metre of rail amplitude - V = {speed:g} m/s, "
                     f"vehicle {vehicle_name}, passive suspension")
            _write_folder(out, lambda: report.write_frf_outputs(frame, modes, out, doc,
                                                                title=title))
    if format is FrfFormat.json:
        typer.echo(text)
        return
    if format is FrfFormat.csv:
        typer.echo(frame.to_csv(index=False), nl=False)
        return
    from rich.table import Table
    from rich.text import Text

    table = Table(title="Peaks of the carbody frequency responses (passive vehicle)")
    table.add_column("response (per m of rail)")
    for p in patterns:
        table.add_column(f"{p}\npeak", justify="right")
        table.add_column(f"{p}\nat (Hz)", justify="right")
    for column, label in FRF_LABELS.items():
        cells = [label]
        for p in patterns:
            peak = doc["peaks"][p][column]
            if peak["frequency_hz"] is None:
                cells += ["0", "not excited"]
            else:
                cells += [f"{peak['magnitude']:#.4g}", f"{peak['frequency_hz']:.3g}"]
        table.add_row(*cells)
    vehicle_name = vehicle_record.get("vehicle_preset") or vehicle_record.get("vehicle_params_file")
    note = Text(f"V = {speed:g} m/s, {points} frequencies from {fmin:g} to {fmax:g} Hz (log "
                f"grid; the peak is the largest value on it), vehicle {vehicle_name}. in-phase: "
                "z_L = z_R; anti-phase: z_L = -z_R; every wheelset sees the pattern delayed by "
                "its distance behind the leading one / V.")
    console = _wide_stdout_console(100)
    for part in (table, note, "", _modes_table(modes)):
        console.print(part)


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
        scale = record.get("damper_scale", 1.0)
        return (f"MR, {record['damper']} dampers" + (f" (force x {scale:g})" if scale != 1.0 else "")
                + f" at {record['voltage_v']:g} V")
    return "passive (viscous c_sz)"


def _metrics_table(doc: dict):
    from rich.markup import escape
    from rich.table import Table

    labels = {"acceleration_m_s2": "acceleration (m/s^2)", "displacement_m": "displacement (m)",
              "pitch_deg": "pitch (deg)", "roll_deg": "roll (deg)"}
    sc, st = doc["scenario"], doc["settings"]
    start, end = st["window_s"]
    vehicle = doc.get("vehicle_preset") or doc.get("vehicle_params_file")
    random = ([f"random track: seed {sc.get('seed')}, wavelengths "
               f"{sc.get('min_wavelength_m'):g}-{sc.get('max_wavelength_m'):g} m"]
              if sc.get("profile") == "random" else [])
    caption = "\n".join([
        f"scenario {sc.get('name')}, speed {sc.get('speed_m_s'):g} m/s",
        *random,
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
        "--scenario", metavar="NAME", help=SCENARIO_HELP)] = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time [s] (default 10).")] = None,
    dt: DtOption = None,
    output_rate: OutputRateOption = None,
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
             "(default railway). The ideal actuator (ideal) needs a controller: see compare "
             "and sweep.")] = None,
    damper_scale: Annotated[Optional[str], typer.Option(
        "--damper-scale", metavar="X",
        help="--suspension mr only: factor on the damper's force capacity, a finite number > 0 "
             "(every force parameter times X; default 1).")] = None,
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
    comfort: ComfortOption = False,
) -> None:
    """Simulate the vehicle on a track and print the ride metrics."""
    with _errors():
        track = _track_options(scenario, track_seed, min_wavelength, max_wavelength)
        doc, result = _run(scenario, amplitude, wavelength, rail_phase, speed, duration, dt,
                           output_rate, window, params, preset, out, suspension, damper, voltage,
                           track=track, comfort=comfort, damper_scale=damper_scale)
    if format is OutputFormat.json:
        _print_json(doc)
    else:
        console = _stdout_console()
        console.print(_metrics_table(doc))
        if "comfort" in doc:
            console.print(_comfort_table(doc["comfort"]))


def _suspension(suspension: str, damper_name, voltage_text, damper_scale=None):
    """(damper model or None, command voltage or None, the record for the JSON document)."""
    if suspension not in SUSPENSIONS:
        raise ValueError(f"--suspension = {suspension!r}: allowed {', '.join(SUSPENSIONS)}")
    if suspension == "passive":
        given = [o for o, v in (("--damper", damper_name), ("--damper-scale", damper_scale),
                                ("--voltage", voltage_text)) if v is not None]
        if given:
            verb = "applies" if len(given) == 1 else "apply"
            raise ValueError(f"{' and '.join(given)} {verb} to --suspension mr only (the passive "
                             "suspension has viscous dampers)")
        return None, None, {"type": "passive"}
    name = DEFAULT_DAMPER if damper_name is None else damper_name
    model = _damper_preset("--damper", name)
    if name in IDEAL_NAMES:  # simulate runs open loop: no demand for it to apply
        raise ValueError(f"--damper = {name!r}: the ideal actuator applies a controller's demand and "
                         "simulate runs no controller (a constant voltage); use railride compare "
                         "--damper ideal or railride sweep --damper ideal with a controller")
    scale = _damper_scale("--damper-scale", damper_scale, name)
    if scale != 1.0:
        model = model.scaled(scale)
    volts = model.v_min if voltage_text is None else _voltage("--voltage", voltage_text, model)
    record = {"type": "mr", "damper": name, "voltage_v": float(volts)}
    if damper_scale is not None:  # only then: the document stays as it was without the option
        record["damper_scale"] = scale
    return model, float(volts), record


def _run(scenario_name, amplitude, wavelength, rail_phase, speed, duration, dt, output_rate,
         window_text, params_file, preset, out, suspension="passive", damper_name=None,
         voltage_text=None, track=None, comfort=False, damper_scale=None):
    from . import report
    from .defaults import DEFAULT_DT, DEFAULT_OUTPUT_RATE
    from .metrics import check_window, parse_window, to_dict
    from .simulation import simulate as run_simulation

    dt = DEFAULT_DT if dt is None else dt
    output_rate = DEFAULT_OUTPUT_RATE if output_rate is None else output_rate
    vehicle_params, vehicle_record = _vehicle_params(params_file, preset)
    damper, voltage, suspension_record = _suspension(suspension, damper_name, voltage_text,
                                                     damper_scale)
    window = parse_window(window_text) if window_text is not None else None
    scen = _make_scenario(scenario_name, dict(amplitude=amplitude, wavelength=wavelength,
                                              rail_phase=rail_phase, speed=speed,
                                              duration=duration, **(track or {})), output_rate)
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
    if comfort:  # only then: the document stays as it was without --comfort
        from .comparison import comfort_record
        doc["comfort"] = comfort_record(result.comfort(window))
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

        damper_model = _damper_preset("--model", model, rig=True)
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

    The inner loop (paper eq. 12-14) sets the voltage so that a damper stroked by
    x = -stroke cos(2 pi f t) follows a desired force; prints the RMS tracking error.
    """
    with _errors():
        from . import report, rig

        if desired not in DESIRED_SIGNALS:
            raise ValueError(f"--desired = {desired!r}: allowed {', '.join(DESIRED_SIGNALS)}")
        damper_model = _damper_preset("--model", model, rig=True)
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


# -- tune and sweep: many runs ------------------------------------------------------------------
SCHEMA_SWEEP = "railride.sweep/1"

#: the controllers a gain table acts in (a --gain of `sweep` combines with these only)
GAIN_CONTROLLERS = {"inner": ("pid", "sas-attitude", "sas-attitude-ride"), "pid": ("pid",),
                    "attitude": ("sas-attitude", "sas-attitude-ride"),
                    "ride": ("sas-attitude-ride",)}
#: the scenario options a sweep can vary: (option, keyword of track.scenario, column, unit)
SWEEP_AXES = (("--speed", "speed", "speed_m_s", "m/s"), ("--wavelength", "wavelength", "wavelength_m", "m"),
              ("--amplitude", "amplitude", "amplitude_m", "m"),
              ("--rail-phase", "rail_phase", "rail_phase_deg", "deg"),
              ("--track-seed", "seed", "track_seed", ""))

#: the keys of Scenario.describe() that each swept scenario option sets
_SCENARIO_KEYS = {"speed": ("speed_m_s",), "wavelength": ("wavelength_m", "length_m"),
                  "amplitude": ("amplitude_m", "height_m"), "rail_phase": ("rail_phase_deg",),
                  "seed": ("seed",)}


class SweepFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


def _utc_now() -> str:
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _executor(workers: Optional[int], scheduler: Optional[str], scheduler_file: Optional[Path]):
    """(executor, record for the JSON): Dask with --scheduler / --scheduler-file, else the local
    executor, whose batches use --workers threads (numba's thread count, 1..cores)."""
    from . import sweep as sweep_lib

    if scheduler is not None and scheduler_file is not None:
        raise ValueError("give either --scheduler ADDRESS or --scheduler-file FILE, not both")
    if scheduler is not None or scheduler_file is not None:
        if workers is not None:
            raise ValueError(f"--workers = {workers}: applies to the local executor only; the "
                             "threads of a Dask cluster are set where its workers start "
                             "(dask worker --nthreads N)")
        if scheduler is not None and not scheduler.strip():
            raise ValueError("--scheduler = '': give the scheduler's address, e.g. "
                             "tcp://host:8786")
        with _status("connecting to the Dask scheduler..."):
            executor = sweep_lib.DaskExecutor(
                address=scheduler, scheduler_file=None if scheduler_file is None else str(scheduler_file))
        where = scheduler if scheduler is not None else str(scheduler_file)
        record = {"type": "dask", "scheduler": where}
        with contextlib.suppress(Exception):
            record["workers"] = len(executor.client.scheduler_info()["workers"])
        return executor, record
    import numba

    cores = int(numba.config.NUMBA_NUM_THREADS)
    if workers is not None:
        if not 1 <= workers <= cores:
            raise ValueError(f"--workers = {workers}: must be a whole number from 1 to {cores} "
                             "(the cores of this machine)")
        numba.set_num_threads(workers)
    return sweep_lib.LocalExecutor(), {"type": "local", "threads": int(numba.get_num_threads())}


def _run_table(out: Optional[Path], resume: bool):
    """(RunTable, its path or None): DIR/runs.csv with --out, kept in memory without it."""
    from . import report
    from . import sweep as sweep_lib

    if out is None:
        if resume:
            raise ValueError("--resume needs --out DIR: the run table it continues is "
                             "DIR/runs.csv")
        return sweep_lib.RunTable(), None
    report.check_out_dir(out)
    path = out / "runs.csv"
    if path.exists() and not resume:
        raise ValueError(f"--out {out}: {path} exists (the run table of an earlier run); add "
                         "--resume to continue it, or choose another folder")
    return sweep_lib.RunTable(path, resume=resume), path


def _saved_runs(table, path: Optional[Path]) -> int:
    """The rows of the run table on disk (what an interrupted run leaves), else in memory."""
    if path is not None and path.exists():
        import pandas as pd

        try:
            return len(pd.read_csv(path, usecols=["key"]))
        except (OSError, ValueError):
            pass
    return len(table.frame)


@contextlib.contextmanager
def _interruptible(table, path: Optional[Path]):
    """Ctrl-C: one line saying what was kept, status 130, no traceback."""
    try:
        yield
    except KeyboardInterrupt:
        n = _saved_runs(table, path)
        if path is not None:
            typer.echo(f"interrupted: {n} runs saved in {path}; run again with --resume to "
                       "continue", err=True)
        else:
            typer.echo(f"interrupted: {n} runs done, none saved (with --out DIR the runs are kept "
                       "in DIR/runs.csv and --resume continues them)", err=True)
        raise typer.Exit(130) from None


class _RunProgress:
    """Progress of many runs, fed by the library's ``progress(done, total, runs_per_second)``
    (once per batch of runs it asks for, then after each chunk). Counts the runs evaluated in
    this session (``evaluated``); shows a bar on stderr only when stderr is a terminal.
    ``log(text)`` prints a line on stderr (above the bar)."""

    def __init__(self, enabled: bool, verb: str):
        self.enabled = enabled
        self.verb = verb
        self.evaluated = 0
        self._base = 0
        self._progress = None
        self._task = None

    def __enter__(self):
        if not self.enabled:
            return self
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        from . import kernels

        compiled = bool(getattr(kernels.run_batch, "signatures", True))
        first = (f"{self.verb}..." if compiled
                 else "loading the stepper (the first run compiles it, up to a minute)...")
        self._progress = Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                                  MofNCompleteColumn(), TextColumn("{task.fields[rate]}"),
                                  TimeElapsedColumn(), console=_stderr_console(), transient=True)
        self._progress.__enter__()
        self._task = self._progress.add_task(first, total=None, rate="")
        return self

    def __call__(self, done: int, total: int, runs_per_second: float) -> None:
        if done == 0:
            self._base = self.evaluated
        self.evaluated = self._base + int(done)
        if self._progress is not None:
            ok = math.isfinite(runs_per_second) and runs_per_second > 0
            self._progress.update(self._task, completed=done, total=total,
                                  description=f"{self.verb} ({self.evaluated} runs)",
                                  rate=f"{runs_per_second:.1f} runs/s" if ok else "")

    def log(self, text: str) -> None:
        if self._progress is not None:
            self._progress.console.print(text, markup=False, highlight=False)
        else:
            typer.echo(text, err=True)

    def __exit__(self, *exc):
        if self._progress is not None:
            self._progress.__exit__(*exc)
        return False


def _scenario_options(**given) -> dict:
    """The keyword arguments of track.scenario that were given (None: the scenario's default)."""
    return {k: float(v) for k, v in given.items() if v is not None}


def _check_int(option: str, value: int, minimum: int, what: str = "") -> int:
    if value < minimum:
        raise ValueError(f"{option} = {value}: must be a whole number >= {minimum}{what}")
    return value


def _objective(kind: Optional[str], weights: Optional[str], bound: Optional[str],
               penalty: Optional[str]):
    """--objective, --weights, --bound, --penalty -> a tuning.Objective. Without --objective,
    the library's DEFAULT_OBJECTIVE; an option not given keeps that default's value when the
    kind is the default's (weights and bound belong to their kind only)."""
    from .objectives import DEFAULT_OBJECTIVE, OBJECTIVE_KINDS, Objective

    name = DEFAULT_OBJECTIVE.kind if kind is None else kind.strip()
    if name not in OBJECTIVE_KINDS:
        raise ValueError(f"--objective = {kind!r}: unknown objective; allowed: "
                         f"{', '.join(OBJECTIVE_KINDS)}")
    default = DEFAULT_OBJECTIVE if name == DEFAULT_OBJECTIVE.kind else Objective()
    which = f"--objective is {name}" if kind is not None else f"the default objective is {name}"
    w = default.weights if name == "weighted" else None
    if weights is not None:
        if name != "weighted":
            raise ValueError(f"--weights = {weights!r}: applies to --objective weighted only "
                             f"({which})")
        w = _weights(weights)
    if name == "weighted" and w is None:
        raise ValueError("--objective weighted needs --weights A,D,P,R: four numbers >= 0, not "
                         "all 0 (acceleration, displacement, pitch, roll)")
    b = default.bound if name == "constrained" else None
    if bound is not None:
        if name != "constrained":
            raise ValueError(f"--bound = {bound!r}: applies to --objective constrained only "
                             f"({which})")
        b = _parse_float("--bound", bound, bound, " (the largest RMS ratio to passive allowed)")
        if b <= 0:
            raise ValueError(f"--bound = {bound!r}: must be a finite number > 0 (the largest "
                             "RMS ratio to passive allowed for every response)")
    if name == "constrained" and b is None:
        raise ValueError("--objective constrained needs --bound X: the largest RMS ratio to "
                         "passive allowed for every response, a finite number > 0")
    p = default.penalty
    if penalty is not None:
        p = _parse_float("--penalty", penalty, penalty)
        if p < 0:
            raise ValueError(f"--penalty = {penalty!r}: must be a finite number >= 0")
    try:
        return Objective(name, w, b, p)
    except ValueError as exc:  # what the checks above cannot see, e.g. a bound too large
        raise ValueError(f"--objective {name}: {exc}") from None


def _weights(weights: str) -> tuple:
    """--weights A,D,P,R -> four numbers >= 0, not all 0."""
    items = [item.strip() for item in weights.split(",")]
    if len(items) != 4:
        raise ValueError(f"--weights = {weights!r}: expected four numbers A,D,P,R (acceleration, "
                         f"displacement, pitch, roll), got {len(items)} item(s)")
    values = []
    for name, item in zip(("A", "D", "P", "R"), items):
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"--weights = {weights!r}: {name} = {item!r} is not a number") from None
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"--weights = {weights!r}: {name} = {item}: must be a finite number >= 0")
        values.append(value)
    if sum(values) == 0:
        raise ValueError(f"--weights = {weights!r}: at least one weight must be > 0")
    return tuple(values)


def _phase_list(items: Optional[list[str]]) -> list[str]:
    """--phase (repeatable, comma lists, `all`) -> the phases in the order they run; none
    given: the library's default (all four)."""
    from .tuning import PHASES, tune

    if not items:
        return list(_default_of(tune, "phases"))
    wanted = set()
    for text in items:
        names = [n.strip() for n in text.split(",")]
        if any(not n for n in names):
            raise ValueError(f"--phase = {text!r}: an empty item; give phases separated by commas "
                             f"from {', '.join(PHASES)}, all")
        for n in names:
            if n == "all":
                wanted.update(PHASES)
            elif n in PHASES:
                wanted.add(n)
            else:
                raise ValueError(f"--phase = {text!r}: unknown phase {n!r}; allowed: "
                                 f"{', '.join(PHASES)}, all")
    return [p for p in PHASES if p in wanted]


def _command_line(ctx: typer.Context, exclude=()) -> str:
    """The railride command being run, with the options given on the command line (not their
    defaults), for the record: reproducing a result needs only this line."""
    import shlex

    words = ["railride", ctx.info_name or ""]
    for param in ctx.command.params:
        source = ctx.get_parameter_source(param.name)
        if param.name in exclude or getattr(source, "name", "") != "COMMANDLINE":
            continue
        value = ctx.params[param.name]
        flag = max(param.opts, key=len)
        if isinstance(value, bool):
            words.append(flag if value else (param.secondary_opts or [flag])[0])
            continue
        for item in value if isinstance(value, (list, tuple)) else [value]:
            words += [flag, str(getattr(item, "value", item))]
    return shlex.join(w for w in words if w)


def _tune_tables(doc: dict, start, tuned, scenario_text: str):
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    from .report import _gain_unit
    from .tuning import PARAMETERS

    parts = []
    passes = Table(title="Tuning: the objective after each pass")
    passes.add_column("phase")
    passes.add_column("pass", justify="right")
    passes.add_column("objective", justify="right")
    passes.add_column("change %", justify="right")
    infeasible = doc["objective"].get("infeasible")  # constrained: J >= offset breaks the bound
    if infeasible:
        passes.add_column("within\nbound")
    previous = {}
    for h in doc["history"]:
        before = previous.get(h["phase"])
        change = "" if before is None else f"{(h['objective'] - before) / abs(before) * 100:+.2f}"
        cells = [h["phase"], str(h["pass"]), f"{h['objective']:.4f}", change]
        if infeasible:
            cells.append("" if h["phase"] == "inner" else
                         "yes" if h["objective"] < infeasible["offset"] else "no")
        passes.add_row(*cells)
        previous[h["phase"]] = h["objective"]
    parts += [passes, Text("objective: " + _objective_text_from_doc(doc) + "; inner phase: the "
                           "normalised force-tracking error on the damper rig"), ""]

    gains = Table(title="Tuned gains")
    gains.add_column("gain")
    gains.add_column("unit")
    gains.add_column("start", justify="right")
    gains.add_column("tuned", justify="right")
    gains.add_column("", no_wrap=True)
    for phase in doc["phases"]:
        for name in PARAMETERS[phase]:
            table, _, entry = name.partition(".")
            a, b = getattr(getattr(start, table), entry), getattr(getattr(tuned, table), entry)
            gains.add_row(name, escape(_gain_unit(name) or ""), f"{a:.4g}", f"{b:.4g}",
                          "" if math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0) else "changed")
        gains.add_section()
    parts += [gains, ""]

    rows = doc["before_after"]
    if rows:
        from .control import LABELS

        table = Table(title="RMS of the carbody responses with the start and the tuned gains")
        table.add_column("suspension", no_wrap=True)
        table.add_column("response")
        table.add_column("passive", justify="right")
        table.add_column("start\ngains", justify="right")
        table.add_column("red. %", justify="right")
        table.add_column("tuned\ngains", justify="right")
        table.add_column("red. %", justify="right")
        for r in rows:
            for i, (key, label) in enumerate(RESPONSE_LABELS.items()):
                table.add_row(escape(LABELS[r["suspension"]]) if i == 0 else "", label,
                              f"{doc['passive_rms'][key]:#.4g}", f"{r['before'][key]:#.4g}",
                              _reduction_text(r["reduction_before_percent"][key]),
                              f"{r['after'][key]:#.4g}",
                              _reduction_text(r["reduction_after_percent"][key]),
                              end_section=i == len(RESPONSE_LABELS) - 1)
        parts.append(table)
    s = doc["settings"]
    parts.append(Text("\n".join([
        f"{scenario_text}, {doc['scenario'].get('duration_s', 0):g} s, dt {s['dt_s']:g} s, "
        f"{_damper_text(s)}; start gains {s['start_gains']}",
        "red. % = (passive - controlled) / passive x 100 (negative: worse than passive, in red)",
        f"{doc['runs']} runs in the run table, {doc['runs_evaluated']} evaluated now "
        f"({doc['runs_per_second']:.1f} runs/s), wall time {doc['wall_time_s']:.1f} s",
    ])))
    return parts


def _tune_start(path: Optional[Path]):
    """--gains FILE, else the neutral reference gains (the library's default start)."""
    from .control import GainSet

    return GainSet.reference() if path is None else _gain_set(path)


def _objective_text_from_doc(doc: dict) -> str:
    return doc["objective"]["statement"]


@app.command("tune")
def tune_command(
    ctx: typer.Context,
    phase: Annotated[Optional[list[str]], typer.Option(
        "--phase", metavar="PHASE[,PHASE...]",
        help="Tuning phases, repeatable or comma-separated: inner (B, G on the damper rig's "
             "force tracking), pid, attitude (the six SAS attitude gains, ride loop off), ride "
             "(the eight ride gains from 0, attitude fixed), all (= inner,pid,attitude,ride). "
             "They run in that order. Default: all.")] = None,
    scenario: Annotated[str, typer.Option(
        "--scenario", metavar="NAME",
        help="paper-sine, bump, file:PATH, fra1..fra6, german-low or german-high, as for "
             "simulate.")] = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time of each run [s] (default 10).")] = None,
    dt: DtOption = None,
    damper: Annotated[str, typer.Option(
        "--damper", metavar="MODEL",
        help="MR damper model: railway, dyke1996 or spencer1997 (ideal-damper or ideal, the "
             "ideal devices, without the inner phase).")] = DEFAULT_DAMPER,
    damper_scale: Annotated[Optional[str], typer.Option(
        "--damper-scale", metavar="X",
        help="Factor on the MR damper's force capacity, a finite number > 0 (every force "
             "parameter times X; default 1); the inner phase tracks demands scaled alike. Not "
             "with an ideal damper.")] = None,
    gains: Annotated[Optional[Path], typer.Option(
        "--gains", metavar="FILE.toml",
        help="Start values: a gains file as for compare (default: the neutral reference gains, "
             "railride/data/reference_gains.toml).")] = None,
    objective_kind: Annotated[Optional[str], typer.Option(
        "--objective", metavar="KIND",
        help="What each run's RMS ratios to passive r_k (acceleration, displacement, pitch, "
             "roll) are scored by: sum (sum of r_k), weighted (sum of w_k r_k, --weights), "
             "minimax (the largest r_k), constrained (sum of r_k with every r_k <= --bound). "
             "Default: the library's DEFAULT_OBJECTIVE; the statement is printed with the "
             "result.")] = None,
    weights: Annotated[Optional[str], typer.Option(
        "--weights", metavar="A,D,P,R",
        help="--objective weighted: the weights of acceleration, displacement, pitch, roll; "
             ">= 0, not all 0.")] = None,
    bound: Annotated[Optional[str], typer.Option(
        "--bound", metavar="X",
        help="--objective constrained: the largest RMS ratio to passive allowed for every "
             "response, > 0.")] = None,
    penalty: Annotated[Optional[str], typer.Option(
        "--penalty", metavar="X",
        help="Added to any objective: X times the sum of the RMS ratios above 1 (responses "
             "worse than passive); >= 0 (default 0).")] = None,
    values: Annotated[int, typer.Option(
        "--values", metavar="N",
        help="Log-spaced values per gain and pass, from 1/span to span times the current value "
             "(0 and the current value are added); >= 3.")] = 13,
    span: Annotated[float, typer.Option(
        "--span", metavar="S", help="Range factor of each sweep, > 1.")] = 30.0,
    passes: Annotated[int, typer.Option(
        "--passes", metavar="N",
        help="At most N passes per phase (a phase stops early when a pass improves the "
             "objective by less than 0.1 %); >= 1.")] = 5,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Keep the run table DIR/runs.csv (updated as runs finish) and write gains.toml, "
             "sensitivity.png, curves.csv and tune.json into DIR at the end.")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume",
        help="Continue the study whose run table is DIR/runs.csv (needs --out): runs already "
             "there are not evaluated again.")] = False,
    format: FormatOption = OutputFormat.table,
) -> None:
    """Tune the controller gains by the paper's sensitivity study (its section V).

    One gain at a time is swept over log-spaced values (and 0) with the others fixed; the best
    value is kept; passes repeat until a pass gains less than 0.1 %. Each run is scored by the
    objective (--objective) over its RMS carbody responses relative to passive. Prints the
    objective per pass, the tuned gains and the RMS with the start and the tuned gains. Ctrl-C
    stops; with --out, --resume continues.
    """
    import time

    command = _command_line(ctx, exclude=("out", "resume", "format"))
    with _errors():
        from . import report, tuning
        from .defaults import DEFAULT_DT, DEFAULT_OUTPUT_RATE

        phases = _phase_list(phase)
        _damper_preset("--damper", damper)
        scale = _damper_scale("--damper-scale", damper_scale, damper)
        if damper in IDEAL_NAMES and "inner" in phases:
            raise ValueError(f"--damper = {damper!r} with the inner phase (--phase "
                             f"{','.join(phases)}): an ideal device has no force tracking "
                             "loop to tune; give --phase pid,attitude,ride")
        start = _tune_start(gains)
        objective = _objective(objective_kind, weights, bound, penalty)
        _check_int("--values", values, 3)
        if not (math.isfinite(span) and span > 1):
            raise ValueError(f"--span = {span:g}: must be a finite number > 1")
        _check_int("--passes", passes, 1)
        dt = DEFAULT_DT if dt is None else _check_number("--dt", dt, "s")
        options = _scenario_options(amplitude=amplitude, wavelength=wavelength,
                                    rail_phase=rail_phase, speed=speed, duration=duration)
        options.update(_track_options(scenario, track_seed, min_wavelength, max_wavelength))
        # every run stores its time histories at the library's default rate
        scen = _make_scenario(scenario, options, DEFAULT_OUTPUT_RATE, "the runs' output rate")
        options = _case_options(options)
        scenario_text = report.describe_scenario(scen.describe())
        table, table_path = _run_table(out, resume)
        executor, executor_record = _executor(workers, scheduler, scheduler_file)
    try:
        with _interruptible(table, table_path), _errors():
            with _RunProgress(_stderr_is_terminal(), "tuning") as progress:
                t0 = time.perf_counter()
                result = tuning.tune(phases, scenario=scenario, scenario_options=options,
                                     gains=start, objective=objective, damper=damper,
                                     damper_scale=scale,
                                     executor=executor, table=table, n_values=values, span=span,
                                     max_passes=passes, dt=dt, progress=progress, log=progress.log)
                wall = time.perf_counter() - t0
            # the facts of this command line, after the library's document
            facts = {"runs_evaluated": progress.evaluated,
                     "runs_per_second": progress.evaluated / wall if wall > 0 else 0.0,
                     "wall_time_s": wall, "executor": executor_record, "command": command}
            doc = {**result.to_dict(), **facts}
            text = json.dumps(doc, indent=2, allow_nan=False)
            if out is not None:
                _write_folder(out, lambda: result.save(out, command, extra=facts))
    finally:
        executor.close()
    if format is OutputFormat.json:
        typer.echo(text)
        return
    console = _wide_stdout_console()
    for part in _tune_tables(doc, result.start, result.gains, scenario_text):
        console.print(part)


# -- pareto -------------------------------------------------------------------------------------
def _pareto_table(doc: dict, caption: str):
    """Counts, then the samples non-dominated over the four ratios by acceleration ratio."""
    from rich.table import Table

    from .pareto import PROJECTIONS

    c = doc["counts"]
    counts = Table(title="Pareto view: samples and non-dominated samples")
    counts.add_column("samples (with the base gains)", justify="right")
    counts.add_column("non-dominated\nover all four ratios", justify="right")
    for x, y in PROJECTIONS:
        counts.add_column(f"non-dominated in\n{x} and {y}", justify="right")
    counts.add_row(str(c["samples"]), str(c["non_dominated"]),
                   *[str(c[f"non_dominated_{x}_{y}"]) for x, y in PROJECTIONS])
    front = sorted((r for r in doc["samples"] if r["non_dominated"]),
                   key=lambda r: (r["acceleration_m_s2_ratio"] is None,
                                  r["acceleration_m_s2_ratio"] or 0.0))
    rows = Table(title="Non-dominated samples by acceleration ratio: RMS / RMS(passive)",
                 caption=caption, caption_justify="left")
    rows.add_column("sample", justify="right")
    for label in RESPONSE_LABELS.values():
        rows.add_column(label.split(" (")[0], justify="right")
    rows.add_column("also non-dominated\nagainst acceleration in")
    for r in front:
        planes = ", ".join(y for x, y in PROJECTIONS if r[f"non_dominated_{x}_{y}"])
        rows.add_row(f"{r['sample']}" + (" (base)" if r["base"] else ""),
                     *[_fmt(r[f"{key}_ratio"], ".3f") for key in RESPONSE_LABELS], planes)
    return [counts, "", rows]


@app.command("pareto")
def pareto_command(
    suspension: Annotated[str, typer.Option(
        "--suspension", metavar="NAME",
        help="The controller whose gains are sampled: pid, sas-attitude or sas-attitude-ride "
             "(every outer-loop gain it reads).")] = "sas-attitude-ride",
    samples: Annotated[Optional[int], typer.Option(
        "--samples", metavar="N",
        help="Sobol' samples of the gains, a power of two (default 128); the base gains are "
             "run too.")] = None,
    seed: Annotated[int, typer.Option(
        "--seed", metavar="S", help="Seed of the scrambled Sobol' sample, >= 0.")] = 0,
    scenario: Annotated[str, typer.Option(
        "--scenario", metavar="NAME",
        help="paper-sine, bump, file:PATH, fra1..fra6, german-low or german-high, as for "
             "simulate.")] = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time of each run [s] (default 10).")] = None,
    dt: DtOption = None,
    damper: Annotated[str, typer.Option(
        "--damper", metavar="MODEL",
        help="Dampers of the controlled runs: railway, dyke1996, spencer1997, ideal-damper or "
             "ideal.")] = DEFAULT_DAMPER,
    gains: Annotated[Optional[Path], typer.Option(
        "--gains", metavar="FILE.toml",
        help="Base gains: the gains not sampled (the inner loop's among them), and one sample "
             "of their own (default: the shipped gains).")] = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Keep the run table DIR/runs.csv (updated as runs finish) and write pareto.png, "
             "pareto.csv and pareto.json into DIR at the end.")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume",
        help="Continue the study whose run table is DIR/runs.csv (needs --out).")] = False,
    format: FormatOption = OutputFormat.table,
) -> None:
    """The trades a controller's gains offer: RMS ratios to passive of sampled gains.

    Samples the gains in log10 over the box of the global optimiser (REFERENCE / 1000 to
    REFERENCE x 100) by a scrambled Sobol' sequence, runs them and the base gains, and marks the
    samples no other beats in every ratio (non-dominated). Prints the counts and the
    non-dominated samples by acceleration ratio. Ctrl-C stops; with --out, --resume continues.
    """
    import time

    with _errors():
        from .pareto import CONTROLLER_PARAMETERS, pareto as run_pareto
        from . import report
        from .defaults import DEFAULT_DT, DEFAULT_OUTPUT_RATE

        if suspension not in CONTROLLER_PARAMETERS:
            raise ValueError(f"--suspension = {suspension!r}: allowed "
                             f"{', '.join(CONTROLLER_PARAMETERS)}")
        n = _default_of(run_pareto, "n_samples") if samples is None else samples
        if n < 1 or n & (n - 1):
            raise ValueError(f"--samples = {n}: must be a power of two (1, 2, 4, ..., 128, "
                             "...), which keeps the balance of the Sobol' sample")
        _check_int("--seed", seed, 0)
        _damper_preset("--damper", damper)
        base = _gain_set(gains)
        dt = DEFAULT_DT if dt is None else _check_number("--dt", dt, "s")
        options = _scenario_options(amplitude=amplitude, wavelength=wavelength,
                                    rail_phase=rail_phase, speed=speed, duration=duration)
        options.update(_track_options(scenario, track_seed, min_wavelength, max_wavelength))
        scen = _make_scenario(scenario, options, DEFAULT_OUTPUT_RATE, "the runs' output rate")
        options = _case_options(options)
        scenario_text = report.describe_scenario(scen.describe())
        table, table_path = _run_table(out, resume)
        executor, executor_record = _executor(workers, scheduler, scheduler_file)
    try:
        with _interruptible(table, table_path), _errors():
            with _RunProgress(_stderr_is_terminal(), "sampling the gains") as progress:
                t0 = time.perf_counter()
                result = run_pareto(suspension, n_samples=n, seed=seed, scenario=scenario,
                                           scenario_options=options, gains=base, damper=damper,
                                           executor=executor, table=table, dt=dt,
                                           progress=progress)
                wall = time.perf_counter() - t0
            doc = result.to_dict()
            if out is not None:
                _write_folder(out, lambda: result.save(out))
    finally:
        executor.close()
    if format is OutputFormat.json:
        _print_json(doc)
        return
    st = doc["settings"]
    lines = [(f"{scenario_text}, {scen.duration:g} s, dt {dt:g} s, {_damper_text(st)}; base "
              f"gains {st['base_gains']}"),
             f"{st['n_samples']} samples, seed {st['seed']}: {st['sampling']}",
             (f"{doc['runs']} runs in the run table, {progress.evaluated} evaluated now, wall "
              f"time {wall:.1f} s ({executor_record['type']})")]
    if doc["note"]:
        lines.append(doc["note"])
    console = _wide_stdout_console()
    for part in _pareto_table(doc, "\n".join(lines)):
        console.print(part)


def _default_of(fn, name: str):
    import inspect

    return inspect.signature(fn).parameters[name].default


# -- sweep ------------------------------------------------------------------------------------
def _tidy(value: float) -> float:
    """A range value without float noise (20:80:13 gives 25, not 25.000000000000004)."""
    return float(f"{value:.12g}")


def _parse_float(option: str, text: str, item: str, what: str = "") -> float:
    try:
        value = float(item)
    except ValueError:
        raise ValueError(f"{option} = {text!r}: {item.strip()!r} is not a number{what}") from None
    if not math.isfinite(value):
        raise ValueError(f"{option} = {text!r}: {item.strip()!r} is not a finite number")
    return value


def _value_list(option: str, text: str, *, integer: bool = False, parse=None) -> list:
    """START:STOP:COUNT (linear, inclusive) or a,b,c -> distinct values, else ValueError naming
    the option. ``parse(item)`` reads a list item (default: a number)."""
    text = text.strip()
    kind = "whole numbers" if integer else "numbers"
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"{option} = {text!r}: expected a range START:STOP:COUNT (e.g. "
                             f"20:80:13) or a list a,b,c of {kind}")
        start, stop = (_parse_float(option, text, p) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise ValueError(f"{option} = {text!r}: COUNT = {parts[2].strip()!r} is not a whole "
                             "number") from None
        if count < 1:
            raise ValueError(f"{option} = {text!r}: COUNT = {count} must be >= 1")
        import numpy as np

        values = [_tidy(v) for v in np.linspace(start, stop, count)]
    else:
        items = text.split(",")
        if any(not item.strip() for item in items):
            raise ValueError(f"{option} = {text!r}: an empty item; give a range START:STOP:COUNT "
                             f"or {kind} separated by commas")
        values = [parse(item) if parse else _parse_float(option, text, item) for item in items]
    if integer:
        bad = [v for v in values if not float(v).is_integer()]
        if bad:
            raise ValueError(f"{option} = {text!r}: {bad[0]:g} is not a whole number")
        values = [int(v) for v in values]
    seen = set()
    for v in values:
        if v in seen:
            raise ValueError(f"{option} = {text!r}: {v:g} is listed twice")
        seen.add(v)
    return values


def _gain_option(text: str) -> tuple[str, list[float]]:
    """--gain TABLE.ENTRY=VALUES -> ("table.entry", values)."""
    from .tuning import PARAMETERS

    name, sep, values_text = text.partition("=")
    name = name.strip()
    if name.startswith("sas."):  # the gains file's [sas.attitude] and [sas.ride]
        name = name[len("sas."):]
    known = [p for ps in PARAMETERS.values() for p in ps]
    if not sep or not values_text.strip():
        raise ValueError(f"--gain = {text!r}: expected TABLE.ENTRY=VALUES, e.g. pid.kd=1e4,1e5 "
                         "or attitude.kp_z=0:4e5:5")
    if name not in known:
        table = name.partition(".")[0]
        if table in PARAMETERS:
            allowed = ", ".join(PARAMETERS[table])
        else:
            allowed = "inner.*, pid.*, attitude.*, ride.* (" + ", ".join(known[:5]) + ", ...)"
        raise ValueError(f"--gain = {text!r}: unknown gain {name!r}; allowed: {allowed}")
    values = _value_list(f"--gain {name}", values_text)
    bad = [v for v in values if v < 0]
    if bad:
        raise ValueError(f"--gain = {text!r}: {bad[0]:g} is negative; gains are >= 0")
    return name, values


def _metric_columns() -> list[str]:
    from .metrics import RESPONSES, STATISTICS

    return [f"{r}_{s}" for s in STATISTICS for r in RESPONSES]


#: (column, heading) of the comfort indices the sweep table shows with --comfort
SWEEP_COMFORT_TABLE = (("centre_aw_Wk", "a_w Wk\ncentre\n(m/s^2)"),
                       ("centre_N_MV_z", "N_MV,z\ncentre"), ("front_N_MV_z", "N_MV,z\nfront"),
                       ("rear_N_MV_z", "N_MV,z\nrear"))


def _sweep_table(rows: list[dict], grid_columns: list[str], caption: str):
    from rich.markup import escape
    from rich.table import Table

    table = Table(title="Sweep: RMS of the carbody responses, one row per run",
                  caption=escape(caption))
    table.add_column("#", justify="right")
    for c in grid_columns:
        heading = {"speed_m_s": "speed\n(m/s)", "wavelength_m": "wavelength\n(m)",
                   "amplitude_m": "amplitude\n(m)", "rail_phase_deg": "rail phase\n(deg)",
                   "voltage_v": "voltage\n(V)", "track_seed": "track\nseed",
                   "damper_scale": "damper\nscale",
                   "seed": "noise\nseed"}.get(c, c)
        table.add_column(escape(heading), justify="left" if c == "suspension" else "right",
                         no_wrap=c == "suspension")
    for key, label in RESPONSE_LABELS.items():
        table.add_column(label.replace(" (", "\n("), justify="right")
    comfort = [(c, h) for c, h in SWEEP_COMFORT_TABLE if rows and c in rows[0]]
    for _, heading in comfort:
        table.add_column(escape(heading), justify="right")
    for i, row in enumerate(rows, start=1):
        cells = [str(i)]
        for c in grid_columns:
            v = row[c]
            cells.append("-" if v is None else (escape(v) if isinstance(v, str) else f"{v:g}"))
        cells += [_fmt(row[f"{k}_rms"], "#.4g") for k in RESPONSE_LABELS]
        cells += [_fmt(row[c], "#.3g") for c, _ in comfort]
        table.add_row(*cells)
    return table


def _sweep_comfort_settings(duration: float, window) -> dict:
    """settings.comfort of a sweep with --comfort: the columns, where the positions are and
    what N_MV_z is (the same for every run of the grid, whose runs share one duration)."""
    from .comfort import INDEX_UNITS, INTERVAL_S
    from .sweep import COMFORT_COLUMNS, COMFORT_INDICES

    start, end = window or (0.0, duration)
    n = max(1, int((end - start + 1e-9) // INTERVAL_S))
    unit = {i: INDEX_UNITS["aw" if i.startswith("aw_") else "vdv" if i.startswith("vdv_") else i]
            for _, i in COMFORT_INDICES}
    return {"columns": list(COMFORT_COLUMNS),
            "units": {c: unit[i] for (_, i), c in zip(COMFORT_INDICES, COMFORT_COLUMNS)},
            "positions": {"centre": "x = 0", "front": "x = +l (above the front bogie centre)",
                          "rear": "x = -l (above the rear bogie centre)"},
            "n_intervals": n,
            "notes": ["N_MV_z is the vertical term of EN 12299 only: the model has no lateral "
                      "or longitudinal motion",
                      f"N_MV_z from {n} interval{'s' if n != 1 else ''} of 5 s"
                      + (" (EN 12299 evaluates 60, 5 minutes): an indication only"
                         if n < 60 else "")]}


@app.command("sweep")
def sweep_command(
    suspension: Annotated[str, typer.Option(
        "--suspension", "--controllers", metavar="NAME[,NAME...]",
        help="Suspensions, comma-separated: passive, mr (constant --voltage), pid, sas-attitude, "
             "sas-attitude-ride. --controllers is the same option.")] = "passive",
    speed: Annotated[Optional[str], typer.Option(
        "--speed", metavar="VALUES",
        help="Vehicle speeds [m/s]: START:STOP:COUNT (linear, inclusive) or a,b,c "
             "(default: the scenario's, 55.56).")] = None,
    wavelength: Annotated[Optional[str], typer.Option(
        "--wavelength", metavar="VALUES",
        help="paper-sine: wavelengths [m]; bump: bump lengths [m]. A range or a list.")] = None,
    amplitude: Annotated[Optional[str], typer.Option(
        "--amplitude", metavar="VALUES",
        help="paper-sine: sine amplitudes [m]; bump: heights [m]. A range or a list.")] = None,
    rail_phase: Annotated[Optional[str], typer.Option(
        "--rail-phase", metavar="VALUES",
        help="paper-sine: phase lags of the right rail [deg]. A range or a list.")] = None,
    voltage: Annotated[Optional[str], typer.Option(
        "--voltage", metavar="VALUES",
        help="mr only: constant command voltages [V] within the damper's range, a range or a list "
             "(passive-off, passive-on allowed in a list; default: passive-off).")] = None,
    gain: Annotated[Optional[list[str]], typer.Option(
        "--gain", metavar="TABLE.ENTRY=VALUES",
        help="Controllers only: values of one gain, e.g. pid.kd=1e4,1e5 or attitude.kp_z=0:4e5:5; "
             "repeatable (each adds a grid axis). Tables inner, pid, attitude, ride.")] = None,
    noise: Annotated[Optional[str], typer.Option(
        "--noise", metavar="Z,ANGLE,VEL,RATE",
        help="Controllers only: sensor noise, standard deviations [m, rad, m/s, rad/s].")] = None,
    seed: Annotated[Optional[str], typer.Option(
        "--seed", metavar="VALUES",
        help="With --noise: seeds of the sensor noise, whole numbers >= 0, a range or a list "
             "(default 0). Not the track: see --track-seed.")] = None,
    track_seed: Annotated[Optional[str], typer.Option(
        "--track-seed", metavar="VALUES",
        help="Random tracks only: seeds of the track's realisation, whole numbers >= 0, a "
             "range or a list (default 0); a grid axis for every suspension.")] = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    scenario: Annotated[str, typer.Option(
        "--scenario", metavar="NAME",
        help="paper-sine, bump, file:PATH, fra1..fra6, german-low or german-high, as for "
             "simulate.")] = "paper-sine",
    duration: Annotated[Optional[float], typer.Option(
        "--duration", metavar="S", help="Simulated time of each run [s] (default 10).")] = None,
    dt: DtOption = None,
    damper: Annotated[Optional[str], typer.Option(
        "--damper", metavar="MODEL",
        help="mr and controllers: MR damper model railway, dyke1996 or spencer1997 "
             "(default railway); controllers only: ideal-damper (the ideal semi-active damper) or "
             "ideal (an ideal actuator whose force is the outer loop's demand).")] = None,
    damper_scale: Annotated[Optional[str], typer.Option(
        "--damper-scale", metavar="VALUES",
        help="mr and controllers: factors on the MR damper's force capacity (every force "
             "parameter times X), finite numbers > 0, a range or a list (default 1); a grid "
             "axis. passive runs once, unscaled; not with --damper ideal.")] = None,
    gains: Annotated[Optional[Path], typer.Option(
        "--gains", metavar="FILE.toml",
        help="Controllers: the base gains that --gain changes (default: the shipped "
             "gains).")] = None,
    window: Annotated[Optional[str], typer.Option(
        "--window", metavar="START:END",
        help="Time window of the metrics [s], e.g. 2:10 (default: the whole run).")] = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Keep the run table DIR/runs.csv (updated as runs finish) and write sweep.json "
             "(and sweep.png when one numeric axis has several values) into DIR at the "
             "end.")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume",
        help="Continue the sweep whose run table is DIR/runs.csv (needs --out): runs already "
             "there are not evaluated again.")] = False,
    format: Annotated[SweepFormat, typer.Option(
        "--format", case_sensitive=False,
        help="Output on stdout: a table, JSON (a list of row objects) or CSV.")] = SweepFormat.table,
    comfort: Annotated[bool, typer.Option(
        "--comfort/--no-comfort",
        help="Evaluate the ride comfort indices of every run (columns centre_aw_Wk, "
             "centre_N_MV_z, front_N_MV_z, rear_N_MV_z, centre_Wz, ...; docs/comfort.md) and, "
             "with sweep.png, plot them against the axis in comfort.png (default: on; "
             "--no-comfort for RMS and peak-to-peak only).")] = True,
) -> None:
    """Run a grid of cases: every combination of the given values (a cartesian product).

    The scenario axes (--speed, --wavelength, --amplitude, --rail-phase, --track-seed) apply
    to every suspension; --voltage combines with mr only, --gain, --noise and --seed (the
    sensor noise's) with the controllers they act in; the other suspensions run once per
    scenario combination. Prints one row per run: the grid values and the RMS of the four
    carbody responses.
    """
    import itertools
    import time

    with _errors():
        from . import report
        from . import sweep as sweep_lib
        from .defaults import DEFAULT_DT, DEFAULT_OUTPUT_RATE
        from .metrics import check_window, parse_window

        # suspensions
        items = [s.strip() for s in suspension.split(",")]
        if any(not s for s in items):
            raise ValueError(f"--suspension = {suspension!r}: an empty item; give names separated "
                             f"by commas from {', '.join(sweep_lib.SUSPENSIONS)}")
        unknown = [s for s in items if s not in sweep_lib.SUSPENSIONS]
        if unknown:
            raise ValueError(f"--suspension = {suspension!r}: unknown suspension {unknown[0]!r}; "
                             f"allowed: {', '.join(sweep_lib.SUSPENSIONS)}")
        if len(set(items)) != len(items):
            twice = next(s for s in items if items.count(s) > 1)
            raise ValueError(f"--suspension = {suspension!r}: {twice} is listed twice")
        suspensions = items
        controllers = [s for s in suspensions if s in GAIN_CONTROLLERS["inner"]]
        has_mr = "mr" in suspensions
        listed = ", ".join(suspensions)

        # what applies where
        if voltage is not None and not has_mr:
            raise ValueError(f"--voltage = {voltage!r}: applies to --suspension mr only "
                             f"(--suspension is {listed})")
        for option, given in (("--gain", gain), ("--noise", noise), ("--gains", gains)):
            if given and not controllers:
                value = given[0] if isinstance(given, list) else str(given)
                raise ValueError(f"{option} = {value!r}: applies to the controllers pid, "
                                 f"sas-attitude, sas-attitude-ride only (--suspension is {listed})")
        if seed is not None and noise is None:
            raise ValueError(f"--seed = {seed!r}: applies with --noise only (without it the "
                             "measurements are ideal)")
        if damper is not None and not (has_mr or controllers):
            raise ValueError(f"--damper = {damper!r}: applies to mr and the controllers only "
                             f"(--suspension is {listed})")
        if damper_scale is not None and not (has_mr or controllers):
            raise ValueError(f"--damper-scale = {damper_scale!r}: applies to mr and the "
                             f"controllers only (--suspension is {listed})")
        damper_name = DEFAULT_DAMPER if damper is None else damper
        damper_model = _damper_preset("--damper", damper_name)
        if damper_name in IDEAL_NAMES and has_mr:
            raise ValueError(f"--damper = {damper_name!r}: applies to the controllers only; mr runs at a "
                             f"constant voltage, which the ideal actuator has not (--suspension "
                             f"is {listed})")
        scales = [1.0]
        if damper_scale is not None:
            if damper_name in IDEAL_NAMES:
                raise ValueError(f"--damper-scale = {damper_scale!r}: the ideal device "
                                 f"(--damper {damper_name}) applies the demand itself and has no force "
                                 "capacity to scale")
            scales = [_check_number("--damper-scale", v, "")
                      for v in _value_list("--damper-scale", damper_scale)]

        # the grid axes
        track = _track_options(scenario, None, min_wavelength, max_wavelength)
        axes = []  # (option, keyword, column, values)
        for option, keyword, column, _ in SWEEP_AXES:
            text = {"speed": speed, "wavelength": wavelength, "amplitude": amplitude,
                    "rail_phase": rail_phase, "seed": track_seed}[keyword]
            if text is None:
                continue
            if keyword == "seed":
                values = _value_list(option, text, integer=True)
                bad = [v for v in values if v < 0]
                if bad:
                    raise ValueError(f"--track-seed = {text!r}: {bad[0]} is negative; track "
                                     "seeds are whole numbers >= 0")
                if scenario not in _random_tracks():
                    raise ValueError(f"--track-seed = {text!r}: applies to the random-track "
                                     f"scenarios ({', '.join(_random_tracks())}) only, not to "
                                     f"--scenario {scenario}")
            else:
                values = _value_list(option, text)
            axes.append((option, keyword, column, values))
        volts = []
        if has_mr:
            if voltage is None:
                volts = [float(damper_model.v_min)]
            else:
                volts = _value_list("--voltage", voltage,
                                    parse=lambda item: _voltage("--voltage", item, damper_model))
                volts = [damper_model.check_voltage(v, "--voltage") for v in volts]
        gain_axes = []  # (name, values)
        for text in gain or []:
            name, values = _gain_option(text)
            if any(name == n for n, _ in gain_axes):
                raise ValueError(f"--gain = {text!r}: {name} is given twice")
            acts_in = GAIN_CONTROLLERS[name.partition(".")[0]]
            if not any(c in acts_in for c in controllers):
                raise ValueError(f"--gain = {text!r}: {name} acts in {', '.join(acts_in)} only, "
                                 f"which --suspension ({listed}) does not list")
            gain_axes.append((name, values))
        noise_values = None if noise is None else tuple(_noise_items("--noise", noise))
        seeds = [0] if seed is None else _value_list("--seed", seed, integer=True)
        bad = [s for s in seeds if s < 0]
        if bad:
            raise ValueError(f"--seed = {seed!r}: {bad[0]} is negative; seeds are whole numbers >= 0")
        base_gains = _gain_set(gains)
        dt = DEFAULT_DT if dt is None else _check_number("--dt", dt, "s")
        common = {} if duration is None else {"duration": float(duration)}
        common.update(track)

        # every scenario of the grid must be valid before anything runs
        combos = list(itertools.product(*[values for *_, values in axes]))
        first_record = None
        for combo in combos:
            options = {**common, **{kw: v for (_, kw, _, _), v in zip(axes, combo)}}
            try:
                # every run stores its time histories at the library's default rate
                scen = _make_scenario(scenario, options, DEFAULT_OUTPUT_RATE,
                                      "the runs' output rate")
            except ValueError as exc:
                if str(exc).startswith("--"):  # names its options and values already
                    raise
                given = ", ".join(f"{opt} {v:g}" for (opt, *_), v in zip(axes, combo))
                raise ValueError(f"{given}: {exc}" if given else str(exc)) from None
            first_record = first_record or scen.describe()
        window_value = None
        if window is not None:
            window_value = check_window(parse_window(window), scen.duration)
        # the scenario's fixed settings (the swept ones are grid axes)
        swept = {key for _, kw, _, _ in axes for key in _SCENARIO_KEYS[kw]}
        scenario_record = {k: v for k, v in first_record.items() if k not in swept}

        # the cases, with the grid values each row reports
        grid_columns = ["suspension"] + [column for _, _, column, _ in axes]
        if damper_scale is not None:
            grid_columns.append("damper_scale")
        if has_mr:
            grid_columns.append("voltage_v")
        grid_columns += [name for name, _ in gain_axes]
        if noise_values is not None:
            grid_columns.append("seed")
        cases, grid = [], []
        for s in suspensions:
            for combo in combos:
                options = _case_options(
                    {**common, **{kw: v for (_, kw, _, _), v in zip(axes, combo)}})
                base = {c: None for c in grid_columns}
                base.update({"suspension": s, **{column: v for (_, _, column, _), v in zip(axes, combo)}})
                if s == "passive":
                    cases.append(sweep_lib.Case(scenario, options))
                    grid.append(base)
                elif s == "mr":
                    for x in scales:
                        for v in volts:
                            cases.append(sweep_lib.Case(scenario, options, suspension="mr",
                                                        damper=damper_name, voltage=v,
                                                        damper_scale=x))
                            grid.append({**base, "voltage_v": v,
                                         **({"damper_scale": x} if damper_scale is not None else {})})
                else:
                    mine = [(n, vs) for n, vs in gain_axes if s in GAIN_CONTROLLERS[n.partition(".")[0]]]
                    for x in scales:
                        for values in itertools.product(*[vs for _, vs in mine]):
                            changes = tuple(zip([n for n, _ in mine], values))
                            for sd in (seeds if noise_values is not None else [0]):
                                cases.append(sweep_lib.Case(
                                    scenario, options, suspension=s, damper=damper_name,
                                    gains=changes, noise=noise_values or (), seed=sd,
                                    damper_scale=x))
                                row = {**base, **dict(changes)}
                                if damper_scale is not None:
                                    row["damper_scale"] = x
                                if noise_values is not None:
                                    row["seed"] = sd
                                grid.append(row)
        table, table_path = _run_table(out, resume)
        executor, executor_record = _executor(workers, scheduler, scheduler_file)
    try:
        with _interruptible(table, table_path), _errors():
            with _RunProgress(_stderr_is_terminal(), "sweeping") as progress:
                t0 = time.perf_counter()
                frame = sweep_lib.run_cases(cases, executor=executor, table=table,
                                            base_gains=base_gains, dt=dt, window=window_value,
                                            progress=progress, comfort=comfort)
                wall = time.perf_counter() - t0
            metrics = _metric_columns() + (list(sweep_lib.COMFORT_COLUMNS) if comfort else [])
            rows = []
            diverged = frame["diverged_at_s"].notna() if "diverged_at_s" in frame else [False] * len(cases)
            for case, values, (_, result), bad in zip(cases, grid, frame.iterrows(), diverged):
                row = {**values, **{m: None if bad else float(result[m]) for m in metrics}}
                if any(diverged):  # a run that diverged has no metrics, but the time it went
                    row["diverged_at_s"] = float(result["diverged_at_s"]) if bad else None
                rows.append({**row, "key": case.key})
            doc = {
                "schema": SCHEMA_SWEEP,
                "railride_version": __version__,
                "date": _utc_now(),
                "settings": {
                    "scenario": scenario_record,
                    "grid": {"suspension": suspensions,
                             **{column: values for _, _, column, values in axes},
                             **({"damper_scale": scales} if damper_scale is not None else {}),
                             **({"voltage_v": volts} if has_mr else {}),
                             **{name: values for name, values in gain_axes},
                             **({"seed": seeds} if noise_values is not None else {})},
                    "damper": damper_name if (has_mr or controllers) else None,
                    "gains_source": base_gains.source if controllers else None,
                    "sensor_noise": None if noise_values is None else dict(
                        zip(("displacement", "angle", "velocity", "angular_rate"), noise_values)),
                    "dt_s": float(dt),
                    "window_s": None if window_value is None else list(window_value),
                    # only with --comfort: the document stays as it was without it
                    **({"comfort": _sweep_comfort_settings(scen.duration, window_value)}
                       if comfort else {}),
                },
                "columns": grid_columns + metrics + (["diverged_at_s"] if any(diverged) else [])
                + ["key"],
                "rows": rows,
                "runs": len(table.frame),
                "runs_evaluated": progress.evaluated,
                "runs_per_second": progress.evaluated / wall if wall > 0 else 0.0,
                "wall_time_s": wall,
                "executor": executor_record,
            }
            text = json.dumps(rows, indent=2, allow_nan=False)  # refuses NaN before writing
            if out is not None:
                _write_folder(out, lambda: report.write_sweep_outputs(out, doc))
    finally:
        executor.close()
    if format is SweepFormat.json:
        typer.echo(text)
        return
    if format is SweepFormat.csv:
        import pandas as pd

        typer.echo(pd.DataFrame(rows, columns=doc["columns"]).to_csv(index=False), nl=False)
        return
    st = doc["settings"]
    start, end = window_value or (0.0, scen.duration)
    lines = [f"scenario at the first grid point: {report.describe_scenario(first_record)}, "
             f"{scen.duration:g} s, dt {dt:g} s, RMS over {start:g}-{end:g} s"]
    if st["damper"]:
        lines.append(_damper_text(st) + (f"; gains {st['gains_source']}" if controllers else ""))
    lines.append(f"{len(rows)} run{'s' if len(rows) != 1 else ''}: {doc['runs_evaluated']} evaluated now, "
                 f"{len(rows) - doc['runs_evaluated']} from the run table; wall time {wall:.1f} s")
    n_bad = sum(r.get("diverged_at_s") is not None for r in rows)
    if n_bad:
        lines.append(f"{n_bad} run{'s' if n_bad > 1 else ''} diverged (a response left +-1000 or "
                     "stopped being finite): no metrics, shown as -; see diverged_at_s in the JSON")
    _wide_stdout_console().print(_sweep_table(rows, grid_columns, "\n".join(lines)))


def main() -> None:
    """Entry point of the ``railride`` console script."""
    app(prog_name="railride")


if __name__ == "__main__":
    main()
