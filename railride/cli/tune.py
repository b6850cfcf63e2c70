"""``railride tune``: every law's gains by the same sensitivity study and budget
(railride.studies.tuning), the parsing of its objective and controllers, and its tables."""

from __future__ import annotations

import json
import math
from pathlib import Path
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
    MaxMemoryOption,
    StartOption,
    MaxStepsOption,
    AmplitudeOption,
    BoundOption,
    DpiOption,
    BackendOption,
    DtOption,
    FigureFormatOption,
    FormatOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    ObjectiveOption,
    OutputFormat,
    MaxPeakOption,
    MaxTravelOption,
    PenaltyOption,
    PresetOption,
    RailPhaseOption,
    ReportOption,
    RunDurationOption,
    RunsScenarioOption,
    SchedulerFileOption,
    SchedulerOption,
    SpeedOption,
    TuneDamperOption,
    TuneDamperScaleOption,
    TuneGainsOption,
    TuneOutOption,
    TuneResumeOption,
    VehicleOption,
    WavelengthOption,
    WeightsOption,
    OptimiserOption,
    OptimiserSeedOption,
    optimiser_seed as optimiser_seed_of,
    ProcessesOption,
    WorkersOption,
    figure_options,
)
from railride.cli._parsing import (
    PROFILE_FIELDS,
    SOLVER_FIELDS,
    TRACK_FIELDS,
    damper_argument,
    load_gains,
    not_given,
    parse_float,
    parse_scale,
    solver_from_options,
    study_scenario,
    value_list,
    vehicle_source,
)
from railride.cli._render import RESPONSE_LABELS, damper_text, reduction_text
from railride.cli._render import check_report_option, save_report

#: the library's names of tune's options, for its errors
TUNE_FIELDS = {
    "dt": SOLVER_FIELDS["dt"],
    "optimiser": "--optimiser",
    "optimiser_seed": "--optimiser-seed",
    "backend": SOLVER_FIELDS["backend"],
    **TRACK_FIELDS,
    "damper": "--damper",
    "damper_scale": "--damper-scale",
    "n_values": "--values",
    "budget": "--budget",
    "span": "--span",
    "aggregate": "--aggregate",
    **PROFILE_FIELDS,
    "load": "--load",
    "output_rate": "output rate",
}


def _objective(
    kind: Optional[str],
    weights: Optional[str],
    bound: Optional[str],
    penalty: Optional[str],
    max_peak: Optional[str] = None,
    max_travel: Optional[str] = None,
):
    """--objective, --weights, --bound, --penalty, --max-peak, --max-travel -> a
    tuning.Objective (the last two: its ``peak_bound`` and ``travel_bound``). Without --objective,
    the library's DEFAULT_OBJECTIVE; an option not given keeps that default's value when the
    kind is the default's (weights and bound belong to their kind only)."""
    from railride.studies.objectives import DEFAULT_OBJECTIVE, OBJECTIVE_KINDS, Objective

    name = DEFAULT_OBJECTIVE.kind if kind is None else kind.strip()
    if name not in OBJECTIVE_KINDS:
        raise InputError(f"--objective = {kind!r}: unknown objective; allowed: {', '.join(OBJECTIVE_KINDS)}")
    default = DEFAULT_OBJECTIVE if name == DEFAULT_OBJECTIVE.kind else Objective()
    which = f"--objective is {name}" if kind is not None else f"the default objective is {name}"
    w = default.weights if name == "weighted" else None
    if weights is not None:
        if name != "weighted":
            raise InputError(f"--weights = {weights!r}: applies to --objective weighted only ({which})")
        w = _weights(weights)
    if name == "weighted" and w is None:
        raise InputError(
            "--objective weighted needs --weights A,D,P,R: four numbers >= 0, not "
            "all 0 (acceleration, displacement, pitch, roll)"
        )
    b = default.bound if name == "constrained" else None
    if bound is not None:
        if name != "constrained":
            raise InputError(f"--bound = {bound!r}: applies to --objective constrained only ({which})")
        b = parse_float("--bound", bound, bound, " (the largest RMS ratio to passive allowed)")
        if b <= 0:
            raise InputError(
                f"--bound = {bound!r}: must be a finite number > 0 (the largest "
                "RMS ratio to passive allowed for every response)"
            )
    if name == "constrained" and b is None:
        raise InputError(
            "--objective constrained needs --bound X: the largest RMS ratio to "
            "passive allowed for every response, a finite number > 0"
        )
    p = default.penalty
    if penalty is not None:
        p = parse_float("--penalty", penalty, penalty)
        if p < 0:
            raise InputError(f"--penalty = {penalty!r}: must be a finite number >= 0")
    limits = {
        "peak_bound": None if max_peak is None else parse_float("--max-peak", max_peak, max_peak),
        "travel_bound": None if max_travel is None else parse_float("--max-travel", max_travel, max_travel),
    }
    try:
        return Objective(name, w, b, p, **limits)
    except ValueError as exc:  # what the checks above cannot see, e.g. a bound too large
        text = str(exc)
        for field, option in (("peak_bound", "--max-peak"), ("travel_bound", "--max-travel"), ("bound", "--bound")):
            text = text.replace(f"objective {field}", option)
        raise InputError(text if text != str(exc) else f"--objective {name}: {exc}") from None


def _weights(weights: str) -> tuple:
    """--weights A,D,P,R -> four numbers >= 0, not all 0."""
    items = [item.strip() for item in weights.split(",")]
    if len(items) != 4:
        raise InputError(
            f"--weights = {weights!r}: expected four numbers A,D,P,R (acceleration, "
            f"displacement, pitch, roll), got {len(items)} item(s)"
        )
    values = []
    for name, item in zip(("A", "D", "P", "R"), items):
        try:
            value = float(item)
        except ValueError:
            raise InputError(f"--weights = {weights!r}: {name} = {item!r} is not a number") from None
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"--weights = {weights!r}: {name} = {item}: must be a finite number >= 0")
        values.append(value)
    if sum(values) == 0:
        raise InputError(f"--weights = {weights!r}: at least one weight must be > 0")
    return tuple(values)


def _score(value) -> str:
    """An objective as the tables show it: the document holds null for J = inf (every candidate
    diverged or broke a hard bound)."""
    return "inf" if value is None else f"{value:.4f}"


def _tunable_list(text: str) -> list[str]:
    """--controllers: comma-separated names from inner and the laws, or all -> what to tune,
    in the order it runs."""
    from railride.studies.tuning import TUNABLE

    items = [n.strip() for n in text.split(",")]
    if any(not n for n in items):
        raise InputError(
            f"--controllers = {text!r}: an empty item; give names separated by commas from {', '.join(TUNABLE)}, all"
        )
    for n in items:  # every name checked, "all" beside others too
        if n not in TUNABLE and n != "all":
            why = " has no gains to tune" if n in ("passive", "passive-on", "passive-off") else " is not known"
            raise InputError(f"--controllers = {text!r}: {n!r}{why}; allowed: {', '.join(TUNABLE)}, all")
    return [n for n in TUNABLE if n in items or "all" in items]


def _tuning_set(scenario, seeds, loads, speed, duration, start, *single):
    """--track-seed with several seeds, or --load: the runs every gain set is scored on (on a
    measured profile's section from ``start``, --start, where given)."""
    import dataclasses

    from railride.studies.tuning import tuning_set

    if any(v is not None for v in single):
        raise InputError(
            "--amplitude, --wavelength, --rail-phase, --min-wavelength and --max-wavelength apply to "
            "a single tuning scenario, not to several --track-seed values or --load"
        )
    with option_names({"track_seeds": "--track-seed", "loads": "--load"}):
        cases = tuning_set(
            scenario,
            track_seeds=None if seeds is None else [int(x) for x in seeds],
            speeds=None if speed is None else [speed],
            loads=[1.0] if loads is None else loads,
            duration=duration,
        )
    if start is None:
        return cases
    return tuple(dataclasses.replace(c, options=tuple(sorted((*c.options, ("start", start))))) for c in cases)


def _tune_start(path: Optional[Path]):
    """--gains FILE, else the neutral reference gains (the library's default start)."""
    from railride.secondary.control import GainSet

    return GainSet.reference() if path is None else load_gains(path)


def _objective_text_from_doc(doc: dict) -> str:
    return doc["objective"]["statement"]


def _tune_tables(doc: dict, start, tuned, scenario_text: str):
    from rich.markup import escape
    from rich.text import Text

    from railride.analysis.labels import gain_unit
    from railride.model.params import vehicle_text
    from railride.studies.tuning import PARAMETERS
    from railride.cli._width import FitTable, Split

    parts: list = []
    settings = doc["settings"]
    per_set = (
        f" gain sets each, {len(settings['tuning_set'])} runs per set ({settings['aggregate']} objective)"
        if "tuning_set" in settings
        else " runs each"
    )
    stopped = {"budget": "budget spent", "passes": "pass limit"}
    study_cells = {  # heading -> (justify, cell of a study)
        "gains": ("right", lambda st: str(len(st["entries"]))),
        "runs": ("right", lambda st: f"{st['runs']}" + ("" if st["budget"] is None else f" / {st['budget']}")),
        "passes": ("right", lambda st: str(st["passes"])),
        "objective\nstart": ("right", lambda st: _score(st["objective_start"])),
        "objective\ntuned": ("right", lambda st: _score(st["objective"])),
        "stopped": ("left", lambda st: stopped.get(st["stopped"], st["stopped"])),
    }

    def studies_table(groups: list[list[str]]):
        studies = FitTable(title=f"Tuning: every law from the same start, at most {settings['budget']}{per_set}")
        studies.add_column("study")
        for heading in (h for g in groups for h in g):
            studies.add_column(heading, justify=study_cells[heading][0], no_wrap=heading == "runs")  # type: ignore[arg-type]
        for st in doc["studies"]:
            studies.add_row(st["controller"], *[study_cells[h][1](st) for g in groups for h in g])
        return studies

    # on a narrow console what each study took, then what it reached
    headings = list(study_cells)
    parts += [Split(studies_table, [headings[:3], headings[3:]]), ""]
    passes = FitTable(title="Tuning: the objective after each pass")
    passes.add_column("study")
    passes.add_column("pass", justify="right")
    passes.add_column("span", justify="right")
    passes.add_column("runs", justify="right")
    passes.add_column("objective", justify="right")
    passes.add_column("change %", justify="right")
    infeasible = doc["objective"].get("infeasible")  # constrained: J >= offset breaks the bound
    if infeasible:
        passes.add_column("within\nbound")
    previous: dict[str, float] = {}
    for h in doc["history"]:
        before, now = previous.get(h["controller"]), h["objective"]
        change = "" if before is None or now is None else f"{(now - before) / abs(before) * 100:+.2f}"
        cells = [h["controller"], str(h["pass"]), f"{h['span']:.3g}", str(h["runs"]), _score(now), change]
        if infeasible:
            inner = h["controller"] == "inner"
            cells.append("" if inner else "yes" if now is not None and now < infeasible["offset"] else "no")
        passes.add_row(*cells)
        previous[h["controller"]] = h["objective"]
    parts += [
        passes,
        Text(
            "objective: "
            + _objective_text_from_doc(doc)
            + (
                "; inner: the normalised force-tracking error on the damper rig (rig runs, not counted in the budget)"
                if "inner" in doc["controllers"]
                else ""
            )
            + "; runs: distinct gain sets scored by the study so far; span: each sweep runs from "
            "1/span to span x the current value"
        ),
        "",
    ]

    gains = FitTable(title="Tuned gains")
    gains.add_column("gain")
    gains.add_column("unit")
    gains.add_column("start", justify="right")
    gains.add_column("tuned", justify="right")
    gains.add_column("", no_wrap=True)
    for study in doc["controllers"]:
        for name in PARAMETERS[study]:
            table_name, _, entry = name.partition(".")
            a = getattr(getattr(start, table_name), entry)
            b = getattr(getattr(tuned, table_name), entry)
            gains.add_row(
                name,
                escape(gain_unit(name) or ""),
                f"{a:.4g}",
                f"{b:.4g}",
                "" if math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0) else "changed",
            )
        gains.add_section()
    parts += [gains, ""]

    rows = doc["before_after"]
    if rows:
        from railride.secondary.control import LABELS

        # passive first, as a block of its own (no gains: the same RMS in both columns), so
        # that the table fits 80 columns without a passive column beside every suspension
        table = FitTable(title="RMS of the carbody responses with the start and the tuned gains", labels=2)
        table.add_column("suspension")
        table.add_column("response")
        table.add_column("start\ngains", justify="right")
        table.add_column("red. %", justify="right", no_wrap=True)
        table.add_column("tuned\ngains", justify="right")
        table.add_column("red. %", justify="right", no_wrap=True)
        for i, (key, label) in enumerate(RESPONSE_LABELS.items()):
            rms = f"{doc['passive_rms'][key]:#.4g}"
            table.add_row(
                "Passive" if i == 0 else "", label, rms, "", rms, "", end_section=i == len(RESPONSE_LABELS) - 1
            )
        for r in rows:
            for i, (key, label) in enumerate(RESPONSE_LABELS.items()):
                table.add_row(
                    escape(LABELS[r["suspension"]]) if i == 0 else "",
                    label,
                    f"{r['before'][key]:#.4g}",
                    reduction_text(r["reduction_before_percent"][key]),
                    f"{r['after'][key]:#.4g}",
                    reduction_text(r["reduction_after_percent"][key]),
                    end_section=i == len(RESPONSE_LABELS) - 1,
                )
        parts.append(table)
    s = doc["settings"]
    parts.append(
        Text(
            "\n".join(
                [
                    f"{scenario_text}, {doc['scenario'].get('duration_s', 0):g} s, dt {s['dt_s']:g} s, "
                    f"{damper_text(s)}; start gains {s['start_gains']}",
                    vehicle_text(s["vehicle"]),
                    "red. % = (passive - controlled) / passive x 100 (negative: worse than passive, in red)",
                    *(_tuned_against_start(rows, {st["controller"] for st in doc["studies"]}) if rows else []),
                    f"{doc['runs']} runs in the run table, {doc['runs_evaluated']} evaluated now "
                    f"({doc['runs_per_second']:.1f} runs/s), wall time {doc['wall_time_s']:.1f} s",
                ]
            )
        )
    )
    return parts


def _tuned_against_start(rows: list[dict], tuned: set) -> list[str]:
    """The lines under the table of the start and tuned gains: that its runs are the tuning's own,
    and per law the responses the tuned gains make better and worse than the start gains (RMS
    within the comparisons' level tolerance of the larger: level). A law not in ``tuned`` (the
    laws whose own study ran) changed only through the inner loop it shares, and is said so."""
    from railride.output.trade_offs import RESPONSE_WORDS
    from railride.secondary.control import LABELS
    from railride.studies.comparison import LEVEL_TOLERANCE, is_level

    lines = [
        "Both columns are runs on the track tuned on: in-sample, not a test on another track "
        "(railride compare --scenario ..., railride design)."
    ]
    for r in rows:
        keys = [k for k in r["before"] if not is_level(r["after"][k], r["before"][k], LEVEL_TOLERANCE)]
        better = [RESPONSE_WORDS.get(k, k) for k in keys if r["after"][k] < r["before"][k]]
        worse = [RESPONSE_WORDS.get(k, k) for k in keys if r["after"][k] > r["before"][k]]
        if better and worse:
            what = (
                ("the tuned gains beat", "are")
                if r["suspension"] in tuned
                else ("not tuned itself, with the tuned inner loop it shares it beats", "is")
            )
            lines.append(
                f"{LABELS[r['suspension']]}: {what[0]} the start on {', '.join(better)} but {what[1]} worse on "
                f"{', '.join(worse)} (the objective scores the four together)."
            )
    return lines


@app.command("tune")
def tune_command(
    ctx: typer.Context,
    controllers: Annotated[
        str,
        typer.Option(
            "--controllers",
            metavar="NAME[,NAME...]",
            help="What to tune, comma-separated: inner (B, G on the damper rig's force tracking), "
            "pid, sas-attitude, sas-attitude-ride, skyhook, skyhook-on-off, groundhook, hybrid, "
            "clipped-optimal, or all (the default). They run in that order; each law starts from "
            "the start gains and gets the same --budget.",
        ),
    ] = "all",
    scenario: RunsScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: Annotated[
        Optional[str],
        typer.Option(
            "--track-seed",
            metavar="N[,N...]|A:B:COUNT",
            help="Random tracks only: the seed of the track's realisation (default 0); several seeds "
            "(a list or a range) tune on all of them at once (robust tuning, see --aggregate).",
        ),
    ] = None,
    load: Annotated[
        Optional[str],
        typer.Option(
            "--load",
            metavar="X[,X...]",
            help="Load factors (carbody mass and inertias times X) to tune on; several tune on all "
            "of them at once (robust tuning, see --aggregate). Default 1.",
        ),
    ] = None,
    aggregate: Annotated[
        str,
        typer.Option(
            "--aggregate",
            metavar="mean|worst",
            help="With several seeds or loads: each gain set's objective is the mean, or the worst, "
            "of its runs' objectives.",
        ),
    ] = "mean",
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    section_start: StartOption = None,
    speed: SpeedOption = None,
    duration: RunDurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    damper: TuneDamperOption = DEFAULT_DAMPER,
    damper_scale: TuneDamperScaleOption = None,
    gains: TuneGainsOption = None,
    objective_kind: ObjectiveOption = None,
    weights: WeightsOption = None,
    bound: BoundOption = None,
    penalty: PenaltyOption = None,
    max_peak: MaxPeakOption = None,
    max_travel: MaxTravelOption = None,
    values: Annotated[
        int,
        typer.Option(
            "--values",
            metavar="N",
            help="Log-spaced values per gain and pass, from 1/span to span times the current value "
            "(0 and the current value are added); >= 3.",
        ),
    ] = 13,
    span: Annotated[float, typer.Option("--span", metavar="S", help="Range factor of each sweep, > 1.")] = 30.0,
    budget: Annotated[
        int,
        typer.Option(
            "--budget",
            metavar="N",
            help="Vehicle runs per law (distinct gain sets scored, the start included), the same "
            "for every law; a law with few gains narrows its sweeps and may stop earlier. At least "
            "the start and one sweep, --values + 2 (with --optimiser evolution, the start and two generations).",
        ),
    ] = 400,
    workers: WorkersOption = None,
    processes: ProcessesOption = None,
    optimiser: OptimiserOption = "sensitivity",
    optimiser_seed: OptimiserSeedOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: TuneOutOption = None,
    resume: TuneResumeOption = False,
    format: FormatOption = OutputFormat.table,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    report: ReportOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """Tune every law's gains by the paper's sensitivity study (its section V), alike.

    One gain at a time is swept over log-spaced values (and 0) with the others fixed; the best
    value is kept; passes repeat. Every law starts from the same gains and gets the same budget
    of vehicle runs; a pass that gains less than 0.1 % narrows the sweeps. Each run is scored by
    the objective (--objective) over its RMS carbody responses relative to passive. Prints each
    law's study, the objective per pass, the tuned gains and the RMS with the start and the
    tuned gains. Ctrl-C stops; with --out, --resume continues.
    """
    import time

    command = command_line(ctx, exclude=OUTPUT_ONLY)
    defaults = not_given(dt=dt, min_wavelength=min_wavelength, max_wavelength=max_wavelength, seed=track_seed)
    seeds: Optional[list] = None
    with errors(), option_names(TUNE_FIELDS, defaults):
        from railride.studies import tuning
        from railride.analysis.labels import describe_scenario

        figures = figure_options(figure_format, dpi, out)
        names = _tunable_list(controllers)
        seed_of_evolution = optimiser_seed_of(optimiser, optimiser_seed)
        source = vehicle_source(vehicle, preset)
        damper = damper_argument("--damper", damper)
        scale = parse_scale("--damper-scale", damper_scale)
        start = _tune_start(gains)
        objective = _objective(objective_kind, weights, bound, penalty, max_peak, max_travel)
        solver = solver_from_options(dt=dt, backend=backend)
        seeds = value_list("--track-seed", track_seed, integer=True) if track_seed is not None else None
        loads = value_list("--load", load) if load is not None else None
        over = None
        if (seeds is not None and len(seeds) > 1) or loads is not None:
            over = _tuning_set(
                scenario,
                seeds,
                loads,
                speed,
                duration,
                section_start,
                amplitude,
                wavelength,
                rail_phase,
                min_wavelength,
                max_wavelength,
            )
        scen, options = study_scenario(
            scenario,
            amplitude=amplitude,
            wavelength=wavelength,
            rail_phase=rail_phase,
            speed=speed,
            duration=duration,
            track_seed=None if seeds is None else int(seeds[0]),
            min_wavelength=min_wavelength,
            max_wavelength=max_wavelength,
            start=section_start,
        )
        scenario_text = describe_scenario(scen.describe())
        check_report_option(report)
        table, table_path = open_run_table(out, resume)
        executor, executor_record = make_executor(workers, scheduler, scheduler_file, processes=processes)
    try:
        with interruptible(table, table_path), errors(), option_names(TUNE_FIELDS, defaults):
            with RunProgress(stderr_is_terminal(), "tuning") as progress:
                t0 = time.perf_counter()
                result = tuning.tune(
                    names,
                    scenario=scenario,
                    scenario_options=None if over is not None else options,
                    over=over,
                    aggregate=aggregate,
                    gains=start,
                    objective=objective,
                    damper=damper,
                    damper_scale=scale,
                    executor=executor,
                    table=table,
                    n_values=values,
                    span=span,
                    budget=budget,
                    vehicle=source,
                    solver=solver,
                    progress=progress,
                    log=progress.log,
                    optimiser=optimiser.strip(),
                    optimiser_seed=seed_of_evolution,
                )
                wall = time.perf_counter() - t0
            # the facts of this command line, after the library's document
            facts = {
                "runs_evaluated": progress.evaluated,
                "runs_per_second": progress.evaluated / wall if wall > 0 else 0.0,
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
    parts = _tune_tables(doc, result.start, result.gains, scenario_text)
    if format is OutputFormat.json:
        typer.echo(text)
    else:
        console = stdout_console()
        for part in parts:
            console.print(part)
    if report is not None:  # after the output: a report that cannot be written loses none of it
        save_report(report, result, parts, ctx)
