"""``railride sweep``: a grid of cases (railride.studies.sweep.grid: every combination of the given
values) run by railride.studies.sweep.run_sweep, with its table.

The command reads its options into the grid's Python values (lists of numbers and names, the
gain axes), calls the library and renders the result: the checks of the grid, its cases and the
sweep's document (`SweepResult.to_dict`) are the library's."""

from __future__ import annotations

import json
from enum import Enum
from typing import Annotated, Optional

import typer

from railride.errors import InputError
from railride.defaults import DEFAULT_DAMPER
from railride.secondary.suspension import NAMES as SUSPENSIONS
from railride.cli._app import app
from railride.cli._common import (
    errors,
    interruptible,
    make_executor,
    open_run_table,
    option_names,
    RunProgress,
    stderr_is_terminal,
    stdout_console,
    write_folder,
)
from railride.cli._options import (
    MaxMemoryOption,
    MaxStepsOption,
    DpiOption,
    BackendOption,
    DtOption,
    FigureFormatOption,
    LoadOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    PresetOption,
    ReportOption,
    RunDurationOption,
    RunsScenarioOption,
    SchedulerFileOption,
    SchedulerOption,
    SweepComfortOption,
    SweepDamperOption,
    SweepDamperScaleOption,
    SweepGainsOption,
    SweepOutOption,
    SweepResumeOption,
    VehicleOption,
    WindowOption,
    ProcessesOption,
    WorkersOption,
    figure_options,
)
from railride.cli._parsing import (
    FIXED_RATE_FIELDS,
    check_table,
    damper_argument,
    load_gains,
    parse_noise,
    solver_from_options,
    value_list,
    vehicle_arguments,
)
from railride.cli._render import RESPONSE_LABELS, damper_text, fmt
from railride.cli._render import check_report_option, save_report, warn_gains_mismatch

#: how the errors of railride.studies.sweep.grid name its keywords: by this command's options
OPTION_NAMES = {
    "suspensions": "--suspension",
    "speed": "--speed",
    "wavelength": "--wavelength",
    "amplitude": "--amplitude",
    "rail_phase": "--rail-phase",
    "track_seed": "--track-seed",
    "min_wavelength": "--min-wavelength",
    "max_wavelength": "--max-wavelength",
    "scenario": "--scenario",
    "voltage": "--voltage",
    "gains": "--gain",
    "base_gains": "--gains",
    "noise": "--noise",
    "seed": "--seed",
    "window": "--window",
    "damper": "--damper",
    "damper_scale": "--damper-scale",
    "duration": "--duration",
}

#: (column, heading) of the comfort indices the sweep table shows with --comfort
SWEEP_COMFORT_TABLE = (
    ("centre_aw_Wk", "a_w Wk\ncentre\n(m/s^2)"),
    ("centre_N_MV_z", "N_MV,z\ncentre"),
    ("front_N_MV_z", "N_MV,z\nfront"),
    ("rear_N_MV_z", "N_MV,z\nrear"),
)


class SweepFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


@app.command("sweep")
def sweep_command(
    ctx: typer.Context,
    suspension: Annotated[
        str,
        typer.Option(
            "--suspension",
            "--controllers",
            metavar="NAME[,NAME...]",
            help="Suspensions, comma-separated: passive, mr (constant --voltage), pid, sas-attitude, "
            "sas-attitude-ride, skyhook, skyhook-on-off, groundhook, hybrid, clipped-optimal, "
            "passive-on, passive-off (mr at v_max, v_min), or all (every one but mr). "
            "--controllers is the same option.",
        ),
    ] = "passive",
    speed: Annotated[
        Optional[str],
        typer.Option(
            "--speed",
            metavar="VALUES",
            help="Vehicle speeds [m/s]: START:STOP:COUNT (linear, inclusive) or a,b,c "
            "(default: the scenario's, 55.56).",
        ),
    ] = None,
    wavelength: Annotated[
        Optional[str],
        typer.Option(
            "--wavelength",
            metavar="VALUES",
            help="paper-sine: wavelengths [m]; bump: bump lengths [m]. A range or a list.",
        ),
    ] = None,
    amplitude: Annotated[
        Optional[str],
        typer.Option(
            "--amplitude",
            metavar="VALUES",
            help="paper-sine: sine amplitudes [m]; bump: heights [m]. A range or a list.",
        ),
    ] = None,
    rail_phase: Annotated[
        Optional[str],
        typer.Option(
            "--rail-phase", metavar="VALUES", help="paper-sine: phase lags of the right rail [deg]. A range or a list."
        ),
    ] = None,
    voltage: Annotated[
        Optional[str],
        typer.Option(
            "--voltage",
            metavar="VALUES",
            help="mr only: constant command voltages [V] within the damper's range, a range or a list "
            "(passive-off, passive-on allowed in a list; default: passive-off).",
        ),
    ] = None,
    gain: Annotated[
        Optional[list[str]],
        typer.Option(
            "--gain",
            metavar="TABLE.ENTRY=VALUES",
            help="Controllers only: values of one gain, e.g. pid.kd=1e4,1e5 or attitude.kp_z=0:4e5:5; "
            "repeatable (each adds a grid axis). Tables inner, pid, attitude (SAS attitude), ride_attitude "
            "and ride (SAS attitude+ride), skyhook, skyhook_on_off, groundhook, hybrid, clipped_optimal.",
        ),
    ] = None,
    noise: Annotated[
        Optional[str],
        typer.Option(
            "--noise",
            metavar="Z,ANGLE,VEL,RATE",
            help="Controllers only: sensor noise, standard deviations [m, rad, m/s, rad/s].",
        ),
    ] = None,
    seed: Annotated[
        Optional[str],
        typer.Option(
            "--seed",
            metavar="VALUES",
            help="With --noise: seeds of the sensor noise, whole numbers >= 0, a range or a list "
            "(default 0). Not the track: see --track-seed.",
        ),
    ] = None,
    track_seed: Annotated[
        Optional[str],
        typer.Option(
            "--track-seed",
            metavar="VALUES",
            help="Random tracks only: seeds of the track's realisation, whole numbers >= 0, a "
            "range or a list (default 0); a grid axis for every suspension.",
        ),
    ] = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    scenario: RunsScenarioOption = "paper-sine",
    duration: RunDurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    damper: SweepDamperOption = None,
    damper_scale: SweepDamperScaleOption = None,
    gains: SweepGainsOption = None,
    window: WindowOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    workers: WorkersOption = None,
    processes: ProcessesOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: SweepOutOption = None,
    resume: SweepResumeOption = False,
    format: Annotated[
        SweepFormat,
        typer.Option(
            "--format", case_sensitive=False, help="Output on stdout: a table, JSON (a list of row objects) or CSV."
        ),
    ] = SweepFormat.table,
    comfort: SweepComfortOption = True,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    report: ReportOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Run a grid of cases: every combination of the given values (a cartesian product).

    The scenario axes (--speed, --wavelength, --amplitude, --rail-phase, --track-seed) apply
    to every suspension; --voltage combines with mr only, --gain, --noise and --seed (the
    sensor noise's) with the controllers they act in; the other suspensions run once per
    scenario combination. Prints one row per run: the grid values and the RMS of the four
    carbody responses.
    """
    import time

    with errors():
        from railride.studies.sweep import grid as make_grid, run_sweep

        figures = figure_options(figure_format, dpi, out)
        check_table("--scenario", scenario)
        vehicle_options = vehicle_arguments(vehicle, preset, load)
        values, texts = _parse(
            suspension=suspension,
            speed=speed,
            wavelength=wavelength,
            amplitude=amplitude,
            rail_phase=rail_phase,
            track_seed=track_seed,
            voltage=voltage,
            gain=gain,
            noise=noise,
            seed=seed,
            damper=damper,
            damper_scale=damper_scale,
            gains=gains,
            dt=dt,
            window=window,
            backend=backend,
        )
        grid = make_grid(
            scenario=scenario,
            duration=duration,
            min_wavelength=min_wavelength,
            max_wavelength=max_wavelength,
            names=OPTION_NAMES,
            texts=texts,
            **values,
        )
        check_report_option(report)
        table, table_path = open_run_table(out, resume)
        executor, executor_record = make_executor(workers, scheduler, scheduler_file, processes=processes)
    try:
        with interruptible(table, table_path), errors():
            with RunProgress(stderr_is_terminal(), "sweeping") as progress:
                t0 = time.perf_counter()
                result = run_sweep(
                    grid, executor=executor, table=table, progress=progress, comfort=comfort, **vehicle_options
                )
                wall = time.perf_counter() - t0
            # the command's own facts, after the library's document
            facts = {
                "runs_evaluated": progress.evaluated,
                "runs_per_second": progress.evaluated / wall if wall > 0 else 0.0,
                "wall_time_s": wall,
                "executor": executor_record,
            }
            doc = {**result.to_dict(), **facts}
            text = json.dumps(doc["rows"], indent=2, allow_nan=False)  # refuses NaN before writing
            if out is not None:
                write_folder(
                    out, lambda: result.save(out, extra=facts, figure_formats=figures.figure_formats, dpi=figures.dpi)
                )
    finally:
        executor.close()
    printed = _sweep_table(doc["rows"], list(grid.columns), _caption(grid, doc, wall))
    warn_gains_mismatch(doc["settings"])
    if out is not None and result.figure_note:  # the folder has sweep.json but no sweep.png: say why
        typer.echo(f"note: {result.figure_note}", err=True)
    if format is SweepFormat.json:
        typer.echo(text)
    elif format is SweepFormat.csv:
        typer.echo(result.to_pandas().to_csv(index=False), nl=False)
    else:
        stdout_console().print(printed)
    if report is not None:  # after the output: a report that cannot be written loses none of it
        save_report(report, result, [printed], ctx)


# -- reading the options ------------------------------------------------------------------------
def _parse(
    *,
    suspension,
    speed,
    wavelength,
    amplitude,
    rail_phase,
    track_seed,
    voltage,
    gain,
    noise,
    seed,
    damper,
    damper_scale,
    gains,
    dt,
    window,
    backend=None,
) -> tuple[dict, dict]:
    """(the keyword arguments of railride.studies.sweep.grid, the text each was read from): only the
    syntax of the options is checked here; what their values may be is the grid's to check."""
    from railride.analysis.metrics import parse_window

    with option_names(FIXED_RATE_FIELDS):
        solver = None if dt is None and backend is None else solver_from_options(dt=dt, backend=backend)
    with option_names({"window": "--window"}):
        window_value = None if window is None else parse_window(window)
    values = {
        "suspensions": _names("--suspension", suspension),
        "damper": damper_argument("--damper", damper),
        "noise": None if noise is None else tuple(parse_noise("--noise", noise)),
        "base_gains": None if gains is None else load_gains(gains),
        "solver": solver,
        "window": window_value,
    }
    for option, key, text in (
        ("--speed", "speed", speed),
        ("--wavelength", "wavelength", wavelength),
        ("--amplitude", "amplitude", amplitude),
        ("--rail-phase", "rail_phase", rail_phase),
        ("--damper-scale", "damper_scale", damper_scale),
    ):
        values[key] = None if text is None else value_list(option, text)
    for option, key, text in (("--track-seed", "track_seed", track_seed), ("--seed", "seed", seed)):
        values[key] = None if text is None else value_list(option, text, integer=True)
    read_voltage = _voltage_item(values["damper"])
    values["voltage"] = None if voltage is None else value_list("--voltage", voltage, parse=read_voltage)
    values["gains"], gain_texts = {}, {}
    for text in gain or []:
        name, axis = _gain_option(text)
        if name in values["gains"]:
            raise InputError(f"--gain = {text!r}: {name} is given twice")
        values["gains"][name], gain_texts[name] = axis, text
    texts = {
        "suspensions": suspension,
        "voltage": voltage,
        "noise": noise,
        "seed": seed,
        "damper": damper,
        "damper_scale": damper_scale,
        "track_seed": track_seed,
        "base_gains": None if gains is None else str(gains),
        "gains": gain_texts or None,
    }
    return values, {key: text for key, text in texts.items() if text is not None}


def _names(option: str, text: str) -> list[str]:
    """NAME[,NAME...] -> the names, not empty (which names are allowed is the grid's check);
    all: every suspension a comparison can name (`railride.secondary.control.CONTROLLERS`)."""
    from railride.secondary.control import CONTROLLERS

    if text.strip() == "all":
        return list(CONTROLLERS)
    items = [s.strip() for s in text.split(",")]
    if any(not s for s in items):
        raise InputError(
            f"{option} = {text!r}: an empty item; give names separated by commas from {', '.join(SUSPENSIONS)}, or all"
        )
    return items


def _voltage_item(damper):
    """The reader of a --voltage item: volts, or passive-off / passive-on from the MR damper's
    range (the word itself for a damper the grid refuses with mr). ``damper``: a name or the
    model of a damper file."""
    from railride.secondary.dampers import PRESETS
    from railride.studies.grid import VOLTAGE_WORDS, voltage_value

    if damper is None or isinstance(damper, str):
        model = PRESETS.get(DEFAULT_DAMPER if damper is None else damper)
    else:
        model = damper

    def read(item: str):
        item = item.strip()
        if item in VOLTAGE_WORDS:
            return item if model is None else voltage_value(item, model)
        try:
            return float(item)
        except ValueError:
            raise InputError(f"--voltage = {item!r}: not a number of volts (nor passive-off, passive-on)") from None

    return read


def _gain_option(text: str) -> tuple[str, list[float]]:
    """--gain TABLE.ENTRY=VALUES -> ("table.entry", values); the gains file's sas.attitude.* and
    sas.ride.* read as attitude.* and ride.*."""
    name, sep, values_text = text.partition("=")
    name = name.strip()
    if name.startswith("sas."):
        name = name[len("sas.") :]
    if not sep or not values_text.strip():
        raise InputError(
            f"--gain = {text!r}: expected TABLE.ENTRY=VALUES, e.g. pid.kd=1e4,1e5 or attitude.kp_z=0:4e5:5"
        )
    return name, value_list(f"--gain {name}", values_text)


# -- the table --------------------------------------------------------------------------------------
def _caption(grid, doc: dict, wall: float) -> str:
    """The sweep table's caption: the scenario, the dampers and gains, the runs."""
    from railride.analysis.labels import describe_scenario
    from railride.model.params import vehicle_text

    st, rows = doc["settings"], doc["rows"]
    start, end = grid.window or (0.0, grid.duration)
    lines = [
        f"scenario at the first grid point: {describe_scenario(grid.first_scenario)}, "
        f"{grid.duration:g} s, dt {grid.solver.dt:g} s, RMS over {start:g}-{end:g} s"
    ]
    if st["damper"]:
        lines.append(damper_text(st) + (f"; gains {st['gains_source']}" if grid.controllers else ""))
    lines.append(vehicle_text(st["vehicle"]))
    if st.get("tracks_judged"):  # which rows' tracks the gains were tuned on
        lines.append(st["tracks_judged"])
    lines += [str(n) for n in (st.get("comfort") or {}).get("notes", [])]  # what the comfort columns rest on
    lines.append(
        f"{len(rows)} run{'s' if len(rows) != 1 else ''}: {doc['runs_evaluated']} evaluated now, "
        f"{len(rows) - doc['runs_evaluated']} from the run table; wall time {wall:.1f} s"
    )
    n_bad = sum(r.get("diverged_at_s") is not None for r in rows)
    if n_bad:
        lines.append(
            f"{n_bad} run{'s' if n_bad > 1 else ''} diverged (a response left +-1000 or "
            "stopped being finite): no metrics, shown as -; see diverged_at_s in the JSON"
        )
    return "\n".join(lines)


def _sweep_table(rows: list[dict], grid_columns: list[str], caption: str):
    """One row per run: its grid values, then the RMS responses and comfort indices; on a narrow
    console, as many of these as fit per table, each table repeating the grid values."""
    from rich.markup import escape

    from railride.cli._width import FitTable, Split

    headings = {
        "speed_m_s": "speed\n(m/s)",
        "wavelength_m": "wavelength\n(m)",
        "amplitude_m": "amplitude\n(m)",
        "rail_phase_deg": "rail phase\n(deg)",
        "voltage_v": "voltage\n(V)",
        "track_seed": "track\nseed",
        "damper_scale": "damper\nscale",
        "seed": "noise\nseed",
    }
    # (heading, cell of a row) of each result column
    results = [(label.replace(" (", "\n("), f"{k}_rms", "#.4g") for k, label in RESPONSE_LABELS.items()]
    results += [(escape(h), c, "#.3g") for c, h in SWEEP_COMFORT_TABLE if rows and c in rows[0]]

    def build(columns: list[tuple[str, str, str]]):
        table = FitTable(
            title="Sweep: RMS of the carbody responses, one row per run",
            caption=escape(caption),
            caption_justify="left",
            labels=1 + len(grid_columns),
        )
        table.add_column("#", justify="right")
        for c in grid_columns:
            table.add_column(
                escape(headings.get(c, c)), justify="left" if c == "suspension" else "right", no_wrap=c == "suspension"
            )
        for heading, _, _ in columns:
            table.add_column(heading, justify="right")
        for i, row in enumerate(rows, start=1):
            cells = [str(i)]
            for c in grid_columns:
                v = row[c]
                cells.append("-" if v is None else (escape(v) if isinstance(v, str) else f"{v:g}"))
            cells += [fmt(row[key], spec) for _, key, spec in columns]
            table.add_row(*cells)
        return table

    return Split(build, results, breaks=[len(RESPONSE_LABELS)])  # parts: the RMS, then comfort
