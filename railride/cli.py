"""The ``railride`` command line: ``railride modes`` and ``railride simulate``.

A thin layer over the library: it parses options, calls `railride.vehicle`, `railride.track`,
`railride.simulate`, `railride.metrics` and `railride.report`, and prints. See docs/cli.md.

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

SCHEMA_SIMULATE = "railride.simulate/1"

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
    help="Vertical ride of a 9-DOF railway vehicle: modes and simulated ride metrics.",
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
    """A progress bar on stderr, only when stderr is a terminal."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self._progress = None
        self._task = None

    def __enter__(self):
        if not self.enabled:
            return self
        from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        from . import kernels

        compiled = bool(getattr(kernels.run_batch, "signatures", True))
        first = "simulating" if compiled else "compiling the stepper (first run only)..."
        self._progress = Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                                  TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                                  console=_stderr_console(), transient=True)
        self._progress.__enter__()
        self._task = self._progress.add_task(first, total=1.0)
        return self

    def __call__(self, done: float) -> None:
        if self._progress is not None:
            self._progress.update(self._task, completed=done, description="simulating")

    def __exit__(self, *exc):
        if self._progress is not None:
            self._progress.__exit__(*exc)
        return False


def _status(message: str):
    if not _stderr_is_terminal():
        return contextlib.nullcontext()
    return _stderr_console().status(message)


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
    params: ParamsOption = None,
    preset: PresetOption = None,
    format: FormatOption = OutputFormat.table,
    out: Annotated[Optional[Path], typer.Option(
        "--out", metavar="DIR",
        help="Also write ride.nc, ride.csv, metrics.json and body_responses.png into DIR "
             "(created if missing; all or nothing).")] = None,
) -> None:
    """Simulate the passive vehicle on a track and print the ride metrics."""
    with _errors():
        doc, result = _run(scenario, amplitude, wavelength, rail_phase, speed, duration, dt,
                           output_rate, window, params, preset, out)
    if format is OutputFormat.json:
        typer.echo(json.dumps(doc, indent=2, allow_nan=False))
    else:
        _stdout_console().print(_metrics_table(doc))


def _run(scenario_name, amplitude, wavelength, rail_phase, speed, duration, dt, output_rate,
         window_text, params_file, preset, out):
    from . import report
    from .metrics import check_window, parse_window, to_dict
    from .simulate import DEFAULT_DT, DEFAULT_OUTPUT_RATE, simulate as run_simulation
    from .track import scenario as make_scenario

    dt = DEFAULT_DT if dt is None else dt
    output_rate = DEFAULT_OUTPUT_RATE if output_rate is None else output_rate
    vehicle_params, vehicle_record = _vehicle_params(params_file, preset)
    window = parse_window(window_text) if window_text is not None else None
    scen = make_scenario(scenario_name, amplitude=amplitude, wavelength=wavelength,
                         rail_phase=rail_phase, speed=speed, duration=duration)
    if out is not None:
        report.check_out_dir(out)
    # check the window before the run, not after it
    start, end = (0.0, scen.duration) if window is None else check_window(window, scen.duration)

    with _Progress(_stderr_is_terminal()) as progress:
        result = run_simulation(scen, vehicle_params, dt=dt, output_rate=output_rate,
                                progress=progress if progress.enabled else None)
    metrics = result.metrics(window)
    doc = {
        "schema": SCHEMA_SIMULATE,
        "railride_version": __version__,
        "scenario": scen.describe(),
        **vehicle_record,
        "settings": {"dt_s": float(dt), "output_rate_hz": float(output_rate),
                     "window_s": [float(start), float(end)]},
        "metrics": to_dict(metrics),
    }
    if out is not None:
        try:
            with _status(f"writing outputs to {out}..."):
                report.write_outputs(result, out, doc)
        except OSError as exc:
            raise CliError(f"cannot write the output folder {out}: {exc.strerror or exc}", 2) from None
        typer.echo(f"wrote {', '.join(report.OUTPUT_FILES)} to {out}", err=True)
    return doc, result


def main() -> None:
    """Entry point of the ``railride`` console script."""
    app(prog_name="railride")


if __name__ == "__main__":
    main()
