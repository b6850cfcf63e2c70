"""``railride damper`` and ``railride tracking``: an MR damper on the test rig (railride.rig),
its hysteresis cycles and the inner loop's force tracking, with their tables and documents."""

from __future__ import annotations

import math
from typing import Annotated, Optional

import typer

from .. import __version__
from ..defaults import DEFAULT_DAMPER
from ._app import app
from ._common import errors, print_json, status_note, stdout_console, write_folder
from ._options import DamperOutOption, FormatOption, OutputFormat, RigModelOption, TrackingOutOption
from ._parsing import check_number, damper_preset, parse_voltages

SCHEMA_DAMPER = "railride.damper/1"
SCHEMA_TRACKING = "railride.tracking/1"
#: --desired values of `tracking` (the signals of railride.rig.desired_force_signal)
DESIRED_SIGNALS = ("sine", "sawtooth")


def _check_cycles(option: str, value: int) -> int:
    if value < 2:
        raise ValueError(f"{option} = {value}: must be a whole number >= 2 (the first cycle is "
                         "start-up)")
    return value


# -- damper -------------------------------------------------------------------------------------
@app.command()
def damper(
    model: RigModelOption = DEFAULT_DAMPER,
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
    out: DamperOutOption = None,
) -> None:
    """Hysteresis cycles of an MR damper on a test rig.

    The damper is stroked by x = A sin(2 pi f t) at each constant voltage; per voltage the
    command prints the force range and the energy dissipated in the last (steady-state) cycle.
    """
    with errors():
        from .. import report, rig

        damper_model = damper_preset("--model", model, rig=True)
        amplitude = check_number("--amplitude", amplitude, "m")
        frequency = check_number("--frequency", frequency, "Hz")
        volts = parse_voltages("--voltage", voltage, damper_model)
        n_cycles = _check_cycles("--cycles", cycles)
        if out is not None:
            report.check_out_dir(out)
        with status_note("driving the damper..."):
            result = rig.cycles(damper_model, amplitude, frequency, volts, n_cycles=n_cycles)
        doc = _damper_document(result.to_dict())
        title = (f"{model} damper ({damper_model.model} model), x = {amplitude * 1e3:g} mm "
                 f"sin(2 pi {frequency:g} Hz t), cycle {n_cycles} of {n_cycles}")
        if not all(math.isfinite(v) for row in doc["cycles"] for v in row.values()):
            raise RuntimeError("the damper rig run gave a non-finite force or energy")
        if out is not None:
            write_folder(out, lambda: report.write_damper_outputs(result, out, doc, title=title))
    if format is OutputFormat.json:
        print_json(doc)
        return
    stdout_console().print(_damper_table(doc, model, damper_model.model, amplitude, frequency, n_cycles))


def _damper_document(record: dict) -> dict:
    """The JSON document of `damper` (damper.json) from rig.cycles(...).to_dict()."""
    return {
        "schema": SCHEMA_DAMPER,
        "railride_version": __version__,
        "damper": record["damper"],
        "amplitude_m": float(record["amplitude_m"]),
        "frequency_hz": float(record["frequency_hz"]),
        "cycles": [{key: float(row[key]) for key in ("voltage_v", "force_max_n", "force_min_n",
                                                     "energy_per_cycle_j")}
                   for row in record["cycles"]],
    }


def _damper_table(doc: dict, name: str, model: str, amplitude: float, frequency: float, n_cycles: int):
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(f"Damper cycles: {name} ({model} model)"),
                  caption=escape(f"x = {amplitude:g} m sin(2 pi {frequency:g} Hz t); cycle "
                                 f"{n_cycles} of {n_cycles} (steady state)\nforce F: tension +"))
    table.add_column("voltage (V)", justify="right")
    table.add_column("max force (kN)", justify="right")
    table.add_column("min force (kN)", justify="right")
    table.add_column("energy per cycle (J)", justify="right")
    for row in doc["cycles"]:
        table.add_row(f"{row['voltage_v']:g}", f"{row['force_max_n'] / 1e3:.3f}",
                      f"{row['force_min_n'] / 1e3:.3f}", f"{row['energy_per_cycle_j']:.4g}")
    return table


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
    model: RigModelOption = DEFAULT_DAMPER,
    stroke: Annotated[float, typer.Option(
        "--stroke", metavar="M",
        help="Amplitude of the prescribed extension x = -stroke cos(2 pi f t) [m], > 0.")] = 0.02,
    cycles: Annotated[int, typer.Option(
        "--cycles", metavar="N",
        help="Cycles simulated, >= 2; the metrics leave out the first (start-up).")] = 3,
    format: FormatOption = OutputFormat.table,
    out: TrackingOutOption = None,
) -> None:
    """Force tracking of an MR damper by the inner loop.

    The inner loop (paper eq. 12-14) sets the voltage so that a damper stroked by
    x = -stroke cos(2 pi f t) follows a desired force; prints the RMS tracking error.
    """
    with errors():
        from .. import report, rig

        if desired not in DESIRED_SIGNALS:
            raise ValueError(f"--desired = {desired!r}: allowed {', '.join(DESIRED_SIGNALS)}")
        damper_model = damper_preset("--model", model, rig=True)
        amplitude = check_number("--amplitude", amplitude, "N")
        frequency = check_number("--frequency", frequency, "Hz")
        gain_b = check_number("--B", gain_b, "", allow_zero=True)
        if gain_g is not None:
            gain_g = check_number("--G", gain_g, "V/N", allow_zero=True)
        stroke = check_number("--stroke", stroke, "m")
        n_cycles = _check_cycles("--cycles", cycles)
        if out is not None:
            report.check_out_dir(out)
        with status_note("tracking..."):
            result = rig.track(damper_model, desired, amplitude, frequency, B=gain_b, G=gain_g,
                               stroke=stroke, n_cycles=n_cycles)
        doc = _tracking_document(result, damper_model, desired, amplitude, frequency, stroke)
        bad = [k for k, v in doc["metrics"].items() if k != "window_s" and not math.isfinite(v)]
        if bad:  # checked before anything is written
            raise RuntimeError(f"the tracking run gave a non-finite {', '.join(bad)}")
        title = (f"{desired} demand {amplitude / 1e3:g} kN at {frequency:g} Hz, {model} damper, "
                 f"B = {doc['B']:g}, G = {doc['G_v_per_n']:.3g} V/N: normalised RMS error "
                 f"{doc['metrics']['normalised_rms_error']:.3f}")
        if out is not None:
            write_folder(out, lambda: report.write_tracking_outputs(result, out, doc, title=title))
    if format is OutputFormat.json:
        print_json(doc)
        return
    stdout_console().print(_tracking_table(doc, model, default_g=gain_g is None))


def _tracking_document(result, damper_model, desired: str, amplitude: float, frequency: float,
                       stroke: float) -> dict:
    """The JSON document of `tracking` (tracking.json) from a rig.track result."""
    metrics = result.metrics()
    attrs = result.dataset.attrs
    return {
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


def _tracking_table(doc: dict, model: str, *, default_g: bool):
    from rich.markup import escape
    from rich.table import Table

    m = doc["metrics"]
    start, end = m["window_s"]
    caption = "\n".join([
        f"desired force amplitude {doc['amplitude_n']:g} N at {doc['frequency_hz']:g} Hz",
        f"stroke x = -{doc['stroke_m']:g} m cos(2 pi f t); force tension +",
        f"metrics over {start:g}-{end:g} s (after the first cycle)",
    ])
    table = Table(title=escape(f"Force tracking: {doc['desired']} demand, {model} damper"),
                  caption=escape(caption), min_width=56)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("RMS tracking error (N)", f"{m['rms_error_n']:.5g}")
    table.add_row("RMS demand (N)", f"{m['rms_demand_n']:.5g}")
    table.add_row("normalised error (-)", f"{m['normalised_rms_error']:.4f}")
    table.add_row("B (-)", f"{doc['B']:g}")
    table.add_row("G (V/N)" + (" default" if default_g else ""), f"{doc['G_v_per_n']:.4g}")
    return table
