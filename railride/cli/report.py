"""``railride report``: the paper's comparison, as `railride compare` runs it, written as one
self-contained HTML file (railride.report); and the helpers with which compare, sweep, tune and
study write the same report of their result with --report."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..defaults import DEFAULT_CONTROL_RATE, DEFAULT_DAMPER
from ._app import app
from ._common import CliError, command_line, errors, status_note
from ._options import (
    MaxMemoryOption,
    MaxStepsOption,
    AmplitudeOption,
    ComfortOption,
    CompareDamperOption,
    CompareDamperScaleOption,
    CompareGainsOption,
    CompareScenarioOption,
    ControlRateOption,
    DtOption,
    DurationOption,
    LoadOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    OutputFormat,
    OutputRateOption,
    ParamsOption,
    PresetOption,
    RailPhaseOption,
    SpeedOption,
    TrackSeedOption,
    WavelengthOption,
    WindowOption,
)
from .compare import BoundsOption, ControllersOption, compare

#: columns of the console the report's tables are rendered on (an HTML page scrolls sideways)
REPORT_WIDTH = 120


def check_report_option(path: Optional[Path], option: str = "--report") -> None:
    """Before any run: ValueError naming ``option`` if no report can be written at ``path``."""
    if path is not None:
        from ..report import check_report_path

        check_report_path(path, option)


def save_report(path: Path, result, parts=(), ctx: Optional[typer.Context] = None) -> None:
    """Write the report of ``result`` to ``path``, with ``parts`` (the rich tables and texts the
    command prints) rendered as HTML, and the command line of ``ctx`` as given; say so on
    stderr. A file that cannot be written: ``error: ...``, status 2."""
    import io

    from rich.console import Console

    from ..report import write_report

    console = Console(record=True, file=io.StringIO(), width=REPORT_WIDTH, highlight=False)
    for part in parts:
        console.print(part)
    fragment = console.export_html(inline_styles=True, code_format='<pre class="console">{code}</pre>')
    with errors():
        try:
            with status_note(f"writing the report {path}..."):
                write_report(
                    result,
                    path,
                    console_html=[fragment] if parts else [],
                    command=None if ctx is None else command_line(ctx),
                )
        except OSError as exc:
            raise CliError(f"cannot write the report {path}: {exc.strerror or exc}", 2) from None
    typer.echo(f"wrote {path}", err=True)


@app.command("report")
def report_command(
    ctx: typer.Context,
    controllers: ControllersOption = "passive,pid,sas-attitude,sas-attitude-ride",
    gains: CompareGainsOption = None,
    damper: CompareDamperOption = DEFAULT_DAMPER,
    damper_scale: CompareDamperScaleOption = None,
    control_rate: ControlRateOption = DEFAULT_CONTROL_RATE,
    scenario: CompareScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: DurationOption = None,
    dt: DtOption = None,
    output_rate: OutputRateOption = None,
    window: WindowOption = None,
    params: ParamsOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    bounds: BoundsOption = True,
    comfort: ComfortOption = False,
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            metavar="FILE.html",
            help="The report: one HTML file (.html or .htm), replaced atomically; its folder is created if missing.",
        ),
    ] = Path("report.html"),
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Run the paper's comparison as `railride compare` does and write it as one HTML file.

    The page needs nothing but a browser, offline: the settings and provenance, the vehicle's
    modes and parameters, the tables compare prints (also printed here), the metrics table, the
    carbody responses and acceleration spectra as interactive figures (zoom, pan, click a
    legend entry to hide a suspension) and the damper figures. The options are compare's for
    one scenario; see docs/report.md.
    """
    with errors():
        check_report_option(out, "--out")
        if "," in scenario:
            raise ValueError(
                f"--scenario = {scenario!r}: the report runs one scenario "
                "(a league table over several: railride compare)"
            )
    compare(
        ctx,
        controllers=controllers,
        gains=gains,
        damper=damper,
        damper_scale=damper_scale,
        control_rate=control_rate,
        sensor_noise=None,
        seed=None,
        delay=None,
        sensing="ideal",
        fault=None,
        scenario=scenario,
        amplitude=amplitude,
        wavelength=wavelength,
        rail_phase=rail_phase,
        track_seed=None if track_seed is None else str(track_seed),
        min_wavelength=min_wavelength,
        max_wavelength=max_wavelength,
        speed=None if speed is None else repr(speed),
        duration=duration,
        dt=dt,
        output_rate=output_rate,
        window=window,
        params=params,
        preset=preset,
        load=load,
        format=OutputFormat.table,
        out=None,
        bounds=bounds,
        comfort=comfort,
        report=out,
    )
