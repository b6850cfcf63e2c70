"""``railride report``: the paper's comparison, as `railride compare` runs it, written as one
self-contained HTML file (railride.output.report). The helpers with which compare, sweep, tune and
study write the same report of their result with --report are in `railride.cli._render`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from railride.errors import InputError
from railride.defaults import DEFAULT_CONTROL_RATE, DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import errors
from railride.cli._options import (
    MaxMemoryOption,
    MaxStepsOption,
    AmplitudeOption,
    ComfortOption,
    CompareDamperOption,
    CompareDamperScaleOption,
    CompareGainsOption,
    CompareScenarioOption,
    ControlRateOption,
    BackendOption,
    MethodOption,
    DtOption,
    DurationOption,
    LoadOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    StartOption,
    OutputFormat,
    OutputRateOption,
    PresetOption,
    RailPhaseOption,
    SpeedOption,
    TrackSeedOption,
    WavelengthOption,
    VehicleOption,
    WindowOption,
)
from railride.cli._render import check_report_option
from railride.cli.compare import BoundsOption, ControllersOption, compare


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
    start: StartOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: DurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    method: MethodOption = None,
    output_rate: OutputRateOption = None,
    window: WindowOption = None,
    vehicle: VehicleOption = None,
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

    The page opens on the answer: the metrics table and the trade-offs; then the carbody
    responses and acceleration spectra as interactive figures (zoom, pan, click a legend entry
    to hide a suspension), the damper figures, the tables compare prints (also printed here),
    the settings and provenance and the vehicle's modes and parameters. It needs nothing but a
    browser, offline, and is small enough to send by e-mail (its script and figures packed).
    The options are compare's for one scenario; see docs/report.md.
    """
    with errors():
        check_report_option(out, "--out")
        if "," in scenario:
            raise InputError(
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
        start=start,
        speed=None if speed is None else repr(speed),
        duration=duration,
        dt=dt,
        backend=backend,
        method=method,
        output_rate=output_rate,
        window=window,
        vehicle=vehicle,
        preset=preset,
        load=None if load is None else repr(load),
        format=OutputFormat.table,
        out=None,
        bounds=bounds,
        comfort=comfort,
        report=out,
    )
