"""``railride design``: which law for this vehicle, tuned on a training set of random tracks and
judged on held-out seeds (railride.studies.design), and its tables."""

from __future__ import annotations

import json
import time
from typing import Annotated, Optional

import typer

from railride.cli._app import app
from railride.cli._common import (
    OUTPUT_ONLY,
    RunProgress,
    command_line,
    errors,
    interruptible,
    make_executor,
    open_run_table,
    option_names,
    stderr_is_terminal,
    stdout_console,
    write_folder,
)
from railride.cli._options import (
    OWN_DAMPER,
    BoundOption,
    DpiOption,
    BackendOption,
    DtOption,
    FigureFormatOption,
    FormatOption,
    MaxMemoryOption,
    MaxStepsOption,
    ObjectiveOption,
    OutputFormat,
    MaxPeakOption,
    MaxTravelOption,
    PenaltyOption,
    ReportOption,
    PresetOption,
    SchedulerFileOption,
    SchedulerOption,
    VehicleOption,
    WeightsOption,
    OptimiserOption,
    OptimiserSeedOption,
    optimiser_seed as optimiser_seed_of,
    ProcessesOption,
    WorkersOption,
    DesignOutOption,
    DesignResumeOption,
    figure_options,
)
from railride.cli._parsing import (
    FIXED_RATE_FIELDS,
    check_table,
    damper_argument,
    number_items,
    solver_from_options,
    value_list,
    vehicle_source,
)
from railride.defaults import DEFAULT_DAMPER

#: the library's names of the design's options, for its errors
DESIGN_FIELDS = {
    "controllers": "--controllers",
    "controller": "--controllers",
    "loads": "--load",
    "load": "--load",
    "tracks": "--track",
    "speeds": "--speed",
    "speed": "--speed",
    "train_seeds": "--train-seeds",
    "test_seeds": "--test-seeds",
    "duration": "--duration",
    "budget": "--budget",
    "values": "--values",
    "aggregate": "--aggregate",
    "speed_shares": "--speed-share",
    "load_shares": "--load-share",
    "objective": "--objective",
    "optimiser": "--optimiser",
    "optimiser_seed": "--optimiser-seed",
    **FIXED_RATE_FIELDS,
}
#: the metrics of the table of ratios, and their headings
RATIO_METRICS = {
    "acceleration_m_s2_rms": "accel.",
    "displacement_m_rms": "displ.",
    "pitch_deg_rms": "pitch",
    "roll_deg_rms": "roll",
    "acceleration_m_s2_ptp": "accel.\np-p",
    "centre_N_MV_z": "N_MV,z",
    "centre_Wz": "Wz",
}
#: passive's absolute values: metric -> (heading, scale, format)
PASSIVE_METRICS = {
    "acceleration_m_s2_rms": ("accel.\n(m/s^2)", 1.0, ".3f"),
    "displacement_m_rms": ("displ.\n(mm)", 1e3, ".2f"),
    "pitch_deg_rms": ("pitch\n(deg)", 1.0, ".4f"),
    "roll_deg_rms": ("roll\n(deg)", 1.0, ".4f"),
    "acceleration_m_s2_ptp": ("accel. p-p\n(m/s^2)", 1.0, ".2f"),
    "centre_N_MV_z": ("N_MV,z\n(-)", 1.0, ".2f"),
    "centre_Wz": ("Wz\n(-)", 1.0, ".2f"),
}
#: the costs: metric -> (heading, scale, format)
COST_METRICS = {
    "force_rms_n": ("force RMS\n(kN)", 1e-3, ".2f"),
    "force_max_n": ("force max\n(kN)", 1e-3, ".1f"),
    "travel_max_m": ("travel max\n(mm)", 1e3, ".1f"),
    "voltage_at_max_fraction": ("at v_max\n(%)", 100.0, ".1f"),
    "coil_power_fraction": ("coil power\n(% of full)", 100.0, ".1f"),
}


#: the columns of the references in the ranking, by device
REFERENCE_HEADS = {"ideal": "ideal\nactuator", "ideal-damper": "ideal\ndamper"}


def _score(value, infeasible=None) -> str:
    from railride.studies.design_result import score_text

    return score_text(value, infeasible, short=True)


def _cell(m: dict, scale: float = 1.0, spec: str = ".3f", band: bool = True) -> str:
    if m is None or m.get("mean") is None:
        return "-"
    text = format(m["mean"] * scale, spec)
    if band and m.get("p5") is not None:
        text += f"\n{m['p5'] * scale:{spec}}-{m['p95'] * scale:{spec}}"
    return text


def _ratio_cell(m: dict) -> str:
    if m is None or m.get("ratio_mean") is None:
        return "-"
    text = f"{m['ratio_mean']:.3f}"
    if m["ratio_mean"] > 1.0:
        text = f"[red]{text}[/red]"
    return text + f"\n{m['ratio_p5']:.2f}-{m['ratio_p95']:.2f}"


def _shares_weigh(aggregate: str) -> str:
    """What the time in service weighs, by the design's aggregate over the training runs."""
    if aggregate == "mean":
        return "the shares weigh the training runs' mean and the ranking"
    return "the shares weigh the ranking; tuning takes the worst training run, which no share changes"


def _tables(doc: dict) -> list:
    from rich.markup import escape
    from rich.text import Text

    from railride.cli._width import FitTable, Split
    from railride.studies.design_result import optimiser_text, service_text
    from railride.model.params import vehicle_text
    from railride.secondary.control import LABELS

    s = doc["settings"]
    groups = doc["results"]
    laws = [g for g in groups if g["controller"] != "passive"]
    passive = [g for g in groups if g["controller"] == "passive"]

    def point(g: dict) -> str:
        return f"{g['speed_m_s']:g} m/s\nload {g['load']:g}"

    # the held-out runs at each speed and load: with few, a 5-95 % band is nearly their range
    n = len(s["tracks"]) * len(s["test_seeds"])
    over = f"over the {n} run{'s' * (n != 1)} at each speed and load" + (
        " (with fewer than 20, the band is close to their range)" if n < 20 else ""
    )

    def ratios(keys: list):
        table = FitTable(title=f"Held out: RMS ratio to passive, mean and 5-95 % band {over}", labels=2)
        table.add_column("law")
        table.add_column("speed\nload", no_wrap=True)
        for key in keys:
            table.add_column(RATIO_METRICS.get(key, "run\nscore"), justify="right")
        if "score" in keys:  # not the ranking's score at the point, which is of the mean ratios
            table.caption = (
                "run score: the objective of each held-out run's own ratios, its mean and band over the runs; the "
                "ranking scores a point by the objective of the mean ratios instead (the table below), which for "
                "minimax is at most this mean."
            )
        last = None
        for g in laws:
            name = g["controller"]
            cells = [
                _cell(g["metrics"]["score"], spec=".3f") if k == "score" else _ratio_cell(g["metrics"][k]) for k in keys
            ]
            table.add_row(escape(LABELS[name]) if name != last else "", point(g), *cells)
            last = name
        return table

    def absolute(keys: list):
        table = FitTable(title=f"Held out: passive, mean and 5-95 % band {over}", labels=1)
        table.add_column("speed\nload", no_wrap=True)
        for key in keys:
            table.add_column(PASSIVE_METRICS[key][0], justify="right")
        for g in passive:
            table.add_row(point(g), *[_cell(g["metrics"][k], *PASSIVE_METRICS[k][1:]) for k in keys])
        return table

    def costs(keys: list):
        table = FitTable(title=f"What each law asks of its dampers (held out, mean and 5-95 % band {over})", labels=2)
        table.add_column("law")
        table.add_column("speed\nload", no_wrap=True)
        for key in keys:
            table.add_column(COST_METRICS[key][0], justify="right")
        last = None
        for g in groups:
            name = g["controller"]
            table.add_row(
                escape(LABELS[name]) if name != last else "",
                point(g),
                *[_cell(g["metrics"][k], *COST_METRICS[k][1:]) for k in keys],
            )
            last = name
        clearance = s.get("clearance_m")
        table.caption = (
            "force: the secondary damper force on the carbody; travel: the secondary deflection, "
            + (f"against a clearance of {clearance * 1e3:g} mm (z_stop)" if clearance else "no bump stops")
            + "; at v_max: the time the command voltage sits at the damper's largest; coil power: the mean "
            "electrical power of the coils as a % of their full power, at v_max (mean (u / v_max)^2, u the "
            "coil voltage)."
        )
        return table

    ranking = FitTable(title="Ranking on held-out track", labels=2)
    refs = doc.get("references") or {}
    infeasible = s["objective"].get("infeasible")  # a score past its offset breaks the constraints
    service = s.get("service")
    heads = ["rank", "law", "score", *(["worst"] if service else []), *[REFERENCE_HEADS[d] for d in refs]]
    heads += ["worst at", "best at"]
    for head in heads:
        ranking.add_column(head, justify="left" if head in ("law", "worst at", "best at") else "right")
    for r in doc["ranking"]:
        worst = r["worst_at"]
        best = ", ".join(f"{p['speed_m_s']:g} m/s load {p['load']:g}" for p in r["best_at"]) or "-"
        ref_cells = [_score(refs[d].get(r["controller"], {}).get("score"), infeasible) for d in refs]
        ranking.add_row(
            "-" if r["rank"] is None else str(r["rank"]),
            escape(LABELS[r["controller"]]) + ("" if r["ranked"] else " (diverged)"),
            _score(r["score"], infeasible),
            *([_score(r.get("worst_score"), infeasible)] if service else []),
            *ref_cells,
            f"{worst['speed_m_s']:g} m/s, load {worst['load']:g}",
            best,
        )
    seeds = ", ".join(map(str, s["test_seeds"]))
    kind = s["objective"]["kind"]
    what = "the worst of a law's four mean RMS ratios to passive" if kind == "minimax" else f"the {kind} objective"
    ranking.caption = (
        f"score: {what} at a speed and load (each ratio the mean over that point's held-out runs); a law's "
        + (
            "score is the mean of its scores at the speeds and loads weighted by their time in service, unless "
            "one breaks a constraint (then its worst); worst: its largest. "
            if service
            else "score is its worst over the speeds and loads. "
        )
        + "Objective: "
        + s["objective"]["statement"]
        + "."
        + (
            " Ideal actuator / ideal damper: the law's score with the same gains on the ideal actuator "
            "(force = demand) and on the ideal semi-active damper; references, not bounds (with the same "
            "gains the MR dampers can do better)."
            if refs
            else ""
        )
    )
    lines = [
        f"Tracks {', '.join(s['tracks'])} at {', '.join(f'{v:g}' for v in s['speeds_m_s'])} m/s, loads "
        f"{', '.join(f'{x:g}' for x in s['loads'])}; {s['duration_s']:g} s a run. Tuned on seeds "
        f"{', '.join(map(str, s['train_seeds']))} ({s['training_runs_per_gain_set']} runs per gain set, the "
        f"{s['aggregate']} objective, at most {s['budget']} gain sets per law); judged on seeds {seeds}.",
        f"Tuned by {optimiser_text(s)}.",
        *([f"Time in service: {service_text(service)} ({_shares_weigh(s['aggregate'])})."] if service else []),
        vehicle_text(s["vehicle"]) + f"; {s['damper'] if isinstance(s['damper'], str) else 'own'} dampers.",
        *([s["comfort_basis"]] if s.get("comfort_basis") else []),
        f"{doc['runs']['training']} training and {doc['runs']['judging']} held-out runs (passive's included)"
        + (
            f"; {doc['runs_evaluated']} evaluated now, with the references' and the fault check's, wall time "
            f"{doc['wall_time_s']:.1f} s."
            if "runs_evaluated" in doc
            else "."
        ),
    ]
    ratio_keys = [*RATIO_METRICS, "score"]
    return [
        Split(ratios, ratio_keys),
        Split(absolute, list(PASSIVE_METRICS)),
        Split(costs, list(COST_METRICS)),
        ranking,
        Text("\n".join(lines)),
        Text("\n" + doc["recommendation"]["text"]),
    ]


@app.command("design")
def design_command(
    ctx: typer.Context,
    controllers: Annotated[
        str,
        typer.Option(
            "--controllers",
            metavar="NAME[,NAME...]",
            help="The laws to consider, comma-separated (pid, sas-attitude, sas-attitude-ride, skyhook, "
            "skyhook-on-off, groundhook, hybrid, clipped-optimal), or all. Passive is always judged.",
        ),
    ] = "all",
    track: Annotated[
        str,
        typer.Option(
            "--track",
            metavar="NAME[,NAME...]",
            help="Random track classes (fra1..fra6, german-low, german-high, psd:PATH: your own spectrum table) or a "
            "measured line (file:PATH, "
            "whose seeds are its sections, each the fastest speed x the duration long).",
        ),
    ] = "fra4,fra5",
    speed: Annotated[
        str, typer.Option("--speed", metavar="M/S[,...]|A:B:COUNT", help="Speeds [m/s] to tune and judge at.")
    ] = "30,50,70",
    load: Annotated[
        str,
        typer.Option("--load", metavar="X[,X...]", help="Load factors: the carbody's mass and inertias times X."),
    ] = "1,1.3",
    train_seeds: Annotated[
        str,
        typer.Option("--train-seeds", metavar="N[,N...]|A:B:COUNT", help="Track seeds tuning runs on."),
    ] = "1,2,3",
    test_seeds: Annotated[
        str,
        typer.Option(
            "--test-seeds",
            metavar="N[,N...]|A:B:COUNT",
            help="Held-out track seeds the laws are judged on; none may be a training seed.",
        ),
    ] = "100,101,102,103,104",
    duration: Annotated[float, typer.Option("--duration", metavar="S", help="Track per run [s].")] = 20.0,
    budget: Annotated[
        int,
        typer.Option(
            "--budget",
            metavar="N",
            help="Gain sets per law (each scored on every training run); at least enough to try every gain once.",
        ),
    ] = 130,
    values: Annotated[int, typer.Option("--values", metavar="N", help="Values per gain and sweep, >= 3.")] = 7,
    aggregate: Annotated[
        str,
        typer.Option(
            "--aggregate",
            metavar="mean|worst",
            help="A gain set's objective over the training runs: their mean, or the worst.",
        ),
    ] = "mean",
    speed_share: Annotated[
        Optional[str],
        typer.Option(
            "--speed-share",
            metavar="X[,X...]",
            help="Time in service at each --speed, in its order (numbers > 0, normalised): the speeds "
            "weigh the training runs' mean and the ranking, which then scores a law by its weighted mean "
            "over the speeds and loads instead of its worst (default: none; every speed alike, ranked by the worst).",
        ),
    ] = None,
    load_share: Annotated[
        Optional[str],
        typer.Option(
            "--load-share",
            metavar="X[,X...]",
            help="Time in service at each --load, as --speed-share (speed and load taken as independent).",
        ),
    ] = None,
    optimiser: OptimiserOption = "sensitivity",
    optimiser_seed: OptimiserSeedOption = None,
    objective_kind: ObjectiveOption = None,
    weights: WeightsOption = None,
    bound: BoundOption = None,
    penalty: PenaltyOption = None,
    max_peak: MaxPeakOption = None,
    max_travel: MaxTravelOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    damper: Annotated[
        str,
        typer.Option(
            "--damper",
            metavar="MODEL|FILE.toml",
            help="Damper of the laws: railway, dyke1996, spencer1997, ideal-damper or ideal." + OWN_DAMPER,
        ),
    ] = DEFAULT_DAMPER,
    dt: DtOption = None,
    backend: BackendOption = None,
    workers: WorkersOption = None,
    processes: ProcessesOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: DesignOutOption = None,
    resume: DesignResumeOption = False,
    format: FormatOption = OutputFormat.table,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    report: ReportOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Which controller for this vehicle: every law tuned alike on a training set of random
    tracks (seeds x speeds x loads), then judged with passive on held-out seeds never used in
    tuning. Prints per speed and load the RMS ratios to passive with their 5-95 % bands, what
    each law asks of its dampers, the ranking and a recommendation in words. Ctrl-C stops; with
    --out, --resume continues."""
    from railride.cli.tune import _objective
    from railride.studies.objectives import OBJECTIVE_KINDS

    from railride.cli._render import check_report_option, save_report

    command = command_line(ctx, exclude=OUTPUT_ONLY)
    with errors(), option_names(DESIGN_FIELDS):
        check_report_option(report)
        figures = figure_options(figure_format, dpi, out)
        names = [c.strip() for c in controllers.split(",")]
        seed_of_evolution = optimiser_seed_of(optimiser, optimiser_seed)
        tracks = [t.strip() for t in track.split(",")]
        for t in tracks:
            check_table("--track", t)
        speeds = value_list("--speed", speed)
        loads = value_list("--load", load)
        train = [int(s) for s in value_list("--train-seeds", train_seeds, integer=True)]
        test = [int(s) for s in value_list("--test-seeds", test_seeds, integer=True)]
        source = vehicle_source(vehicle, preset)
        damper = damper_argument("--damper", damper)
        if objective_kind is not None and objective_kind.strip() not in OBJECTIVE_KINDS:
            objective = objective_kind  # the library names what it allows, and knows other spellings
        else:
            objective = _objective(objective_kind, weights, bound, penalty, max_peak, max_travel)
        solver = solver_from_options(dt=dt, backend=backend)
        from railride.studies.design import check_design

        settings = dict(
            vehicle=source,
            loads=loads,
            tracks=tracks,
            speeds=speeds,
            objective=objective,
            aggregate=aggregate,
            budget=budget,
            values=values,
            optimiser=optimiser.strip(),
            optimiser_seed=seed_of_evolution,
            train_seeds=train,
            test_seeds=test,
            duration=duration,
            damper=damper,
            solver=solver,
            speed_shares=None if speed_share is None else number_items("--speed-share", speed_share),
            load_shares=None if load_share is None else number_items("--load-share", load_share),
        )
        check_design(None if controllers.strip() == "all" else names, **settings)  # before the folder
        table, table_path = open_run_table(out, resume)
        # only the chunks that fill the threads (one on 2 cores): one more, whose rows are made
        # beside them, took the default design to 2.09 GiB, above its 2 GiB (docs/performance.md)
        executor, executor_record = make_executor(
            workers, scheduler, scheduler_file, processes=processes, rows_beside=False
        )
    try:
        with interruptible(table, table_path), errors(), option_names(DESIGN_FIELDS):
            from railride.studies.design import design

            with RunProgress(stderr_is_terminal(), "designing") as progress:
                t0 = time.perf_counter()
                result = design(
                    None if controllers.strip() == "all" else names,
                    **settings,
                    executor=executor,
                    table=table,
                    progress=progress,
                    log=progress.log,
                )
                wall = time.perf_counter() - t0
            facts = {
                "runs_evaluated": progress.evaluated,
                "wall_time_s": wall,
                "executor": executor_record,
                "command": command,
            }
            doc = {**result.to_dict(), **facts}
            text = json.dumps(doc, indent=2, allow_nan=False)
            if out is not None:
                write_folder(
                    out,
                    lambda: result.save(
                        out, command, extra=facts, figure_formats=figures.figure_formats, dpi=figures.dpi
                    ),
                )
    finally:
        executor.close()
    if format is OutputFormat.json:
        typer.echo(text)
    else:
        console = stdout_console()
        for part in _tables(doc):
            console.print(part)
    if report is not None:  # after the output: a report that cannot be written loses none of it
        save_report(report, result, _tables(doc), ctx)
