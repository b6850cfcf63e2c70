"""``railride frf``: frequency responses of the passive vehicle (railride.vehicle), the peaks
table and the FRF document."""

from __future__ import annotations

import json
from enum import Enum
from typing import Annotated

import typer

from .. import __version__
from ._app import app
from ._common import errors, wide_stdout_console, write_folder
from ._options import FrfOutOption, FrfSpeedOption, ParamsOption, PresetOption
from ._parsing import check_int, check_number, vehicle_from_options
from ._render import modes_table

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

    from ..track import Scenario

    return float(next(f.default for f in dataclasses.fields(Scenario) if f.name == "speed"))


@app.command()
def frf(
    speed: FrfSpeedOption = None,
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
    out: FrfOutOption = None,
) -> None:
    """Frequency responses of the passive vehicle: carbody bounce, pitch, roll and acceleration
    per metre of rail amplitude, for in-phase and anti-phase rails.

    Every wheelset sees the same rail pattern, delayed by its distance behind the leading one
    divided by the speed. Prints the peak of each response and the modes.
    """
    with errors():
        import numpy as np

        from .. import report
        from ..vehicle import Vehicle

        speed = _default_speed() if speed is None else check_number("--speed", speed, "m/s")
        if rails not in FRF_RAILS:
            raise ValueError(f"--rails = {rails!r}: allowed {', '.join(FRF_RAILS)}")
        fmin = check_number("--fmin", fmin, "Hz")
        fmax = check_number("--fmax", fmax, "Hz")
        if not fmax > fmin:
            raise ValueError(f"--fmax = {fmax:g} Hz: must be above --fmin = {fmin:g} Hz")
        check_int("--points", points, 2)
        vehicle_params, vehicle_record = vehicle_from_options(params, preset)
        if out is not None:
            report.check_out_dir(out)
        patterns = list(report.FRF_PATTERNS) if rails == "both" else [rails]
        vehicle = Vehicle(vehicle_params)
        frequency = np.geomspace(fmin, fmax, points)
        frequency[0], frequency[-1] = fmin, fmax  # exactly, without rounding
        frame = report.frf_frame({p: vehicle.frequency_response(frequency, speed, p)
                                  for p in patterns})
        modes = [m.to_dict() for m in vehicle.modes()]
        doc = _frf_document(vehicle_record, frequency, frame, modes, speed=speed,
                            patterns=patterns, fmin=fmin, fmax=fmax, points=points)
        text = json.dumps(doc, indent=2, allow_nan=False)  # refuses NaN before writing
        if out is not None:
            title = (f"Carbody frequency responses per metre of rail amplitude - V = {speed:g} m/s, "
                     f"vehicle {_vehicle_name(doc)}, passive suspension")
            write_folder(out, lambda: report.write_frf_outputs(frame, modes, out, doc,
                                                               title=title))
    if format is FrfFormat.json:
        typer.echo(text)
        return
    if format is FrfFormat.csv:
        typer.echo(frame.to_csv(index=False), nl=False)
        return
    console = wide_stdout_console(100)
    for part in _frf_tables(doc):
        console.print(part)


def _frf_document(vehicle_record: dict, frequency, frame, modes: list[dict], *, speed: float,
                  patterns: list[str], fmin: float, fmax: float, points: int) -> dict:
    """The JSON document of `frf` (frf.json)."""
    from .. import report

    magnitudes = [c for c in report.FRF_MAGNITUDES]
    return {
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


def _vehicle_name(doc: dict) -> str:
    return doc.get("vehicle_preset") or doc.get("vehicle_params_file")


def _frf_tables(doc: dict) -> list:
    """The peaks table, its note and the modes table."""
    from rich.table import Table
    from rich.text import Text

    settings = doc["settings"]
    patterns = settings["rails"]
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
    note = Text(f"V = {settings['speed_m_s']:g} m/s, {settings['points']} frequencies from "
                f"{settings['fmin_hz']:g} to {settings['fmax_hz']:g} Hz (log grid; the peak is the "
                f"largest value on it), vehicle {_vehicle_name(doc)}. in-phase: z_L = z_R; "
                "anti-phase: z_L = -z_R; every wheelset sees the pattern delayed by its distance "
                "behind the leading one / V.")
    return [table, note, "", modes_table(doc["modes"])]
