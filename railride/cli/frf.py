"""``railride frf``: frequency responses of the passive vehicle (railride.frequency.frf), the peaks
table and the modes."""

from __future__ import annotations

from enum import Enum
from typing import Annotated

import typer

from railride.cli._app import app
from railride.cli._common import errors, option_names, print_json, stdout_console, write_folder
from railride.cli._options import (
    MaxMemoryOption,
    DpiOption,
    FigureFormatOption,
    FrfOutOption,
    FrfSpeedOption,
    LoadOption,
    PresetOption,
    VehicleOption,
    figure_options,
)
from railride.cli._parsing import vehicle_arguments
from railride.cli._render import modes_table

#: the library's names of the options of `frf`, for its errors
FRF_OPTIONS = {"speed": "--speed", "rails": "--rails", "fmin": "--fmin", "fmax": "--fmax", "points": "--points"}


class FrfFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


#: table labels of the magnitudes `frf` summarises (keys of railride.analysis.spectra.FRF_MAGNITUDES)
FRF_LABELS = {
    "bounce_m_per_m": "bounce (m/m)",
    "pitch_deg_per_m": "pitch (deg/m)",
    "roll_deg_per_m": "roll (deg/m)",
    "acceleration_m_s2_per_m": "acceleration ((m/s^2)/m)",
}


@app.command()
def frf(
    speed: FrfSpeedOption = None,
    rails: Annotated[
        str,
        typer.Option(
            "--rails",
            metavar="in-phase|anti-phase|both",
            help="Rail pattern: in-phase (z_L = z_R: bounce and pitch), anti-phase (z_L = -z_R: roll) or both.",
        ),
    ] = "both",
    fmin: Annotated[float, typer.Option("--fmin", metavar="HZ", help="Lowest frequency [Hz], > 0.")] = 0.1,
    fmax: Annotated[float, typer.Option("--fmax", metavar="HZ", help="Highest frequency [Hz], > --fmin.")] = 30.0,
    points: Annotated[
        int, typer.Option("--points", metavar="N", help="Frequencies, log-spaced from --fmin to --fmax, >= 2.")
    ] = 400,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    format: Annotated[
        FrfFormat,
        typer.Option(
            "--format",
            case_sensitive=False,
            help="Output on stdout: a summary table (peaks and modes), the JSON document, or the "
            "CSV table of magnitudes and phases.",
        ),
    ] = FrfFormat.table,
    out: FrfOutOption = None,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    max_memory: MaxMemoryOption = None,
) -> None:
    """Frequency responses of the passive vehicle: carbody bounce, pitch, roll and acceleration
    per metre of rail amplitude, for in-phase and anti-phase rails.

    Every wheelset sees the same rail pattern, delayed by its distance behind the leading one
    divided by the speed. Prints the peak of each response and the modes.
    """
    with errors(), option_names(FRF_OPTIONS):
        from railride.output.files import check_out_dir
        from railride.frequency.frf import frequency_responses

        figures = figure_options(figure_format, dpi, out)
        vehicle_options = vehicle_arguments(vehicle, preset, load)
        if out is not None:
            check_out_dir(out, "--out")
        result = frequency_responses(**vehicle_options, speed=speed, rails=rails, fmin=fmin, fmax=fmax, points=points)
        doc = result.to_dict()
        if out is not None:
            write_folder(out, lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi))
    if format is FrfFormat.json:
        print_json(doc)
        return
    if format is FrfFormat.csv:
        typer.echo(result.to_pandas().to_csv(index=False), nl=False)
        return
    console = stdout_console()
    for part in _frf_tables(doc, result.vehicle_name):
        console.print(part)


def _frf_tables(doc: dict, vehicle: str) -> list:
    """The peaks table, its note and the modes table."""
    from railride.cli._width import FitTable
    from rich.text import Text

    settings = doc["settings"]
    patterns = settings["rails"]
    table = FitTable(title="Peaks of the carbody frequency responses (passive vehicle)")
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
    note = Text(
        f"V = {settings['speed_m_s']:g} m/s, {settings['points']} frequencies from "
        f"{settings['fmin_hz']:g} to {settings['fmax_hz']:g} Hz (log grid; the peak is the "
        f"largest value on it), vehicle {vehicle}. in-phase: z_L = z_R; "
        "anti-phase: z_L = -z_R; every wheelset sees the pattern delayed by its distance "
        "behind the leading one / V. The linear passive vehicle: viscous secondary dampers c_sz, "
        "no MR dampers and no controller (their nonlinear ride is simulate's and compare's)."
    )
    from railride.model.params import vehicle_text

    return [table, note, "", modes_table(doc["modes"], vehicle_text(doc["vehicle"]))]
