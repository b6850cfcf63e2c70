"""``railride fmu``: the vehicle as an FMI 2.0 co-simulation FMU (railride.frequency.fmu)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from railride.cli._app import app
from railride.cli._common import errors, option_names, stdout_console
from railride.cli._options import DtOption, LoadOption, PresetOption, VehicleOption
from railride.cli._parsing import vehicle_arguments


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
            "dampers: coil commands or force demands in), or ideal (an actuator: force demands in).",
        ),
    ] = "railway",
    dt: DtOption = None,
    sources_only: Annotated[
        bool,
        typer.Option("--sources-only", help="Ship the C sources alone; build no binary for this machine."),
    ] = False,
) -> None:
    """Write the vehicle as an FMI 2.0 co-simulation FMU with C sources and a binary for this
    machine, for Simulink's FMU block, SIMPACK, Dymola, OpenModelica or FMPy (docs/fmu.md)."""
    with errors():
        from railride.defaults import DEFAULT_DT
        from railride.frequency.fmu import export_fmu

        given = vehicle_arguments(vehicle, preset, load)
        with option_names({"out": "--out", "damper": "--damper", "dt": "--dt", "binary": "--sources-only"}):
            path = export_fmu(out, **given, damper=damper, dt=DEFAULT_DT if dt is None else dt, binary=not sources_only)
    stdout_console().print(f"wrote {path}")
