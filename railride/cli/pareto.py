"""``railride pareto``: the trades a controller's gains offer (railride.studies.pareto), with its
tables."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from railride.defaults import DEFAULT_DAMPER
from railride.cli._app import app
from railride.cli._common import (
    errors,
    interruptible,
    make_executor,
    open_run_table,
    option_names,
    print_json,
    RunProgress,
    stderr_is_terminal,
    stdout_console,
    write_folder,
)
from railride.cli._options import (
    MaxMemoryOption,
    MaxStepsOption,
    AmplitudeOption,
    DpiOption,
    BackendOption,
    DtOption,
    FigureFormatOption,
    FormatOption,
    LoadOption,
    MaxWavelengthOption,
    MinWavelengthOption,
    OutputFormat,
    ParetoDamperOption,
    ParetoGainsOption,
    ParetoOutOption,
    ParetoResumeOption,
    PresetOption,
    RailPhaseOption,
    RunDurationOption,
    RunsScenarioOption,
    SchedulerFileOption,
    SchedulerOption,
    SpeedOption,
    TrackSeedOption,
    VehicleOption,
    WavelengthOption,
    ProcessesOption,
    WorkersOption,
    figure_options,
)
from railride.cli._parsing import (
    PROFILE_FIELDS,
    SOLVER_FIELDS,
    TRACK_FIELDS,
    damper_argument,
    default_of,
    load_gains,
    not_given,
    solver_from_options,
    study_scenario,
    vehicle_arguments,
)
from railride.cli._render import RESPONSE_LABELS, damper_text, fmt, warn_gains_mismatch

#: the library's names of pareto's options, for its errors (the track's seed is named while the
#: scenario is built, the sample's after)
PARETO_FIELDS = {
    "dt": SOLVER_FIELDS["dt"],
    "backend": SOLVER_FIELDS["backend"],
    **TRACK_FIELDS,
    "suspension": "--suspension",
    "n_samples": "--samples",
    "seed": "--seed",
    **PROFILE_FIELDS,
    "load": "--load",
    "output_rate": "output rate",
}


def _pareto_table(doc: dict, caption: str):
    """Counts, then the samples non-dominated over the four ratios by acceleration ratio."""
    from railride.cli._width import FitTable

    from railride.studies.pareto import PROJECTIONS

    c = doc["counts"]
    counts = FitTable(title="Pareto view: samples and non-dominated samples")
    counts.add_column("samples (with the base gains)", justify="right")
    counts.add_column("non-dominated\nover all four ratios", justify="right")
    for x, y in PROJECTIONS:
        counts.add_column(f"non-dominated in\n{x} and {y}", justify="right")
    travel = "non_dominated_with_travel" in c
    if travel:
        counts.add_column("non-dominated over\nthe four and travel", justify="right")
    counts.add_row(
        str(c["samples"]),
        str(c["non_dominated"]),
        *[str(c[f"non_dominated_{x}_{y}"]) for x, y in PROJECTIONS],
        *([str(c["non_dominated_with_travel"])] if travel else []),
    )
    if 2 * c["non_dominated"] > c["samples"]:  # four objectives: most of few points are on the front
        counts.caption = (
            f"{c['non_dominated']} of {c['samples']} samples are non-dominated over the four ratios: more than "
            "half, a front this thinly sampled in four ratios (more --samples fill it)."
        )
    front = sorted(
        (r for r in doc["samples"] if r["non_dominated"]),
        key=lambda r: (r["acceleration_m_s2_ratio"] is None, r["acceleration_m_s2_ratio"] or 0.0),
    )
    caption += (
        "\n2-D fronts: the planes of the figure (acceleration against pitch, against roll) in which the sample is "
        "also non-dominated."
    )
    rows = FitTable(
        title="Non-dominated samples by acceleration ratio: ratios to passive (RMS; largest travel)",
        caption=caption,
        caption_justify="left",
    )
    rows.add_column("sample", justify="right")
    for label in RESPONSE_LABELS.values():
        rows.add_column(label.split(" (")[0], justify="right")
    if travel:
        rows.add_column("max\ntravel", justify="right")
    rows.add_column("2-D fronts")
    for r in front:
        planes = "/".join(y for x, y in PROJECTIONS if r[f"non_dominated_{x}_{y}"]) or "-"
        rows.add_row(
            f"{r['sample']}" + (" (base)" if r["base"] else ""),
            *[fmt(r[f"{key}_ratio"], ".3f") for key in RESPONSE_LABELS],
            *([fmt(r["travel_ratio"], ".3f")] if travel else []),
            planes,
        )
    return [counts, "", rows, *([travel_text(doc)] if travel else [])]


def travel_text(doc: dict) -> str:
    """The document's ``front_travel`` (`ParetoResult.front_travel`) in words."""
    t, passive = doc.get("front_travel"), doc.get("passive_travel_m")
    if not t or not passive or not t["samples"]:
        return ""
    head = (
        f"Travel: max travel is each sample's largest secondary travel over passive's ({passive * 1e3:.3g} mm); "
        "the four-ratio front does not weigh it. "
    )
    if not t["more_than_passive"]:
        return head + f"None of the {t['samples']} samples on the front needs more travel than passive."
    text = head + (
        f"{t['more_than_passive']} of the {t['samples']} samples on the front need more travel than passive (up to "
        f"x{t['largest_ratio']:.3g}): ride bought with rattle space."
    )
    clearance = t["clearance_m"]
    if t["past_clearance"]:
        stiff = t["stop_stiffness_n_per_m"] > 0
        stops = "the stops then bound it" if stiff else "no stop force is modelled, k_stop = 0"
        text += (
            f" {t['past_clearance']} of them go past the {clearance * 1e3:g} mm clearance (z_stop; {stops}): a real "
            "car would be on its stops."
        )
    elif clearance:
        text += f" None passes the {clearance * 1e3:g} mm clearance (z_stop)."
    front_with_travel = doc["counts"]["non_dominated_with_travel"]
    return text + f" Over the four ratios and travel {front_with_travel} samples are non-dominated."


@app.command("pareto")
def pareto_command(
    suspension: Annotated[
        str,
        typer.Option(
            "--suspension",
            metavar="NAME",
            help="The controller whose gains are sampled: pid, sas-attitude or sas-attitude-ride "
            "(every outer-loop gain it reads).",
        ),
    ] = "sas-attitude-ride",
    samples: Annotated[
        Optional[int],
        typer.Option(
            "--samples",
            metavar="N",
            help="Sobol' samples of the gains, a power of two (default 128); the base gains are run too.",
        ),
    ] = None,
    seed: Annotated[int, typer.Option("--seed", metavar="S", help="Seed of the scrambled Sobol' sample, >= 0.")] = 0,
    scenario: RunsScenarioOption = "paper-sine",
    amplitude: AmplitudeOption = None,
    wavelength: WavelengthOption = None,
    rail_phase: RailPhaseOption = None,
    track_seed: TrackSeedOption = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    speed: SpeedOption = None,
    duration: RunDurationOption = None,
    dt: DtOption = None,
    backend: BackendOption = None,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
    damper: ParetoDamperOption = DEFAULT_DAMPER,
    gains: ParetoGainsOption = None,
    workers: WorkersOption = None,
    processes: ProcessesOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: ParetoOutOption = None,
    resume: ParetoResumeOption = False,
    format: FormatOption = OutputFormat.table,
    figure_format: FigureFormatOption = None,
    dpi: DpiOption = None,
    max_memory: MaxMemoryOption = None,
    max_steps: MaxStepsOption = None,
) -> None:
    """The trades a controller's gains offer: RMS ratios to passive of sampled gains.

    Samples the gains in log10 over the box of the global optimiser (REFERENCE / 1000 to
    REFERENCE x 100) by a scrambled Sobol' sequence, runs them and the base gains, and marks the
    samples no other beats in every ratio (non-dominated). Prints the counts and the
    non-dominated samples by acceleration ratio. Ctrl-C stops; with --out, --resume continues.
    """
    import time

    from railride.model.params import vehicle_text

    defaults = not_given(dt=dt, min_wavelength=min_wavelength, max_wavelength=max_wavelength)
    with errors(), option_names(PARETO_FIELDS, defaults):
        from railride.analysis.labels import describe_scenario
        from railride.studies.pareto import pareto as run_pareto

        figures = figure_options(figure_format, dpi, out)
        n = default_of(run_pareto, "n_samples") if samples is None else samples
        vehicle_options = vehicle_arguments(vehicle, preset, load)
        damper_given, damper = damper, damper_argument("--damper", damper)
        base = load_gains(gains)
        solver = solver_from_options(dt=dt, backend=backend)
        scen, options = study_scenario(
            scenario,
            amplitude=amplitude,
            wavelength=wavelength,
            rail_phase=rail_phase,
            speed=speed,
            duration=duration,
            track_seed=track_seed,
            min_wavelength=min_wavelength,
            max_wavelength=max_wavelength,
        )
        scenario_text = describe_scenario(scen.describe())
        table, table_path = open_run_table(out, resume)
        executor, executor_record = make_executor(workers, scheduler, scheduler_file, processes=processes)
    try:
        with interruptible(table, table_path), errors(), option_names(PARETO_FIELDS, defaults):
            with RunProgress(stderr_is_terminal(), "sampling the gains") as progress:
                t0 = time.perf_counter()
                result = run_pareto(
                    suspension,
                    n_samples=n,
                    seed=seed,
                    scenario=scenario,
                    scenario_options=options,
                    gains=base,
                    damper=damper,
                    executor=executor,
                    table=table,
                    solver=solver,
                    progress=progress,
                    **vehicle_options,
                )
                wall = time.perf_counter() - t0
            doc = result.to_dict()
            if out is not None:
                write_folder(out, lambda: result.save(out, figure_formats=figures.figure_formats, dpi=figures.dpi))
    finally:
        executor.close()
    warn_gains_mismatch(doc["settings"], damper_given)
    if format is OutputFormat.json:
        print_json(doc)
        return
    st = doc["settings"]
    lines = [
        (f"{scenario_text}, {scen.duration:g} s, dt {solver.dt:g} s, {damper_text(st)}; base gains {st['base_gains']}"),
        f"{st['n_samples']} samples, seed {st['seed']}: {st['sampling']}",
        vehicle_text(st["vehicle"]),
        (
            f"{doc['runs']} runs in the run table, {progress.evaluated} evaluated now, wall "
            f"time {wall:.1f} s ({executor_record['type']})"
        ),
    ]
    if doc["note"]:
        lines.append(doc["note"])
    console = stdout_console()
    for part in _pareto_table(doc, "\n".join(lines)):
        console.print(part)
