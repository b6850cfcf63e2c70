"""``railride compare``: the suspensions on one scenario, beside the paper's Table 1 when it is
the paper's case (railride.studies.comparison.compare), with the tables it prints; several scenarios,
speeds, seeds or loads go to the league table (`_league`)."""

from __future__ import annotations

import json
import math
from typing import Annotated, Optional

import typer

from railride.errors import InputError
from railride.secondary.dampers import IDEAL_NAMES
from railride.output.trade_offs import paper_ranking_text, trade_off_lines
from railride.defaults import DEFAULT_CONTROL_RATE, DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import ProgressBar, errors, option_names, stderr_is_terminal, stdout_console, write_folder
from railride.cli._common import OUTPUT_ONLY, command_line
from railride.cli._options import (
    MaxMemoryOption,
    MaxStepsOption,
    AmplitudeOption,
    ComfortOption,
    CompareDamperOption,
    CompareDamperScaleOption,
    LevelToleranceOption,
    CompareGainsOption,
    CompareOutOption,
    CompareScenarioOption,
    ControlRateOption,
    DpiOption,
    BackendOption,
    MethodOption,
    DtOption,
    DurationOption,
    FigureFormatOption,
    FormatOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    StartOption,
    OutputFormat,
    OutputRateOption,
    VehicleOption,
    PresetOption,
    RailPhaseOption,
    ReportOption,
    WavelengthOption,
    WindowOption,
    HistoryFormatOption,
    figure_options,
    history_options,
)
from railride.cli._parsing import (
    RUN_FIELDS,
    damper_argument,
    load_gains,
    make_scenario,
    not_given,
    parse_noise,
    parse_scale,
    solver_from_options,
    track_options,
    value_list,
    vehicle_arguments,
)
from railride.cli._league import run_league
from railride.cli._render import (
    RESPONSE_LABELS,
    warn_gains_mismatch,
    alike_text,
    compare_comfort_table,
    gains_text,
    damper_text,
    fmt,
    reduction_text,
    stops_note,
    untuned_text,
)

#: --controllers and --references, shared with `railride report`
ControllersOption = Annotated[
    str,
    typer.Option(
        "--controllers",
        metavar="NAME[,NAME...]",
        help="Suspensions to compare, comma-separated: passive, pid, sas-attitude, "
        "sas-attitude-ride (the paper's, the default), skyhook, skyhook-on-off, groundhook, "
        "hybrid, clipped-optimal, passive-on, passive-off (MR dampers at v_max, v_min), or all. "
        "Passive always runs as the baseline.",
    ),
]
BoundsOption = Annotated[
    bool,
    typer.Option(
        "--references/--no-references",
        "--bounds/--no-bounds",
        help="Also run the same control laws and gains on the ideal semi-active damper and the "
        "ideal actuator, and print their reductions beside the MR dampers' (default on; "
        "MR dampers only). References, not bounds: the MR dampers can beat them; --bounds is "
        "the older spelling.",
    ),
]
#: --load: compare's own (the shared `LoadOption` takes one factor), several make a league table
CompareLoadOption = Annotated[
    Optional[str],
    typer.Option(
        "--load",
        metavar="X[,X...]",
        help="Load factor: the carbody's mass and inertias times X (1: as the parameters give "
        "them; 1.3: crush-laden, 30 % more mass). The controllers keep their gains. Default: 1. "
        "Several (a,b or START:STOP:COUNT) make a league table, every case at every load, the "
        "loads kept apart.",
    ),
]
#: the library's names of compare's options, for its errors
COMPARE_FIELDS = {
    **RUN_FIELDS,
    "damper": "--damper",
    "damper_scale": "--damper-scale",
    "delay": "--delay",
    "window": "--window",
    "level_tolerance": "--level-tolerance",
}


def _load_list(text: str) -> list[float]:
    """--load X[,X...] -> the load factors, each checked by the vehicle's own rule (> 0,
    finite) where it is used, so that 0, -0.5 and nan get the same message as one load."""

    def item(part: str) -> float:
        try:
            return float(part)
        except ValueError:
            raise InputError(
                f"--load = {text!r}: {part.strip()!r} is not a number; give load factors > 0 separated by commas"
            ) from None

    return value_list("--load", text, parse=item)


def _controller_list(text: str) -> list[str]:
    """--controllers: comma-separated names, or all -> the suspensions to run, passive first."""
    from railride.studies.comparison import check_controllers
    from railride.secondary.control import CONTROLLERS

    items = [item.strip() for item in text.split(",")]
    if any(not item for item in items):
        raise InputError(
            f"--controllers = {text!r}: an empty item; give names separated by commas from "
            f"{', '.join(CONTROLLERS)}, or all"
        )
    try:
        return check_controllers(items)
    except ValueError as exc:
        raise InputError(f"--controllers = {text!r}: {exc}") from None


def _sensing(name: str):
    """--sensing ideal|accelerometers -> None or the default `railride.secondary.sensing.Accelerometers`."""
    from railride.secondary.sensing import SENSING, Accelerometers

    if name not in SENSING:
        raise InputError(f"--sensing = {name!r}: allowed {', '.join(SENSING)}")
    return None if name == "ideal" else Accelerometers()


def _fault_list(text: Optional[str], damper: str, scale: float, dt: float, duration: float) -> tuple:
    """--fault CORNER-MODE[@S][,...] -> the checked `railride.secondary.faults.DamperFault` tuple."""
    from railride.secondary.faults import DamperFault, check_faults, fault_table
    from railride.secondary.suspension import damper_model

    if text is None:
        return ()
    try:
        items = [item.strip() for item in text.split(",")]
        if any(not item for item in items):
            raise InputError("an empty item; give CORNER-MODE[@S] items separated by commas")
        faults = check_faults([DamperFault.parse(item) for item in items], damper_model(damper, scale))
        fault_table([faults], dt, duration)
    except ValueError as exc:
        raise InputError(f"--fault = {text!r}: {exc}") from None
    return faults


def _sensor_noise(text: Optional[str], seed: Optional[int]):
    """--sensor-noise Z,ANGLE,VEL,RATE and --seed -> a control.SensorNoise, or None."""
    from railride.secondary.control import SensorNoise

    if text is None:
        if seed is not None:
            raise InputError(
                f"--seed = {seed}: applies with --sensor-noise only (without it the measurements are ideal)"
            )
        return None
    z, angle, velocity, rate = parse_noise("--sensor-noise", text)
    try:
        with option_names({"'seed'": "--seed"}):  # as the noise's field check quotes it
            return SensorNoise(z, angle, velocity, rate, seed=0 if seed is None else seed)
    except ValueError as exc:
        if "--seed" in str(exc):
            raise
        raise InputError(f"--sensor-noise = {text!r}: {exc}") from None


def _compare_tables(doc: dict, shipped: bool):
    """The three tables of `compare`: Table 1 beside the paper, peak-to-peak, damper demands."""
    from rich.markup import escape
    from rich.text import Text

    from railride.analysis.labels import describe_scenario
    from railride.cli._width import FitTable, Split
    from railride.model.params import vehicle_text

    rows = doc["controllers"]
    settings = doc["settings"]
    controlled = [r for r in rows if r["name"] != "passive"]

    # 1. the paper's Table 1: RMS and reduction, railride above the paper
    start, end = settings["window_s"] or (0.0, settings["scenario"].get("duration_s", 0.0))
    info = [
        describe_scenario(settings["scenario"]),
        f"dt {settings['dt_s']:g} s, RMS over {start:g}-{end:g} s",
        vehicle_text(settings["vehicle"]),
    ]
    if controlled:
        noise = settings.get("sensor_noise")
        noise_text = (
            "ideal measurements"
            if not noise
            else "sensor noise z {displacement:g} m, angle {angle:g} rad, velocity {velocity:g} m/s, "
            "rate {angular_rate:g} rad/s, seed {seed}".format(**noise)
        )
        delay = settings.get("delay_periods", 1)
        sensed = settings.get("sensing")
        if sensed:
            noise_text = (
                f"accelerometers at the corners (noise {sensed['noise']:g} m/s^2, bias {sensed['bias']:g} m/s^2, "
                f"anti-alias {sensed['antialias_hz']:g} Hz, band-limited integration from {sensed['cutoff_hz']:g} Hz)"
            )
        info.append(
            f"{damper_text(settings)}, controller {settings['control_rate_hz']:g} Hz, "
            f"delay {delay} period{'s' * (delay != 1)}, {noise_text}"
        )
        info.append(gains_text(doc["gains"]["source"], shipped))
        tuning = doc.get("tuning") or {}
        if tuning.get("objective"):
            info.append(
                (f"gains tuned by `{tuning['command']}`, " if tuning.get("command") else "gains tuned, ")
                + f"objective {tuning['objective']}"
            )
        if tuning.get("track"):  # in-sample, the tuned track at another speed, or held out
            info.append(tuning["track"]["note"])
        if tuning.get("alike"):
            info.append(alike_text(tuning["alike"]))
        if tuning.get("untuned"):
            info.append(untuned_text(tuning["untuned"]))
        info += trade_off_lines(doc)
        if settings.get("faults"):  # the library runs no ideal device with faults: said, not left out silently
            info.append(
                "With faults the trade-offs are the faulted runs', and no ideal-device references are run (an ideal "
                "device has no damper to fail); run without --fault for them."
            )
    for name, why in (settings.get("not_run") or {}).items():
        info.append(f"{name}: not run ({why})")
    paper_case = doc.get("paper_case", True)
    faults = settings.get("faults") or []
    info.append(
        (
            "The paper's absolute values depend on settings it does not give (sine wavelength, "
            "rail phase, damper, gains): compare the ranking and the size of the reductions, "
            "not the digits. "
            if paper_case
            else "No published reference exists for this case: the paper's Table 1 is for its sine "
            "(paper-sine) at 55.56 m/s with its vehicle" + (", and healthy dampers. " if faults else ". ")
        )
        + "red. % = (passive - controlled) / passive x 100 (negative: worse than passive, in red)."
    )
    if doc.get("paper_ranking"):
        info.append(paper_ranking_text(doc["paper_ranking"]))  # where the order agrees with Table 1
    title = "Ride comparison: RMS of the carbody responses" + (" beside the paper's Table 1" if paper_case else "")
    if faults:  # every controlled run below has them; passive is healthy
        title += f", the controllers' dampers with the faults {', '.join(faults)} (passive healthy)"

    def rms_table(group: list[dict]):
        table = FitTable(title=title)
        table.add_column("response")
        table.add_column("", no_wrap=True)
        for r in group:
            table.add_column(escape(r["label"].replace(" (", "\n(")), justify="right", min_width=8)
            if r["name"] != "passive":
                table.add_column("red. %", justify="right", no_wrap=True)
        for key, label in RESPONSE_LABELS.items():
            ours, paper = [label, "railride"], ["", "[dim]paper[/dim]"]
            for r in group:
                ours.append(f"{r['metrics'][key]['rms']:#.4g}")
                p = r["paper"][key] if r["paper"] else None  # None: not in the paper
                paper.append(f"[dim]{p['rms']:g}[/dim]" if p else "[dim]-[/dim]")
                if r["name"] != "passive":
                    ours.append(reduction_text(r["reduction_percent"][key]))
                    paper.append(f"[dim]{p['reduction_percent']:.1f}[/dim]" if p else "[dim]-[/dim]")
            table.add_row(*ours, end_section=not paper_case)
            if paper_case:
                table.add_row(*paper, end_section=True)
        return table

    # on a narrow console, one table per group of suspensions, each beside passive
    passive = [r for r in rows if r["name"] == "passive"]
    table = Split(rms_table, [r for r in rows if r["name"] != "passive"], repeat=passive)

    # 1b. the same gains on the ideal devices: what a damper, and an actuator, could reach
    bounds_parts = []
    if doc.get("bounds"):
        # one row per law and response: MR dampers and both references side by side at any width
        bt = FitTable(title="RMS reduction % beside the references: the same control laws and gains on ideal devices")
        bt.add_column("suspension")
        bt.add_column("response")
        for head in ("MR\ndampers", "ideal\ndamper", "ideal\nactuator"):
            bt.add_column(head, justify="right")
        # passive-on and passive-off have no reference (a constant voltage): said below the table
        unbounded = [r for r in controlled if doc["bounds"]["ideal"][r["name"]].get("note")]
        bounded = [r for r in controlled if r not in unbounded]
        for r in bounded:
            for i, (key, label) in enumerate(RESPONSE_LABELS.items()):
                cells = [escape(r["label"]) if i == 0 else "", label, reduction_text(r["reduction_percent"][key])]
                for device in ("ideal-damper", "ideal"):
                    value = doc["bounds"][device][r["name"]]["reduction_percent"][key]
                    cells.append("diverged" if value is None else reduction_text(value))
                bt.add_row(*cells, end_section=i == len(RESPONSE_LABELS) - 1)
        bounds_parts = [
            "",
            bt,
            Text(
                "ideal damper: the demand where it dissipates energy, no force where it would push "
                "energy in (no force limit, no lag, no hysteresis). ideal actuator: the demand, "
                "always (an active suspension). References for these gains, not bounds: the MR "
                "dampers can beat the ideal damper with them (their lag and hysteresis change the "
                "loop), and gains tuned for an ideal device reach further (docs/results.md)."
                + "".join(
                    f" {r['label']}: no reference ({doc['bounds']['ideal'][r['name']]['note']})." for r in unbounded
                )
            ),
        ]

    # 2. peak-to-peak
    def ptp_table(group: list[dict]):
        ptp = FitTable(title="Peak-to-peak of the carbody responses (railride)")
        ptp.add_column("response")
        for r in group:
            ptp.add_column(escape(r["label"].replace(" (", "\n(")), justify="right", min_width=8)
        for key, label in RESPONSE_LABELS.items():
            ptp.add_row(label, *[f"{r['metrics'][key]['ptp']:#.4g}" for r in group])
        return ptp

    ptp = Split(ptp_table, [r for r in rows if r["name"] != "passive"], repeat=passive)

    # 3. what each suspension asks of its dampers: forces, travel, voltage (split when narrow)
    def demand_cells(d: dict) -> dict:
        at_max, demand = d.get("voltage_at_max_fraction"), d.get("demand_rms_n")
        return {
            "RMS demand\n(kN)": "-" if demand is None else f"{demand / 1e3:.2f}",
            "RMS force\n(kN)": f"{d['force_rms_n'] / 1e3:.2f}",
            "max force\n(kN)": f"{d['force_max_n'] / 1e3:.2f}",
            "RMS travel\n(mm)": f"{d['travel_rms_m'] * 1e3:.1f}",
            "max travel\n(mm)": f"{d['travel_max_m'] * 1e3:.1f}" + (" *" if d.get("reached_stops") else ""),
            "mean voltage\n(V)": fmt(d.get("voltage_mean_v"), ".2f"),
            "time at v_max\n(%)": "-" if at_max is None else f"{at_max * 100:.1f}",
        }

    def demands_table(groups: list[tuple[str, ...]]):
        demands = FitTable(title="What each suspension asks of its dampers")
        demands.add_column("suspension")
        for heading in (h for g in groups for h in g):
            demands.add_column(heading, justify="right", min_width=6)
        for r in rows:
            cells = demand_cells(r["damper"])
            demands.add_row(escape(r["label"]), *[cells[h] for g in groups for h in g])
        return demands

    column_groups = [  # forces; travel and voltage: each fits 80 columns unwrapped
        ("RMS demand\n(kN)", "RMS force\n(kN)", "max force\n(kN)"),
        ("RMS travel\n(mm)", "max travel\n(mm)", "mean voltage\n(V)", "time at v_max\n(%)"),
    ]
    demands = Split(demands_table, column_groups)
    demands_note = (
        "All four corners, over the metric window. demand: the force the outer loop "
        "asks for; force: the secondary damper force on the carbody; travel: the "
        "secondary deflection (suspension travel); passive: the viscous dampers c_sz."
        + (" The ideal devices have no voltage." if settings.get("damper") in IDEAL_NAMES and controlled else "")
        + stops_note(rows)
    )
    parts = [table, Text("\n".join(info)), *bounds_parts, "", ptp, "", demands, Text(demands_note)]
    if all("comfort" in r for r in rows):
        parts += ["", compare_comfort_table(rows)]
    if "faults" in doc:
        parts += ["", *_fault_tables(doc)]
    return parts


def _fault_tables(doc: dict):
    """With --fault: per controller and response, the reduction against passive with healthy
    dampers and with the faults, and the change the faults make (railride.secondary.faults.degradation)."""
    from rich.markup import escape
    from rich.text import Text

    from railride.cli._width import FitTable

    record = doc["faults"]
    labels = {r["name"]: r["label"] for r in doc["controllers"]}
    table = FitTable(title=f"With the faults {', '.join(record['faults'])} against healthy dampers")
    for name, justify in (("suspension", "left"), ("response", "left")):
        table.add_column(name, justify=justify)  # type: ignore[arg-type]
    for name in ("red. %\nhealthy", "red. %\nfaulted", "RMS change %\nby the faults"):
        table.add_column(name, justify="right")
    worse = []
    for name, row in record["controllers"].items():
        for i, (key, label) in enumerate(RESPONSE_LABELS.items()):
            healthy = row["healthy_reduction_percent"][key]
            change = row["change_percent"][key]
            table.add_row(
                escape(labels[name]) if i == 0 else "",
                label,
                reduction_text(healthy),
                reduction_text(row["reduction_percent"][key]),
                "" if change is None else (f"[red]{change:+.1f}[/red]" if change > 0 else f"{change:+.1f}"),
                end_section=i == len(RESPONSE_LABELS) - 1,
            )
        if row["worse_than_passive"]:
            words = ", ".join(k.split("_")[0] for k in row["worse_than_passive"])
            worse.append(f"{labels[name]} ({words})")
    note = (
        "red. % = (passive - controlled) / passive RMS x 100, passive healthy; RMS change = (faulted - healthy) / "
        "healthy x 100, + is worse. "
        + (
            "Worse than passive with the faults: " + "; ".join(worse) + "."
            if worse
            else "With the faults no response is worse than passive."
        )
    )
    return [table, Text(note)]


@app.command()
def compare(
    ctx: typer.Context,
    controllers: ControllersOption = "passive,pid,sas-attitude,sas-attitude-ride",
    gains: CompareGainsOption = None,
    damper: CompareDamperOption = DEFAULT_DAMPER,
    damper_scale: CompareDamperScaleOption = None,
    control_rate: ControlRateOption = DEFAULT_CONTROL_RATE,
    sensor_noise: Annotated[
        Optional[str],
        typer.Option(
            "--sensor-noise",
            metavar="Z,ANGLE,VEL,RATE",
            help="White noise on the measured carbody states, standard deviations: heave [m], "
            "pitch and roll angle [rad], heave velocity [m/s], pitch and roll rate [rad/s] "
            "(default: ideal measurements).",
        ),
    ] = None,
    seed: Annotated[
        Optional[int],
        typer.Option("--seed", metavar="N", help="Seed of the sensor noise, >= 0 (default 0); needs --sensor-noise."),
    ] = None,
    delay: Annotated[
        Optional[int],
        typer.Option(
            "--delay",
            metavar="N",
            help="The controllers' computation and communication delay in controller periods, 1..64 "
            "(default 1: a demand takes effect one period after its sample). A controller that "
            "goes unstable is said, not run.",
        ),
    ] = None,
    sensing: Annotated[
        str,
        typer.Option(
            "--sensing",
            metavar="ideal|accelerometers",
            help="What the controllers measure: ideal (the exact states) or accelerometers (four "
            "at the carbody corners, with noise, bias and an anti-alias filter, and band-limited "
            "integration; docs/control.md). Laws that read the bogies do not run with accelerometers.",
        ),
    ] = "ideal",
    fault: Annotated[
        Optional[str],
        typer.Option(
            "--fault",
            metavar="CORNER-MODE[@S][,...]",
            help="Dampers that fail in every controlled suspension: corner 1R, 1L, 2R or 2L, mode off "
            "(coil at v_min), on (stuck at v_max) or disconnected (no force), from time S [s] "
            "(default 0), e.g. 1R-off or 2L-on@2.5,1R-disconnected. Also runs the healthy dampers "
            "and prints how the ride degrades; no ideal-device references.",
        ),
    ] = None,
    scenario: CompareScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: Annotated[
        Optional[str],
        typer.Option(
            "--track-seed",
            metavar="N[,N...]",
            help="Random tracks (fra1..fra6, german-low, german-high, psd:PATH) only: the seed of the track's "
            "realisation, a whole number >= 0; the same seed gives the same track (default 0). Several "
            "seeds make a league table.",
        ),
    ] = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    start: StartOption = None,
    speed: Annotated[
        Optional[str],
        typer.Option(
            "--speed",
            metavar="M/S[,M/S...]",
            help="Vehicle speed [m/s] (default 55.56); several (a,b or START:STOP:COUNT) make a league table.",
        ),
    ] = None,
    duration: DurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    method: MethodOption = None,
    output_rate: OutputRateOption = None,
    window: WindowOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: CompareLoadOption = None,
    format: FormatOption = OutputFormat.table,
    out: CompareOutOption = None,
    bounds: BoundsOption = True,
    comfort: ComfortOption = False,
    report: ReportOption = None,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    history_format: HistoryFormatOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
    level_tolerance: LevelToleranceOption = None,
) -> None:
    """Compare passive, PID and SAS suspensions on one scenario, as in the paper's Table 1.

    Runs the passive vehicle (the baseline) and each controller (MR dampers closed by the
    force-tracking inner loop, or by the on-off and clipped voltage laws of skyhook-on-off
    and clipped-optimal) with the shipped gains, and prints the RMS of the carbody
    responses with the reduction against passive beside the paper's values, the peak-to-peak
    values and what each suspension asks of its dampers. Without options: the paper's
    scenario paper-sine.
    """
    with errors(), option_names(COMPARE_FIELDS, not_given(dt=dt, output_rate=output_rate)):
        from railride.studies.comparison import compare as run_compare
        from railride.output.files import check_out_dir, write_compare_outputs
        from railride.analysis.metrics import check_window, parse_window
        from railride.cli._render import check_report_option, save_report

        figures = figure_options(figure_format, dpi, out)
        histories = history_options(history_format, out)
        scenarios = [item.strip() for item in scenario.split(",")]
        speeds = value_list("--speed", speed) if speed is not None else None
        seeds = value_list("--track-seed", track_seed, integer=True) if track_seed is not None else None
        loads = _load_list(load) if load is not None else None
        if any(len(values or [0]) > 1 for values in (scenarios, speeds, seeds, loads)):
            check_report_option(report)
            if history_format is not None:
                raise InputError(
                    "--history-format: a league table (several --scenario, --speed, --track-seed or --load "
                    "values) writes no time histories"
                )
            if level_tolerance is not None:
                raise InputError("--level-tolerance: a league table (several values) prints no trade-offs")
            given = dict(
                amplitude=amplitude,
                wavelength=wavelength,
                rail_phase=rail_phase,
                min_wavelength=min_wavelength,
                max_wavelength=max_wavelength,
                start=start,
                sensor_noise=sensor_noise,
                seed=seed,
                fault=fault,
                delay=delay,
                sensing=None if sensing == "ideal" else sensing,
            )
            run_league(
                scenarios,
                speeds,
                seeds,
                given,
                names=_controller_list(controllers),
                gains=gains,
                damper=damper,
                damper_scale=damper_scale,
                solver=solver_from_options(
                    dt=dt, output_rate=output_rate, control_rate=control_rate, backend=backend, method=method
                ),
                duration=duration,
                window=window,
                vehicle=vehicle,
                preset=preset,
                loads=loads,
                format=format,
                out=out,
                bounds=bounds,
                figures=figures,
                report=report,
                ctx=ctx,
            )
            return
        speed_value = speeds[0] if speeds else None
        seed_value = seeds[0] if seeds else None
        names = _controller_list(controllers)
        gain_set = load_gains(gains)
        damper_given, damper = damper, damper_argument("--damper", damper)
        scale = parse_scale("--damper-scale", damper_scale)
        noise = _sensor_noise(sensor_noise, seed)
        solver = solver_from_options(
            dt=dt, output_rate=output_rate, control_rate=control_rate, backend=backend, method=method
        )
        vehicle_options = vehicle_arguments(vehicle, preset, loads[0] if loads else None)
        window_value = parse_window(window) if window is not None else None
        track = track_options(scenario, seed_value, min_wavelength, max_wavelength)
        if start is not None:  # a measured profile's section (the library checks the scenario)
            track["start"] = start
        scen = make_scenario(
            scenario,
            dict(
                amplitude=amplitude,
                wavelength=wavelength,
                rail_phase=rail_phase,
                speed=speed_value,
                duration=duration,
                **track,
            ),
            solver.output_rate,
        )
        if out is not None:
            check_out_dir(out, "--out")
        check_report_option(report)
        # check the window before the runs, and record it resolved
        window_value = check_window(window_value or (0.0, math.inf), scen.duration)
        faults = _fault_list(fault, damper, scale, solver.dt, scen.duration)

        controlled = [n for n in names if n != "passive"]

        def describe(done: float) -> str:
            if done < 0.5 or not controlled:
                return "running the passive baseline..."
            return f"running {', '.join(controlled)}..."

        with ProgressBar(stderr_is_terminal(), describe) as progress:
            result = run_compare(
                scen,
                **vehicle_options,
                controllers=names,
                gains=gain_set,
                damper=damper,
                damper_scale=scale,
                window=window_value,
                solver=solver,
                sensor_noise=noise,
                comfort=comfort,
                bounds=bounds,
                progress=progress,
                faults=faults,
                delay=1 if delay is None else delay,
                sensing=_sensing(sensing),
                **({} if level_tolerance is None else {"level_tolerance": level_tolerance}),
            )
        # the command line for the record: this line alone makes the result again
        command = command_line(ctx, exclude=OUTPUT_ONLY)
        doc = {**result.to_dict(), "command": command}
        text = json.dumps(doc, indent=2, allow_nan=False)  # refuses NaN before anything is written
        if out is not None:
            write_folder(out, lambda: write_compare_outputs(result, out, doc, figures=figures, histories=histories))
    warn_gains_mismatch(doc["settings"], damper_given)
    if format is OutputFormat.json:
        typer.echo(text)
    else:
        console = stdout_console()
        for part in _compare_tables(doc, shipped=gains is None):
            console.print(part)
    if report is not None:  # after the tables: a report that cannot be written loses no output
        save_report(report, result, _compare_tables(doc, shipped=gains is None), ctx)
