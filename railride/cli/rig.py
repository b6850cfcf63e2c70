"""``railride damper`` and ``railride tracking``: an MR damper on the test rig (railride.run.rig),
its hysteresis cycles and the inner loop's force tracking, with their tables."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from railride.defaults import DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import errors, option_names, print_json, status_note, stdout_console, write_folder
from railride.cli._options import (
    MaxMemoryOption,
    DamperOutOption,
    DpiOption,
    FigureFormatOption,
    FormatOption,
    OutputFormat,
    RigModelOption,
    TrackingOutOption,
    figure_options,
)
from railride.cli._parsing import damper_preset, parse_voltages

#: the library's names of the options of `damper` and `tracking`, for its errors
DAMPER_OPTIONS = {
    "amplitude": "--amplitude",
    "frequency": "--frequency",
    "voltage": "--voltage",
    "voltages": "--voltage",
    "n_cycles": "--cycles",
}
TRACKING_OPTIONS = {
    "desired": "--desired",
    "amplitude": "--amplitude",
    "frequency": "--frequency",
    "B": "--B",
    "G": "--G",
    "stroke": "--stroke",
    "n_cycles": "--cycles",
}


# -- damper -------------------------------------------------------------------------------------
@app.command()
def damper(
    *,  # keyword-only, so that the required options may follow ones with defaults
    model: RigModelOption = DEFAULT_DAMPER,
    amplitude: Annotated[
        float, typer.Option("--amplitude", metavar="M", help="Amplitude of the sine extension x [m], > 0.")
    ],
    frequency: Annotated[
        float, typer.Option("--frequency", metavar="HZ", help="Frequency of the sine extension [Hz], > 0.")
    ],
    voltage: Annotated[
        str,
        typer.Option(
            "--voltage",
            metavar="V[,V...]",
            help="Constant command voltages [V], comma-separated, each within the damper's range "
            "(passive-off and passive-on stand for its lowest and highest voltage).",
        ),
    ],
    cycles: Annotated[
        int,
        typer.Option(
            "--cycles", metavar="N", help="Cycles driven per voltage, >= 2; the last one is reported (steady state)."
        ),
    ] = 4,
    format: FormatOption = OutputFormat.table,
    out: DamperOutOption = None,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    max_memory: MaxMemoryOption = None,
) -> None:
    """Hysteresis cycles of an MR damper on a test rig.

    The damper is stroked by x = A sin(2 pi f t) at each constant voltage; per voltage the
    command prints the force range and the energy dissipated in the last (steady-state) cycle.
    """
    with errors(), option_names(DAMPER_OPTIONS):
        from railride.run import rig
        from railride.output.files import check_out_dir

        figures = figure_options(figure_format, dpi, out)
        damper_model = damper_preset("--damper", model, rig=True)
        volts = parse_voltages("--voltage", voltage, damper_model)
        if out is not None:
            check_out_dir(out, "--out")
        with status_note("driving the damper..."):
            result = rig.cycles(damper_model, amplitude, frequency, volts, n_cycles=cycles)
        doc = result.to_dict()
        if out is not None:
            write_folder(out, lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi))
    if format is OutputFormat.json:
        print_json(doc)
        return
    stdout_console().print(_damper_table(doc, model, result))


def _damper_table(doc: dict, name: str, result):
    from rich.markup import escape
    from railride.cli._width import FitTable

    n = result.n_cycles
    table = FitTable(
        title=escape(f"Damper cycles: {name} ({result.damper.model} model)"),
        caption=escape(
            f"x = {result.motion.amplitude:g} m sin(2 pi {result.motion.frequency:g} Hz "
            f"t); cycle {n} of {n} (steady state)\nforce F: tension +"
        ),
    )
    table.add_column("voltage (V)", justify="right")
    table.add_column("max force (kN)", justify="right")
    table.add_column("min force (kN)", justify="right")
    table.add_column("energy per cycle (J)", justify="right")
    for row in doc["cycles"]:
        table.add_row(
            f"{row['voltage_v']:g}",
            f"{row['force_max_n'] / 1e3:.3f}",
            f"{row['force_min_n'] / 1e3:.3f}",
            f"{row['energy_per_cycle_j']:.4g}",
        )
    return table


# -- tracking -----------------------------------------------------------------------------------
@app.command()
def tracking(
    desired: Annotated[
        str,
        typer.Option(
            "--desired",
            metavar="sine|sawtooth",
            help="Desired force: sine, or sawtooth (rising from -A to A each period).",
        ),
    ] = "sine",
    amplitude: Annotated[
        float, typer.Option("--amplitude", metavar="N", help="Amplitude of the desired force [N], > 0.")
    ] = 10e3,
    frequency: Annotated[
        float,
        typer.Option("--frequency", metavar="HZ", help="Frequency of the desired force and of the stroke [Hz], > 0."),
    ] = 1.0,
    gain_b: Annotated[
        float, typer.Option("--B", metavar="B", help="Inner-loop gain B on the measured force [-], >= 0.")
    ] = 1.0,
    gain_g: Annotated[
        Optional[float],
        typer.Option(
            "--G",
            metavar="V/N",
            help="Inner-loop gain G [V/N], >= 0 (default: the damper's default gain, which "
            "saturates the voltage at a force error of a tenth of its range).",
        ),
    ] = None,
    model: RigModelOption = DEFAULT_DAMPER,
    stroke: Annotated[
        float,
        typer.Option(
            "--stroke", metavar="M", help="Amplitude of the prescribed extension x = -stroke cos(2 pi f t) [m], > 0."
        ),
    ] = 0.02,
    cycles: Annotated[
        int,
        typer.Option(
            "--cycles", metavar="N", help="Cycles simulated, >= 2; the metrics leave out the first (start-up)."
        ),
    ] = 3,
    format: FormatOption = OutputFormat.table,
    out: TrackingOutOption = None,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    max_memory: MaxMemoryOption = None,
) -> None:
    """Force tracking of an MR damper by the inner loop.

    The inner loop (paper eq. 12-14) sets the voltage so that a damper stroked by
    x = -stroke cos(2 pi f t) follows a desired force; prints the RMS tracking error.
    """
    with errors(), option_names(TRACKING_OPTIONS):
        from railride.run import rig
        from railride.output.files import check_out_dir

        figures = figure_options(figure_format, dpi, out)
        damper_model = damper_preset("--damper", model, rig=True)
        if out is not None:
            check_out_dir(out, "--out")
        with status_note("tracking..."):
            result = rig.track(
                damper_model, desired, amplitude, frequency, B=gain_b, G=gain_g, stroke=stroke, n_cycles=cycles
            )
        doc = result.to_dict()
        if out is not None:
            write_folder(out, lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi))
    if format is OutputFormat.json:
        print_json(doc)
        return
    stdout_console().print(_tracking_table(doc, model, default_g=gain_g is None))


def _tracking_table(doc: dict, model: str, *, default_g: bool):
    from rich.markup import escape
    from railride.cli._width import FitTable

    m = doc["metrics"]
    start, end = m["window_s"]
    caption = "\n".join(
        [
            f"desired force amplitude {doc['amplitude_n']:g} N at {doc['frequency_hz']:g} Hz",
            f"stroke x = -{doc['stroke_m']:g} m cos(2 pi f t); force tension +",
            f"metrics over {start:.4g}-{end:.4g} s (after the first cycle)",
        ]
    )
    table = FitTable(
        title=escape(f"Force tracking: {doc['desired']} demand, {model} damper"), caption=escape(caption), min_width=56
    )
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("RMS tracking error (N)", f"{m['rms_error_n']:.5g}")
    table.add_row("RMS demand (N)", f"{m['rms_demand_n']:.5g}")
    table.add_row("normalised error (-)", f"{m['normalised_rms_error']:.4f}")
    table.add_row("B (-)", f"{doc['B']:g}")
    table.add_row("G (V/N)" + (" default" if default_g else ""), f"{doc['G_v_per_n']:.4g}")
    return table
