"""``railride ride-spectrum``: the ride on a random track in the frequency domain
(railride.frequency.ride_spectrum), and ``railride state-space``: the linear model's matrices
(railride.frequency.linear)."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated, Optional

import typer

from railride.cli._app import app
from railride.cli._common import errors, option_names, print_json, stdout_console, write_folder
from railride.cli._options import (
    MaxMemoryOption,
    DpiOption,
    FigureFormatOption,
    LoadOption,
    PresetOption,
    ReportOption,
    VehicleOption,
    figure_options,
)
from railride.cli._parsing import load_gains, table_errors, vehicle_arguments
from railride.frequency.ride_spectrum import ACTUATOR_DEVICE

#: the library's names of the options, for its errors
SPECTRUM_OPTIONS = {
    "track": "--track",
    "speed": "--speed",
    "min_wavelength": "--min-wavelength",
    "max_wavelength": "--max-wavelength",
    "points": "--points",
    "control_rate": "--control-rate",
    "delay": "--delay",
    "controllers": "--controllers",
}


#: what the note says of the shipped gains: the robust set, tuned on random track with the MR dampers
SHIPPED = (
    " (the shipped robust set, tuned on FRA classes 4 and 5 with the MR dampers; "
    "--gains paper: the set tuned on the paper's sine)"
)


class SpectrumFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


@app.command("ride-spectrum")
def ride_spectrum(
    ctx: typer.Context,
    track: Annotated[
        str,
        typer.Option(
            "--track",
            metavar="SPECTRUM",
            help="Track spectrum: fra1..fra6, german-low, german-high, or psd:PATH, your own table (docs/track.md).",
        ),
    ] = "fra4",
    speed: Annotated[
        Optional[float], typer.Option("--speed", metavar="M/S", help="Speed [m/s] (default 55.56).")
    ] = None,
    controllers: Annotated[
        str,
        typer.Option(
            "--controllers",
            metavar="NAMES",
            help="Comma-separated: passive and outer loops on the ideal actuator (pid, "
            "sas-attitude, sas-attitude-ride, skyhook, ...), or all.",
        ),
    ] = "passive,pid,sas-attitude,sas-attitude-ride",
    gains: Annotated[
        Optional[Path],
        typer.Option(
            "--gains",
            metavar="paper|robust|FILE.toml",
            help="Controller gains: a shipped set or a gains file (default: robust, the set tuned on random track).",
        ),
    ] = None,
    min_wavelength: Annotated[
        float, typer.Option("--min-wavelength", metavar="M", help="Shortest wavelength of the track [m].")
    ] = 1.0,
    max_wavelength: Annotated[
        float, typer.Option("--max-wavelength", metavar="M", help="Longest wavelength of the track [m].")
    ] = 100.0,
    points: Annotated[
        int, typer.Option("--points", metavar="N", help="Frequencies, log-spaced over the band, 16..200000.")
    ] = 2000,
    control_rate: Annotated[
        Optional[float],
        typer.Option(
            "--control-rate",
            metavar="HZ",
            help="Apply each loop's demand through a sample-and-hold at this rate (default: continuously).",
        ),
    ] = None,
    delay: Annotated[
        Optional[int],
        typer.Option(
            "--delay", metavar="N", help="With --control-rate: the delay in controller periods, 0..64 (default 1)."
        ),
    ] = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    format: Annotated[
        SpectrumFormat,
        typer.Option(
            "--format",
            case_sensitive=False,
            help="Output on stdout: tables, the JSON document or the CSV of RMS values.",
        ),
    ] = SpectrumFormat.table,
    out: Annotated[
        Optional[Path],
        typer.Option(
            "--out",
            metavar="DIR",
            help="Also write ride_spectrum.json, ride_spectrum.csv, ride_spectrum_psd.csv and "
            "the figure ride_spectrum (--figure-format) into DIR (created if missing; all or nothing).",
        ),
    ] = None,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    report: ReportOption = None,
    max_memory: MaxMemoryOption = None,
) -> None:
    """The ride on a random track from the frequency response and the track spectrum, without a
    time simulation: PSDs, RMS and ISO 2631-1 Wb/Wk-weighted RMS of the carbody floor
    acceleration, for the passive vehicle and linear outer loops on the ideal actuator."""
    with errors(), option_names(SPECTRUM_OPTIONS):
        from railride.output.files import check_out_dir
        from railride.frequency.ride_spectrum import ride_spectrum as run

        from railride.cli._render import check_report_option, save_report, warn_gains_mismatch

        figures = figure_options(figure_format, dpi, out)
        check_report_option(report)
        vehicle_options = vehicle_arguments(vehicle, preset, load)
        if out is not None:
            check_out_dir(out, "--out")
        try:
            result = run(
                track,
                speed=speed,
                **vehicle_options,
                controllers=controllers,
                gains=None if gains is None else load_gains(gains),
                min_wavelength=min_wavelength,
                max_wavelength=max_wavelength,
                points=points,
                control_rate=control_rate,
                delay=delay,
            )
        except ValueError as exc:
            table_errors(track, str(exc), "--track")
            raise
        if out is not None:
            write_folder(out, lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi))
    parts = _tables(result)
    warn_gains_mismatch(result.settings)  # gains tuned for another vehicle, load or track: one line
    if format is SpectrumFormat.json:
        print_json(result.to_dict())
    elif format is SpectrumFormat.csv:
        typer.echo(result.to_pandas().to_csv(index=False), nl=False)
    else:
        console = stdout_console()
        for part in parts:
            console.print(part)
    if report is not None:  # after the output: a report that cannot be written loses none of it
        save_report(report, result, parts, ctx)


#: the first line of the tables: which device each number is for
HEADLINE = (
    "Controllers on the ideal actuator (force = demand: an active device with no lag and no force "
    "limit), passive on its viscous dampers; not the MR dampers, which are not linear: their ride "
    "is railride compare's, whose 'ideal actuator' column is this device. A reference for these "
    "gains, not a bound."
)


def _tables(result) -> list:
    """The headline (which device), the floor table (RMS, Wb, Wk and their reductions against
    passive, per suspension and point), the carbody table and the note."""
    from rich.markup import escape
    from railride.cli._width import FitTable
    from rich.text import Text

    from railride.cli._render import reduction_text
    from railride.secondary.control import LABELS
    from railride.frequency.ride_spectrum import FLOOR
    from railride.model.params import vehicle_text

    doc = result.to_dict()
    st = doc["settings"]
    red_rms, red_weighted = doc["rms_reduction_percent"], doc["weighted_rms_reduction_percent"]
    floor = FitTable(
        title=escape("Carbody floor acceleration (m/s^2), frequency domain"),
        caption="red. % = (passive - controlled) / passive x 100 (negative: worse than passive, in red)."
        if red_rms
        else None,
    )
    heads = ("suspension", "point", "RMS", "red. %", "aw Wb", "red. %", "aw Wk")
    for i, head in enumerate(heads):
        floor.add_column(escape(head), justify="left" if i < 2 else "right", no_wrap=head == "red. %")
    for s in result.suspensions:
        for k, point in enumerate(FLOOR):
            wb, wk = (doc["weighted_rms_m_s2"][s][point][w] for w in ("Wb", "Wk"))
            rms = doc["rms"][s][f"floor_acceleration_{point}"]
            floor.add_row(
                escape(LABELS.get(s, s)) if k == 0 else "",
                point,
                f"{rms:.4g}",
                reduction_text(red_rms.get(s, {}).get(f"floor_acceleration_{point}")),
                f"{wb:.4g}",
                reduction_text(red_weighted.get(s, {}).get(point, {}).get("Wb")),
                f"{wk:.4g}",
            )
    body = FitTable(title="Carbody accelerations and secondary travel (RMS)")
    for head in ("suspension", "bounce\n(m/s^2)", "pitch\n(rad/s^2)", "roll\n(rad/s^2)", "travel 1R\n(mm)"):
        body.add_column(escape(head), justify="left" if head == "suspension" else "right")
    for s in result.suspensions:
        r = doc["rms"][s]
        body.add_row(
            escape(LABELS.get(s, s)),
            f"{r['carbody_bounce_acceleration']:.4g}",
            f"{r['carbody_pitch_acceleration']:.4g}",
            f"{r['carbody_roll_acceleration']:.4g}",
            f"{1000 * r['secondary_deflection_1R']:#.4g}",
        )
    rate = "continuously" if st["control_rate_hz"] is None else f"held at {st['control_rate_hz']:g} Hz"
    note = Text(
        f"{st['track']} at V = {st['speed_m_s']:g} m/s, wavelengths {st['min_wavelength_m']:g}-"
        f"{st['max_wavelength_m']:g} m ({st['fmin_hz']:.3g}-{st['fmax_hz']:.3g} Hz, {st['points']} "
        f"frequencies). Controllers on the ideal actuator (force = demand), applied {rate}; "
        f"gains {st.get('gains_source', st['gains'])}{SHIPPED if st['gains'] == 'shipped' else ''}. "
        f"{vehicle_text(st['vehicle'])}."
    )
    controlled = any(d == ACTUATOR_DEVICE for d in doc["devices"].values())
    parts: list = ([Text(HEADLINE)] if controlled else []) + [floor, body, note]
    if "passive" in doc["rms"]:  # what the floor's gain costs in travel: a trade the tables show apart
        base = doc["rms"]["passive"]["secondary_deflection_1R"]
        more = [
            f"{LABELS.get(s, s)} {100 * (doc['rms'][s]['secondary_deflection_1R'] / base - 1):+.3g} %"
            for s in result.suspensions
            if s != "passive" and base > 0 and doc["rms"][s]["secondary_deflection_1R"] > base * 1.01
        ]
        if more:
            parts.append(
                Text(
                    f"Secondary travel (1R, RMS) above passive's: {', '.join(more)}: less floor acceleration, "
                    "more travel."
                )
            )
    for name, reason in st["not_run"].items():
        parts.append(Text(f"not run: {name}: {reason}"))
    return parts


class StateSpaceFormat(str, Enum):
    table = "table"
    json = "json"


@app.command("state-space")
def state_space(
    suspension: Annotated[
        str,
        typer.Option(
            "--suspension",
            metavar="NAME",
            help="passive (the viscous dampers, corner forces in parallel), plant (no secondary "
            "dashpots: what an actuator acts on) or an outer loop closed on the ideal actuator "
            "(pid, sas-attitude, ...).",
        ),
    ] = "passive",
    gains: Annotated[
        Optional[Path],
        typer.Option(
            "--gains",
            metavar="paper|robust|FILE.toml",
            help="Controller gains: a shipped set or a gains file (default: paper, the set tuned on the paper's sine).",
        ),
    ] = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    format: Annotated[
        StateSpaceFormat,
        typer.Option("--format", case_sensitive=False, help="Output on stdout: a summary or the JSON document."),
    ] = StateSpaceFormat.table,
    out: Annotated[
        Optional[Path],
        typer.Option(
            "--out",
            metavar="FILE",
            help="Write the model to FILE: .mat (MATLAB: A, B, C, D and the names) or .json.",
        ),
    ] = None,
) -> None:
    """The linear vehicle as state-space matrices x' = A x + B u, y = C x + D u, with named
    states, inputs and outputs, for MATLAB or python-control."""
    with errors(), option_names({"suspension": "--suspension", "controllers": "--suspension"}):
        from railride.output.files import check_model_path, write_model
        from railride.frequency.linear import linear_model, linear_suspensions

        vehicle_options = vehicle_arguments(vehicle, preset, load)
        if out is not None:
            check_model_path(out, "--out")
        from railride.errors import InputError
        from railride.secondary.control import OUTER_LOOPS

        # one model: "all" and lists, which linear_suspensions takes for ride-spectrum, are refused
        # here in this command's terms, not unpacked into one
        if suspension.strip() not in ("passive", "plant", *OUTER_LOOPS):
            several = "," in suspension or suspension.strip() == "all"
            why = (
                "state-space models one suspension at a time"
                if several
                else "not a linear suspension (MR dampers, in open or closed loop, have a hysteretic, clipped force "
                "and no state-space model)"
            )
            raise InputError(
                f"--suspension = {suspension!r}: {why}; allowed: passive, plant, {', '.join(OUTER_LOOPS)} (each on "
                "the ideal actuator)"
            )
        named = [suspension.strip()]
        gain_set = None if gains is None else load_gains(gains)
        (secondary,) = linear_suspensions(named, gain_set).values()
        model = linear_model(suspension=secondary, **vehicle_options)
        if out is not None:
            write_folder(out.parent, lambda: [write_model(model, out)], own_folder=False)
    # where a closed loop's gains came from, and whether the study that made them tuned this law
    source = None
    if model.controller is not None:
        from railride.secondary.control import GainSet

        ran = gain_set if gain_set is not None else GainSet.default()
        untuned = ran.untuned(named)
        source = f"gains {ran.source}" + (
            f"; {named[0]} was not tuned by the study that made them: its start values" if untuned else ""
        )
    if format is StateSpaceFormat.json:
        print_json({**model.to_dict(), **({"gains_source": source} if source else {})})
        return
    import numpy as np

    from railride.model.params import vehicle_text

    poles = model.poles()
    console = stdout_console()
    console.print(
        f"State-space model, secondary {model.secondary}: {len(model.states)} states, "
        f"{len(model.inputs)} inputs, {len(model.outputs)} outputs; the largest real part of a "
        f"pole is {float(np.max(poles.real)):.4g} 1/s; {vehicle_text(model.record())}"
        + (f"; {source}." if source else ".")
    )
    for kind in ("states", "inputs", "outputs"):
        console.print(f"{kind}: " + ", ".join(getattr(model, kind)))
