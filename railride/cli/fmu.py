"""``railride fmu``: the vehicle as an FMI 2.0 co-simulation FMU (railride.frequency.fmu)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from railride.cli._app import app
from railride.cli._common import errors, option_names, stdout_console
from railride.cli._options import (
    AmplitudeOption,
    DtOption,
    DurationOption,
    LoadOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    PresetOption,
    RailPhaseOption,
    ScenarioOption,
    SpeedOption,
    TrackSeedOption,
    VehicleOption,
    WavelengthOption,
)
from railride.cli._parsing import PROFILE_FIELDS, make_scenario, track_options, vehicle_arguments


@app.command()
def fmu(
    out: Annotated[
        Path,
        typer.Option("--out", metavar="FILE", help="The FMU to write (a path ending in .fmu; replaced whole)."),
    ],
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    damper: Annotated[
        str,
        typer.Option(
            "--damper",
            metavar="MODEL",
            help="The secondary in the FMU: passive (the vehicle's dashpots), railway or dyke1996 (Bouc-Wen MR "
            "dampers: coil commands or force demands in), the path of a FILE.toml with a [damper] table of a "
            "Bouc-Wen model (your own MR damper), or ideal (an actuator: force demands in).",
        ),
    ] = "railway",
    dt: DtOption = None,
    scenario: ScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: DurationOption = None,
    sources_only: Annotated[
        bool,
        typer.Option("--sources-only", help="Ship the C sources alone; build no binary for this machine."),
    ] = False,
) -> None:
    """Write the vehicle as an FMI 2.0 co-simulation FMU with C sources and a binary for this
    machine, for Simulink's FMU block, SIMPACK, Dymola, OpenModelica or FMPy (docs/fmu.md). The
    scenario options set the track the FMU starts with: the paper's sine (its settings and speed
    the defaults of the FMU's parameters), or a random track, whose realisation the FMU carries;
    every run can also take its rails from the FMU's inputs."""
    with errors():
        from railride.defaults import DEFAULT_DT
        from railride.frequency.fmu import export_fmu
        from railride.secondary import damper_file

        given = vehicle_arguments(vehicle, preset, load)
        track = track_options(scenario, track_seed, min_wavelength, max_wavelength)
        options = dict(amplitude=amplitude, wavelength=wavelength, rail_phase=rail_phase, speed=speed)
        with option_names(PROFILE_FIELDS):
            sc = make_scenario(scenario, dict(options, duration=duration, **(track or {})))
        fields = {
            "out": "--out",
            "damper": "--damper",
            "dt": "--dt",
            "binary": "--sources-only",
            "scenario": "--scenario",
        }
        with option_names(fields):
            path = export_fmu(
                out,
                **given,
                damper=damper_file.file_model(damper, "--damper") or damper,  # a name: the FMU's to check
                dt=DEFAULT_DT if dt is None else dt,
                scenario=sc,
                binary=not sources_only,
            )
    stdout_console().print(f"wrote {path}", soft_wrap=True, markup=False, highlight=False)
