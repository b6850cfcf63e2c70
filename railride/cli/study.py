"""``railride study``: statistics over many tracks, speeds, payloads and damper faults
(railride.studies.study), and its table."""

from __future__ import annotations

import json
import time
from typing import Annotated, Optional

import typer

from railride.errors import InputError
from railride.defaults import DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import (
    OUTPUT_ONLY,
    command_line,
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
    OWN_DAMPER,
    MaxMemoryOption,
    MaxStepsOption,
    DpiOption,
    BackendOption,
    DtOption,
    FigureFormatOption,
    FormatOption,
    OutputFormat,
    PresetOption,
    SchedulerFileOption,
    SchedulerOption,
    StartOption,
    StudyGainsOption,
    StudyOutOption,
    ReportOption,
    StudyResumeOption,
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
    solver_from_options,
    value_list,
    vehicle_source,
)
from railride.cli._render import RESPONSE_LABELS, reduction_text
from railride.cli._render import check_report_option, save_report, warn_gains_mismatch

#: the library's names of the study's options, for its errors
STUDY_FIELDS = {
    "scenario": "--scenario",
    "track_seeds": "--track-seed",
    "speeds": "--speed",
    "speed": "--speed",
    "loads": "--load",
    "load": "--load",
    "stiffness": "--stiffness",
    "fault": "--fault",
    "faults": "--fault",
    "duration": "--duration",
    "start": "--start",
    "delays": "--delay",
    "sensing": "--sensing",
    **FIXED_RATE_FIELDS,
    "window": "--window",
}
#: the metrics of the table, and their labels
TABLE_METRICS = {
    **{f"{k}_rms": v for k, v in RESPONSE_LABELS.items()},
    "centre_N_MV_z": "N_MV,z centre (-)",
    "centre_aw_Wk": "a_w Wk centre (m/s^2)",
}


def _faults(text: str) -> list[str]:
    """--fault: comma-separated conditions, each `none` or faults joined by `+` (the library
    checks each, naming it)."""
    items = [item.strip() for item in text.split(",")]
    if any(not item for item in items):
        raise InputError(f"--fault = {text!r}: an empty item; give none or CORNER-MODE[@S] items separated by commas")
    return items


def _table(doc: dict):
    from rich.markup import escape
    from rich.text import Text

    from railride.secondary.control import LABELS
    from railride.secondary.dampers import record_name
    from railride.cli._width import FitTable, Split
    from railride.model.params import vehicle_text

    s = doc["settings"]
    lo, hi = doc["percentiles"]
    seeds = s["track_seeds"] or []
    over = f"{len(seeds)} track seeds, per speed and condition" if seeds else "one run per speed and condition"

    def cells(m: dict) -> dict:
        return {
            "mean": "" if m["mean"] is None else f"{m['mean']:#.4g}",
            "band": "" if m["p5"] is None else f"{m['p5']:#.3g}-{m['p95']:#.3g}",
            "red": reduction_text(m["reduction_mean"]),
            "red band": "" if m["reduction_p5"] is None else f"{m['reduction_p5']:.1f} to {m['reduction_p95']:.1f}",
        }

    band = f"p{lo:g}-p{hi:g}"
    headings = {"mean": "mean", "band": band, "red": "red. %\nmean", "red band": f"red. %\n{band}"}

    def build(groups: list[tuple[str, str]]):
        table = FitTable(title=f"Statistics over {over}", labels=2)
        # what the row group holds, one item a line down its rows: the column stays narrow
        table.add_column("suspension, case")
        table.add_column("metric")
        keys = [k for g in groups for k in g]
        for key in keys:
            table.add_column(headings[key], justify="right", no_wrap=key == "red band")
        for group in doc["results"]:
            if group["controller"] == "passive" and all(k.startswith("red") for k in keys):
                continue  # no reduction of passive against itself: no rows in a table of reductions
            case = [
                escape(LABELS[group["controller"]]),
                f"{group['speed_m_s']:g} m/s",
                f"load {group['load']:g}",
                f"k_sz x {group['stiffness']:g}",
                f"fault {group['fault']}",
                f"delay {group['delay']}",
            ]
            for i, (metric, label) in enumerate(TABLE_METRICS.items()):
                row = cells(group["metrics"][metric])
                table.add_row(
                    case[i] if i < len(case) else "",
                    label,
                    *[row[k] for k in keys],
                    end_section=i == len(TABLE_METRICS) - 1,
                )
        return table

    # on a narrow console the RMS and its reduction in two tables
    table = Split(build, [("mean", "band"), ("red", "red band")])
    speeds = ", ".join(f"{v:g}" for v in s["speeds_m_s"])
    lines = [
        f"{s['scenario']} at {speeds} m/s" + (f", track seeds {', '.join(map(str, seeds))}" if seeds else "") + "; "
        f"{record_name(s['damper'])} dampers, gains {s['gains']} (kept for every load and fault); "
        + ("exact states measured." if s.get("sensing", "ideal") == "ideal" else "accelerometers measured."),
        f"Mean and {lo:g}th to {hi:g}th percentile over the runs of each row (its track seeds)"
        + (
            f"; with {len(seeds)} runs a row, fewer than 20, the band is close to their range"
            if 1 < len(seeds) < 20
            else ""
        )
        + ". red. % = "
        "(passive - controlled) / passive x 100 on the same track, speed and load, run by run; passive "
        "is always healthy.",
        vehicle_text(s["vehicle"]),
        *[s[k] for k in ("tracks_judged", "comfort_basis") if s.get(k)],
    ]
    if doc["failed"]:
        failed = "; ".join(
            f"{f['controller']} load {f['load']:g} {f['fault']} delay {f['delay_periods']}"
            + (f" seed {f['track_seed']}" if f["track_seed"] is not None else "")
            + f" at {f['speed_m_s']:g} m/s "
            f"(t = {f['diverged_at_s']:.3g} s)"
            for f in doc["failed"]
        )
        lines.append(f"Unstable (the run diverged), left out of the statistics: {failed}.")
    from railride.output.trade_offs import study_trade_off_lines
    from railride.studies.study import LEVEL_PERCENT

    lines += study_trade_off_lines(doc["trade_offs"], LEVEL_PERCENT)
    return [table, Text("\n".join(lines))]


@app.command("study")
def study_command(
    ctx: typer.Context,
    controllers: Annotated[
        str,
        typer.Option(
            "--controllers",
            metavar="NAME[,NAME...]",
            help="Suspensions, comma-separated, as for compare, or all; passive always runs as the baseline.",
        ),
    ] = "passive,pid,sas-attitude,sas-attitude-ride",
    scenario: Annotated[
        str,
        typer.Option(
            "--scenario", metavar="NAME", help="The track: fra1..fra6, german-low, german-high (or any scenario)."
        ),
    ] = "fra4",
    track_seed: Annotated[
        Optional[str],
        typer.Option(
            "--track-seed",
            metavar="N[,N...]|A:B:COUNT",
            help="Random-track seeds: a list or a range (default 0:9:10; random tracks only).",
        ),
    ] = None,
    speed: Annotated[
        Optional[str],
        typer.Option("--speed", metavar="M/S[,...]|A:B:COUNT", help="Speeds [m/s] (default: the scenario's)."),
    ] = None,
    load: Annotated[
        str,
        typer.Option(
            "--load",
            metavar="X[,X...]",
            help="Load factors: the carbody's mass and inertias times X (1: as the parameters give them).",
        ),
    ] = "1",
    stiffness: Annotated[
        str,
        typer.Option(
            "--stiffness",
            metavar="X[,X...]",
            help="Secondary stiffness tolerance: k_sz times X (e.g. 0.9,1,1.1). Default 1.",
        ),
    ] = "1",
    fault: Annotated[
        str,
        typer.Option(
            "--fault",
            metavar="CONDITION[,...]",
            help="Fault conditions, comma-separated: none, or CORNER-MODE[@S] faults joined by + "
            "(e.g. none,1R-off,2L-on+1R-disconnected@2). Faults apply to the controlled suspensions.",
        ),
    ] = "none",
    delay: Annotated[
        str,
        typer.Option(
            "--delay",
            metavar="N[,N...]|A:B:COUNT",
            help="The controllers' computation and communication delay in controller periods, 1..64 "
            "(1: a demand takes effect one period after its sample). A run that diverges is listed.",
        ),
    ] = "1",
    sensing: Annotated[
        str,
        typer.Option(
            "--sensing",
            metavar="ideal|accelerometers",
            help="What the controllers measure: the exact states, or accelerometers at the carbody "
            "corners with band-limited integration (docs/control.md).",
        ),
    ] = "ideal",
    duration: Annotated[
        Optional[float], typer.Option("--duration", metavar="S", help="Run length [s] (default 10).")
    ] = None,
    start: StartOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    window: WindowOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    damper: Annotated[
        str,
        typer.Option(
            "--damper",
            metavar="MODEL|FILE.toml",
            help="Damper model of the controllers (as for compare)." + OWN_DAMPER,
        ),
    ] = DEFAULT_DAMPER,
    gains: StudyGainsOption = None,
    workers: WorkersOption = None,
    processes: ProcessesOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: StudyOutOption = None,
    resume: StudyResumeOption = False,
    format: FormatOption = OutputFormat.table,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    report: ReportOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Statistics over many tracks: every controller on every track seed and speed, for each
    load factor and fault condition; mean and 5th-95th percentiles of each RMS response and
    comfort index, and of its reduction against passive on the same track.
    Ctrl-C stops; with --out, --resume continues."""
    from railride.studies.comparison import check_controllers
    from railride.analysis.metrics import parse_window

    with errors(), option_names(STUDY_FIELDS):
        figures = figure_options(figure_format, dpi, out)
        try:
            names = check_controllers(controllers)
        except InputError as exc:  # the library's words name no option
            raise InputError(f"--controllers = {controllers!r}: {exc}") from None
        source = vehicle_source(vehicle, preset)
        check_table("--scenario", scenario)
        seeds = value_list("--track-seed", track_seed, integer=True) if track_seed is not None else None
        speeds = value_list("--speed", speed) if speed is not None else None
        loads = value_list("--load", load)
        stiffness_factors = value_list("--stiffness", stiffness)
        faults = _faults(fault)
        delays = value_list("--delay", delay, integer=True)
        damper_given, damper = damper, damper_argument("--damper", damper)
        gain_set = load_gains(gains)
        solver = solver_from_options(dt=dt, backend=backend)
        window_value = parse_window(window) if window is not None else None
        check_report_option(report)
        table, table_path = open_run_table(out, resume)
        executor, executor_record = make_executor(workers, scheduler, scheduler_file, processes=processes)
    try:
        with interruptible(table, table_path), errors(), option_names(STUDY_FIELDS):
            from railride.studies.study import study

            with RunProgress(stderr_is_terminal(), "running the study") as progress:
                t0 = time.perf_counter()
                result = study(
                    names,
                    scenario=scenario,
                    track_seeds=None if seeds is None else [int(s) for s in seeds],
                    speeds=speeds,
                    loads=loads,
                    stiffness=stiffness_factors,
                    faults=faults,
                    delays=[int(d) for d in delays],
                    sensing=sensing,
                    duration=duration,
                    start=start,
                    gains=gain_set,
                    damper=damper,
                    vehicle=source,
                    solver=solver,
                    window=window_value,
                    executor=executor,
                    table=table,
                    progress=progress,
                )
                wall = time.perf_counter() - t0
            facts = {
                "runs_evaluated": progress.evaluated,
                "wall_time_s": wall,
                "executor": executor_record,
                "command": command_line(ctx, exclude=OUTPUT_ONLY),
            }
            doc = {**result.to_dict(), **facts}
            text = json.dumps(doc, indent=2, allow_nan=False)
            if out is not None:
                write_folder(
                    out,
                    lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi, extra=facts),
                )
    finally:
        executor.close()
    warn_gains_mismatch(doc["settings"], damper_given)
    if format is OutputFormat.json:
        typer.echo(text)
    else:
        console = stdout_console()
        for part in _table(doc):
            console.print(part)
    if report is not None:  # after the output: a report that cannot be written loses none of it
        save_report(report, result, _table(doc), ctx)
