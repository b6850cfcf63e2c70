"""``railride simulate``: one run of the vehicle on a track (railride.run.simulation.simulate) and its
ride metrics, printed as a table or as the run's document (`RideResult.to_dict`)."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from railride import validation
from railride.errors import InputError
from railride.defaults import DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import (
    INTERRUPTED,
    ProgressBar,
    errors,
    option_names,
    print_json,
    stderr_is_terminal,
    stdout_console,
    write_folder,
)
from railride.cli._options import (
    MaxMemoryOption,
    MaxStepsOption,
    AmplitudeOption,
    ComfortOption,
    BackendOption,
    MethodOption,
    DtOption,
    DpiOption,
    DurationOption,
    FigureFormatOption,
    FormatOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    OutputFormat,
    OutputRateOption,
    LoadOption,
    VehicleOption,
    PresetOption,
    RailPhaseOption,
    ScenarioOption,
    SimulateDamperOption,
    SimulateDamperScaleOption,
    SimulateOutOption,
    SimulateWindowOption,
    SpeedOption,
    StartOption,
    TrackSeedOption,
    WavelengthOption,
    HistoryFormatOption,
    figure_options,
    history_options,
)
from railride.cli._parsing import (
    PROFILE_FIELDS,
    SOLVER_FIELDS,
    damper_argument,
    make_scenario,
    not_given,
    parse_scale,
    parse_voltage,
    solver_from_options,
    track_options,
    vehicle_from_options,
)
from railride.cli._render import comfort_table

#: --suspension values of `simulate` (`railride.Suspension.named`: passive, or MR dampers at a voltage)
SUSPENSIONS = ("passive", "mr")
#: the library's names of simulate's options, for its errors
SIMULATE_FIELDS = {
    "dt": SOLVER_FIELDS["dt"],
    "backend": SOLVER_FIELDS["backend"],
    "method": SOLVER_FIELDS["method"],
    "output_rate": SOLVER_FIELDS["output_rate"],
    "damper": "--damper",
    "damper_scale": "--damper-scale",
    "voltage": "--voltage",
    "window": "--window",
    **PROFILE_FIELDS,
}


def _describe_suspension(record: dict) -> str:
    if record.get("type") == "mr":
        scale = record.get("damper_scale", 1.0)
        from railride.secondary.dampers import record_name

        return (
            f"MR, {record_name(record['damper'])} dampers"
            + (f" (force x {scale:g})" if scale != 1.0 else "")
            + f" at {record['voltage_v']:g} V"
        )
    return "passive (viscous c_sz)"


def _metrics_table(doc: dict):
    from rich.markup import escape
    from railride.cli._width import FitTable
    from railride.model.params import vehicle_text

    labels = {
        "acceleration_m_s2": "acceleration (m/s^2)",
        "displacement_m": "displacement (m)",
        "pitch_deg": "pitch (deg)",
        "roll_deg": "roll (deg)",
    }
    sc, st = doc["scenario"], doc["settings"]
    start, end = st["window_s"]
    random = (
        [
            f"random track: seed {sc.get('seed')}, wavelengths "
            f"{sc.get('min_wavelength_m'):g}-{sc.get('max_wavelength_m'):g} m"
        ]
        if sc.get("profile") == "random"
        else []
    )
    caption = "\n".join(
        [
            f"scenario {sc.get('name')}, speed {sc.get('speed_m_s'):g} m/s",
            *random,
            f"duration {sc.get('duration_s'):g} s, dt {st['dt_s']:g} s, window {start:g}-{end:g} s",
            vehicle_text(doc["vehicle"]),
            f"suspension {_describe_suspension(doc.get('suspension') or {'type': 'passive'})}",
            *_travel_lines(doc.get("travel")),
        ]
    )
    table = FitTable(title="Ride metrics (carbody CG)", caption=escape(caption))
    table.add_column("response")
    table.add_column("RMS", justify="right")
    table.add_column("peak-to-peak", justify="right")
    for key, values in doc["metrics"].items():
        table.add_row(labels.get(key, key), f"{values['rms']:.5g}", f"{values['ptp']:.5g}")
    return table


def _travel_lines(travel: dict | None) -> list[str]:
    """The largest suspension travel against the bump stops' clearance, for the caption."""
    if travel is None:
        return []
    top, z = travel["max_m"] * 1e3, travel["clearance_m"]
    if z is None:
        return [f"max secondary travel {top:.1f} mm (no bump stops)"]
    reached = ""
    if travel["reached_stops"]:
        bounded = travel.get("stop_stiffness_n_per_m", 0.0) > 0.0
        reached = ": REACHED the bump stops, which bound it" if bounded else ": BEYOND it (no stop force: unbounded)"
    stops = "" if travel.get("stop_stiffness_n_per_m", 0.0) > 0.0 else " (z_stop; no stop force modelled, k_stop = 0)"
    return [f"max secondary travel {top:.1f} mm of {z * 1e3:g} mm clearance{stops}{reached}"]


@app.command()
def simulate(
    scenario: ScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    start: StartOption = None,
    speed: SpeedOption = None,
    duration: DurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    method: MethodOption = None,
    output_rate: OutputRateOption = None,
    window: SimulateWindowOption = None,
    suspension: Annotated[
        str,
        typer.Option(
            "--suspension",
            metavar="passive|mr",
            help="Secondary vertical dampers: passive (viscous c_sz) or mr (an MR damper model at "
            "each corner, constant command voltage).",
        ),
    ] = "passive",
    damper: SimulateDamperOption = None,
    damper_scale: SimulateDamperScaleOption = None,
    voltage: Annotated[
        Optional[str],
        typer.Option(
            "--voltage",
            metavar="V",
            help="--suspension mr only: constant command voltage [V] within the damper's range, or "
            "passive-off (v_min, the default) or passive-on (v_max).",
        ),
    ] = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    format: FormatOption = OutputFormat.table,
    out: SimulateOutOption = None,
    comfort: ComfortOption = False,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    history_format: HistoryFormatOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Simulate the vehicle on a track and print the ride metrics."""
    with errors():
        figures = figure_options(figure_format, dpi, out)
        histories = history_options(history_format, out)
        track = track_options(scenario, track_seed, min_wavelength, max_wavelength)
        if start is not None:  # a measured profile's section (the library checks the scenario)
            track["start"] = start
        doc, result = _run(
            scenario,
            amplitude,
            wavelength,
            rail_phase,
            speed,
            duration,
            dt,
            output_rate,
            window,
            vehicle,
            preset,
            out,
            suspension,
            damper,
            voltage,
            track=track,
            comfort=comfort,
            damper_scale=damper_scale,
            load=load,
            figures=figures,
            histories=histories,
            backend=backend,
            method=method,
        )
    if "partial" in doc:  # Ctrl-C, what was computed saved in --out
        part = doc["partial"]
        typer.echo(
            f"interrupted at t = {part['until_s']:.4g} s of {part['duration_s']:.4g} s: the partial results "
            f"(time histories up to the last finished chunk, marked partial) are saved in {out}",
            err=True,
        )
        raise typer.Exit(INTERRUPTED)
    if format is OutputFormat.json:
        print_json(doc)
    else:
        console = stdout_console()
        console.print(_metrics_table(doc))
        if "comfort" in doc:
            console.print(comfort_table(doc["comfort"]))


def _suspension(name: str, damper_name, voltage_text, damper_scale=None):
    """--suspension, --damper, --damper-scale, --voltage -> a railride.Suspension."""
    from railride.secondary.suspension import Suspension

    validation.choice("--suspension", name, SUSPENSIONS)
    if name == "passive":
        given = [
            o
            for o, v in (("--damper", damper_name), ("--damper-scale", damper_scale), ("--voltage", voltage_text))
            if v is not None
        ]
        if given:
            verb = "applies" if len(given) == 1 else "apply"
            raise InputError(
                f"{' and '.join(given)} {verb} to --suspension mr only (the passive suspension has viscous dampers)"
            )
        return Suspension.passive()
    damper = DEFAULT_DAMPER if damper_name is None else damper_name
    damper = damper_argument("--damper", damper)
    scale = parse_scale("--damper-scale", damper_scale)
    suspension = Suspension.named("mr", damper=damper, damper_scale=scale)
    if voltage_text is None:  # the coils at v_min, "passive-off"
        return suspension
    volts = parse_voltage("--voltage", voltage_text, suspension.damper)
    return Suspension.named("mr", damper=damper, damper_scale=scale, voltage=volts)


def _run(
    scenario_name,
    amplitude,
    wavelength,
    rail_phase,
    speed,
    duration,
    dt,
    output_rate,
    window_text,
    vehicle,
    preset,
    out,
    suspension="passive",
    damper_name=None,
    voltage_text=None,
    track=None,
    comfort=False,
    damper_scale=None,
    load=None,
    figures=None,
    histories=("nc", "csv"),
    backend=None,
    method=None,
):
    from railride.errors import Interrupted
    from railride.output.files import check_out_dir, write_outputs
    from railride.analysis.metrics import check_window, parse_window
    from railride.run.simulation import simulate as run_simulation

    with option_names(SIMULATE_FIELDS, not_given(dt=dt, output_rate=output_rate)):
        solver = solver_from_options(dt=dt, output_rate=output_rate, backend=backend, method=method)
        vehicle_params, vehicle_record = vehicle_from_options(vehicle, preset, load)
        secondary = _suspension(suspension, damper_name, voltage_text, damper_scale)
        window = parse_window(window_text) if window_text is not None else None
        scen = make_scenario(
            scenario_name,
            dict(
                amplitude=amplitude,
                wavelength=wavelength,
                rail_phase=rail_phase,
                speed=speed,
                duration=duration,
                **(track or {}),
            ),
            solver.output_rate,
        )
        if out is not None:
            check_out_dir(out, "--out")
        if window is not None:  # check the window before the run, not after it
            check_window(window, scen.duration)

        interrupted = None
        with ProgressBar(stderr_is_terminal()) as progress:
            try:
                result = run_simulation(scen, vehicle_params, secondary, solver=solver, progress=progress)
            except Interrupted as exc:
                if out is None or exc.result is None:  # nothing to keep it in: status 130 as ever
                    raise
                interrupted, result = exc, exc.result
        if interrupted is not None:  # the metrics over the part of the window that was run
            start, end = window if window is not None else (0.0, interrupted.until)
            window = (start, min(end, interrupted.until)) if start < interrupted.until else (0.0, interrupted.until)
        doc = result.to_dict(window, comfort=comfort, vehicle=vehicle_record)
        if interrupted is not None:
            doc["partial"] = {"until_s": interrupted.until, "duration_s": scen.duration}
    if out is not None:
        write_folder(out, lambda: write_outputs(result, out, doc, figures=figures, histories=histories))
    return doc, result
